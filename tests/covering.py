"""The kernel specialisations the default test run compiles (issue 40), and how a test case outside them is marked.

Each specialisation compiles for 10 to 30 s of CPU (sim/compile_estimate.py: the measured table), so the default run
compiles a covering set, once, before the tests start (conftest.py), and no test compiles another:
- each preset's own (what a user runs first), the system step and the loads of rm3's bodies among them;
- each scheme (points, still water) and each force model (implicit, still water), every term in each: a scene with
  drag and one without share a specialisation (kernels.EVERY_TERM: every scheme compiles drag and skips it at a zero
  coefficient, issue 57), so the integrators' orders and energy without drag run on the same kernels;
- the panels model in waves (the cube's heave against the linear RAO: no preset has panels in waves without
  radiation);
- the force kernels only (seconds to compile, so left to the test) of each term alone (on points in still water and
  on panels in waves), and of every term on panels in waves.
The rest of the product of schemes x force models x waters x terms (x radiation) runs under `-m exhaustive` (.ci/run).
"""

from __future__ import annotations

from functools import cache

import pytest

from sim.kernels import COMPILED_TERMS, EVERY_TERM, SCHEMES, Spec

LINEAR = tuple(t for t in COMPILED_TERMS if t != "drag")
"""The terms of a scene without drag (its kernels compile every term all the same: kernels.compiled_terms)."""
EVERY = COMPILED_TERMS


def terms_for(scheme: str, terms: tuple[str, ...]) -> tuple[str, ...]:
    """The terms the kernels of a scene using `terms` compile under `scheme` (kernels.compiled_terms: every one for
    kernels.EVERY_TERM's schemes)."""
    return EVERY if scheme in EVERY_TERM else terms


def still(scheme: str, model: str, terms: tuple[str, ...] = EVERY, current: bool = False) -> Spec:
    return Spec(scheme, model, terms_for(scheme, terms), False, False, current)


def waves(scheme: str, model: str, terms: tuple[str, ...] = EVERY) -> Spec:
    return Spec(scheme, model, terms_for(scheme, terms), True, False)


FORCES_ONLY = [spec for term in COMPILED_TERMS for spec in (still("implicit", "points", (term,)), waves("implicit", "panels", (term,)))]
FORCES_ONLY += [waves("implicit", "panels")]
"""Specialisations whose force kernels alone the default run calls, each compiled by its test in seconds (no step, no
frame): each term alone, and every term on panels in waves (no preset steps panels in waves without radiation)."""


@cache
def compiled_first() -> list[Spec]:
    """The covering set's full specialisations (step and frame), compiled before the tests start."""
    from sim.commands.compile import preset_specs

    specs = preset_specs()
    specs += [still(scheme, "points") for scheme in SCHEMES]  # (the integrators' own tests, with drag and without)
    specs += [still("implicit", model) for model in ("panels", "cells")]
    specs += [waves("implicit", "panels")]
    return list(dict.fromkeys(specs))


def covered(spec: Spec, forces_only: bool = False) -> bool:
    """Whether the default run has the kernels of `spec` (forces_only: only its force kernels are called, seconds to compile)."""
    return spec in compiled_first() or (forces_only and spec in FORCES_ONLY)


def exhaustive(spec: Spec) -> list:
    """The marks of a test needing kernels outside the covering set: `exhaustive`, and one xdist group per
    specialisation, so that one worker compiles it, not both."""
    return [pytest.mark.exhaustive, pytest.mark.xdist_group(f"kernels-{spec.key}")]


def cases(params, spec_of_case, forces_only: bool = False) -> list:
    """pytest.param of each case (a tuple of arguments); those whose kernels (`spec_of_case(*case)`) the covering set
    lacks are marked `exhaustive`: they run in .ci/run, not in the default run."""
    return [pytest.param(*case, marks=_marks(spec, forces_only)) for case in params for spec in [spec_of_case(*case)]]


def _marks(spec: Spec, forces_only: bool) -> list:
    if not covered(spec, forces_only):
        return exhaustive(spec)
    if spec not in compiled_first():  # force kernels a test compiles: its cases on one worker, which compiles them once
        return [pytest.mark.xdist_group(f"kernels-{spec.key}")]
    return []

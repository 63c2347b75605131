"""How long the compiled kernels take to compile on this machine now: one measured table for the CLI, the viewer and
the README.

`floatsim bench --startup` measures each preset's compile in CPU seconds from an empty kernel cache (docs/performance.md);
COMPILE_CPU is that table as a sum of parts, one a feature of a kernels.Spec, fitted to it. This machine's speed now
(its load included) comes from timing a fixed piece of pure Python, the kind of work numba's compiler does, against the
same piece on the machine that measured the table: a machine twice as slow, or one core shared with another job, reads
as twice the estimate. A run compares it with its own time on the numpy reference, measured on the same machine at the
same moment, so the choice of one or the other does not follow the machine's load.
"""

from __future__ import annotations

import os
import statistics
import time

COMPILE_CPU = {
    "points": 12.0,
    "panels": 13.8,
    "cells": 13.3,
    "euler": -3.5,
    "splitting": -2.2,
    "rk4": -3.5,
    "drag": 1.1,
    "current": 2.7,
    "waves": 15.2,
    "radiating": 5.1,
    "held": 0.0,
    "system-step": 18.5,
    "system-linear": 23.6,
}
"""CPU seconds on the reference machine from an empty cache: a spec's force model under the implicit scheme, what
another scheme saves (no exact modes), then what each feature adds. Fitted on 2026-12-07 to `floatsim bench --startup`
on a quiet machine (docs/performance.md, after the fifth step: drop 12.5, log 13.8, sphere 18.9, waves 27.2, storm
28.3, moored-buoy 33.7 s; rm3, absorber-pair, farm and rm3-moored 31.7-33.7 s with their bodies' loads 13.3-14.1 s
measured apart, rm3-wecsim-moorings 23.6 s). A held load costs nothing of its own now: the moored step replaces the
scheme's n steps a call. The schemes' own parts are the earlier table's, scaled to it (not measured again). The water's
shared kernels are counted in every spec that uses them, as a first compile on a machine pays them."""

BODY_OF_SEVERAL = 0.47
"""The share of a body's spec that one of several bodies compiles: its loads, without a step or a frame of its own."""

REFERENCE_PROBE = 0.0109
"""Seconds `_probe` took on the reference machine (AMD EPYC, 2 cores, Python 3.11; quiet, as when the table was
measured)."""


def spec_cpu(spec) -> float:
    """The reference machine's CPU seconds to compile `spec`'s kernels from an empty cache (COMPILE_CPU's parts)."""
    if spec.scheme in ("system-step", "system-linear"):
        return COMPILE_CPU[spec.scheme]
    parts = [spec.model, *((spec.scheme,) if spec.scheme in COMPILE_CPU else ()), *(("drag",) if "drag" in spec.terms else ())]
    parts += [
        name for name, on in (("waves", spec.waves), ("current", spec.current), ("radiating", spec.radiating), ("held", spec.held)) if on
    ]
    return sum(COMPILE_CPU[p] for p in parts) * (BODY_OF_SEVERAL if spec.system else 1.0)


def _probe() -> float:
    """Seconds of a fixed piece of pure Python (dicts, strings, small objects: what a compiler's passes do), the median
    of 5 (not the best: on a machine shared with other work the compile gets the share of it a median slice gets)."""
    times = []
    for _ in range(5):
        started = time.perf_counter()
        table: dict = {}
        for i in range(20_000):
            key = f"v{i % 997}.{i}"
            table[key] = (i, key.upper(), [i, i + 1])
            table.pop(f"v{(i - 5) % 997}.{i - 5}", None)
        times.append(time.perf_counter() - started)
    return statistics.median(times)


def slowness() -> float:
    """How many times slower this machine is now than the one COMPILE_CPU was measured on (at least 1/4)."""
    return max(_probe() / REFERENCE_PROBE, 0.25)


SHARED_CPU = {"base": 4.5, "waves": 12.0}
"""What one process compiling several single-body specs pays once, not per spec: the kernels every such spec shares
(the rotations, the integrators' parts, numba's own array code) and the water's. Measured in the tests' first compile
from an empty cache (2026-12-07): the implicit scheme on points in still water 6.6 s after other specs in the same
process, 10.6 s alone (rest); on points in waves 10.8 s after other specs in waves, 27.2 s alone (waves). A system's
step shares about 1 s with its bodies' loads (rm3: 31.7 s together, 32.9 apart): not counted."""


def compile_seconds(specs, factor: float | None = None) -> float:
    """The seconds one process takes to compile `specs` on this machine now from an empty cache, the parts they share
    (SHARED_CPU) once (`factor`: slowness(), measured when not given)."""
    total, seen = 0.0, set()
    for spec in specs:
        total += spec_cpu(spec)
        shared = () if spec.scheme in ("system-step", "system-linear") else ("base", *(("waves",) if spec.waves else ()))
        total -= sum(SHARED_CPU[part] for part in shared if part in seen)
        seen.update(shared)
    return total * (slowness() if factor is None else factor)


def shares_of(specs, processes: int | None = None) -> list[tuple]:
    """`specs` in one share per core (or per one of `processes`; at most one per spec) of about equal compile time: the
    longest first, each to the share with the least so far (compiling.Compiler compiles the shares side by side)."""
    shares: list[list] = [[] for _ in range(min(len(specs), processes or os.cpu_count() or 1))]
    for spec in sorted(specs, key=spec_cpu, reverse=True):
        min(shares, key=lambda share: sum(map(spec_cpu, share))).append(spec)
    return [tuple(share) for share in shares]


def compile_wall(specs, factor: float | None = None) -> float:
    """The wall seconds compiling `specs` takes on this machine now from an empty cache, their shares side by side."""
    factor = slowness() if factor is None else factor
    return max((compile_seconds(share, factor) for share in shares_of(specs)), default=0.0)

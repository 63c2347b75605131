"""The array contract the numpy reference and its compiled twin share. Plain Python, no numba.

State vector y, (13,) float64: x_world (0:3, m), q_world_body (3:7, w x y z), u_world (7:10, m/s),
L_world (10:13, kg m^2/s). Twist (6,): (u_world, omega_world).

Geometry tuple `Body.packed`: (r_body (n, 3) m, n_body (n, 3), area (n,) m^2, mesh_vertices (v, 3) m,
mesh_faces (f, 3) int64, face_normals (f, 3), sample_moments (n, MOMENTS), cell_corners (n, 4, 3) m,
cell_reach (n,) m, and the mesh's triangles as a tree of parts (clusters.bisection_tree): face_order (f,) int64,
face_spans (parts, 4) int64, face_spheres (parts, 4) m), all body frame, C order.
Sample moments, per sample (sums over the wet set give every still-water integral, since z is linear
in r): a | a r (3) | a r r^T as xx xy xz yy yz zz (6) | a n (3) | a n r^T row-major (9) | a c (3) |
a c r^T row-major (9), with c = r x n.

Sea `sea_pack(water, body)`: (components (n, 8): a, omega, k_x, k_y, k, phase, cos and sin of the
direction; depth (inf: deep); whether the kernels may sum it as a series (kernels/water.py); the body's radius about its
centre of mass, m; the uniform current (3,) (u, v, 0), m/s; the ramp's duration, s (water.Waves.ramp)).
Still water has no components.

Coefficients `coef`, (COEF_BASE + number of term parameters + 6,) float64: rho, g, then every force
term's parameters in `forces.TERMS` order, then the held load (forces.Model.held: zero without). Terms mask `terms`: bit i set when `forces.TERMS[i]` is
used by the scene. So a new term gets its bit and its slots from its registry line alone.
"""

from __future__ import annotations

from functools import lru_cache
from typing import NamedTuple

import numpy as np

from sim.hydro.forces import TERMS

A, OMEGA, KX, KY, K, PHASE, COS, SIN = range(8)
"""Columns of the sea's components array (sea_pack)."""
STATE_SIZE = 13
MOMENTS = 34
RHO, G = 0, 1
COEF_BASE = 2
SCHEMES = {"euler": 0, "splitting": 1, "implicit": 2, "rk4": 3}
"""Integrators with a compiled twin, by their number in `integrators.advance`."""
MODELS = {"points": 0, "panels": 1, "cells": 2}
"""Force models (`surface.FORCE_MODELS`) by their number in the kernels."""
TERM_PARAMS = [p.key for term in TERMS for p in term.params]
COMPILED_TERMS = ("gravity", "pressure", "damping", "drag", "heave_damping")
"""The terms kernels/terms.py compiles, in registry order: a scene with any other runs on the numpy
reference, with a note (a test checks this list against forces.TERMS)."""


HELD = COEF_BASE + len(TERM_PARAMS)
"""Where the held load (6,) starts in `coef`: a wrench another model gives over a step (the mooring lines)."""
COEF_SIZE = HELD + 6


def bit(term: str) -> int:
    """The mask bit of a registered term."""
    return 1 << [t.name for t in TERMS].index(term)


def slot(key: str) -> int:
    """Where a term parameter sits in `coef`."""
    return COEF_BASE + TERM_PARAMS.index(key)


def coefficients(fluid, held: np.ndarray | None = None) -> np.ndarray:
    return np.array([fluid.rho, fluid.g, *(float(getattr(fluid, key)) for key in TERM_PARAMS), *(np.zeros(6) if held is None else held)])


def pack(model) -> tuple[int, np.ndarray]:
    """(terms mask, coef) of a `forces.Model`: only the terms it uses are switched on."""
    mask = 0
    for term in model.terms:
        mask |= bit(term.name)
    return mask, coefficients(model.fluid, model.held)


def sea_pack(water, body, expand: bool = True) -> tuple[np.ndarray, float, bool, float, np.ndarray, float]:
    """The water as the kernels take it (kernels/water.py), for this body. expand=False keeps the
    kernels on the direct sum over components (for benchmarks and checks of the expansion)."""
    reach = float(max(body.radius, np.linalg.norm(body.mesh_vertices, axis=1).max()))
    return _sea(water, reach, expand)


@lru_cache(maxsize=256)  # asked at every frame, by every body of an ensemble; the water is immutable
def _sea(water, radius: float, expand: bool) -> tuple[np.ndarray, float, bool, float, np.ndarray, float]:
    current = np.array([*water.current, 0.0])
    if water.flat:
        return np.zeros((0, 8)), float("inf"), True, radius, current, 0.0
    beta = water.direction
    comps = np.column_stack(
        [water.amplitude, water.omega, water.k * np.cos(beta), water.k * np.sin(beta), water.k, water.phase, np.cos(beta), np.sin(beta)]
    )
    return np.ascontiguousarray(comps), float(water.depth), bool(expand), radius, current, float(water.ramp)


NO_RADIATION = None
"""radiation_pack of a scene without radiation (the kernels specialise on it: see kernels/radiation.py)."""


def radiation_pack(radiation, body, dt: float) -> tuple:
    """A radiation.Radiation as the kernels take it (kernels/radiation.py): the generalised mass's
    inverse, inverse square root and square root in the body frame, the memory's output, its exact
    step over dt and its system (block-diagonal: bands and each row's block start). None: NO_RADIATION."""
    if radiation is None:
        return NO_RADIATION
    return radiation.kernel_arrays(body, dt)


class Model(NamedTuple):
    """A body as the kernels take it: geometry (`Body.packed`), mass (kg), principal inertia (3,) and coefficients (`coef`)."""

    geom: tuple
    mass: float
    inertia: np.ndarray
    coef: np.ndarray


class Scratch(NamedTuple):
    """What one pose's loads leave for the next evaluation: which samples are wet and the running sums over
    them (the sampled model), and the workspace for the twist terms (surface.workspace)."""

    flags: np.ndarray
    acc: np.ndarray
    ws: tuple


class Wet(NamedTuple):
    """The wet surface's integrals at a pose (kernels/wet.py), which the force terms read."""

    pressure: np.ndarray
    """(6,) the integral of -p nu dA and its torque about the centre of mass, N and N m."""
    area: float
    """The wet area, m^2."""
    first: np.ndarray
    """(3,) the integral of r dA, r the lever from the centre of mass, m^3."""
    second: np.ndarray
    """(3, 3) the integral of r r^T dA, m^4."""
    flow: np.ndarray
    """(6,) the integral of the water's velocity dA and its torque (zero in still water)."""

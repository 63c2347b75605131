"""Bodies that would start inside one another, refused before anything is built: boxes and cubes, turned or not, by
the separating-axis test of two oriented boxes (Gottschalk, Lin and Manocha 1996). A mesh is not measured here, and a
body and its parent (a joint may sit where they meet) are not compared."""

from __future__ import annotations

import itertools

import numpy as np

from sim.bodies.rotation import quat_to_matrix
from sim.errors import ConfigError

MAX_COMPARED = 500
"""Bodies past which no pair is compared (a farm's devices are checked by its spacing, in scene/farm.py)."""
DEPTH = 1e-6
"""How far, m, two boxes must reach into one another to count: boxes that touch are apart."""


def box(entry) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """(centre, axes as columns, half sides) of a [[bodies]] entry at its start, or None for a shape not measured."""
    b = entry.body
    if b.shape not in ("cube", "box"):
        return None
    sides = [float(b.size)] * 3 if b.shape == "cube" else [float(v) for v in b.extents]
    q = np.asarray(entry.initial.orientation, float)
    return np.asarray(entry.initial.position, float), quat_to_matrix(q), 0.5 * np.asarray(sides)


def depth(a, b) -> float:
    """How far two oriented boxes reach into one another along their least separating axis (<= 0: apart)."""
    (ca, A, ha), (cb, B, hb) = a, b
    d = cb - ca
    axes = [*A.T, *B.T, *(np.cross(u, v) for u in A.T for v in B.T)]
    least = np.inf
    for axis in axes:
        n = np.linalg.norm(axis)
        if n < 1e-9:  # parallel edges: their cross product says nothing
            continue
        axis = axis / n
        reach = ha @ np.abs(A.T @ axis) + hb @ np.abs(B.T @ axis)
        least = min(least, reach - abs(d @ axis))
    return float(least)


def check_apart(entries) -> None:
    """ConfigError naming the first two bodies (boxes or cubes, neither the other's parent) that start inside one another."""
    if len(entries) > MAX_COMPARED:
        return
    boxes = [(e, box(e)) for e in entries]
    for (e, a), (f, b) in itertools.combinations(boxes, 2):
        if a is None or b is None or e.name == f.parent or f.name == e.parent:
            continue
        if (reach := depth(a, b)) > DEPTH:
            raise ConfigError(f"[[bodies]] {e.name} and {f.name} start inside one another (by {reach:.3g} m): place them apart")

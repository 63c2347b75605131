"""Bodies that would start inside one another, refused before anything is built: boxes and cubes, turned or not, by
the separating-axis test of two oriented boxes (Gottschalk, Lin and Manocha 1996). A mesh is not measured here, and a
body and its parent (a joint may sit where they meet) are not compared."""

from __future__ import annotations

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
    R = quat_to_matrix(np.asarray(entry.initial.orientation, float))
    shift = np.zeros(3) if b.centre_of_mass is None else R @ np.asarray(b.centre_of_mass, float)
    return np.asarray(entry.initial.position, float) - shift, R, 0.5 * np.asarray(sides)  # (position: the centre of mass)


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
    """ConfigError naming the first two bodies (boxes or cubes, neither the other's parent) that start inside one another.
    Only pairs whose bounding spheres meet are tested (a farm's hundreds of devices cost a few ms)."""
    if len(entries) > MAX_COMPARED:
        return
    boxes = [(e, b) for e in entries if (b := box(e)) is not None]
    if len(boxes) < 2:
        return
    centres = np.array([b[0] for _, b in boxes])
    radii = np.array([np.linalg.norm(b[2]) for _, b in boxes])
    apart = np.linalg.norm(centres[:, None] - centres[None], axis=-1) >= radii[:, None] + radii[None]
    for i, j in zip(*np.nonzero(np.triu(~apart, 1))):
        (e, a), (f, b) = boxes[i], boxes[j]
        if e.name == f.parent or f.name == e.parent:
            continue
        if (reach := depth(a, b)) > DEPTH:
            raise ConfigError(f"[[bodies]] {e.name} and {f.name} start inside one another (by {reach:.3g} m): place them apart")

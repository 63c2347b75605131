"""The wet part of a body's surface at one pose and time, as quadrature points every force term shares.

Three models (`[fluid] forces`):
- 'points': the body's samples under the surface, each one node of weight = its area (midpoint rule);
  a sample is wet or dry as a whole, so the wet area jumps as samples cross the surface (the report's model);
- 'cells': the same samples, but a sample whose cell (the patch its area stands for) crosses the
  surface keeps only the cell's wet part: its node moves to that part's centroid and weighs its
  area. Wetting is continuous, the pressure force exact (pressure is linear over the planar wet part),
  the torque and damping integrals still the midpoint rule's;
- 'panels': the mesh's triangles clipped where they cross the surface, each wet triangle carrying
  the three nodes at its edge midpoints with weight area/3, a rule exact for quadratic integrands:
  in still water pressure (linear) times position (linear), so Archimedes' force, its torque and the
  hydrostatic energy are exact at any pose.
The water is asked where its surface is (`Water.height_above_surface`); the crossing of an edge is
found by linear interpolation of that height, which is exact for a plane surface.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

FORCE_MODELS = ("points", "cells", "panels")
# Dunavant's 6-point rule (degree 4) on a triangle: barycentric nodes and weights (sum 1). Used where
# the integrand is no longer quadratic: wave pressure, and drag's cubic torque integrand.
DUNAVANT4 = np.array([[0.108103018168070, 0.445948490915965, 0.445948490915965], [0.445948490915965, 0.108103018168070, 0.445948490915965],
                      [0.445948490915965, 0.445948490915965, 0.108103018168070], [0.816847572980459, 0.091576213509771, 0.091576213509771],
                      [0.091576213509771, 0.816847572980459, 0.091576213509771], [0.091576213509771, 0.091576213509771, 0.816847572980459]])  # fmt: skip
DUNAVANT4_WEIGHTS = np.array([0.223381589678011] * 3 + [0.109951743655322] * 3)


@dataclass(frozen=True, eq=False)
class WetSurface:
    """Quadrature nodes of the wet surface, world frame, SI units."""

    x: np.ndarray
    """(3,) centre of mass the levers are taken from, m."""
    point: np.ndarray
    """(m, 3) node positions, m."""
    lever: np.ndarray
    """(m, 3) node positions relative to the centre of mass, m."""
    weight: np.ndarray
    """(m,) node weights (areas), m^2."""
    normal: np.ndarray
    """(m, 3) outward unit normals at the nodes."""
    owner: np.ndarray
    """(m,) the sample or mesh triangle each node belongs to."""
    triangles: np.ndarray | None = None
    """(k, 3, 3) wet triangles as vertex levers, m (panels only; None for points)."""
    triangle_normal: np.ndarray | None = None
    """(k, 3) their outward unit normals."""
    water: object = None
    """The water it is wet in (asked lazily, once, for the pressure and flow at the nodes)."""
    t: float = 0.0
    """Time, s."""
    given_flow: np.ndarray | None = None
    """(m, 3) the water's velocity at the nodes when already known (interpolated), m/s."""

    @cached_property
    def _field(self) -> tuple[np.ndarray, np.ndarray]:
        return self.water.field(self.point, self.t) if len(self.weight) else (np.zeros(0), np.zeros((0, 3)))

    @property
    def pressure(self) -> np.ndarray:
        """(m,) the water's pressure at the nodes, Pa."""
        return self._field[0]

    @property
    def flow(self) -> np.ndarray:
        """(m, 3) the water's velocity at the nodes, m/s."""
        return self._field[1] if self.given_flow is None else self.given_flow

    @cached_property
    def submerged_area(self) -> float:
        return float(self.weight.sum())

    @cached_property
    def first_moment(self) -> np.ndarray:
        """(3,) integral of r dA, m^3."""
        return self.weight @ self.lever

    @cached_property
    def second_moment(self) -> np.ndarray:
        """(3, 3) integral of r r^T dA, m^4."""
        return (self.lever * self.weight[:, None]).T @ self.lever

    @property
    def submerged_volume(self) -> float:
        """V = integral of z nu_z dA over the wet surface (divergence theorem with the field (0, 0, z);
        the still water plane z = 0 adds nothing), m^3."""
        return float((self.weight * self.point[:, 2]) @ self.normal[:, 2])

    @property
    def index(self) -> np.ndarray:
        """Which samples (or mesh triangles) are wet, sorted."""
        return np.unique(self.owner)


def empty_surface(x: np.ndarray) -> WetSurface:
    z3 = np.zeros((0, 3))
    return WetSurface(x, z3, z3, np.zeros(0), z3, np.zeros(0, int), np.zeros((0, 3, 3)), z3)


def wet_points(body, water, x: np.ndarray, R: np.ndarray, t: float) -> WetSurface:
    """The samples under the water surface, each a node weighted by its area."""
    if water.flat:  # a flat surface: the samples' heights alone decide
        wet = np.flatnonzero(x[2] + body.r_body @ R[2] < water.elevation(x[:2], t))
    else:
        wet = np.flatnonzero(water.height_above_surface(x + body.r_body @ R.T, t) < 0.0)
    lever = body.r_body[wet] @ R.T
    return WetSurface(x, x + lever, lever, body.area[wet], body.n_body[wet] @ R.T, wet, water=water, t=t)


def wet_cells(body, water, x: np.ndarray, R: np.ndarray, t: float) -> WetSurface:
    """The samples with their cells clipped at the water surface: a whole wet cell is its sample
    (as in 'points'); a cell the surface crosses is one node at the centroid of its wet part,
    weighted by that part's area (the surface between corners taken linear, exact for still water)."""
    corners = body.cell_corners @ R.T  # (n, 4, 3) levers
    if water.flat:
        h = x[2] + corners[..., 2] - water.elevation(x[:2], t)
    else:
        h = water.height_above_surface(x + corners.reshape(-1, 3), t).reshape(-1, 4)
    below = h < 0.0
    whole = np.flatnonzero(below.all(axis=1))
    cut = np.flatnonzero(below.any(axis=1) & ~below.all(axis=1))
    fans = ([0, 1, 2], [0, 2, 3])  # the cell as two triangles (degenerate for a triangle cell)
    P, owner = clip_triangles(np.concatenate([corners[cut][:, f] for f in fans]), np.concatenate([h[cut][:, f] for f in fans]))
    owner = np.concatenate([cut, cut])[owner]
    area = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    n = body.n_samples
    wet_area = np.bincount(owner, area, minlength=n)[cut]
    moment = np.stack([np.bincount(owner, area * P[:, :, i].mean(axis=1), minlength=n)[cut] for i in range(3)], axis=1)
    keep = wet_area > 0.0
    index = np.concatenate([whole, cut[keep]])
    lever = np.concatenate([body.r_body[whole] @ R.T, moment[keep] / wet_area[keep, None]])
    weight = np.concatenate([body.area[whole], wet_area[keep]])
    return WetSurface(x, x + lever, lever, weight, body.n_body[index] @ R.T, index, water=water, t=t)


def clip_triangles(P: np.ndarray, h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The parts of triangles P (k, 3, c) where the linear function with vertex values h (k, 3) is
    negative, as triangles (same winding) and the index of the triangle each came from. Columns past
    the position (c > 3) are interpolated like it.

    One vertex below keeps a triangle, two keep a quadrilateral (split in two); rolling the
    vertices to put the odd one first keeps the winding, hence the outward normal."""
    below = h < 0.0
    count = below.sum(axis=1)
    whole = np.flatnonzero(count == 3)
    tris, owners = [P[whole]], [whole]
    for n_below in (1, 2):
        sel = np.flatnonzero(count == n_below)
        if not len(sel):
            continue
        first = np.argmax(below[sel] if n_below == 1 else ~below[sel], axis=1)  # the odd vertex
        order = (first[:, None] + np.arange(3)) % 3
        p = np.take_along_axis(P[sel], order[:, :, None], axis=1)
        v = np.take_along_axis(h[sel], order, axis=1)
        e01 = p[:, 0] + (p[:, 1] - p[:, 0]) * (v[:, 0] / (v[:, 0] - v[:, 1]))[:, None]
        e20 = p[:, 2] + (p[:, 0] - p[:, 2]) * (v[:, 2] / (v[:, 2] - v[:, 0]))[:, None]
        if n_below == 1:
            tris.append(np.stack([p[:, 0], e01, e20], axis=1))
            owners.append(sel)
        else:  # quadrilateral e01 -> p1 -> p2 -> e20
            tris += [np.stack([e01, p[:, 1], p[:, 2]], axis=1), np.stack([e01, p[:, 2], e20], axis=1)]
            owners += [sel, sel]
    return np.concatenate(tris), np.concatenate(owners)


def triangle_areas(T: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Signed areas of triangles T (k, 3, 3) along their normals (k, 3)."""
    return 0.5 * np.einsum("ki,ki->k", np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), normal)


def wet_panels(body, water, x: np.ndarray, R: np.ndarray, t: float) -> WetSurface:
    """The mesh's triangles clipped at the water surface. Still water: three edge-midpoint nodes on
    each (exact: the integrands are quadratic). Waves: the surface between vertices is the plane
    through the surface points above them, and Dunavant's degree-4 rule integrates the pressure,
    no longer linear; both errors shrink under refinement (the clipping's as h^2)."""
    lever_v = body.mesh_vertices @ R.T
    heights = water.height_above_surface(x + lever_v, t)
    faces = body.mesh_faces
    T, owner = clip_triangles(lever_v[faces], heights[faces])
    if not len(T):
        return empty_surface(x)
    normal = body.face_normals[owner] @ R.T
    area = triangle_areas(T, normal)
    if water.flat:
        nodes, weights = 0.5 * (T + T[:, [1, 2, 0]]), np.full(3, 1 / 3)  # edge midpoints (k, 3, 3)
    else:
        nodes, weights = np.einsum("qv,kvi->kqi", DUNAVANT4, T), DUNAVANT4_WEIGHTS
    q = len(weights)
    lever = nodes.reshape(-1, 3)
    return WetSurface(x, x + lever, lever, (area[:, None] * weights).ravel(), np.repeat(normal, q, axis=0), np.repeat(owner, q), T, normal,
                      water, t)  # fmt: skip


WET_SURFACE = {"points": wet_points, "cells": wet_cells, "panels": wet_panels}

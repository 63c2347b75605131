"""The lid a boundary-element solve needs against irregular frequencies: the body's own cross-section just under the
water line, closed and meshed.

A BEM solve of a surface-piercing body fails near the sloshing frequencies of the water *inside* its hull (the
irregular frequencies, e.g. 7.36 rad/s for a cylinder of radius 0.5 m and draft 0.5 m); a lid over that interior
free surface removes them (Capytaine's extended boundary integral equation, Babarit & Delhommeau 2015). The lid must
cover the whole interior: a partial one leaves the irregular frequencies in, and can make them worse. Here it is
the exact section of the hull's triangles at the lid's depth (the same clipping as floatsim's wet surface, so
every hull, annulus or many-hulled, gets its true outline), triangulated with panels about as large as the hull's:
the outline's edges split to the panel size, a grid of points inside kept half a panel from it, their Delaunay
triangles kept where their centroid is inside (even-odd, so holes stay open), outline edges forced in by splitting
any the triangulation misses. Its area is checked against the outline's.
"""

from __future__ import annotations

import numpy as np

from sim.hydro.hydrostatics import waterline

THIN = 0.05
"""Outline points closer than this share of a panel are one where the outline runs on nearly straight (the lid's
edge moves by far less than that, across)."""
STRAIGHT = np.radians(20.0)


def section_loops(P: np.ndarray, z: float, tol: float) -> list[np.ndarray]:
    """The closed outlines (each (m, 2), x and y) where the plane at height z cuts the triangles P (k, 3, 3);
    endpoints closer than `tol` are one point."""
    seg = waterline(P, P[:, :, 2] - z)[:, :, :2]
    seg = seg[np.linalg.norm(seg[:, 0] - seg[:, 1], axis=1) > tol]
    if not len(seg):
        return []
    ids = _clusters(seg.reshape(-1, 2), tol).reshape(-1, 2)
    points = np.zeros((ids.max() + 1 if len(ids) else 0, 2))
    points[ids.ravel()] = seg.reshape(-1, 2)
    links: dict[int, list[int]] = {}
    for a, b in ids:
        if a != b:
            links.setdefault(int(a), []).append(int(b))
            links.setdefault(int(b), []).append(int(a))
    if any(len(v) != 2 for v in links.values()):
        raise ValueError("the hull's section is not a set of closed outlines (is the mesh closed?)")
    loops, seen = [], set()
    for start in links:
        if start in seen:
            continue
        loop, prev, here = [start], None, start
        seen.add(start)
        while True:
            nxt = links[here][0] if links[here][0] != prev else links[here][1]
            if nxt == start:
                break
            loop.append(nxt)
            seen.add(nxt)
            prev, here = here, nxt
        loops.append(points[loop])
    return loops


def _clusters(points: np.ndarray, tol: float) -> np.ndarray:
    """(n,) labels 0..k-1: points closer than `tol` (through chains of such) share one. The wet mesh drops its
    slivers, so two triangles' cuts of one edge can lie a sliver's width (~1e-8 of the body) apart."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    pairs = cKDTree(points).query_pairs(tol, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(points), len(points)))
    return connected_components(graph, directed=False)[1]


def signed_area(loop: np.ndarray) -> float:
    x, y = loop[:, 0], loop[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def inside(points: np.ndarray, loops: list[np.ndarray]) -> np.ndarray:
    """Even-odd: a point is inside when a ray from it crosses the outlines an odd number of times."""
    odd = np.zeros(len(points), bool)
    x, y = points[:, 0:1], points[:, 1:2]
    for loop in loops:
        a, b = loop, np.roll(loop, -1, axis=0)
        crosses = (a[:, 1] > y) != (b[:, 1] > y)
        with np.errstate(divide="ignore", invalid="ignore"):
            xc = a[:, 0] + (y - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
        odd ^= (crosses & (x < xc)).sum(axis=1) % 2 == 1
    return odd


def region_area(loops: list[np.ndarray]) -> float:
    """The area inside the outlines (even-odd: an outline inside another is a hole)."""
    total = 0.0
    for k, loop in enumerate(loops):
        depth = sum(bool(inside(loop[:1], [other])[0]) for j, other in enumerate(loops) if j != k)
        total += (-1) ** depth * abs(signed_area(loop))
    return total


def _thin(loop: np.ndarray, gap: float) -> np.ndarray:
    """The outline without the points a hair (under `gap`) from the last one kept where it runs straight on (the
    hull's fine triangles cut it in places a hair apart: slivers in the lid); corners stay."""

    def turn(a, b, c) -> float:
        u, v = b - a, c - b
        return abs(np.arctan2(u[0] * v[1] - u[1] * v[0], u @ v))

    keep = [0]
    for i in range(1, len(loop)):
        near = min(np.linalg.norm(loop[i] - loop[keep[-1]]), np.linalg.norm(loop[i] - loop[0]))
        if near >= gap or turn(loop[keep[-1]], loop[i], loop[(i + 1) % len(loop)]) > STRAIGHT:
            keep.append(i)
    return loop[keep]


def _split(loop: np.ndarray, panel: float) -> np.ndarray:
    """The outline with each edge cut into pieces no longer than `panel`."""
    out = []
    for a, b in zip(loop, np.roll(loop, -1, axis=0)):
        n = max(1, int(np.ceil(np.linalg.norm(b - a) / panel)))
        out.append(a + (b - a) * (np.arange(n) / n)[:, None])
    return np.concatenate(out)


def _distance_to_edges(points: np.ndarray, loops: list[np.ndarray]) -> np.ndarray:
    out = np.full(len(points), np.inf)
    for loop in loops:
        a, b = loop, np.roll(loop, -1, axis=0)
        ab = b - a
        t = np.clip(((points[:, None] - a) * ab).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-300), 0.0, 1.0)
        out = np.minimum(out, np.linalg.norm(points[:, None] - (a + t[..., None] * ab), axis=-1).min(axis=1))
    return out


def triangulate(loops: list[np.ndarray], panel: float) -> tuple[np.ndarray, np.ndarray]:
    """(points (p, 2), triangles (t, 3)) covering the inside of the outlines with triangles of about `panel`."""
    from scipy.spatial import Delaunay

    loops = [_split(_thin(loop, THIN * panel), panel) for loop in loops]
    lo = np.min([loop.min(axis=0) for loop in loops], axis=0)
    hi = np.max([loop.max(axis=0) for loop in loops], axis=0)
    gx, gy = np.meshgrid(np.arange(lo[0], hi[0] + panel, panel), np.arange(lo[1], hi[1] + panel, panel * np.sqrt(0.75)))
    gx = gx + 0.5 * panel * (np.arange(len(gx))[:, None] % 2)  # a triangular lattice: equilateral panels inside
    grid = np.column_stack([gx.ravel(), gy.ravel()])
    grid = grid[inside(grid, loops)]
    grid = grid[_distance_to_edges(grid, loops) > 0.5 * panel]
    centre, reach = 0.5 * (lo + hi), 10.0 * float((hi - lo).max())
    frame = centre + reach * np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])  # keeps the outline off the hull:
    for _ in range(12):  # no flat triangles along its straight runs
        points = np.concatenate([*loops, grid])
        tri = Delaunay(np.concatenate([points, frame])).simplices
        tri = tri[(tri < len(points)).all(axis=1)]
        tri = tri[inside(points[tri].mean(axis=1), loops)]
        edges = {tuple(sorted(e)) for t in tri for e in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))}
        start, missing = 0, []
        for k, loop in enumerate(loops):
            n = len(loop)
            for i in range(n):
                if tuple(sorted((start + i, start + (i + 1) % n))) not in edges:
                    missing.append((k, i))
            start += n
        if not missing:
            return points, tri
        for k, i in sorted(missing, reverse=True):  # split each missed edge at its midpoint, then triangulate again
            loop = loops[k]
            loops[k] = np.insert(loop, i + 1, 0.5 * (loop[i] + loop[(i + 1) % len(loop)]), axis=0)
    raise ValueError("the lid could not be meshed to follow the hull's outline")


def make_lid(vertices: np.ndarray, faces: np.ndarray, panel: float, z: float) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (v, 3), faces (f, 3)): the lid of the hull (vertices, faces) at height z, panels of about `panel`,
    its triangles facing down; empty when the plane does not cut the hull. ValueError if the lid does not cover
    the section (to 1e-3 of its area: the merged outline points move it by less)."""
    size = float(np.ptp(vertices, axis=0).max())
    loops = section_loops(np.asarray(vertices, float)[np.asarray(faces)], z, 1e-6 * size)
    if not loops:
        return np.zeros((0, 3)), np.zeros((0, 3), int)
    points, tri = triangulate(loops, panel)
    a, b, c = (points[tri[:, k]] for k in range(3))
    up = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]) > 0
    tri[up] = tri[up][:, ::-1]  # facing down, out of the water inside the hull
    covered = 0.5 * np.abs((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])).sum()
    area = region_area(loops)
    if abs(covered - area) > 1e-3 * area:
        raise ValueError(f"the lid covers {covered:.6g} m2 of the hull's {area:.6g} m2 section")
    return np.column_stack([points, np.full(len(points), z)]), tri

"""Where the water meets the hull, for display: the waterline and the wet part of the body, in the body's frame.

Both are found on the actual surface, waves included: each mesh edge whose ends lie on either side of
the surface is cut where z = eta(x, y, t) along it (regula falsi, to `TOL`), so every vertex of the
line lies on the hull and on the water. Meshes whose faces are long against the shortest wave are
refined once first (at most `MAX_FACES` triangles), so that the line follows the surface between
vertices too. The nodes are children of the body's frame: between updates they move with the body and
stay on its hull.
"""

from __future__ import annotations

import math
import time

import numpy as np

from sim.bodies.rotation import quat_to_matrix

HULL_HZ = 10.0
"""Updates a second at most (and whenever the wave surface goes out: the two then show the same instant)."""
LINE_COLOUR = (250, 240, 40)
WET_COLOUR = (165, 215, 225)
"""The hull under water: a pale sea tint, unlike the dry hull and the blue wet samples, and light enough to show through the water."""
LIFT = 2e-3
"""The wet part is drawn this fraction of the body's radius off the hull (no flicker between the two surfaces)."""
TOL = 1e-7
"""How far (m) a cut may lie off the surface."""
MAX_FACES = 20_000
EDGES_PER_WAVE = 16
"""A refined mesh has no edge longer than the shortest wave over this."""


def shortest_wave(water) -> float:
    """The shortest wavelength of the water's components (inf in still water), m."""
    k = np.asarray(getattr(water, "k", np.zeros(0)), float)
    return 2 * math.pi / k.max() if k.size and k.max() > 0 else math.inf


def refined(vertices: np.ndarray, faces: np.ndarray, max_edge: float) -> tuple[np.ndarray, np.ndarray]:
    """The mesh with no edge longer than max_edge, unless that needs more than MAX_FACES triangles (then as given)."""
    import trimesh

    P = vertices[faces]
    longest = np.linalg.norm(P - np.roll(P, 1, axis=1), axis=2).max()
    if not math.isfinite(max_edge) or longest <= max_edge or len(faces) * (longest / max_edge) ** 2 > MAX_FACES:
        return vertices, faces
    return trimesh.remesh.subdivide_to_size(vertices, faces, max_edge)


class Hull:
    """A body's mesh (body frame) with its edges, cut at the water surface by `cut`."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray):
        self.vertices, self.faces = np.asarray(vertices, float), np.asarray(faces, np.int64)
        edges = np.sort(self.faces[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2), axis=1)
        self.edges, index = np.unique(edges, axis=0, return_inverse=True)
        self.face_edges = index.reshape(-1, 3)
        """Edge k of face f joins its corners k and k + 1."""

    @classmethod
    def of(cls, body, water) -> Hull:
        return cls(*refined(body.mesh_vertices, body.mesh_faces, shortest_wave(water) / EDGES_PER_WAVE))

    def cut(self, R: np.ndarray, x: np.ndarray, water, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """At pose (R, x) and time t: the waterline (s, 2, 3) and the wet part (vertices, faces), body frame."""
        V = self.vertices
        h = water.height_above_surface(V @ R.T + x, t)
        wet = h < 0.0
        crossing = wet[self.edges[:, 0]] != wet[self.edges[:, 1]]
        a, b = self.edges[crossing].T
        s = _root(lambda s: water.height_above_surface((V[a] + s[:, None] * (V[b] - V[a])) @ R.T + x, t), h[a], h[b])
        cuts = V[a] + s[:, None] * (V[b] - V[a])
        cut_of_edge = np.full(len(self.edges), -1)
        cut_of_edge[crossing] = np.arange(len(cuts))

        count = wet[self.faces].sum(axis=1)
        inside = self.faces[count == 3]
        sel = np.flatnonzero((count == 1) | (count == 2))
        lone = wet[self.faces[sel]] == (count[sel] == 1)[:, None]  # the corner alone on its side
        odd = np.argmax(lone, axis=1)
        corner = lambda k: self.faces[sel, (odd + k) % 3]  # noqa: E731 -- corners from the odd one, in the face's order
        qa = len(V) + cut_of_edge[self.face_edges[sel, odd]]  # on the edge odd -> odd + 1
        qb = len(V) + cut_of_edge[self.face_edges[sel, (odd + 2) % 3]]  # on the edge odd + 2 -> odd
        segments = np.stack([cuts[qa - len(V)], cuts[qb - len(V)]], axis=1)
        single = count[sel] == 1  # the wet corner alone: one wet triangle; else a wet quad, two triangles
        wet_faces = np.concatenate([
            inside,
            np.stack([corner(0), qa, qb], axis=1)[single],
            np.stack([qa, corner(1), corner(2)], axis=1)[~single],
            np.stack([qa, corner(2), qb], axis=1)[~single],
        ])  # fmt: skip
        points = np.concatenate([V, cuts])
        used, local = np.unique(wet_faces, return_inverse=True)
        return segments, points[used], local.reshape(-1, 3)


def _root(height, h0: np.ndarray, h1: np.ndarray) -> np.ndarray:
    """s in (0, 1) where height(s) = 0 on each edge, its ends' heights h0 and h1 of opposite signs (Illinois)."""
    lo, hi = np.zeros_like(h0), np.ones_like(h1)
    s = lo
    for _ in range(40):
        s = (lo * h1 - hi * h0) / (h1 - h0)
        hs = height(s)
        if not len(hs) or np.abs(hs).max() < TOL:
            break
        low = np.sign(hs) == np.sign(h0)  # the root lies above s
        h1 = np.where(low, 0.5 * h1, hs)  # Illinois: halve the end kept twice
        h0 = np.where(low, hs, 0.5 * h0)
        lo, hi = np.where(low, s, lo), np.where(low, hi, s)
    return s


class HullView:
    """The waterline and the wet part as children of the body's frame; `show` runs on the simulation thread only."""

    def __init__(self, server, body, water, root: str = "", hz: float = HULL_HZ, node: str = "body"):
        """Its nodes hang from the body's frame, `root`/`node`."""
        self.hull = Hull.of(body, water)
        self._for = (body, getattr(water, "k", None))
        scene, r = server.scene, body.radius
        self.line = scene.add_line_segments(
            f"{root}/{node}/waterline", np.zeros((1, 2, 3), np.float32), LINE_COLOUR, thickness=0.012 * r, visible=False
        )
        dot = np.zeros((3, 3), np.float32)
        self.wet = scene.add_mesh_simple(
            f"{root}/{node}/wet", dot, np.array([[0, 1, 2]], np.uint32), color=WET_COLOUR, flat_shading=True, visible=False
        )
        self._normals = _vertex_normals(self.hull.vertices, self.hull.faces) * (LIFT * r)
        self.hz = hz
        self._sent = -np.inf
        self.latest: tuple | None = None
        """(t, x, q, segments) of the waterline last sent (body frame), for tests."""

    def fits(self, body, water) -> bool:
        """Whether this view was made for this body in this sea (else make another: its mesh may need refining anew)."""
        return self._for[0] is body and np.array_equal(self._for[1], getattr(water, "k", None))

    def show(self, frame, water, line: bool, wet: bool, now: float | None = None, due: bool = False) -> None:
        """The line (if `line`) and the wet part (if `wet`) at the body's pose and time (its Frame) in `water`; throttled unless `due`."""
        now = time.monotonic() if now is None else now
        if not line and self.line.visible:
            self.line.visible = False
        if not wet and self.wet.visible:
            self.wet.visible = False
        if not (line or wet) or not (due or now - self._sent >= 1.0 / self.hz):
            return

        segments, vertices, faces = self.hull.cut(quat_to_matrix(frame.q_world_body), frame.x_world, water, frame.t)
        if line:
            if len(segments):
                self.line.points = segments.astype(np.float32)
            if self.line.visible != bool(len(segments)):
                self.line.visible = bool(len(segments))
        if wet:
            if len(faces):
                self.wet.vertices = (vertices + self._lift(vertices)).astype(np.float32)
                self.wet.faces = faces.astype(np.uint32)
            if self.wet.visible != bool(len(faces)):
                self.wet.visible = bool(len(faces))
        self.latest = (frame.t, frame.x_world.copy(), frame.q_world_body.copy(), segments)
        self._sent = now

    def _lift(self, points: np.ndarray) -> np.ndarray:
        """Each point's offset off the hull: its nearest hull vertex's normal (the cuts lie on edges: near enough)."""
        from scipy.spatial import cKDTree

        if not hasattr(self, "_tree"):
            self._tree = cKDTree(self.hull.vertices)
        return self._normals[self._tree.query(points)[1]]


def _vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Unit outward normals at the vertices: the area-weighted mean of their faces'."""
    P = vertices[faces]
    n = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    normals = np.zeros_like(vertices)
    for k in range(3):
        np.add.at(normals, faces[:, k], n)
    return normals / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-300)

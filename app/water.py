"""The water in the 3D scene: a calm translucent sheet in still water; in waves an animated surface whose
heights come from the simulation's own `Water`, shaded by height and slope, sent at most `WAVE_HZ` times a
second and only while shown (ARCHITECTURE rule 7: stream only what changed and is visible).

viser's simple meshes take one colour each, so the sea is drawn as `BANDS` meshes, one per shade: each
update sorts the surface's triangles into them by height and by how squarely they face the light. A fine
patch around the body (cells of `WAVE_PATCH * size / CELLS`) sits in a coarse ring of the same surface
reaching `FAR` patch widths out, which fades into the sky's colour (fog) at the horizon.
"""

from __future__ import annotations

import time

import numpy as np
import viser

WAVE_HZ = 10.0
CELLS = 48
"""Grid cells per side of the fine patch around the body."""
REPLAY_CELLS, REPLAY_HZ = 20, 5.0
"""A recording's fine patch: 441 vertices, 5 times a simulated second."""
RING_CELLS = 4
"""Cells of the coarse ring along each side of the fine patch (CELLS and REPLAY_CELLS are multiples of it);
outside it they grow geometrically to the horizon."""
FAR = 16.0
"""The ring reaches this many patch half-widths from the body (waves of storms are 100 m and more long)."""
WATER_COLOUR, WATER_OPACITY = (25, 95, 175), 0.6
"""Calm sheet: deep enough a blue to read as water, translucent enough that the submerged part shows under it."""
WAVE_OPACITY = 0.85
TROUGH, CREST = np.array([4, 30, 80]), np.array([125, 185, 230])
"""The sea's darkest and lightest shades (deep troughs facing away from the light, crests facing it)."""
BANDS = 16
SKY = (222, 232, 242)
"""The background and the fog the far water fades into."""
LIGHT = np.array([0.45, -0.55, 0.70]) / np.linalg.norm([0.45, -0.55, 0.70])
"""Where the shading's light comes from: behind the default camera, above."""
SLOPE_GAIN = 4.0
"""Shade per unit of slope facing the light (a slope of 0.1 toward it: six bands lighter)."""
WAVE_PATCH = 3.0
"""The fine patch spans this many times the scene's base size."""


def grid_faces(n: int) -> np.ndarray:
    """Two triangles per cell of an (n + 1) x (n + 1) vertex grid, counter-clockwise seen from above."""
    return _cell_faces(n, n, np.ones((n, n), bool))


def _cell_faces(nx: int, ny: int, keep: np.ndarray) -> np.ndarray:
    """Two counter-clockwise triangles per kept cell of an (nx + 1) x (ny + 1) vertex grid (x index major)."""
    i, j = np.nonzero(keep)
    a = i * (ny + 1) + j
    b, c, d = a + ny + 1, a + 1, a + ny + 2
    return np.concatenate([np.stack([a, b, d], axis=1), np.stack([a, d, c], axis=1)]).astype(np.uint32)


def sea_grid(half: float, cells: int, far: float = FAR) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(xy (v, 2), faces (f, 3), spacing (v,), seam (s, 3)) of the sea around the origin: a fine square patch
    of `cells` per side and half-width `half`, then a coarse ring from it out to `far * half`; `spacing` is
    each vertex's largest cell side. The ring's inner edge runs along the patch's, through every few of its
    vertices; seam rows (i, a, b) say patch edge vertex i lies on the ring's edge between vertices a and b
    halfway or so: `sea_heights` puts it on that edge, and the two meet without a gap."""
    fine = np.linspace(-half, half, cells + 1)
    g = np.meshgrid(fine, fine, indexing="ij")
    xy_fine = np.column_stack([g[0].ravel(), g[1].ravel()])
    per = cells // RING_CELLS  # patch cells per ring cell along the seam
    inner = fine[::per]
    step, out = inner[1] - inner[0], [half]
    while out[-1] < far * half:  # cells growing by a quarter each: a few dozen vertices to the horizon
        step *= 1.25
        out.append(out[-1] + step)
    outer = np.array(out[1:])
    ring = np.concatenate([-outer[::-1], inner, outer])
    n, m = len(ring) - 1, len(outer)
    centre = 0.5 * (ring[:-1] + ring[1:])
    inside = np.abs(centre) < half
    keep = ~(inside[:, None] & inside[None, :])
    g = np.meshgrid(ring, ring, indexing="ij")
    xy_ring = np.column_stack([g[0].ravel(), g[1].ravel()])
    gap = np.diff(ring)
    side = np.maximum(np.r_[gap, gap[-1]], np.r_[gap[0], gap])  # each ring coordinate's wider neighbouring cell
    spacing = np.concatenate([np.full(len(xy_fine), fine[1] - fine[0]), np.maximum.outer(side, side).ravel()])
    faces = np.concatenate([grid_faces(cells), _cell_faces(n, n, keep) + len(xy_fine)])
    seam = []
    for fixed in (0, cells):  # the patch's four sides: the ring's vertices there take the patch's heights
        for k in range(cells + 1):
            for i, j in ((fixed, k), (k, fixed)):
                ri, rj = m + i // per if i % per == 0 else None, m + j // per if j % per == 0 else None
                if ri is not None and rj is not None:
                    spacing[len(xy_fine) + ri * (n + 1) + rj] = fine[1] - fine[0]
                    continue
                if ri is None:  # between two of the ring's vertices along x
                    a, b = (m + i // per) * (n + 1) + rj, (m + i // per + 1) * (n + 1) + rj
                else:
                    a, b = ri * (n + 1) + m + j // per, ri * (n + 1) + m + j // per + 1
                seam.append((i * (cells + 1) + j, len(xy_fine) + a, len(xy_fine) + b))
    return np.concatenate([xy_fine, xy_ring]), faces, spacing, np.array(seam, np.int64)


def sea_heights(water, xy: np.ndarray, t: float, spacing: np.ndarray, seam: np.ndarray) -> np.ndarray:
    """The surface's heights at the grid's vertices (sea_grid), the patch's seam on the ring's edges."""
    z = water.elevation_on_grid(xy, t, spacing)
    i, a, b = seam.T
    s = np.linalg.norm(xy[i] - xy[a], axis=1) / np.linalg.norm(xy[b] - xy[a], axis=1)
    z[i] = (1.0 - s) * z[a] + s * z[b]
    return z


def shade_bands(vertices: np.ndarray, faces: np.ndarray, scale: float) -> np.ndarray:
    """Each triangle's shade (0 .. BANDS - 1): lighter the higher it lies (height over `scale`, about twice the
    sea's standard deviation) and the more squarely it faces LIGHT."""
    P = vertices[faces]
    n = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    height = P[:, :, 2].mean(axis=1) / scale
    value = 0.5 + 0.35 * np.clip(height, -1.0, 1.0) + SLOPE_GAIN * (n @ LIGHT - LIGHT[2])
    return np.clip((value * BANDS).astype(int), 0, BANDS - 1)


def band_colours() -> list[tuple[int, int, int]]:
    return [tuple(int(c) for c in TROUGH + (CREST - TROUGH) * (k + 0.5) / BANDS) for k in range(BANDS)]


def sea_scale(water) -> float:
    """Twice the surface's standard deviation (regular waves: sqrt(2) a; irregular: the spectrum's), m."""
    amplitude = np.asarray(getattr(water, "amplitude", np.zeros(0)), float)
    return max(2.0 * float(np.sqrt(0.5 * np.sum(amplitude**2))), 1e-3)


class WaterView:
    """Scene nodes for the water; `show` runs on the simulation thread only."""

    def __init__(self, server: viser.ViserServer, size: float, lighter: bool = False, root: str = ""):
        """lighter=True: a coarser surface sent less often (recordings: the file stays small); `root`: the frame
        the nodes hang from."""
        self.server = server
        self.size = WAVE_PATCH * size
        self.cells, self.hz = (REPLAY_CELLS, REPLAY_HZ) if lighter else (CELLS, WAVE_HZ)
        half = 0.5 * self.size
        reach = FAR * half  # calm water: one translucent sheet the submerged part shows through (no floor-like grid)
        sheet = np.array([[-reach, -reach, 0.0], [reach, -reach, 0.0], [reach, reach, 0.0], [-reach, reach, 0.0]], dtype=np.float32)
        self.calm = server.scene.add_mesh_simple(
            f"{root}/water", sheet, np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32), color=WATER_COLOUR, opacity=WATER_OPACITY,
            side="double", cast_shadow=False, receive_shadow=False,
        )  # fmt: skip
        self._xy, self._faces, self._spacing, self._seam = sea_grid(half, self.cells)
        self.surface = server.scene.add_frame(f"{root}/waves", show_axes=False, visible=False)
        """The sea's node: its children are the shades (hidden with it)."""
        dot = np.zeros((3, 3), np.float32)
        self.bands = [
            server.scene.add_mesh_simple(
                f"{root}/waves/shade{k}",
                dot,
                np.array([[0, 1, 2]], np.uint32),
                color=colour,
                opacity=WAVE_OPACITY,
                flat_shading=True,
                material="toon5",
                side="double",
                cast_shadow=False,
                receive_shadow=False,
                visible=False,
            )  # fmt: skip
            for k, colour in enumerate(band_colours())
        ]
        server.scene.configure_fog(3.0 * half, 0.9 * reach, color=SKY)  # the far water fades into the sky at the horizon
        server.scene.set_background_image(np.full((2, 2, 3), SKY, np.uint8), format="png")
        self._sent = -np.inf
        self.sent_time = 0.0
        """Simulated time of the surface last sent."""
        self.updates = 0
        """How many wave surfaces were sent (tests check the throttle and the still-water silence)."""
        self.vertices = np.zeros((0, 3), np.float32)
        """The surface last sent (every shade's vertices), world frame."""

    def show(self, water, t: float, centre: np.ndarray, visible: bool, now: float | None = None) -> bool:
        """The flat sheet for still water; otherwise the surface around `centre` (x, y) at time t, throttled.
        Whether a surface went out."""
        still = water.flat
        if self.calm.visible != (visible and still):
            self.calm.visible = visible and still
        if self.surface.visible != (visible and not still):
            self.surface.visible = visible and not still
        now = time.monotonic() if now is None else now
        if still or not visible or now - self._sent < 1.0 / self.hz:
            return False
        cell = self.size / self.cells
        origin = np.round(np.asarray(centre[:2]) / cell) * cell  # follow the body in whole cells
        xy = self._xy + origin
        vertices = np.column_stack([xy, sea_heights(water, xy, t, self._spacing, self._seam)]).astype(np.float32)
        shade = shade_bands(vertices, self._faces, sea_scale(water))
        for k, node in enumerate(self.bands):
            faces = self._faces[shade == k]
            if not len(faces):
                if node.visible:
                    node.visible = False
                continue
            used, local = np.unique(faces, return_inverse=True)
            node.vertices = vertices[used]
            node.faces = local.reshape(-1, 3).astype(np.uint32)
            if not node.visible:
                node.visible = True
        self.vertices = vertices
        self._sent, self.sent_time = now, t
        self.updates += 1
        return True

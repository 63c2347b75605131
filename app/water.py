"""The water in the 3D scene: a flat translucent sheet in still water; in waves an animated surface mesh whose
heights come from the simulation's own `Water`, sent at most `WAVE_HZ` times a second and only while
shown (ARCHITECTURE rule 7: stream only what changed and is visible)."""

from __future__ import annotations

import time

import numpy as np
import viser

WAVE_HZ = 10.0
CELLS = 48
"""Grid cells per side of the wave surface ((CELLS + 1)^2 vertices, ~28 KB per update)."""
REPLAY_CELLS, REPLAY_HZ = 20, 5.0
"""A recording's wave surface: 441 vertices, 5 times a simulated second."""
WATER_COLOUR, WATER_OPACITY = (25, 95, 175), 0.6
"""Calm sheet and wave surface alike: deep enough a blue to read as water, translucent enough that the
submerged part of the body shows under it."""
WAVE_PATCH = 3.0
"""The water spans this many times the scene's base size (waves are long: show more of them)."""


def grid_faces(n: int) -> np.ndarray:
    """Two triangles per cell of an (n + 1) x (n + 1) vertex grid, counter-clockwise seen from above."""
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    a = (i * (n + 1) + j).ravel()
    b, c, d = a + n + 1, a + 1, a + n + 2
    return np.concatenate([np.stack([a, b, d], axis=1), np.stack([a, d, c], axis=1)]).astype(np.uint32)


class WaterView:
    """Scene nodes for the water; `show` runs on the simulation thread only."""

    def __init__(self, server: viser.ViserServer, size: float, lighter: bool = False):
        """lighter=True: a coarser surface sent less often (recordings: the file stays small)."""
        self.server = server
        self.size = WAVE_PATCH * size
        self.cells, self.hz = (REPLAY_CELLS, REPLAY_HZ) if lighter else (CELLS, WAVE_HZ)
        cells = self.cells
        half = 0.5 * self.size  # calm water: one translucent sheet the submerged part shows through (no floor-like grid)
        sheet = np.array([[-half, -half, 0.0], [half, -half, 0.0], [half, half, 0.0], [-half, half, 0.0]], dtype=np.float32)
        self.calm = server.scene.add_mesh_simple(
            "/water", sheet, np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32), color=WATER_COLOUR, opacity=WATER_OPACITY,
            side="double", cast_shadow=False, receive_shadow=False,
        )  # fmt: skip
        c = (np.arange(cells + 1) / cells - 0.5) * self.size
        gx, gy = np.meshgrid(c, c, indexing="ij")
        self._xy = np.column_stack([gx.ravel(), gy.ravel()])
        self.surface = server.scene.add_mesh_simple(
            "/waves", np.column_stack([self._xy, np.zeros(len(self._xy))]).astype(np.float32), grid_faces(cells),
            color=WATER_COLOUR, opacity=WATER_OPACITY, flat_shading=True, side="double", cast_shadow=False, visible=False,
        )  # fmt: skip
        self._sent = -np.inf
        self.sent_time = 0.0
        """Simulated time of the surface last sent."""
        self.updates = 0
        """How many wave surfaces were sent (tests check the throttle and the still-water silence)."""

    def show(self, water, t: float, centre: np.ndarray, visible: bool, now: float | None = None) -> None:
        """The flat sheet for still water; otherwise the surface around `centre` (x, y) at time t, throttled."""
        still = water.flat
        if self.calm.visible != (visible and still):
            self.calm.visible = visible and still
        if self.surface.visible != (visible and not still):
            self.surface.visible = visible and not still
        now = time.monotonic() if now is None else now
        if still or not visible or now - self._sent < 1.0 / self.hz:
            return
        cell = self.size / self.cells
        origin = np.round(np.asarray(centre[:2]) / cell) * cell  # follow the body in whole cells
        xy = self._xy + origin
        self.surface.vertices = np.column_stack([xy, water.elevation(xy, t)]).astype(np.float32)
        self._sent, self.sent_time = now, t
        self.updates += 1

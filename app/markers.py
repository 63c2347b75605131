"""Why it floats, in the scene: the centre of buoyancy B, the metacentre M (calm-water hydrostatics of
the current pose, sim/hydrostatics.py) and the waterline where the water meets the body (the actual
surface, waves included). Sent at most `MARKER_HZ` times a second and only while shown."""

from __future__ import annotations

import numpy as np
import viser

from sim.hydrostatics import waterline
from sim.rotation import quat_to_matrix

MARKER_HZ = 10.0
B_COLOUR = (30, 90, 220)
M_COLOUR = (200, 30, 160)
LINE_COLOUR = (250, 240, 40)


class MarkersView:
    """Scene nodes for B, M and the waterline; `show` runs on the simulation thread only."""

    def __init__(self, server: viser.ViserServer, radius: float):
        scene = server.scene
        r = 0.045 * radius
        self.b = scene.add_icosphere("/markers/B", radius=r, color=B_COLOUR, visible=False)
        self.m = scene.add_icosphere("/markers/M", radius=r, color=M_COLOUR, visible=False)
        scene.add_label("/markers/B/label", "B", position=(1.5 * r, 0.0, -1.5 * r))  # children follow the marker, and hide with it
        scene.add_label("/markers/M/label", "M", position=(1.5 * r, 0.0, 1.5 * r))
        self.line = scene.add_line_segments("/markers/waterline", np.zeros((1, 2, 3), np.float32), LINE_COLOUR, thickness=0.012 * radius,
                                            visible=False)  # fmt: skip
        self._sent = -np.inf
        self.latest = None
        """The Hydrostatics last shown (None: dry, submerged, or not shown)."""

    def _show_nodes(self, b: bool, line: bool) -> None:
        for node, want in ((self.b, b), (self.m, b), (self.line, line)):
            if node.visible != want:
                node.visible = want

    def show(self, snap, now: float, visible: bool) -> None:
        if not visible:
            self._show_nodes(False, False)
            self.latest = None
            return
        if now - self._sent < 1.0 / MARKER_HZ:
            return
        frame, body = snap.frame, snap.body
        R = quat_to_matrix(frame.q_world_body)
        h = snap.hydrostatics
        P = (body.mesh_vertices @ R.T + frame.x_world)[body.mesh_faces]
        water = snap.water
        heights = None if water.flat else water.height_above_surface(P.reshape(-1, 3), frame.t).reshape(P.shape[:2])
        segments = waterline(P, heights)
        self._show_nodes(h is not None, len(segments) > 0)
        if h is not None:
            self.b.position = h.buoyancy_centre
            self.m.position = h.metacentre
        if len(segments):
            self.line.points = segments.astype(np.float32)
        self.latest = h
        self._sent = now

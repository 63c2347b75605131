"""Why it floats, in the scene: the centre of buoyancy B and the metacentre M (calm-water hydrostatics of
the current pose, sim/hydro/hydrostatics.py); the waterline is the hull's (drawn/hull.py). Sent at most `MARKER_HZ`
times a second and only while shown."""

from __future__ import annotations

import numpy as np
import viser

MARKER_HZ = 10.0
B_COLOUR = (30, 90, 220)
M_COLOUR = (200, 30, 160)


class MarkersView:
    """Scene nodes for B and M; `show` runs on the simulation thread only."""

    def __init__(self, server: viser.ViserServer, radius: float, root: str = ""):
        scene = server.scene
        r = 0.045 * radius
        self.b = scene.add_icosphere(f"{root}/markers/B", radius=r, color=B_COLOUR, visible=False)
        self.m = scene.add_icosphere(f"{root}/markers/M", radius=r, color=M_COLOUR, visible=False)
        scene.add_label(f"{root}/markers/B/label", "B", position=(1.5 * r, 0.0, -1.5 * r))  # children follow the marker, and hide with it
        scene.add_label(f"{root}/markers/M/label", "M", position=(1.5 * r, 0.0, 1.5 * r))
        self._sent = -np.inf
        self.latest = None
        """The Hydrostatics last shown (None: dry, submerged, or not shown)."""

    def _show_nodes(self, b: bool) -> None:
        for node, want in ((self.b, b), (self.m, b)):
            if node.visible != want:
                node.visible = want

    def show(self, snap, now: float, visible: bool) -> None:
        if not visible:
            self._show_nodes(False)
            self.latest = None
            return
        if now - self._sent < 1.0 / MARKER_HZ:
            return
        h = snap.hydrostatics
        self._show_nodes(h is not None)
        if h is not None:
            self.b.position = h.buoyancy_centre
            self.m.position = h.metacentre
        self.latest = h
        self._sent = now

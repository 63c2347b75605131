"""The scene's wave gauges ([[gauges]], sim/scene/gauges.py): a small sphere on the sea's surface at each, labelled with
its name and elevation. Sent at most `GAUGE_HZ` times a second, only what changed, and only while the water is shown."""

from __future__ import annotations

import numpy as np
import viser

GAUGE_HZ = 10.0
GAUGE_COLOUR = (250, 170, 20)


class GaugesView:
    """Scene nodes for the gauges of the running scene; `show` runs on the simulation thread only."""

    def __init__(self, server: viser.ViserServer, radius: float, root: str = ""):
        self.server, self.root, self.size = server, root, 0.2 * max(radius, 1.0)
        self.nodes: dict[str, tuple] = {}
        """name -> (sphere, label, the label's text)."""
        self._sent = -np.inf

    def _node(self, name: str) -> tuple:
        if name not in self.nodes:
            scene = self.server.scene
            sphere = scene.add_icosphere(f"{self.root}/gauges/{name}", radius=self.size, color=GAUGE_COLOUR)
            label = scene.add_label(f"{self.root}/gauges/{name}/label", name, position=(0.0, 0.0, 3.0 * self.size))
            self.nodes[name] = (sphere, label, name)
        return self.nodes[name]

    def show(self, gauges: tuple, now: float, visible: bool) -> None:
        """`gauges`: a frame's ((name, x, y, eta, record), ...)."""
        names = {name for name, *_ in gauges}
        for name, (sphere, _, _) in self.nodes.items():
            want = visible and name in names
            if sphere.visible != want:
                sphere.visible = want
        if not visible or not gauges or now - self._sent < 1.0 / GAUGE_HZ:
            return
        for name, x, y, eta, _ in gauges:
            sphere, label, said = self._node(name)
            sphere.position = (float(x), float(y), float(eta))
            text = f"{name}: {eta:+.2f} m"
            if text != said:
                label.text = text
                self.nodes[name] = (sphere, label, text)
        self._sent = now

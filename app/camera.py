"""The view's own controls: Follow body (the body stays in view) and Reset view.

Following moves the world, not the cameras: the frame every scene node hangs from (scene.ROOT) is
shifted by minus the body's position smoothed over `SMOOTHING` seconds, so the body stays near the
origin the cameras look at, a bobbing body does not shake the view, and each page's own orbit and zoom
are never touched (a camera moved from the server would fight its user's gesture). One small message
at most `FOLLOW_HZ` times a second, the same for every page. Switched off, the world goes back to its
own coordinates.
"""

from __future__ import annotations

import math
import time

import numpy as np
import viser

FOLLOW_HZ = 20.0
SMOOTHING = 0.5
"""Seconds: the time constant of the followed point's lag behind the body."""


class CameraView:
    """The View folder; `follow` runs on the simulation thread only."""

    def __init__(self, server: viser.ViserServer, follow: bool):
        self.server = server
        with server.gui.add_folder("View"):
            self.follow_box = server.gui.add_checkbox("Follow body", follow, hint="Keep the body in view: the world moves under the camera")
            self.reset_button = server.gui.add_button("Reset view", hint="The camera as a new page starts")
        self.reset_button.on_click(lambda event: self.reset(event.client))
        self.target: np.ndarray | None = None
        """The followed point (the body's smoothed position; None: not following)."""
        self._time = -math.inf

    def follow(self, root, x: np.ndarray, now: float | None = None) -> None:
        """Move the followed point toward the body's position x, and the world `root` (a frame handle) by minus it."""
        now = time.monotonic() if now is None else now
        if not self.follow_box.value:
            if self.target is not None:
                self.target = None
                root.position = (0.0, 0.0, 0.0)
            return
        if now - self._time < 1.0 / FOLLOW_HZ:
            return
        x = np.asarray(x, float)
        if not np.isfinite(x).all():
            return
        if self.target is None:
            self.target = x.copy()
        else:
            self.target += (1.0 - math.exp(-(now - self._time) / SMOOTHING)) * (x - self.target)
        self._time = now
        root.position = -self.target

    def reset(self, client: viser.ClientHandle | None) -> None:
        """The page's camera (every page's when None) as a new page starts."""
        initial = self.server.initial_camera
        for page in [client] if client is not None else list(self.server.get_clients().values()):
            if page.camera._state.update_timestamp == 0.0:  # the page has not told its camera yet
                continue
            with page.atomic():
                page.camera.position = np.asarray(initial.position, float)  # (moves look_at along)
                page.camera.look_at = np.asarray(initial.look_at, float)

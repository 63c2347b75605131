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


class Follower:
    """The followed point, the body's position smoothed over SMOOTHING seconds; `step` moves the world frame
    `root` by minus it (at most FOLLOW_HZ times a second of the clock `now` counts in), `stop` puts it back."""

    def __init__(self, hz: float = FOLLOW_HZ):
        self.hz = hz
        self.target: np.ndarray | None = None
        """The followed point (None: not following)."""
        self._time = -math.inf

    def step(self, root, x: np.ndarray, now: float) -> None:
        if now - self._time < 1.0 / self.hz:
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

    def stop(self, root) -> None:
        if self.target is not None:
            self.target = None
            root.position = (0.0, 0.0, 0.0)


class CameraView:
    """The View folder; `follow` runs on the simulation thread only."""

    def __init__(self, server: viser.ViserServer, follow: bool):
        self.server = server
        with server.gui.add_folder("View"):
            self.follow_box = server.gui.add_checkbox("Follow body", follow, hint="Keep the body in view: the world moves under the camera")
            self.reset_button = server.gui.add_button("Reset view", hint="The camera as a new page starts")
        self.reset_button.on_click(lambda event: self.reset(event.client))
        self.follower = Follower()

    def follow(self, root, x: np.ndarray, now: float | None = None) -> None:
        """While Follow body is on, move the world `root` (a frame handle) by minus the body's smoothed position x."""
        if self.follow_box.value:
            self.follower.step(root, x, time.monotonic() if now is None else now)
        else:
            self.follower.stop(root)

    def reset(self, client: viser.ClientHandle | None) -> None:
        """The page's camera (every page's when None) as a new page starts."""
        initial = self.server.initial_camera
        for page in [client] if client is not None else list(self.server.get_clients().values()):
            if page.camera._state.update_timestamp == 0.0:  # the page has not told its camera yet
                continue
            with page.atomic():
                page.camera.position = np.asarray(initial.position, float)  # (moves look_at along)
                page.camera.look_at = np.asarray(initial.look_at, float)

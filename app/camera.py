"""The view's own controls: Follow body (the camera keeps the body in view) and Reset view.

Following moves every page's camera with the body: the point it looks at goes to the body's position
smoothed over `SMOOTHING` seconds (a bobbing body does not shake the view), and the camera keeps its
offset from that point, so a page's own orbit and zoom stay as its user left them. Sent at most
`FOLLOW_HZ` times a second, and not at all while the body stays put.
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
    """The View folder and each page's camera; `follow` runs on the simulation thread only."""

    def __init__(self, server: viser.ViserServer, follow: bool):
        self.server = server
        with server.gui.add_folder("View"):
            self.follow_box = server.gui.add_checkbox(
                "Follow body", follow, hint="Keep the body in view: the camera moves with it, your orbit and zoom kept"
            )
            self.reset_button = server.gui.add_button("Reset view", hint="The camera as a new page starts (around the body when following)")
        self.reset_button.on_click(lambda event: self.reset(event.client))
        self._target: np.ndarray | None = None  # the followed point (smoothed body position)
        self._time = -math.inf
        self._sent: dict[int, np.ndarray] = {}  # per page: the point its camera was last moved to

    def follow(self, x: np.ndarray, now: float | None = None) -> None:
        """Move the followed point toward the body's position x and every page's camera with it."""
        now = time.monotonic() if now is None else now
        if not self.follow_box.value:
            self._target = None
            return
        if now - self._time < 1.0 / FOLLOW_HZ:
            return
        x = np.asarray(x, float)
        if self._target is None or not np.isfinite(self._target).all():
            self._target = x.copy()
        else:
            self._target += (1.0 - math.exp(-(now - self._time) / SMOOTHING)) * (x - self._target)
        self._time = now
        for client in list(self.server.get_clients().values()):
            self._aim(client, self._target)

    def _aim(self, client: viser.ClientHandle, target: np.ndarray) -> None:
        """The page's camera onto `target`, its offset from the point it looked at kept."""
        camera = client.camera
        if camera._state.update_timestamp == 0.0:  # the page has not told its camera yet
            return
        last = self._sent.get(client.client_id)
        if last is not None and np.linalg.norm(target - last) < 1e-4:
            return
        try:
            camera.position = target + (camera.position - camera.look_at)  # viser moves look_at by the same step: onto target
        except ValueError:  # a degenerate camera the page sent: leave it
            return
        self._sent[client.client_id] = target.copy()

    def reset(self, client: viser.ClientHandle | None) -> None:
        """The page's camera (every page's when None) as a new page starts; around the followed point when following."""
        initial = self.server.initial_camera
        position, look_at = np.asarray(initial.position, float), np.asarray(initial.look_at, float)
        if self.follow_box.value and self._target is not None:
            position, look_at = self._target + (position - look_at), self._target.copy()
        for page in [client] if client is not None else list(self.server.get_clients().values()):
            if page.camera._state.update_timestamp == 0.0:
                continue
            with page.atomic():
                page.camera.position = position  # with look_at moved along
                page.camera.look_at = look_at
            self._sent[page.client_id] = look_at.copy()

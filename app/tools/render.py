"""Pictures of a scene as the live viewer shows it: the viewer started paused, rendered by headless chromium."""

from __future__ import annotations

import contextlib
import io
import time
from pathlib import Path

from app.args import ViewArgs
from app.main import start
from app.recording.browser import launch, missing

View = tuple[tuple[float, float, float], tuple[float, float, float], tuple[float, float, float]]
"""Camera position, look-at point and up direction, world frame."""


def render_scene(scene: str, views: dict[str, View], paths: dict[str, Path], size: tuple[int, int] = (450, 600)) -> str | None:
    """Save one PNG per view of `scene` (a preset or .toml path) at its initial pose, through viser's
    client.get_render. Returns None on success, else why not (the caller falls back to its own plot)."""
    if why := missing():
        return why
    from PIL import Image
    from playwright.sync_api import sync_playwright

    viewer = None
    try:
        with contextlib.redirect_stdout(io.StringIO()):  # viser's banner
            viewer = start(ViewArgs(scene=scene, port=0))
        viewer.loop.post("pause", True)
        viewer.sync()
        with sync_playwright() as p:
            browser = launch(p)
            try:
                page = browser.new_page(viewport={"width": 800, "height": 600})
                page.set_default_timeout(60_000)
                page.goto(viewer.url)
                page.wait_for_selector("canvas")
                deadline = time.monotonic() + 30.0
                while not viewer.server.get_clients():
                    if time.monotonic() > deadline:
                        return "no browser client connected to the viewer within 30 s"
                    time.sleep(0.1)
                client = next(iter(viewer.server.get_clients().values()))
                time.sleep(3.0)  # the environment map fades in
                for name, path in paths.items():
                    position, look_at, up = views[name]
                    client.camera.up_direction = up
                    client.camera.position = position
                    client.camera.look_at = look_at
                    time.sleep(2.0)  # the browser applies the camera on its next frames
                    Image.fromarray(client.get_render(*size, timeout=60.0)).save(path)
            finally:
                browser.close()
    except Exception as e:  # noqa: BLE001 -- a failed render must not lose the caller's page
        return f"the viewer render failed ({type(e).__name__}: {e})"
    finally:
        if viewer is not None:
            with contextlib.redirect_stdout(io.StringIO()):  # and its goodbye
                viewer.stop()
    return None

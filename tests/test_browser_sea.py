"""The sea as a browser shows it (headless chromium, software WebGL): a storm's shading, and Follow body keeping
the body in the middle of the frame while the storm carries it about."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest
from viewer import wait_for


def start_viewer(scene: str, **kwargs):
    from app.args import ViewArgs
    from app.main import start

    return start(ViewArgs(scene=scene, port=0), publish_hz=20.0, **kwargs)


def open_page(app, page):
    page.goto(app.url + "/?fixedDpr=0.5")
    page.wait_for_selector("canvas")
    wait_for(app, lambda s: len(app.server.get_clients()) == 1, what="the browser to connect")
    return next(iter(app.server.get_clients().values()))


def water_spread(render: np.ndarray) -> tuple[float, float]:
    """(standard deviation of the grey level over the water's pixels, their share of the frame): water is the
    bluish pixels (blue well above red)."""
    rgb = render.astype(float)
    water = rgb[..., 2] > rgb[..., 0] + 25
    return float(rgb[water].mean(axis=1).std()), float(water.mean())


@pytest.mark.slow
def test_a_storm_is_shaded_where_still_water_is_one_calm_sheet(browser_page):
    """The grey levels over the water of a storm spread several times as widely as over still water."""
    spreads = {}
    for scene in ("damped", "storm"):
        app = start_viewer(scene, kernels=False)
        try:
            client = open_page(app, browser_page)
            time.sleep(4.0)  # the environment map fades in; a few wave surfaces go out
            render = client.get_render(240, 320, timeout=60.0)
            spreads[scene] = water_spread(render)
        finally:
            app.stop()
    (still, still_share), (storm, storm_share) = spreads["damped"], spreads["storm"]
    assert still_share > 0.2 and storm_share > 0.2  # the water fills much of the frame in both
    assert storm > 3.0 * still, spreads


def projected(camera, x: np.ndarray) -> np.ndarray:
    """Where the point x falls in the page's frame, in half-widths and half-heights from its centre (viser's
    cameras are OpenCV's: +z forward, +y down; fov is vertical)."""
    from sim.rotation import quat_to_matrix

    p = quat_to_matrix(np.asarray(camera.wxyz, float)).T @ (x - np.asarray(camera.position, float))
    tan = math.tan(0.5 * camera.fov)
    return np.array([p[0] / p[2] / (tan * camera.aspect), p[1] / p[2] / tan])


@pytest.mark.slow
def test_follow_keeps_the_body_in_the_middle_half_of_the_frame_through_a_storm_and_reset_view_goes_back(browser_page):
    """60 s of `storm` (Follow on by default there): at every sample the body's centre, projected with the camera the
    browser reports, lies in the middle half of its frame, while the body itself wanders well beyond that half
    from where it started. Reset view brings back the starting camera's offset."""
    app = start_viewer("storm")
    try:
        assert app.camera.follow_box.value
        client = open_page(app, browser_page)
        start = None
        spots, wander = [], []
        t0 = app.sync().frame.t
        while True:
            snap = app.sync()
            if snap.frame.t - t0 >= 60.0:
                break
            time.sleep(2.0)
            snap = app.sync()
            start = snap.frame.x_world.copy() if start is None else start
            spots.append(projected(client.camera, snap.frame.x_world))
            wander.append(np.linalg.norm(snap.frame.x_world - start))
        spots = np.array(spots)
        assert len(spots) >= 15
        assert np.abs(spots).max() < 0.5, spots  # the middle half, at every sample
        assert max(wander) > 1.0  # and the body did move (an unmoving camera would have lost it)

        browser_page.get_by_role("button", name="Reset view").click()
        initial = np.asarray(app.server.initial_camera.position) - np.asarray(app.server.initial_camera.look_at)
        deadline = time.monotonic() + 20.0
        while np.linalg.norm(client.camera.position - client.camera.look_at - initial) > 1e-3 and time.monotonic() < deadline:
            time.sleep(0.2)
        np.testing.assert_allclose(client.camera.position - client.camera.look_at, initial, atol=1e-3)
    finally:
        app.stop()

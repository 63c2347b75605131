"""The Live tab's plots as a newcomer meets them, in a real browser (Debian's chromium through Playwright).

What is checked is what the page draws: the readout's text, and each uPlot chart's x scale, data and tick
labels as the page holds them (viser's own E2E testpoint, `window.__viserTestpoints.uplots`).
"""

from __future__ import annotations

import re
import time

import pytest
from viewer import wait_for

CHARTS = """() => Object.values((window.__viserTestpoints || {}).uplots || {}).map(({chart: c}) => ({
    label: c.series[1].label, x: Array.from(c.data[0]), xmin: c.scales.x.min, xmax: c.scales.x.max,
    xticks: c.axes[0]._values, yticks: c.axes[1]._values, width: c.width}))"""
"""Every mounted chart as the page draws it: its data's times, x scale, and both axes' tick labels."""


@pytest.fixture
def app():
    from app.args import ViewArgs
    from app.main import start

    viewer = start(ViewArgs(scene="damped", port=0), kernels=False, strict=True, publish_hz=20.0)
    yield viewer
    viewer.stop()


def readout_t(page) -> float:
    """The time the Live tab's readout shows ('t = 25.01 s')."""
    return float(re.search(r"t = (-?[\d.]+) s", page.get_by_text("t = ", exact=False).first.inner_text()).group(1))


def shown(page) -> tuple[float, list[dict]]:
    """The readout's t and every chart, read in one go."""
    charts = page.evaluate(CHARTS)
    return readout_t(page), charts


def drawn(chart: dict) -> list[float]:
    """The sample times inside the chart's x range: what its line covers."""
    return [t for t in chart["x"] if chart["xmin"] <= t <= chart["xmax"]]


@pytest.mark.slow
def test_live_tab_opened_mid_run_shows_the_current_window_and_a_reset_starts_it_afresh(app, browser_page, tmp_path):
    """The run goes on with the About tab open (the damped cube, 4 points per edge, asked 10x: settled by t = 40 s); the Live
    tab opened once the plots' window is all after that draws the window that ends at the readout's t at once (viser's client drew the first second
    of the window, for good: opened at t = 26 s, its plots showed 0.9-2.1 s), the settled series' tick labels are
    distinct (they read '-0.4, -0.4, -0.4'), and after Reset no plot shows a negative time."""
    page = browser_page
    page.goto(app.url + "/?fixedDpr=0.5&speed=10&points_per_edge=4")
    page.wait_for_selector("canvas")
    wait_for(app, lambda s: s.settings.speed == 10.0 and s.frame.t > 1.0, what="the link's speed on the server")
    # A newcomer reads the About tab until the plots' window (200 samples) all lies after the cube settled (t > 40 s).
    wait_for(app, lambda s: app.readouts._history and app.readouts._history[0][0] > 40.0, timeout=120.0, what="a settled window")
    page.get_by_role("tab", name="Live").click()
    page.wait_for_function("() => Object.keys((window.__viserTestpoints || {}).uplots || {}).length >= 4")
    t, charts = shown(page)
    page.screenshot(path=str(tmp_path / "live-opened-mid-run.png"))
    assert t > 40.0 and len(charts) == 4  # z, |L|, |F|, E (the take-off's plot is hidden: no joint)
    for chart in charts:
        times = drawn(chart)
        sample = (chart["x"][-1] - chart["x"][0]) / (len(chart["x"]) - 1)  # one sample: 1 s of simulation at 10x
        assert times and abs(times[-1] - t) <= 2 * sample + 0.5, (chart["label"], chart["xmin"], chart["xmax"], t)
        assert times[-1] - times[0] > 0.9 * (chart["x"][-1] - chart["x"][0])  # the whole window, not its start
        assert chart["yticks"] and len(set(chart["yticks"])) == len(chart["yticks"]), (chart["label"], chart["yticks"])

    page.get_by_role("button", name="Reset", exact=True).click()
    wait_for(app, lambda s: s.frame.t < 3.0, what="the reset on the server")
    time.sleep(2.0)
    t, charts = shown(page)
    page.screenshot(path=str(tmp_path / "live-after-reset.png"))
    assert t < 30.0
    for chart in charts:
        assert chart["x"][0] >= 0.0 and chart["xmin"] >= 0.0, (chart["label"], chart["x"][0], chart["xmin"])
        assert all(not label.startswith(("-", "−")) for label in chart["xticks"]), (chart["label"], chart["xticks"])
        assert drawn(chart) and abs(drawn(chart)[-1] - t) <= 2.5, (chart["label"], chart["xmin"], chart["xmax"], t)

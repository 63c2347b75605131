"""Issue 12 in a real browser (Debian chromium through Playwright): a setup link applied, a mesh
uploaded through the page's file input (and a broken one refused with the old body still running), and
a recording that replays offline, with no server, at the poses of its CSV."""

from __future__ import annotations

import io
import time

import numpy as np
import pytest
import trimesh
from conftest import _require
from test_share import pose_at, recording_messages
from viewer import wait_for


@pytest.fixture
def page(browser_page):
    return browser_page  # conftest's: Debian chromium, 800x600, generous timeouts (downloads accepted)


@pytest.fixture
def app(tmp_path, monkeypatch):
    from app.args import ViewArgs
    from app.main import start

    monkeypatch.chdir(tmp_path)  # recordings go to ./floatsim-recordings
    monkeypatch.setattr("app.live.upload.UPLOADS", tmp_path / "uploads")
    viewer = start(ViewArgs(scene="damped", port=0), kernels=False, strict=True, publish_hz=20.0)
    yield viewer
    viewer.stop()


def moved_pixels(before: np.ndarray, after: np.ndarray) -> int:
    """How many pixels changed visibly (by more than 40 of 255 in some channel) between two pictures."""
    return int((np.abs(after - before).max(axis=2) > 40.0).sum())


def picture(png: bytes) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=float)


@pytest.mark.slow
def test_a_link_sets_the_scene_and_its_parameters_and_restarts_it(app, page):
    time.sleep(1.0)  # the run goes on before anyone watches
    page.goto(app.url + "/?scene=drop&density=500&damping=40&wobble=3&fixedDpr=0.5")
    page.wait_for_selector("canvas")
    snap = wait_for(app, lambda s: s.settings.scene == "drop" and s.density == 500.0 and s.damping == 40.0, what="the link's setup")
    assert snap.frame.t < 5.0 and app.connections == 1  # restarted for the newcomer
    wait_for(app, lambda s: "unknown parameter 'wobble'" in s.notice, what="the note on the unknown parameter")
    # and Copy link writes them back: the clipboard holds this page's address with the running setup
    page.context.grant_permissions(["clipboard-read", "clipboard-write"], origin=app.url)
    wait_for(app, lambda s: "density=500" in app.link_text.content, what="the link to follow the setup")
    time.sleep(1.0)
    page.get_by_role("button", name="Copy link").click()
    page.get_by_role("button", name="Link copied").wait_for()
    copied = page.evaluate("navigator.clipboard.readText()")
    assert copied.startswith(app.url + "/?scene=drop") and "density=500" in copied and "damping=40" in copied


@pytest.mark.slow
def test_upload_a_mesh_through_the_page_and_refuse_a_broken_one(app, page, tmp_path):
    time.sleep(2.0)
    before = app.sync()
    page.goto(app.url + "/?fixedDpr=0.5")
    # the first browser restarts the run: a newcomer sees the drop from its start
    wait_for(app, lambda s: s.epoch > before.epoch and s.frame.t < before.frame.t, what="the run to restart for the first browser")
    page.get_by_text("Your body", exact=True).last.click()  # open the folder (the first match is the About text)
    page.get_by_text("Load mesh (STL, OBJ, PLY)").wait_for()
    good = tmp_path / "crate.stl"
    trimesh.creation.box(extents=(0.8, 0.6, 0.5)).export(good)
    with page.expect_file_chooser() as chooser:
        page.get_by_text("Load mesh (STL, OBJ, PLY)").click()
    chooser.value.set_files(str(good))
    snap = wait_for(app, lambda s: s.body.name.startswith("crate"), what="the uploaded body")
    assert snap.body.volume == pytest.approx(0.24, rel=1e-6)  # STL stores float32
    assert snap.body.mass == pytest.approx(900.0 * snap.body.volume, rel=1e-12)  # the running density is kept
    wait_for(app, lambda s: "crate" in app.body_file.info.content and "draft" in app.body_file.info.content, what="the body's description")
    broken = tmp_path / "broken.stl"
    box = trimesh.creation.box(extents=(0.8, 0.6, 0.5))
    trimesh.Trimesh(box.vertices, box.faces[:-1]).export(broken)
    with page.expect_file_chooser() as chooser:
        page.get_by_text("Load mesh (STL, OBJ, PLY)").click()
    chooser.value.set_files(str(broken))
    snap = wait_for(app, lambda s: "not watertight" in s.notice, what="the refusal")
    t = snap.frame.t
    snap = wait_for(app, lambda s: s.frame.t > t + 0.5, what="the old body to keep running")
    assert snap.body.name.startswith("crate")
    page.get_by_text("not watertight", exact=False).first.wait_for()  # the reason is in the panel


@pytest.mark.slow
def test_record_then_replay_offline_at_the_csv_poses(app, page, tmp_path):
    page.goto(app.url + "/?fixedDpr=0.5")
    page.get_by_role("button", name="Record").wait_for()
    wait_for(app, lambda s: app.connections == 1, what="the browser")
    # (set-up, not the feature under test) record the drop from its start, however slowly this machine clicks:
    # the run waits, paused at its start, until the recording is under way
    app.loop.post("pause", True)
    app.loop.post("reset", None)
    app.sync()
    page.get_by_role("button", name="Record").click()
    wait_for(app, lambda s: app.recorder.recording, what="recording to start")
    t0 = app.sync().frame.t
    assert t0 == 0.0
    app.loop.post("pause", False)
    wait_for(app, lambda s: s.frame.t > t0 + 2.0, what="two simulated seconds recorded")  # not wall time: a loaded machine runs slower
    downloads = []
    page.on("download", lambda d: downloads.append(d))
    with page.expect_download(predicate=lambda d: d.suggested_filename.endswith(".html")) as first:  # the CSV may arrive first
        page.get_by_role("button", name="Stop recording").click()
    html_path = tmp_path / "replay.html"
    first.value.save_as(html_path)
    for _ in range(150):  # the CSV, if it comes second: up to 30 s on a loaded machine
        if len(downloads) >= 2:
            break
        page.wait_for_timeout(200)
    assert sorted(d.suggested_filename.rsplit(".", 1)[1] for d in downloads) == ["csv", "html"]  # both offered, once each
    csv_path = app.recorder.files["csv"]
    app.stop()  # no server from here on

    rows = np.loadtxt(csv_path, delimiter=",", skiprows=1)
    assert len(rows) > 20
    _, messages = recording_messages(html_path.read_text())
    k = int(np.argmax(np.linalg.norm(rows[:, 1:4] - rows[0, 1:4], axis=1)))  # where the body is farthest from the start
    assert np.linalg.norm(rows[k, 1:4] - rows[0, 1:4]) > 0.05
    seek = rows[k, 0] - rows[0, 0]
    position, wxyz = pose_at(messages, seek)
    np.testing.assert_allclose(position, rows[k, 1:4], atol=1e-6)
    np.testing.assert_allclose(wxyz, rows[k, 4:8], atol=1e-6)

    page.goto(html_path.as_uri() + "?fixedDpr=0.5")
    page.wait_for_selector("canvas")
    time.sleep(4.0)
    slider = page.locator("[role=slider]").first  # the player's timeline
    play = slider.locator("xpath=ancestor::div[.//button][1]//button").first  # its play/pause, left of it
    play.click()  # pause
    slider.focus()
    slider.press("Home")
    time.sleep(1.5)
    canvas = page.locator("canvas").first
    start = picture(canvas.screenshot())
    assert start.std() > 10.0  # not blank
    box = page.locator("input[inputmode=decimal]").first
    box.fill(f"{seek:.3f}")
    box.press("Enter")
    time.sleep(1.5)
    assert float(slider.get_attribute("aria-valuenow")) == pytest.approx(seek, abs=0.05)
    later = picture(canvas.screenshot())
    for _ in range(16):  # software WebGL on a loaded machine may draw the seek a few frames late: look again for 8 s
        if moved_pixels(start, later) > 300:
            break
        time.sleep(0.5)
        later = picture(canvas.screenshot())
    assert later.std() > 10.0 and moved_pixels(start, later) > 300  # the body moved (the replay of still water is otherwise still)


@pytest.mark.slow
def test_export_video_of_the_last_recording(app):
    from app.recording.browser import missing

    _require(missing() is None, missing() or "")
    import av

    app.recorder.start()
    t0 = app.sync().frame.t
    wait_for(app, lambda s: s.frame.t > t0 + 1.0, what="a second of run")
    files = app.recorder.stop()
    assert files["html"].is_file() and files["csv"].is_file()
    path = app.recorder.export_video(fps=10)
    with av.open(str(path)) as video:
        frames = list(video.decode(video=0))
    assert len(frames) == int(app.recorder.last.duration * 10 + 1e-9) + 1 and (frames[0].width, frames[0].height) == (640, 360)
    assert not app.recorder.progress.visible and not app.recorder.video.disabled


@pytest.mark.slow
def test_the_banners_link_drives_the_run_and_pages_without_the_token_cannot(browser_page):
    """--token in chromium: the link the banner prints changes density through the page's own slider box;
    the same page opened without the token, or with a wrong one, cannot."""
    import contextlib

    from test_browser import control_row

    from app.args import ViewArgs
    from app.main import start

    page = browser_page
    with contextlib.redirect_stdout(io.StringIO()):
        viewer = start(ViewArgs(scene="rest", port=0, token="s3cret"), kernels=False, publish_hz=10.0)
    try:

        def set_density(address: str, value: str, ready=lambda: True) -> None:
            before = set(viewer.server.get_clients())
            page.goto(address)
            box = control_row(page, "Density (kg/m³)").locator("input.mantine-NumberInput-input")
            box.wait_for()

            def connected() -> bool:  # the new page, not the one it replaced (a loaded machine may count that a while)
                clients = set(viewer.server.get_clients())
                return len(clients) == 1 and not clients & before and ready()

            wait_for(viewer, lambda s: connected(), what="the page to connect")
            time.sleep(1.0)  # its address probe answered
            box.fill(value)
            box.press("Enter")

        set_density(viewer.address() + "&fixedDpr=0.5", "500", ready=lambda: len(viewer.drivers) == 1)
        wait_for(viewer, lambda s: s.density == 500.0, what="density 500 from the banner's link")
        for address in (viewer.url + "/?fixedDpr=0.5", viewer.url + "/?token=wrong&fixedDpr=0.5"):
            refused = viewer.refusals.count
            set_density(address, "700")
            wait_for(viewer, lambda s: viewer.refusals.count > refused, what="the update to be refused")
            assert viewer.sync().density == 500.0
        box = control_row(page, "Density (kg/m³)").locator("input.mantine-NumberInput-input")
        for retry in range(6):  # the reason is shown (a notice lasts 10 s: a loaded machine may draw the page later; ask again)
            try:
                page.get_by_text("this page has no access token", exact=False).first.wait_for(timeout=10_000)
                break
            except Exception:  # noqa: BLE001 - Playwright's timeout
                box.fill(str(710 + retry))  # a value the box does not show yet: the same one again would send nothing
                box.press("Enter")
        else:
            raise AssertionError("the page refused without the token never showed why")
    finally:
        viewer.stop()

"""Spend limits of Record and Export video, driven by the viewer's own buttons through viser's protocol
(issue 23, item 10): the recordings folder stays bounded (takes and bytes, the oldest takes removed, no
other file touched), two takes in the same second never overwrite each other, and Export video refuses
a take whose render would take longer than its stated limit, before any browser starts."""

from __future__ import annotations

import asyncio
import contextlib
import io
import os

import msgspec
import pytest
import viser
import websockets
from test_upload_guard import CAMERA, _drain


@pytest.fixture
def app(tmp_path, monkeypatch):
    from app.args import ViewArgs
    from app.main import start

    monkeypatch.chdir(tmp_path)  # recordings go to ./floatsim-recordings
    with contextlib.redirect_stdout(io.StringIO()):
        viewer = start(ViewArgs(scene="damped", port=0), kernels=False, strict=True, publish_hz=20.0)
    yield viewer
    viewer.stop()


async def _clicks(app, steps) -> None:
    """One page: after its camera message, for each (button, wait) in `steps`, clicks the button as
    viser's page does (a GuiUpdateMessage setting its value to true), then waits until wait() holds."""
    async with websockets.connect(f"ws://127.0.0.1:{app.port}", subprotocols=[f"viser-v{viser.__version__}"], max_size=None,
                                  origin=app.url) as ws:  # fmt: skip
        reader = asyncio.ensure_future(_drain(ws))
        await ws.send(msgspec.msgpack.encode(CAMERA))
        for button, done in steps:
            await ws.send(msgspec.msgpack.encode({"type": "GuiUpdateMessage", "uuid": button._impl.uuid, "updates": {"value": True}}))
            for _ in range(600):
                if done():
                    break
                await asyncio.sleep(0.05)
            else:
                raise AssertionError(f"the click on {button.label!r} had no effect")
        reader.cancel()


def record_takes(app, n: int, seconds: float = 0.0) -> None:
    """n takes, each Record, a few frames (at least `seconds` of run), Stop recording."""
    rec = app.recorder
    steps = []
    for _ in range(n):
        steps.append((rec.record, lambda: rec.recording and len(rec._take) > 3 and rec._take.duration >= seconds))
        steps.append((rec.record, lambda: not rec.recording and rec.status.content.startswith("Recorded")))
    asyncio.run(_clicks(app, steps))


def takes_in(folder) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def test_two_takes_in_the_same_second_get_their_own_files(app, tmp_path, monkeypatch):
    monkeypatch.setattr("app.recording.recorder.stamp", lambda: "20260101-120000")  # every take in the same second
    record_takes(app, 1)
    folder = tmp_path / "floatsim-recordings"
    first = (folder / "floatsim-20260101-120000.csv").read_text()
    record_takes(app, 2)
    assert takes_in(folder) == sorted(f"floatsim-20260101-120000{n}.{kind}" for n in ("", "-2", "-3") for kind in ("csv", "html"))
    assert (folder / "floatsim-20260101-120000.csv").read_text() == first  # not overwritten
    assert app.recorder.files["csv"].name == "floatsim-20260101-120000-3.csv" and app.recorder.files["csv"].read_text() != first
    assert all((folder / name).stat().st_size > 100 for name in takes_in(folder))


def test_the_recordings_folder_keeps_the_newest_takes_within_its_bounds(app, tmp_path, monkeypatch):
    import app.recording.recorder as recorder

    folder = tmp_path / "floatsim-recordings"
    folder.mkdir()
    for i in range(40):  # old takes, oldest first, 100 kB each
        for kind in ("html", "csv"):
            old = folder / f"floatsim-20250101-0000{i:02d}.{kind}"
            old.write_bytes(b"x" * 50_000)
            os.utime(old, (1e9 + i, 1e9 + i))
    (folder / "notes.txt").write_text("mine")  # not the recorder's: never touched
    (folder / "floatsim-final.html").write_text("mine too")
    record_takes(app, 1)
    names = takes_in(folder)
    kept = [n for n in names if n.startswith("floatsim-2025") and n.endswith(".html")]
    assert len(kept) == recorder.KEPT_TAKES - 1 and kept[0] == "floatsim-20250101-000011.html"  # the oldest 11 went
    assert "notes.txt" in names and "floatsim-final.html" in names and app.recorder.files["html"].name in names
    new_take = sum(p.stat().st_size for p in app.recorder.files.values())
    monkeypatch.setattr(recorder, "KEPT_BYTES", new_take * 2 + 500_000)  # room for the two new takes and about 5 old ones
    record_takes(app, 1)
    ours = [p for p in folder.iterdir() if recorder.TAKE_FILE.fullmatch(p.name)]
    assert sum(p.stat().st_size for p in ours) <= recorder.KEPT_BYTES
    old = sorted(p.name for p in ours if p.name.startswith("floatsim-2025") and p.suffix == ".html")
    assert 1 <= len(old) <= 6 and old == [f"floatsim-20250101-0000{i:02d}.html" for i in range(40 - len(old), 40)]  # the newest
    assert "notes.txt" in takes_in(folder) and all(p.exists() for p in app.recorder.files.values())


def test_export_video_refuses_a_take_that_would_render_too_long(app, tmp_path, monkeypatch):
    import app.recording.video as video

    monkeypatch.setattr(video, "MAX_RENDER_SECONDS", 6.0)  # a take of a few frames: 5 s to start and about 12 frames a second
    monkeypatch.setattr(video, "launch", lambda *a: pytest.fail("a browser was started"))
    record_takes(app, 1, seconds=1.0)
    rec = app.recorder
    asyncio.run(_clicks(app, [(rec.video, lambda: "Video not exported" in rec.status.content)]))
    assert "over the limit of 0.1 min" in rec.status.content and "frames at 30 fps" in rec.status.content
    assert not list((tmp_path / "floatsim-recordings").glob("*.mp4")) and not rec.video.disabled and not rec.progress.visible

"""A browser that sends bad GUI updates (speaking viser's own protocol) cannot take the viewer from
everyone: after a fixed list of a few hundred bad messages a second page still connects, every
control still works, memory is where it was, and the simulation is still advancing."""

from __future__ import annotations

import asyncio
import contextlib
import gc
import io
import math
import time

import msgspec
import pytest
import viser
import websockets

from app.guards.gui_guard import MAX_NUMBER, Refusals, refusal
from app.tools.page import CAMERA

BAD_UPDATES = (
    {"value": 1e300}, {"value": -1e300}, {"value": math.inf}, {"value": math.nan}, {"value": 2.0 * MAX_NUMBER},
    {"value": "x" * 200_000}, {"value": [1.0, 2.0]}, {"value": [1.0, 2.0, 3.0, 4.0, 5.0]}, {"value": None}, {"value": {"a": 1}},
    {"value": "not a choice"}, {"disabled": True}, {"visible": False}, {"min": 5.0, "max": 6.0}, {"value": 1.0, "disabled": True},
    {"label": "pwned"}, {}, {"value": [math.nan, 0.0, 0.0]},
)  # fmt: skip


def rss_mib() -> float:
    for line in open("/proc/self/status"):
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def bad_messages(uuids: list[str]) -> list[bytes]:
    out = []
    for uuid in uuids:
        for updates in BAD_UPDATES:
            out.append(msgspec.msgpack.encode({"type": "GuiUpdateMessage", "uuid": uuid, "updates": updates}))
    return out


async def send_all(port: int, frames: list[bytes]) -> None:
    """From a page viser counts as connected (it sent a camera message first), so every check is reached."""
    async with websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=[f"viser-v{viser.__version__}"], max_size=None) as ws:
        await ws.send(msgspec.msgpack.encode(CAMERA))
        await asyncio.sleep(0.5)
        for frame in frames:
            await ws.send(frame)
        await asyncio.sleep(1.0)


async def connects(port: int) -> int:
    """Bytes a fresh page receives in its first two seconds (0: dropped)."""
    received = 0
    with contextlib.suppress(Exception):
        async with websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=[f"viser-v{viser.__version__}"], max_size=None) as ws:
            deadline = time.monotonic() + 2.0
            while time.monotonic() < deadline:
                try:
                    received += len(await asyncio.wait_for(ws.recv(), timeout=0.5))
                except asyncio.TimeoutError:
                    continue
    return received


def shown(handle) -> tuple:
    """What a message could switch on a control: its declared properties (viser 1.1.1: `_impl.props`)."""
    return tuple(getattr(handle._impl.props, name, None) for name in ("disabled", "visible", "label", "min", "max", "options"))


def test_refusal_keeps_only_a_sane_value_of_the_controls_own_type():
    class State:  # as viser 1.1.1 keeps a control: its value, and its declared properties in `props`
        def __init__(self, value, options=None):
            self.value, self.props = value, type("Props", (), {"options": options, "label": "x"})()

    assert refusal(State(10), {"value": 12}) is None and refusal(State(10), {"value": 12.5})
    assert refusal(State(10), {"value": 1e300}) and refusal(State(1.5), {"value": math.nan}) and refusal(State(1.5), {"value": True})
    assert refusal(State(False), {"value": True}) is None and refusal(State(False), {"value": 1})
    assert refusal(State("a", ("a", "b")), {"value": "b"}) is None and refusal(State("a", ("a", "b")), {"value": "c"})
    assert refusal(State((0.0, 0.0, 0.0)), {"value": [1, 2, 3]}) is None and refusal(State((0.0, 0.0, 0.0)), {"value": [1, 2]})
    assert refusal(State(1.0), {"value": 1.0, "disabled": True}) and refusal(State(1.0), {"visible": False})


def test_refusals_in_a_burst_give_one_notice_now_and_one_with_the_rest_at_the_intervals_end(monkeypatch):
    """A page refused just after another must still be told why: not dropped by the rate limit."""
    import app.guards.gui_guard as guard

    monkeypatch.setattr(guard, "NOTICE_SECONDS", 0.3)
    notes: list[str] = []
    refused = Refusals(notes.append)
    refused("first reason")
    assert notes == ["Ignored 1 control update from a browser: first reason."]
    for _ in range(3):
        refused("second reason")
    assert len(notes) == 1  # held back inside the interval...
    time.sleep(0.6)
    assert notes[1:] == ["Ignored 3 control updates from a browser: second reason."]  # ...and said at its end, once
    time.sleep(0.4)
    assert len(notes) == 2 and refused.count == 4


@pytest.mark.slow
def test_bad_gui_updates_leave_the_viewer_working_for_everyone():
    from app.args import ViewArgs
    from app.main import start

    with contextlib.redirect_stdout(io.StringIO()):
        app = start(ViewArgs(scene="damped", port=0), kernels=False)
    try:
        handles = app.server.gui._gui_input_handle_from_uuid
        uuids = list(handles)
        frames = bad_messages(uuids)
        assert len(frames) >= 200
        time.sleep(1.0)
        gc.collect()
        before, t0 = rss_mib(), app.sync().frame.t
        props = {uuid: shown(h) for uuid, h in handles.items()}
        asyncio.run(send_all(app.port, frames))
        time.sleep(1.0)
        assert app.refusals.count >= len(frames) - len(uuids)  # every one refused ({"value": 1.0} alone on a number control is fine)
        for uuid, h in handles.items():  # no property of any control was changed by them
            assert shown(h) == props[uuid]
        assert asyncio.run(connects(app.port)) > 1000  # a new page gets the scene
        c = app.controls
        c.density.value = 500.0
        assert app.sync().density == pytest.approx(500.0)
        c.paused.value = True
        assert app.sync().settings.paused
        c.paused.value = False
        snap = app.sync()
        assert len(snap.notice) < 200  # the refusal notice names no input
        time.sleep(1.0)
        assert app.sync().frame.t > t0 + 1.0  # still advancing
        gc.collect()
        assert rss_mib() - before < 20.0
    finally:
        app.stop()


def test_serving_beyond_loopback_warns_that_anyone_can_drive_the_run():
    import subprocess
    import sys

    from app.main import is_loopback

    assert is_loopback("127.0.0.1") and is_loopback("::1") and is_loopback("localhost")
    assert not is_loopback("0.0.0.0") and not is_loopback("::") and not is_loopback("192.168.1.2")
    proc = subprocess.Popen([sys.executable, "-m", "app", "--host", "0.0.0.0", "--port", "0", "--scene", "rest"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)  # fmt: skip
    try:
        line = ""
        deadline = time.monotonic() + 120
        while "warning" not in line and time.monotonic() < deadline:
            line = proc.stderr.readline()
        assert "anyone who can reach port" in line
    finally:
        proc.terminate()
        proc.wait(timeout=30)

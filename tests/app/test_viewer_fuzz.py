"""A client that sends malformed or oversized websocket frames is dropped; the server keeps no
lasting memory for it, logs one line per kind of mistake (no traceback: the page's mistake, not the server's), and the
simulation runs on for the others."""

from __future__ import annotations

import asyncio
import contextlib
import gc
import io
import logging
import os
import sys
import time

import msgspec
import pytest
import viser
import websockets

BAD_FRAMES = (
    lambda: os.urandom(5_000_000),  # 5 MB of garbage
    lambda: b"\x91" * 100_000 + b"\xc0",  # msgpack nested 100 000 deep
    lambda: msgspec.msgpack.encode("x" * 20_000_000),  # a 20 MB string
    lambda: msgspec.msgpack.encode({"type": "GuiUpdateMessage", "uuid": "nope", "updates": {"value": "y" * 5_000_000}}),
    lambda: msgspec.msgpack.encode([{"type": "Bogus"}] * 100_000),
)


def rss_mib() -> float:
    for line in open("/proc/self/status"):
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


async def attack(port: int, connections: int) -> None:
    for _ in range(connections):
        with contextlib.suppress(Exception):
            async with websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=[f"viser-v{viser.__version__}"], max_size=None) as ws:
                for frame in BAD_FRAMES:
                    await ws.send(frame())
                await asyncio.sleep(0.2)


@pytest.mark.slow
def test_malformed_frames_cost_no_lasting_memory_and_one_line_per_kind(capfd, monkeypatch):
    from app.args import ViewArgs
    from app.guards.gate import TRIM_SECONDS
    from app.main import start

    # as in a terminal: the server's log to stderr, not into pytest's record keeping (which keeps every record)
    logger = logging.getLogger("websockets")
    monkeypatch.setattr(logger, "propagate", False)
    handler = logging.StreamHandler(sys.stderr)
    logger.addHandler(handler)
    monkeypatch.setattr(logger, "handlers", [handler])

    with contextlib.redirect_stdout(io.StringIO()):
        app = start(ViewArgs(scene="damped", port=0), kernels=False)
    try:
        time.sleep(1.0)
        gc.collect()
        before = rss_mib()
        t0 = app.sync().frame.t
        asyncio.run(attack(app.port, 12))
        time.sleep(1.5 + TRIM_SECONDS)  # disconnects seen, memory handed back by the next trim
        gc.collect()
        grew = rss_mib() - before
        snap = app.sync()
        assert app.loop.is_alive() and snap.frame.t > t0 + 1.0  # the run went on
        assert grew < 20.0, f"the server kept {grew:.0f} MiB after the burst"
    finally:
        app.stop()
    err = capfd.readouterr().err
    said = [line for line in err.splitlines() if "its message did not decode" in line]
    assert "Traceback" not in err and 1 <= len(said) <= len(BAD_FRAMES), err[-2000:]  # a line per kind of mistake, not per message


ISSUE_59 = (
    msgspec.msgpack.encode({"type": "GuiUpdateMessage", "updates": {"value": 1}}),  # no uuid
    msgspec.msgpack.encode({"type": "NoSuchMessage"}),  # an unknown kind
    msgspec.msgpack.encode(5),  # not a mapping
    b"\x91" * 20_000 + b"\x90",  # a list 20 000 deep
)


def test_a_malformed_message_is_one_quiet_line_and_the_run_goes_on(capfd, monkeypatch):
    """The four malformed messages of issue 59, each from a page of its own over viser's protocol: each page's
    connection is closed and the server's log says so in one line per kind (no traceback: the page's mistake), while
    the run goes on."""
    from app.args import ViewArgs
    from app.main import start

    logger = logging.getLogger("websockets")  # as in a terminal (see above)
    monkeypatch.setattr(logger, "propagate", False)
    handler = logging.StreamHandler(sys.stderr)
    monkeypatch.setattr(logger, "handlers", [handler])

    async def send_each(port: int) -> None:
        for message in ISSUE_59:
            with contextlib.suppress(Exception):
                async with websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=[f"viser-v{viser.__version__}"], max_size=None) as ws:
                    await ws.send(message)
                    await asyncio.sleep(0.3)

    with contextlib.redirect_stdout(io.StringIO()):
        app = start(ViewArgs(scene="damped", port=0), kernels=False)
    try:
        t0 = app.sync().frame.t
        asyncio.run(send_each(app.port))
        time.sleep(0.5)
        assert app.loop.is_alive() and app.sync().frame.t > t0
    finally:
        app.stop()
    err = capfd.readouterr().err
    said = [line for line in err.splitlines() if "its message did not decode" in line]
    assert "Traceback" not in err and "UserWarning" not in err, err[-3000:]
    assert [line.split("(")[1].split(":")[0] for line in said] == ["TypeError", "KeyError", "AttributeError", "RecursionError"], said

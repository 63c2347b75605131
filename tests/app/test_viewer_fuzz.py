"""A client that sends malformed or oversized websocket frames is dropped; the server keeps no
lasting memory for it, logs one traceback per kind, and the simulation runs on for the others."""

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
def test_malformed_frames_cost_no_lasting_memory_and_one_traceback_per_kind(capfd, monkeypatch):
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
    assert 1 <= err.count("Traceback") <= 3, err[-2000:]  # one per kind of failure, not one per message

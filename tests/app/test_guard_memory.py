"""The viewer's memory upkeep stays cheap: the heap trim it runs every few seconds finds the C library
once, instead of forking `ldconfig -p` each time (ctypes.util.find_library does that on Linux)."""

import ctypes.util
import subprocess

import pytest


def test_heap_trim_forks_no_process_after_the_first(monkeypatch):
    import app.guards.guard as guard

    guard._libc.cache_clear()
    looked_up, forked = [], []
    real_find, real_popen = ctypes.util.find_library, subprocess.Popen.__init__
    monkeypatch.setattr(ctypes.util, "find_library", lambda name: looked_up.append(name) or real_find(name))

    def popen(self, *args, **kwargs):
        forked.append(args[0] if args else kwargs.get("args"))
        return real_popen(self, *args, **kwargs)

    guard.big_blocks_go_back()
    monkeypatch.setattr(subprocess.Popen, "__init__", popen)
    for _ in range(5):
        guard.release_memory()
    assert looked_up == ["c"] and forked == []
    assert hasattr(guard._libc(), "malloc_trim")  # glibc here: the trim really runs


@pytest.mark.slow
def test_pages_that_come_and_go_leave_nothing_behind():
    """300 pages connect (speaking viser's protocol), get the scene and the address probe, and leave:
    the server keeps no handle of any of them and its memory does not grow with them."""
    import asyncio
    import contextlib
    import gc
    import io
    import time

    import msgspec
    import viser
    import websockets

    from app.args import ViewArgs
    from app.guards.guard import release_memory
    from app.main import start
    from app.tools.page import CAMERA
    from tests.app.test_gui_guard import rss_mib

    camera = msgspec.msgpack.encode(CAMERA)

    async def come_and_go(port: int, n: int) -> None:
        for _ in range(n):
            async with websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=[f"viser-v{viser.__version__}"], max_size=None) as ws:
                await ws.send(camera)
                with contextlib.suppress(asyncio.TimeoutError):
                    for _ in range(4):
                        await asyncio.wait_for(ws.recv(), timeout=0.05)

    def handles() -> int:
        gc.collect()
        return sum(isinstance(o, viser.ClientHandle) for o in gc.get_objects())

    with contextlib.redirect_stdout(io.StringIO()):
        app = start(ViewArgs(scene="damped", port=0), kernels=False)
    try:
        asyncio.run(come_and_go(app.port, 50))  # the first pages warm viser's and the allocator's pools
        time.sleep(1.0)
        release_memory()
        before, seen = rss_mib(), app.connections
        asyncio.run(come_and_go(app.port, 300))
        time.sleep(1.0)
        assert app.connections - seen == 300  # every page counted as a browser: the on-connect path ran for each
        assert handles() == 0 and not app.server.get_clients()
        release_memory()
        assert rss_mib() - before < 8.0  # measured: under 1 MiB per 1000 pages
    finally:
        app.stop()

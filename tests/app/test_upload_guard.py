"""Uploads through viser's own file-transfer protocol (the messages a page sends over the websocket):
bytes are capped as they arrive, a file with too many faces is refused before any parser sees it, the
uploads folder stays bounded, and a mesh that cannot be a body (no volume, too small, a name with a NUL
byte) leaves the running body running, with a note that says why (issue 23, items 3 and 4)."""

from __future__ import annotations

import asyncio
import contextlib
import gc
import io
import math
import os
import time
import uuid

import msgspec
import pytest
import trimesh
import viser
import websockets
from viewer import wait_for

from app.tools.page import CAMERA

PART = 512 * 1024  # what viser's page sends per part
DEGENERATE_OBJ = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 2\n"  # two triangles back to back: closed, no volume


def memory(field: str = "VmRSS") -> float:
    """This process's resident (or, with VmHWM, peak resident) memory, MiB: the server runs in it."""
    for line in open("/proc/self/status"):
        if line.startswith(field + ":"):
            return int(line.split()[1]) / 1024
    return math.nan


def live_memory() -> float:
    """memory() once the garbage is collected and the C library has handed its freed heap back (malloc_trim):
    what is still held, not what the allocator keeps cached after a burst (load-dependent)."""
    from app.guards.guard import release_memory

    gc.collect()
    release_memory()
    return memory()


def reset_peak() -> None:
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")  # VmHWM starts again from VmRSS


def stl(mesh: trimesh.Trimesh) -> bytes:
    return mesh.export(file_type="stl")


@pytest.fixture
def app(tmp_path, monkeypatch, request):
    """A viewer on the damped scene, uploads kept in tmp_path; `strict` (the default) runs the physics
    with floating-point errors raised; `@pytest.mark.parametrize("app", [False], indirect=True)`: as the
    user's viewer runs."""
    from app.args import ViewArgs
    from app.main import start

    monkeypatch.setattr("app.live.upload.UPLOADS", tmp_path / "uploads")
    with contextlib.redirect_stdout(io.StringIO()):
        viewer = start(ViewArgs(scene="damped", port=0), kernels=False, strict=getattr(request, "param", True), publish_hz=20.0)
    yield viewer
    viewer.stop()


async def _drain(ws) -> None:
    with contextlib.suppress(Exception):
        while True:
            await ws.recv()


async def _transfer(app, name: str, size: int, parts: int, chunks, linger: float = 1.0) -> None:
    """One page: declares a transfer of `size` bytes in `parts` parts to the upload button, then sends
    `chunks` (an iterable of bytes) as parts 0, 1, 2, ..., and stays `linger` seconds."""
    port, button = app.port, app.body_file.button._impl.uuid
    async with websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=[f"viser-v{viser.__version__}"], max_size=None,
                                  origin=app.url, compression=None) as ws:  # fmt: skip
        reader = asyncio.ensure_future(_drain(ws))
        transfer = uuid.uuid4().hex
        encode = msgspec.msgpack.encode
        await ws.send(encode(CAMERA))  # viser counts a page as connected from its first camera message
        await ws.send(encode({"type": "FileTransferStartUpload", "source_component_uuid": button, "transfer_uuid": transfer,
                              "filename": name, "mime_type": "", "part_count": parts, "size_bytes": size}))  # fmt: skip
        for i, chunk in enumerate(chunks):
            await ws.send(encode({"type": "FileTransferPart", "source_component_uuid": button, "transfer_uuid": transfer,
                                  "part_index": i, "content": chunk}))  # fmt: skip
        await asyncio.sleep(linger)
        reader.cancel()


def upload(app, name: str, content: bytes) -> None:
    """What viser's page does with a file chosen in the upload button."""
    parts = [content[i : i + PART] for i in range(0, len(content), PART)]
    asyncio.run(_transfer(app, name, len(content), len(parts), parts))


def still_running(app, body_name: str) -> None:
    """The old body is the one running, its frames advance, and no publish failed."""
    t = app.sync().frame.t
    snap = wait_for(app, lambda s: s.frame.t > t + 0.5, what="the run to go on")
    assert snap.body.name == body_name and not snap.settings.paused and math.isfinite(snap.density)
    assert not [key for key in app.loop._errors_logged if key.startswith(("publish", "observe", "advance"))]


@pytest.mark.slow
def test_meshes_that_cannot_be_a_body_leave_the_running_one_running(app, tmp_path):
    body = app.sync().body.name
    cases = [("flat.obj", DEGENERATE_OBJ, "encloses no volume"),
             ("speck.stl", stl(trimesh.creation.box(extents=(1e-9,) * 3)), "too small"),
             ("two.stl", stl(trimesh.util.concatenate([trimesh.creation.box(), trimesh.creation.box().apply_translation((0.5, 0, 0))])),
              "2 separate closed surfaces")]  # fmt: skip
    for name, content, reason in cases:
        upload(app, name, content)
        snap = wait_for(app, lambda s, r=reason: r in s.notice, what=f"the note on {name}")
        assert "Mesh not loaded" in snap.notice and "unchanged" in snap.notice and "not watertight" not in snap.notice
        still_running(app, body)
    # a name with a NUL byte and a terminal escape: loaded, named without them, no traceback
    upload(app, "cr\x00ate\x1b[2J.stl", stl(trimesh.creation.box(extents=(0.8, 0.6, 0.5))))
    snap = wait_for(app, lambda s: s.body.name.startswith("cr_ate"), what="the box with the odd name")
    assert "Loaded cr_ate" in snap.notice and "\x00" not in snap.notice and "\x1b" not in snap.notice
    kept = [p.name for p in (tmp_path / "uploads").iterdir()]
    assert len(kept) == 1 and kept[0].startswith("cr_ate") and kept[0].isprintable()  # kept under a clean name
    still_running(app, snap.body.name)


@pytest.mark.parametrize("app", [True, False], indirect=True, ids=["strict", "as-served"])
def test_a_body_the_loop_cannot_build_never_replaces_the_running_one(app, monkeypatch):
    """With the file checks switched off, the zero-volume mesh reaches the simulation thread (as it did
    before this fix, when the body was swapped before the failure and every publish then raised
    ZeroDivisionError): the new simulation fails while it is built, and the running one goes on."""
    import sim.bodies.body

    monkeypatch.setattr(sim.bodies.body, "check_closed", lambda mesh, name: None)
    monkeypatch.setattr(sim.bodies.body, "check_body", lambda body: body)
    body = app.sync().body.name
    upload(app, "flat.obj", DEGENERATE_OBJ)
    snap = wait_for(app, lambda s: "Mesh not loaded" in s.notice, what="the loop's refusal")
    assert "unchanged" in snap.notice
    still_running(app, body)


@pytest.mark.slow
def test_a_transfer_declaring_480_mib_is_refused_before_its_bytes_are_kept(app):
    body = app.sync().body.name
    chunk = os.urandom(PART)
    time.sleep(1.0)
    before = live_memory()
    sent = 256  # 128 MiB of the 480 MiB declared, as 512 KiB parts
    asyncio.run(_transfer(app, "huge.stl", 480 * 2**20, 10**6, (chunk for _ in range(sent))))
    snap = wait_for(app, lambda s: "Upload refused" in s.notice, what="the refusal")
    assert "503 MB, more than 50 MB" in snap.notice and app.uploads.refused >= 1
    assert not app.server.gui._current_file_upload_states  # nothing kept of it
    # the bounds are far below what keeping the bytes would cost (128 MiB, then 48 MiB), and far above
    # what the running viewer's own buffers may add meanwhile (a few MiB, load-dependent)
    assert live_memory() - before < 40.0
    # a transfer that declares 1 MB and sends 8 MiB parts is dropped at its first excess part
    before = live_memory()
    asyncio.run(_transfer(app, "liar.stl", 2**20, 2, (os.urandom(8 * 2**20) for _ in range(6))))
    snap = wait_for(app, lambda s: "more bytes arrived than it declared" in s.notice, what="the liar's refusal")
    assert not app.server.gui._current_file_upload_states
    assert live_memory() - before < 24.0
    still_running(app, body)


def test_an_obj_with_too_many_faces_is_refused_before_it_is_parsed(app):
    faces = 1_500_000
    content = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n" + b"f 1 2 3\n" * faces  # 12 MB
    time.sleep(1.0)
    gc.collect()
    reset_peak()
    before = memory()
    upload(app, "dense.obj", content)
    snap = wait_for(app, lambda s: "1,500,000 faces" in s.notice, what="the refusal")
    assert "Mesh not loaded" in snap.notice
    peak = memory("VmHWM") - before
    assert peak < 80.0, f"peak +{peak:.0f} MiB: parsed?"  # the file itself is 12 MB (kept in parts, then joined)


def test_the_uploads_folder_is_bounded_and_keeps_the_running_body(tmp_path, monkeypatch):
    """Thirty old uploads and the running body's file (the oldest of all) in the folder: one more
    upload leaves at most KEPT_FILES files, removing the oldest first, never the running body's."""
    import app.live.upload

    folder = tmp_path / "uploads"
    folder.mkdir()
    running = folder / "running-000000000000.stl"
    running.write_bytes(stl(trimesh.creation.box(extents=(0.8, 0.6, 0.5))))
    os.utime(running, (1e9, 1e9))
    for i in range(30):
        old = folder / f"old{i:02d}-{i:012d}.stl"
        old.write_bytes(b"x" * 1000)
        os.utime(old, (2e9 + i, 2e9 + i))
    viewer = None
    try:
        from app.args import ViewArgs
        from app.main import start

        monkeypatch.setattr("app.live.upload.UPLOADS", folder)
        with contextlib.redirect_stdout(io.StringIO()):
            viewer = start(ViewArgs(scene="damped", port=0, mesh=str(running)), kernels=False, strict=True, publish_hz=20.0)
        wait_for(viewer, lambda s: s.body.name.startswith("running"), what="the running mesh")
        upload(viewer, "crate.stl", stl(trimesh.creation.box(extents=(0.7, 0.6, 0.5))))
        wait_for(viewer, lambda s: s.body.name.startswith("crate"), what="the upload")
        left = sorted(p.name for p in folder.iterdir())
        assert len(left) == app.live.upload.KEPT_FILES and running.name in left and any(n.startswith("crate") for n in left)
        assert [n for n in left if n.startswith("old")] == [f"old{i:02d}-{i:012d}.stl" for i in range(12, 30)]  # the newest 18
    finally:
        if viewer is not None:
            viewer.stop()
    # and by size: the folder's bytes, newest first, within KEPT_BYTES
    assert app.live.upload.prune_uploads(folder, {running}, size=10_000) and sum(p.stat().st_size for p in folder.iterdir()) <= 10_000
    assert running.exists()

"""Hostile-user campaign (not a unit test): attack a running viewer as a hostile page would, through
viser's own websocket protocol, and count what got through.

    python -m app.hostile --rounds 5 --seed 0

Each round sends fuzzed control updates (from a page that never sent a camera message and from one
that did), share-tunnel requests, connections from a foreign Origin, damaged and oversized uploads,
share links with repeated and refused keys, and connect/leave cycles; then it checks the viewer as a
user would: a fresh page receives the scene, density and Pause still drive the run, every control
shows what the run uses. The summary counts messages, tracebacks, lockouts, mismatched controls,
tunnels opened, foreign connections accepted, bodies broken, restarts by refused links and RSS growth.
"""

from __future__ import annotations

import asyncio
import contextlib
import io
import logging
import math
import random
import sys
import threading
import time
from dataclasses import dataclass, field

import msgspec
import tyro
import viser
import websockets

CAMERA = {"type": "ViewerCameraMessage", "wxyz": (1.0, 0.0, 0.0, 0.0), "position": (3.0, 3.0, 3.0), "fov": 1.0, "near": 0.01,
          "far": 100.0, "image_height": 600, "image_width": 800, "look_at": (0.0, 0.0, 0.0), "up_direction": (0.0, 0.0, 1.0)}  # fmt: skip
BAD_VALUES = (1e11, -1.0, 1e300, math.inf, math.nan, True, None, "../../etc/passwd", "x" * 10_000, [1.0], [math.nan, 0.0, 0.0], {"a": 1})
BAD_UPDATES = ({"disabled": True}, {"visible": False}, {"label": "pwned"}, {"min": 1e9}, {})
MESHES = {
    "flat.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 2\n",  # closed, zero volume
    "tiny.obj": b"".join(f"v {x * 1e-9} {y * 1e-9} {z * 1e-9}\n".encode() for x in (0, 1) for y in (0, 1) for z in (0, 1))
    + b"f 1 3 2\nf 2 3 4\nf 5 6 7\nf 6 8 7\nf 1 2 5\nf 2 6 5\nf 3 7 4\nf 4 7 8\nf 1 5 3\nf 3 5 7\nf 2 4 6\nf 4 8 6\n",
    "nul\x00name.obj": b"v 0 0 0\n",
    "garbage.stl": bytes(range(256)) * 40,
}
LINKS = ("?density=500&density=600", "?damping=1e300")
REFUSED_LINKS = ("?density=abc", "?scene=../../etc/passwd", "?nope=1", "?integrator=evil")
"""Links none of whose values is taken: they must not restart the run."""


def rss_mib() -> float:
    for line in open("/proc/self/status"):
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return math.nan


@dataclass
class HostileArgs:
    """Attack a viewer in this process through viser's protocol and report what got through."""

    rounds: int = 5
    updates: int = 300
    """Fuzzed control updates per round."""
    connections: int = 100
    """Pages that connect and leave per round."""
    seed: int = 0
    scene: str = "damped"


@dataclass
class Tally:
    messages: int = 0
    connections: int = 0
    uploads: int = 0
    uploads_refused_with_a_note: int = 0
    links: int = 0
    lockouts: int = 0
    mismatched: int = 0
    tunnels: int = 0
    foreign_accepted: int = 0
    broken_bodies: int = 0
    restarts_by_refused_links: int = 0
    tracebacks: int = 0
    notes: list[str] = field(default_factory=list)


class _Counter(io.TextIOBase):
    """stderr that counts the tracebacks written to it (threads' and the thread pool's included)."""

    def __init__(self, out):
        self.out, self.count = out, 0

    def write(self, text: str) -> int:
        self.count += text.count("Traceback (most recent call last)")
        return self.out.write(text)


async def _page(port: int, frames: list[bytes], camera: bool = True, origin: str | None = None, linger: float = 0.1) -> bool:
    """One page: connect (with `origin`), say hello, send `frames`; False when the server refused it."""
    try:
        async with websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=[f"viser-v{viser.__version__}"], max_size=None,
                                      origin=origin) as ws:  # fmt: skip
            if camera:
                await ws.send(msgspec.msgpack.encode(CAMERA))
            for frame in frames:
                await ws.send(frame)
            with contextlib.suppress(asyncio.TimeoutError):
                await asyncio.wait_for(ws.recv(), timeout=linger)
            await asyncio.sleep(linger)
        return True
    except (OSError, websockets.exceptions.WebSocketException):
        return False


def _fuzz(app, rng: random.Random, n: int) -> list[bytes]:
    handles = app.server.gui._gui_input_handle_from_uuid
    uuids = list(handles)
    out = []
    for _ in range(n):
        uuid = rng.choice(uuids)
        current = handles[uuid].value
        if rng.random() < 0.3 and isinstance(current, (int, float)) and not isinstance(current, bool):
            updates = {"value": type(current)(current * rng.choice((0.5, 2.0, 1e3)))}  # in type, maybe out of range
        elif rng.random() < 0.8:
            updates = {"value": rng.choice(BAD_VALUES)}
        else:
            updates = rng.choice(BAD_UPDATES)
        out.append(msgspec.msgpack.encode({"type": "GuiUpdateMessage", "uuid": uuid, "updates": updates}))
    return out


def _upload(button_uuid: str, name: str, content: bytes, declared: int | None = None, parts: int | None = None) -> list[bytes]:
    transfer = f"t{random.random()}"
    chunk = 1 << 20
    pieces = [content[i : i + chunk] for i in range(0, len(content), chunk)] or [b""]
    start = {"type": "FileTransferStartUpload", "source_component_uuid": button_uuid, "transfer_uuid": transfer, "filename": name,
             "mime_type": "", "part_count": parts or len(pieces), "size_bytes": declared or len(content)}  # fmt: skip
    return [msgspec.msgpack.encode(start)] + [
        msgspec.msgpack.encode(
            {"type": "FileTransferPart", "source_component_uuid": button_uuid, "transfer_uuid": transfer, "part_index": i, "content": p}
        )  # fmt: skip
        for i, p in enumerate(pieces)
    ]


def _mismatches(app) -> list[str]:
    """Controls whose shown value is not the one the run uses."""
    from .loop import CONTROLLED

    snap = app.sync()
    wrong = []
    for key in CONTROLLED:
        shown, used = getattr(app.controls, key).value, snap.settings.value(key)
        same = shown == used if isinstance(used, (str, bool)) else all(math.isclose(a, b, rel_tol=1e-6, abs_tol=1e-12) for a, b in
                                                                      zip(*(v if isinstance(v, tuple) else (v,) for v in (shown, used))))  # fmt: skip
        if not same:
            wrong.append(f"{key}: shows {shown!r:.40}, runs {used!r:.40}")
    return wrong


def _still_works(app) -> bool:
    """What a user checks: a new page gets the scene, density and Pause drive the run, time goes on."""
    t0 = app.sync().frame.t
    density = app.controls.density.value
    app.controls.density.value = 321.0
    ok = app.sync().density == 321.0
    app.controls.density.value = density
    app.controls.paused.value = True
    ok &= app.sync().settings.paused
    app.controls.paused.value = False
    time.sleep(0.5)
    ok &= not app.sync().settings.paused and app.sync().frame.t > t0
    return bool(ok and asyncio.run(_page(app.port, [], linger=0.3)))


def _round(app, rng: random.Random, args: HostileArgs, tally: Tally) -> None:
    frames = _fuzz(app, rng, args.updates)
    half = len(frames) // 2
    asyncio.run(_page(app.port, frames[:half], camera=False))  # never sent a camera message
    asyncio.run(_page(app.port, frames[half:]))
    tally.messages += len(frames)
    time.sleep(0.5)
    wrong = _mismatches(app)
    tally.mismatched += len(wrong)
    tally.notes += wrong[:2]

    share = [msgspec.msgpack.encode({"type": "ShareUrlRequest"}), msgspec.msgpack.encode({"type": "ShareUrlDisconnect"})]
    asyncio.run(_page(app.port, share[:1]))
    tally.messages += 1
    time.sleep(0.3)
    tally.tunnels += getattr(app.server, "_share_tunnel", None) is not None
    tally.foreign_accepted += asyncio.run(_page(app.port, [], origin="http://evil.example"))

    button = app.body_file.button._impl.uuid
    body = app.sync().body
    for name, content in MESHES.items():
        asyncio.run(_page(app.port, _upload(button, name, content), linger=0.5))
        tally.uploads += 1
    asyncio.run(_page(app.port, _upload(button, "huge.stl", b"\0" * (8 << 20), declared=480 << 20, parts=10**6)))
    tally.uploads += 1
    time.sleep(1.0)
    snap = app.sync()
    tally.broken_bodies += snap.body is not body or not snap.body.volume > 0 or not math.isfinite(snap.frame.E_total)

    for query in LINKS + REFUSED_LINKS:
        restarted = _open_link(app, query)
        tally.links += 1
        tally.restarts_by_refused_links += query in REFUSED_LINKS and restarted

    for _ in range(args.connections):
        asyncio.run(_page(app.port, [], linger=0.02))
    tally.connections += args.connections
    try:
        tally.lockouts += not _still_works(app)
    except Exception as e:  # noqa: BLE001 -- a viewer the campaign broke: that is the finding
        tally.lockouts += 1
        tally.notes.append(f"check failed: {type(e).__name__}: {e}")


def _open_link(app, query: str) -> bool:
    """A page whose address is `query` (it answers the viewer's address probe over the protocol) while another
    page watches (the first page to connect restarts the run by design); whether the watched run restarted."""

    async def visit() -> bool:
        async with websockets.connect(f"ws://127.0.0.1:{app.port}", subprotocols=[f"viser-v{viser.__version__}"], max_size=None) as watcher:
            await watcher.send(msgspec.msgpack.encode(CAMERA))
            await asyncio.sleep(0.3)
            epoch, t0 = app.sync().epoch, app.sync().frame.t
            await _visit(app, query)
            snap = app.sync()
            return snap.epoch != epoch or snap.frame.t < t0

    return asyncio.run(visit())


async def _visit(app, query: str) -> None:
    async with websockets.connect(f"ws://127.0.0.1:{app.port}", subprotocols=[f"viser-v{viser.__version__}"], max_size=None) as ws:
        await ws.send(msgspec.msgpack.encode(CAMERA))
        probe = None
        for _ in range(40):
            await asyncio.sleep(0.05)
            newest = app.server.get_clients().get(max(app.server.get_clients(), default=-1))  # this page, not the watcher
            probe = newest and next((u for u, h in newest.gui._gui_input_handle_from_uuid.items()
                                     if getattr(h._impl.props, "label", "") == "floatsim-address"), None)  # fmt: skip
            if probe:
                break
        if probe:
            await ws.send(msgspec.msgpack.encode({"type": "GuiUpdateMessage", "uuid": probe, "updates": {"value": query}}))
            await asyncio.sleep(0.3)


def main(args: HostileArgs) -> int:
    from .args import ViewArgs
    from .guard import release_memory
    from .main import start

    counter = _Counter(sys.stderr)
    sys.stderr = counter
    logged = []
    handler = logging.Handler()
    handler.emit = lambda record: logged.append(record) if record.exc_info or record.exc_text else None
    logging.getLogger().addHandler(handler)
    threading.excepthook = lambda hook_args: logged.append(hook_args)
    with contextlib.redirect_stdout(io.StringIO()):
        app = start(ViewArgs(scene=args.scene, port=0))
    rng, tally = random.Random(args.seed), Tally()
    show_error = app.body_file._show_error

    def refused(text, client=None):  # counts the notes a refused upload gets (they go on to the page as usual)
        tally.uploads_refused_with_a_note += 1
        show_error(text, client)

    app.body_file._show_error = refused
    try:
        time.sleep(2.0)
        release_memory()
        before = rss_mib()
        for k in range(args.rounds):
            _round(app, rng, args, tally)
            print(f"round {k + 1}/{args.rounds}: RSS {rss_mib():.1f} MiB, lockouts {tally.lockouts}, mismatched {tally.mismatched}",
                  file=sys.__stderr__, flush=True)  # fmt: skip
        app.loop.post("scene", args.scene)  # back to the setup measured before: what stays is what was retained
        app.sync()
        time.sleep(1.0)
        release_memory()
        grew = rss_mib() - before
    finally:
        app.stop()
    tally.tracebacks = counter.count + len(logged)
    print("\n".join(f"{k:>26}: {v}" for k, v in vars(tally).items() if k != "notes"))
    print(f"{'RSS growth':>26}: {grew:+.1f} MiB")
    for note in tally.notes[:10]:
        print("  note:", note)
    bad = tally.lockouts + tally.mismatched + tally.tunnels + tally.foreign_accepted + tally.broken_bodies + tally.restarts_by_refused_links
    return 1 if bad or tally.tracebacks else 0


if __name__ == "__main__":
    raise SystemExit(main(tyro.cli(HostileArgs)))

"""Hostile-user campaign (not a unit test): attack a running viewer, one body or several, as a hostile page
would, through viser's own websocket protocol, and count what got through.

    python -m app.tools.hostile --rounds 5 --scene rm3

Each round sends fuzzed control updates (wrong types, numbers past msgpack's range, nested values, other
properties than the value; from a page that never sent a camera message and from one that did), file
transfers aimed at every control and at the page's own address probe, share-tunnel requests, connections
from a foreign Origin, damaged and oversized meshes to the upload button (where the viewer has one), share
links with repeated and refused keys, and connect/leave cycles; then it checks the viewer as a user would:
Pause and Speed (and damping, with one body) still drive the run from the server and from a page, time
goes on, a new page is let in and receives the scene, and every control shows what the run uses, on the
server and on that new page; a check that fails is made again 2 s later, and a lockout is one that fails both times
(one that passes then is a slow machine, counted apart and not as bad), each named in a note. The summary counts
messages, lockouts, mismatched controls (server, new page),
tunnels opened, foreign connections accepted, bytes held for refused transfers, pages refused, bodies
broken, restarts by refused links and tracebacks, with RSS after each round.
"""

from __future__ import annotations

import asyncio
import contextlib
import gc
import io
import logging
import math
import os
import random
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field

import msgspec
import tyro
import viser
import websockets

from app.args import ViewArgs
from app.guards.guard import release_memory
from app.live.loop import CONTROLLED
from app.main import start
from app.tools.page import CAMERA, PROBE, Page

HUGE = (2**63, -(2**63), 2**64 - 1, 10**18 + 1)
"""Whole numbers msgpack carries that no control takes (the first three are its limits)."""
NESTED = ([[[[1.0]]]], {"a": {"b": [1, {"c": 1e300}]}}, [{"value": 1}] * 3, [2**64 - 1, 0, 0])
BAD_VALUES = (1e11, -1.0, 1e300, math.inf, math.nan, True, None, "../../etc/passwd", "x" * 10_000, [1.0], [math.nan, 0.0, 0.0], {"a": 1})
BAD_VALUES += HUGE + NESTED
BAD_UPDATES = ({"disabled": True}, {"visible": False}, {"label": "pwned"}, {"min": 1e9}, {}, {"removed": True}, {"update_cb": []},
               {"update_cb": 5}, {"value": 1.0, "max": 2**64 - 1})  # fmt: skip
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
    """Any preset, one body or several."""
    kernels: bool = False
    """Compile and load the scene's fast kernels as the viewer does for a user (slower to start; the gate is the same)."""


@dataclass
class Tally:
    messages: int = 0
    connections: int = 0
    transfers_at_controls: int = 0
    held_for_refused_transfers_mib: float = 0.0
    uploads: int = 0
    uploads_refused_with_a_note: int = 0
    links: int = 0
    lockouts: int = 0
    slow_checks: int = 0
    """User checks that failed and passed on a retry 2 s later (a loaded machine, not a lockout: not counted bad)."""
    mismatched: int = 0
    mismatched_on_a_new_page: int = 0
    pages_refused: int = 0
    tunnels: int = 0
    foreign_accepted: int = 0
    broken_bodies: int = 0
    restarts_by_refused_links: int = 0
    tracebacks: int = 0
    notes: list[str] = field(default_factory=list)

    def bad(self) -> int:
        return (self.lockouts + self.mismatched + self.mismatched_on_a_new_page + self.pages_refused + self.tunnels + self.foreign_accepted
                + self.broken_bodies + self.restarts_by_refused_links + self.tracebacks + (self.held_for_refused_transfers_mib > 1.0))  # fmt: skip


class _Counter(io.TextIOBase):
    """stderr that counts the tracebacks written to it (threads' and the thread pool's included)."""

    def __init__(self, out):
        self.out, self.count = out, 0

    def write(self, text: str) -> int:
        self.count += text.count("Traceback (most recent call last)")
        return self.out.write(text)


def _encode(message: dict) -> bytes:
    return msgspec.msgpack.encode(message)


async def _page(port: int, frames: list[bytes], camera: bool = True, origin: str | None = None, linger: float = 0.1) -> bool:
    """One page: connect (with `origin`), say hello, send `frames`; False when the server refused it."""
    try:
        async with websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=[f"viser-v{viser.__version__}"], max_size=None,
                                      origin=origin) as ws:  # fmt: skip
            if camera:
                await ws.send(_encode(CAMERA))
            for frame in frames:
                await ws.send(frame)
            with contextlib.suppress(asyncio.TimeoutError):
                await asyncio.wait_for(ws.recv(), timeout=linger)
            await asyncio.sleep(linger)
        return True
    except (OSError, websockets.exceptions.WebSocketException):
        return False


# ---- what the viewer has, one body or several


def _fields(app) -> dict[str, object]:
    """The controls a user sets, by the field the run keeps its value under."""

    keys = (*CONTROLLED, "speed", "paused")
    return {key: getattr(app.controls, key) for key in keys}


def _used(app, snap, key: str):
    return snap.settings.paused if key == "paused" else snap.settings.value(key)


def _same(shown, used) -> bool:
    if isinstance(used, (str, bool)) or isinstance(shown, (str, bool)):
        return shown == used
    shown, used = (v if isinstance(v, (tuple, list)) else (v,) for v in (shown, used))
    try:
        return len(shown) == len(used) and all(math.isclose(a, b, rel_tol=1e-6, abs_tol=1e-12) for a, b in zip(shown, used))
    except TypeError:  # not numbers at all (a file where a number belongs)
        return False


def _mismatches(app) -> list[str]:
    """Controls whose shown value (the server's handle) is not the one the run uses."""
    snap = app.sync()
    return [f"{key}: shows {h.value!r:.40}, runs {_used(app, snap, key)!r:.40}" for key, h in _fields(app).items()
            if not _same(h.value, _used(app, snap, key))]  # fmt: skip


async def _newcomer(app) -> tuple[bool, list[str]]:
    """A new page: whether it was let in and received the scene, and the controls it is shown with a value the run does not use."""
    try:
        async with Page.open(app.port) as page:
            await page.camera()
            labels = {h.label: key for key, h in _fields(app).items()}
            await page.read(3.0, until=lambda p: labels.keys() <= p.controls.keys() and p.nodes)
            await page.read(0.3)
            snap = app.sync()
            wrong = [f"new page: {label}: shows {page.value(label)!r:.40}, runs {_used(app, snap, key)!r:.40}"
                     for label, key in labels.items() if label in page.controls and not _same(page.value(label), _used(app, snap, key))]  # fmt: skip
            return bool(page.nodes) and labels.keys() <= page.controls.keys(), wrong
    except (OSError, websockets.exceptions.WebSocketException) as e:
        return False, [f"new page refused: {type(e).__name__}: {e}"]


def _paused(app) -> bool:
    snap = app.sync()
    return snap.settings.paused


def _still_works(app) -> list[str]:
    """What a user checks, the checks that fail (none: all pass): damping (with one body), Pause from the server and
    from a page and Speed drive the run; time goes on."""
    c = app.controls
    failed = []
    damping = c.damping.value  # (a density would need a new boundary-element solve where the body radiates, refused live)
    c.damping.value = 32.1
    if app.sync().damping != 32.1:
        failed.append("damping set from the server")
    c.damping.value = damping
    c.speed.value = 1.0
    c.paused.value = True
    if not _paused(app):
        failed.append("Pause from the server")
    c.paused.value = False
    if _paused(app):
        failed.append("unpause from the server")

    async def from_a_page() -> bool:
        async with Page.open(app.port) as page:
            await page.read(2.0, until=lambda p: "Pause" in p.controls)
            await page.camera()
            await page.read(0.5)
            await page.update("Pause", True)
            await page.read(0.5)
            paused = _paused(app)
            await page.update("Pause", False)
            await page.read(0.5)
            return paused and not _paused(app)

    if not asyncio.run(from_a_page()):
        failed.append("Pause and unpause from a new page")
    t0 = app.sync().frame.t
    time.sleep(0.5)
    if not app.sync().frame.t > t0:
        failed.append("time going on")
    return failed


def _lockout(app, tally: Tally) -> None:
    """The user's checks, and where some fail, again 2 s later: a slow machine catches up (noted, not counted), a
    lockout does not (counted, with the checks that failed both times)."""
    failed = _still_works(app)
    if not failed:
        return
    time.sleep(2.0)
    again = _still_works(app)
    if again:
        tally.lockouts += 1
        tally.notes.append(f"lockout: {', '.join(again)} failed, and again 2 s later")
    else:
        tally.slow_checks += 1
        tally.notes.append(f"slow, not locked out: {', '.join(failed)} failed, then passed 2 s later")


# ---- the attacks


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
        out.append(_encode({"type": "GuiUpdateMessage", "uuid": uuid, "updates": updates}))
    return out


def _upload(target: str, name: str, content: bytes, declared: int | None = None, parts: int | None = None) -> list[bytes]:
    """A file transfer to the control `target`, as a page sends it (1 MiB parts)."""
    transfer = f"t{random.random()}"
    chunk = 1 << 20
    pieces = [content[i : i + chunk] for i in range(0, len(content), chunk)]
    start = {"type": "FileTransferStartUpload", "source_component_uuid": target, "transfer_uuid": transfer, "filename": name,
             "mime_type": "", "part_count": len(pieces) if parts is None else parts, "size_bytes": len(content) if declared is None else declared}  # fmt: skip
    return [_encode(start)] + [
        _encode({"type": "FileTransferPart", "source_component_uuid": target, "transfer_uuid": transfer, "part_index": i, "content": p})
        for i, p in enumerate(pieces)
    ]


def _held(app) -> int:
    """Bytes viser holds from file transfers, the server's and every page's own: unfinished ones' parts and finished
    ones' files left on a control."""
    apis = [app.server.gui] + [client.gui for client in app.server.get_clients().values()]
    parts = sum(sum(len(p) for p in state["parts"].values()) for api in apis for state in list(api._current_file_upload_states.values()))
    files = sum(len(h.value.content) for api in apis for h in list(api._gui_input_handle_from_uuid.values())
                if isinstance(h.value, viser.UploadedFile))  # fmt: skip
    return parts + files


def _transfers_at_controls(app, tally: Tally) -> None:
    """File transfers aimed at every control that takes no file (an empty one finishes at once; a small one in one part),
    and 8 of a declared 16 MiB aimed at the page's own address probe: all refused before a byte is kept."""
    targets = [uuid for uuid, h in app.server.gui._gui_input_handle_from_uuid.items() if not isinstance(h, viser.GuiUploadButtonHandle)]
    frames = [f for uuid in targets for f in _upload(uuid, "x.obj", b"") + _upload(uuid, "y.obj", b"v 0 0 0\n")]
    asyncio.run(_page(app.port, frames, linger=0.3))
    tally.transfers_at_controls += 2 * len(targets)
    tally.messages += len(frames)

    async def at_the_probe() -> int:
        async with Page.open(app.port) as page:
            await page.camera()
            await page.read(5.0, until=lambda p: PROBE in p.controls)
            if PROBE not in page.controls:
                return 0
            for frame in _upload(page.control(PROBE)["uuid"], "z.stl", b"\0" * (8 << 20), declared=16 << 20, parts=16):
                await page.ws.send(frame)  # half of what it declared: an unfinished transfer, kept while the page stays
            await page.read(1.0)
            return _held(app)  # while the page is still here

    held = asyncio.run(at_the_probe())
    tally.transfers_at_controls += 1
    tally.held_for_refused_transfers_mib = max(tally.held_for_refused_transfers_mib, held / 2**20)


def _round(app, rng: random.Random, args: HostileArgs, tally: Tally) -> None:
    frames = _fuzz(app, rng, args.updates)
    half = len(frames) // 2
    asyncio.run(_page(app.port, frames[:half], camera=False))  # never sent a camera message
    asyncio.run(
        _page(app.port, frames[half:] + [_encode({"type": "GuiUpdateMessage", "uuid": "x", "updates": {"value": "y" * (20 << 20)}})])
    )
    tally.messages += len(frames) + 1
    _transfers_at_controls(app, tally)
    time.sleep(0.5)
    wrong = _mismatches(app)
    tally.mismatched += len(wrong)
    tally.notes += wrong[:2]

    share = [_encode({"type": "ShareUrlRequest"}), _encode({"type": "ShareUrlDisconnect"})]
    asyncio.run(_page(app.port, share[:1]))
    tally.messages += 1
    time.sleep(0.3)
    tally.tunnels += getattr(app.server, "_share_tunnel", None) is not None
    tally.foreign_accepted += asyncio.run(_page(app.port, [], origin="http://evil.example"))

    _meshes(app, tally)
    for query in LINKS + REFUSED_LINKS:
        restarted = _open_link(app, query)
        tally.links += 1
        tally.restarts_by_refused_links += query in REFUSED_LINKS and restarted

    for _ in range(args.connections):
        tally.pages_refused += not asyncio.run(_page(app.port, [], linger=0.02))
    tally.connections += args.connections
    try:
        _lockout(app, tally)
        let_in, wrong = asyncio.run(_newcomer(app))
        tally.pages_refused += not let_in
        tally.mismatched_on_a_new_page += len(wrong)
        tally.notes += wrong[:2]
    except Exception as e:  # noqa: BLE001 -- a viewer the campaign broke: that is the finding
        tally.lockouts += 1
        tally.notes.append(f"check failed: {type(e).__name__}: {e}")


def _meshes(app, tally: Tally) -> None:
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


def _open_link(app, query: str) -> bool:
    """A page whose address is `query` (it answers the viewer's address probe over the protocol) while another
    page watches (the first page to connect restarts a one-body run by design); whether the watched run restarted."""

    async def visit() -> bool:
        async with Page.open(app.port) as watcher:
            await watcher.camera()
            await watcher.read(0.3)
            epoch, t0 = app.sync().epoch, app.sync().frame.t
            async with Page.open(app.port) as page:
                await page.camera()
                await page.give_address(query)
                await page.read(0.3)
            snap = app.sync()
            return snap.epoch != epoch or snap.frame.t < t0

    return asyncio.run(visit())


def main(args: HostileArgs) -> int:

    counter = _Counter(sys.stderr)
    sys.stderr = counter
    logged = []
    handler = logging.Handler()
    handler.emit = lambda record: logged.append(record) if record.exc_info or record.exc_text else None
    logging.getLogger().addHandler(handler)
    threading.excepthook = lambda hook_args: logged.append(hook_args)
    scene = os.path.abspath(args.scene) if os.path.exists(args.scene) else args.scene  # a scene file named from here
    scratch = tempfile.TemporaryDirectory(prefix="floatsim-hostile-")
    os.chdir(scratch.name)  # the fuzz presses Record and Export video too: their files go here, and with it
    with contextlib.redirect_stdout(io.StringIO()):
        app = start(ViewArgs(scene=scene, port=0), kernels=args.kernels)
    rng, tally = random.Random(args.seed), Tally()
    show_error = app.body_file._show_error

    def refused(text, client=None):  # counts the notes a refused upload gets (they go on to the page as usual)
        tally.uploads_refused_with_a_note += 1
        show_error(text, client)

    app.body_file._show_error = refused
    growth = []
    try:
        time.sleep(2.0)
        gc.collect()
        release_memory()
        before = rss_mib()
        for k in range(args.rounds):
            _round(app, rng, args, tally)
            app.loop.post("scene", scene)  # back to the setup measured before: what stays is what was retained
            app.sync()
            gc.collect()  # what is still held, not garbage awaiting collection
            release_memory()
            growth.append(rss_mib() - before)
            print(f"round {k + 1}/{args.rounds}: RSS {growth[-1]:+.1f} MiB since the start, lockouts {tally.lockouts}, "
                  f"mismatched {tally.mismatched + tally.mismatched_on_a_new_page}", file=sys.__stderr__, flush=True)  # fmt: skip
    finally:
        app.stop()
        scratch.cleanup()
    tally.tracebacks = counter.count + len(logged)
    print(f"{'scene':>32}: {args.scene}")
    print("\n".join(f"{k:>32}: {v:.1f}" if isinstance(v, float) else f"{k:>32}: {v}" for k, v in vars(tally).items() if k != "notes"))
    print(f"{'RSS growth per round (MiB)':>32}: " + ", ".join(f"{b - a:+.1f}" for a, b in zip([0.0] + growth, growth)))
    print(f"{'RSS after each round (MiB)':>32}: " + ", ".join(f"{g:+.1f}" for g in growth) + " (from the start)")
    first = [n for n in tally.notes if n.startswith(("lockout", "slow"))]  # which checks failed: always shown
    for note in first + [n for n in tally.notes if n not in first][:10]:
        print("  note:", note)
    return 1 if tally.bad() else 0


if __name__ == "__main__":
    raise SystemExit(main(tyro.cli(HostileArgs)))

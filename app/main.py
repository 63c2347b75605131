"""Start the viewer: a viser server, the GUI, the scene and the simulation thread. `start` returns at once (tests), `serve` blocks until Ctrl-C."""

from __future__ import annotations

import signal
import socket
import sys
import threading

import viser

from sim.config import ConfigError, available_scenes, load_scene

from .args import ViewArgs
from .controls import Controls, Layers
from .loop import SimLoop, Snapshot
from .readouts import Readouts
from .scene import SceneView


class ViewerApp:
    """A running viewer. GUI and scene are server-global: every browser tab shows and drives the same run."""

    def __init__(self, server: viser.ViserServer, loop: SimLoop, host: str):
        self.server = server
        self.loop = loop
        self.port = server.get_port()
        shown = "localhost" if host in ("0.0.0.0", "::", "") else (f"[{host}]" if ":" in host else host)
        self.url = f"http://{shown}:{self.port}"
        server.gui.configure_theme(control_width="large", show_share_button=False)
        snap = loop.latest()
        self.controls = Controls(server, loop.post, snap.settings, loop.scene_options)
        self.layers = Layers(server)
        self.readouts = Readouts(server)
        self.scene = SceneView(server, self.layers, snap.body, waves=not snap.water.is_still)
        self._notice_id = snap.notice_id
        loop.attach(self._publish, self.controls.show_setting)
        loop.start()

    def latest(self) -> Snapshot:
        """The last published snapshot: frame, settings (density, damping, ...), body, notice. Thread-safe."""
        return self.loop.latest()

    def sync(self, timeout: float = 10.0) -> Snapshot:
        """Wait until the simulation thread applied every command posted so far; a fresh snapshot."""
        return self.loop.sync(timeout)

    def stop(self) -> None:
        self.loop.stop()
        self.server.stop()

    def _publish(self, snap: Snapshot) -> None:
        """Runs on the simulation thread, about 30 times a second. One atomic block: the clients apply the
        frame at once, and viser's event loop is woken once per frame rather than once per message."""
        with self.server.atomic():
            self.scene.show(snap)
            self.readouts.update(snap)
            fresh = snap.notice_id != self._notice_id and snap.notice
            if fresh or (not snap.notice and self.controls.notice.visible):
                self.controls.show_notice(snap.notice)
        if snap.notice_id != self._notice_id:
            self._notice_id = snap.notice_id
            if fresh:
                for client in self.server.get_clients().values():
                    client.add_notification("floatsim", snap.notice, color="red" if snap.diverged else "yellow", auto_close_seconds=8.0)


def check_address(host: str, port: int) -> None:
    """Refuse an address viser could never bind (it would retry 1000 ports and hang), as a one-line ConfigError."""
    if not 0 <= port <= 65535:
        raise ConfigError(f"--port must be in 0..65535, got {port}")
    try:
        family, *_, address = socket.getaddrinfo(host, None, type=socket.SOCK_STREAM)[0]
    except socket.gaierror as e:
        raise ConfigError(f"cannot resolve --host {host!r}: {e.strerror}") from None
    with socket.socket(family, socket.SOCK_STREAM) as s:
        try:
            s.bind((address[0], 0))
        except OSError as e:
            raise ConfigError(f"cannot listen on --host {host!r}: {e.strerror}") from None


def warm_kernels() -> None:
    """Compile (first run on a machine) or load the physics kernels before the simulation thread needs
    them, so a first launch never stalls a running viewer; say so when it takes a while."""
    from sim.simulation import default_backend

    if default_backend() != "numba":
        return
    from sim.kernels import warm_up

    note = threading.Timer(5.0, lambda: print("floatsim: compiling the fast kernels (first run on this machine only, about two minutes)...",
                                              file=sys.stderr, flush=True))  # fmt: skip
    note.start()
    try:
        warm_up()
    finally:
        note.cancel()


def start(args: ViewArgs, *, publish_hz: float = 30.0, strict: bool = False) -> ViewerApp:
    """Load the scene (a bad one raises ConfigError before any server starts), start server and simulation thread.

    strict=True runs the physics under np.errstate(all="raise") (tests): a NaN pauses the run with a note.
    """
    scene = load_scene(args.scene)
    check_address(args.host, args.port)
    warm_kernels()
    presets = available_scenes()
    options = tuple(presets) + (() if args.scene in presets else (args.scene,))
    loop = SimLoop(scene, args.scene, publish_hz=publish_hz, fp_raise=strict, scene_options=options)
    server = viser.ViserServer(host=args.host, port=args.port, label="floatsim", verbose=False)
    try:
        return ViewerApp(server, loop, args.host)
    except BaseException:
        loop.stop()
        server.stop()
        raise


def serve(args: ViewArgs) -> int:
    """Run the viewer until Ctrl-C (or SIGTERM); exit status 0."""
    app = start(args)
    moved = f" (port {args.port} was busy)" if args.port not in (0, app.port) else ""
    print(f"floatsim viewer: {app.url}{moved}  scene '{args.scene}'; Ctrl-C to stop", flush=True)
    done = threading.Event()
    if threading.current_thread() is threading.main_thread():
        # Both set explicitly: a shell starts background jobs with SIGINT ignored, and Ctrl-C must still stop us.
        for sig in (signal.SIGINT, signal.SIGTERM):
            signal.signal(sig, lambda *_: done.set())
    try:
        while not done.wait(0.5):
            pass
    except KeyboardInterrupt:
        pass
    finally:
        app.stop()
    print("floatsim viewer: stopped", file=sys.stderr)
    return 0

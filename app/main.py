"""Start the viewer: a viser server, the GUI, the scene and the simulation thread. `start` returns at once (tests), `serve` blocks until Ctrl-C."""

from __future__ import annotations

import signal
import socket
import sys
import threading
import time
from pathlib import Path

import viser

from app.args import ViewArgs
from app.drawn.camera import CameraView
from app.drawn.scene import SceneView
from app.guards.access import own_origin_only, viewer_address
from app.guards.gate import Gate
from app.live.about import About
from app.live.controls import Controls, Layers, current_values_for_new_pages
from app.live.loop import SimLoop, Snapshot
from app.live.readouts import Readouts
from app.live.share import copy_button_html, link_query, mesh_left_out, parse_link
from app.live.upload import BodyFile
from app.recording.recorder import RecordPanel
from sim.bodies.body import load_mesh
from sim.hydro.hydrostatics import describe_rest
from sim.scene.config import ConfigError, available_scenes, load_scene


class ViewerApp:
    """A running viewer. GUI and scene are server-global: every browser tab shows and drives the same run."""

    def __init__(self, server: viser.ViserServer, loop: SimLoop, host: str, token: str | None = None, share: bool = False):
        self.server = server
        self.loop = loop
        self.port = server.get_port()
        self.host, self.url = host, viewer_address(host, self.port)
        self.token = token
        self.gate = Gate(server, lambda text: loop.post("notice", text), token=token, share=share, on_link=self._apply_link)
        """Checks every message a page sends (app/guards/gate.py), from before the first control exists."""
        self.refusals, self.uploads, self.drivers = self.gate.refusals, self.gate.uploads, self.gate.drivers
        server.gui.configure_theme(control_width="large", show_share_button=share)
        snap = loop.latest()
        tabs = server.gui.add_tab_group()  # the panel's top: the guide first, the live numbers and plots one click away
        with tabs.add_tab("About", viser.Icon.INFO_CIRCLE):
            self.about = About(server)
        with tabs.add_tab("Live", viser.Icon.CHART_LINE):
            self.readouts = Readouts(server)
        self.controls = Controls(server, loop.post, snap.settings, loop.scene_options, tuple(p.name for p in snap.parts))
        self.camera = CameraView(server, follow=not snap.water.flat)  # a sea carries the body off: follow it there
        self._view_of = snap.settings.scene
        self.layers = Layers(server)
        self.body_file = BodyFile(server, loop.post, lambda text, client=None: loop.post("notice", text))
        self.body_file.running = self._running_mesh
        self.recorder = RecordPanel(server, self._notify)
        with server.gui.add_folder("Share a link"):
            self.link = server.gui.add_html(copy_button_html(link_query(snap.settings)))
            self.link_text = server.gui.add_markdown("")
        self.scene = SceneView(server, self.layers, snap.body, waves=not snap.water.flat, parts=snap.parts)
        self._notice_id = snap.notice_id
        self._query, self._link_time = None, -1e9
        self._described = None
        self.connections = 0
        """Browsers that connected so far (the first one restarts the scene: a newcomer sees it from the start)."""
        server.on_client_connect(self._connected)
        current_values_for_new_pages(server)  # a new page's first window shows every control as it is now, not as it was made
        loop.attach(self._publish, self.controls.show_setting)
        loop.start()

    def address(self) -> str:
        """The link the banner prints: with a token, the page it opens may drive the run."""
        return viewer_address(self.host, self.port, self.token)

    def _connected(self, client: viser.ClientHandle) -> None:
        """A new page: the first browser restarts the run (its address, which may carry a setup, comes to _apply_link)."""
        self.connections += 1
        if len(self.server.get_clients()) <= 1:
            self.loop.post("reset")

    def _running_mesh(self) -> str | None:
        """The running body's mesh file, which the uploads folder's bound never removes."""
        settings = self.loop.latest().settings  # (the chosen body's, of several)
        return str(settings.value("mesh")) if settings.value("shape") == "mesh" and settings.value("mesh") else None

    def _apply_link(self, client: viser.ClientHandle, query: str) -> None:
        """A page's address (its token, if one is asked, already checked by the gate): the setup it carries."""
        commands, problems = parse_link(query, self.loop.scene_options)
        for name, value in commands:
            self.loop.post(name, value)
        if commands:
            self.loop.post("reset")  # the setup from its start
        if problems:
            self.loop.post("notice", "Link: " + "; ".join(problems) + " (ignored).")

    def _notify(self, text: str, client=None, error: bool = False) -> None:
        targets = [client] if client is not None else list(self.server.get_clients().values())
        for c in targets:
            c.add_notification("floatsim", text, color="red" if error else "blue", auto_close_seconds=8.0)

    def latest(self) -> Snapshot:
        """The last published snapshot: frame, settings (density, damping, ...), body, notice. Thread-safe."""
        return self.loop.latest()

    def sync(self, timeout: float = 10.0) -> Snapshot:
        """Wait until the simulation thread applied every command posted so far; a fresh snapshot."""
        return self.loop.sync(timeout)

    def stop(self) -> None:
        self.gate.stop()
        self.loop.stop()
        self.server.stop()

    def _publish(self, snap: Snapshot) -> None:
        """Runs on the simulation thread, about 30 times a second. One atomic block: the clients apply the
        frame at once, and viser's event loop is woken once per frame rather than once per message."""
        self.recorder.capture(snap)
        with self.server.atomic():
            self.scene.show(snap)
            if snap.settings.scene != self._view_of:  # another preset: following as it suits that one
                self._view_of = snap.settings.scene
                self.camera.follow_box.value = not snap.water.flat
            self.camera.follow(self.scene.root, snap.frame.x_world)
            self.readouts.update(snap)
            self.controls.show_shape(snap.settings.value("shape"))
            self._update_link(snap)
            fresh = snap.notice_id != self._notice_id and snap.notice
            if fresh or (not snap.notice and self.controls.notice.visible):
                self.controls.show_notice(snap.notice)
        if snap.notice_id != self._notice_id:
            self._notice_id = snap.notice_id
            if fresh:
                for client in self.server.get_clients().values():
                    client.add_notification("floatsim", snap.notice, color="red" if snap.diverged else "yellow", auto_close_seconds=8.0)

    def _update_link(self, snap: Snapshot) -> None:
        """The Copy link button's setup (twice a second at most) and the body's description (on a new body)."""
        now = time.monotonic()
        if now - self._link_time < 0.5:
            return
        self._link_time = now
        query = link_query(snap.settings)
        if query != self._query:
            self._query = query
            self.link.content = copy_button_html(query)
            note = " (your mesh stays on this server: it is not in the link)" if mesh_left_out(snap.settings) else ""
            self.link_text.content = f"`{query}`{note}"
        if snap.body is not self._described:
            self._described = snap.body
            body, fluid = snap.body, snap.params
            threading.Thread(target=lambda: self.body_file.describe(f"**{body.name}**: {describe_rest(body, fluid)}."), daemon=True).start()


def check_address(host: str, port: int) -> int:
    """The port to serve on: `port`, or the next free one above it (0: any). Refuses, as a one-line
    ConfigError, an address viser could never bind (it would retry past 65535 and hang)."""
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
    for candidate in range(port, min(port + 100, 65535) + 1) if port else (0,):
        with socket.socket(family, socket.SOCK_STREAM) as s:
            try:
                s.bind((address[0], candidate))
                return candidate
            except OSError:
                continue
    raise ConfigError(f"port {port} is busy and so is every port up to {min(port + 100, 65535)}: give another --port (0: any free one)")


def start(args: ViewArgs, *, publish_hz: float = 30.0, strict: bool = False, kernels: bool = True) -> ViewerApp:
    """Load the scene (a bad one raises ConfigError before any server starts), start server and simulation thread.

    strict=True runs the physics under np.errstate(all="raise") (tests): a NaN pauses the run with a note.
    kernels=False: the run stays on the numpy reference, compiling and loading nothing (tests of the controls:
    no compile child killed a few seconds later, no load fighting the simulation thread for the GIL).
    """
    scene = load_scene(args.scene)
    if scene.bodies and args.mesh is not None:
        raise ConfigError(f"--mesh gives the one body of a scene its mesh: {args.scene} has several bodies (choose one under Body in the "
                          "viewer and load its mesh there, or give it in its [[bodies]] entry)")  # fmt: skip
    if args.mesh is not None:
        load_mesh(args.mesh, args.mesh, args.mesh_unit)  # a bad file: one line and exit 2, before any server starts
    port = check_address(args.host, args.port)
    presets = available_scenes()
    options = tuple(presets) + (() if args.scene in presets else (args.scene,))
    loop = SimLoop(
        scene, args.scene, publish_hz=publish_hz, fp_raise=strict, scene_options=options, background_compile=True, kernels=kernels
    )
    if args.mesh is not None:
        loop.post("mesh", (str(Path(args.mesh).resolve()), args.mesh_unit))  # as an upload: at rest height, with its description
    with own_origin_only(args.host):  # pages from other sites may not open its websocket (app/guards/access.py)
        server = viser.ViserServer(host=args.host, port=port, label="floatsim", verbose=False)
    try:
        return ViewerApp(server, loop, args.host, args.token, args.share)
    except BaseException:
        loop.stop()
        server.stop()
        raise


def is_loopback(host: str) -> bool:
    """Whether `host` only listens on this machine."""
    import ipaddress

    if host in ("localhost", ""):
        return host == "localhost"
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def serve(args: ViewArgs) -> int:
    """Run the viewer until Ctrl-C (or SIGTERM); exit status 0."""
    app = start(args)
    done = threading.Event()
    if threading.current_thread() is threading.main_thread():
        # Both set explicitly: a shell starts background jobs with SIGINT ignored, and Ctrl-C must still stop us. Before the
        # address is printed: whoever reads it may stop us at once (a loaded machine once took the signal before this).
        for sig in (signal.SIGINT, signal.SIGTERM):
            signal.signal(sig, lambda *_: done.set())
    moved = f" (port {args.port} was busy)" if args.port not in (0, app.port) else ""
    print(f"floatsim viewer: {app.address()}{moved}  scene '{args.scene}'; Ctrl-C to stop", flush=True)
    if not is_loopback(args.host) and not args.token:
        print(f"floatsim viewer: warning: --host {args.host} serves beyond this machine: anyone who can reach port {app.port} can "
              "watch and drive this run; give --token SECRET so only pages opened with ?token=SECRET can drive it, or keep the "
              "default 127.0.0.1 and use an SSH tunnel (ssh -L 8080:127.0.0.1:8080 host)", file=sys.stderr, flush=True)  # fmt: skip
    try:
        while not done.wait(0.5):
            pass
    except KeyboardInterrupt:
        pass
    finally:
        app.stop()
    print("floatsim viewer: stopped", file=sys.stderr)
    return 0

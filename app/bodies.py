"""The viewer for a scene of several bodies ([[bodies]], e.g. the rm3 preset): every body at its pose, each
joint's axis, the water (the wave surface in waves), and the take-offs' power and energy as readouts and a plot;
Pause, Step, Reset and Speed. The run starts at once on the numpy reference while a child process compiles the
bodies' loads (sim/compiling.py), then moves to them between two steps.

A lean sibling of the one-body viewer (app/main.py, app/loop.py), which keeps what only one body has: the live
density, damping and mesh controls, the markers, the force arrows, recordings. One simulation thread changes the
run (GUI callbacks only post), as there.
"""

from __future__ import annotations

import collections
import math
import queue
import sys
import threading
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
import viser

from sim.assembly import Assembly, AssemblyFrame
from sim.compiling import Compiler, Loader, kernels_ready
from sim.errors import SimulationDiverged
from sim.simulation import default_backend

from .access import viewer_address
from .controls import Bound, _control
from .gate import Gate
from .loop import SHOWN, SPEED, Mailbox
from .recorder import RecordPanel
from .scene import LINES_HZ
from .take import MAX_SHOTS, Take
from .tension import THICKNESS, TensionLegend, TensionScale, segment_colours
from .water import LINED_OPACITY, WAVE_OPACITY, WaterView

JOINT_COLOUR = (250, 170, 40)
BODY_COLOURS = ((215, 235, 250), (250, 215, 160), (200, 240, 200), (240, 200, 230))
PLOT_HZ, WINDOW = 5.0, 600
"""The plot is redrawn at most this often and shows this many points (2 minutes at 5 a second)."""


@dataclass(frozen=True)
class BodiesSnapshot:
    """One published state of the run: what the viewer draws and tests read."""

    frame: AssemblyFrame
    scene_name: str
    speed: float
    paused: bool
    real_time_factor: float
    """Simulated seconds per wall second over the last ~2 s (nan while paused or just started)."""
    notice: str
    notice_id: int
    diverged: bool
    epoch: int
    """Counts resets (the plot starts again)."""
    engine: str
    """'compiled' or 'numpy reference' (with the compile's progress)."""
    water: Any


class BodiesLoop(Mailbox):
    """Runs one Assembly on its own thread in (scaled) real time; `post(name, value)` queues a command
    (pause, step, reset, speed), applied between steps."""

    def __init__(self, scene, scene_name: str, *, publish_hz: float = 30.0, budget: float = 0.7, kernels: bool = True):
        """kernels=False: the numpy reference only, nothing compiled or loaded (tests of the controls)."""
        self.scene_name = scene_name
        self.period = 1.0 / publish_hz
        self._budget = budget * self.period
        self._background = kernels and default_backend() == "numba"
        self.run = Assembly(scene, backend="numpy")
        for note in self.run.notes:
            print(f"floatsim: note: {note}", file=sys.stderr)
        self._jobs: dict = {}  # spec -> its Compiler or Loader under way
        self._loaded: set = set()
        self._failed: set = set()
        self.publish = None
        self.on_setting = None
        """`on_setting(field, value)`: the GUI shows a value the loop chose (a clamped speed, a pause it made)."""
        self._speed, self._paused, self._diverged = 1.0, False, False
        self._notice, self._notice_id = "", 0
        self._epoch = self._steps = 0
        self._anchor: tuple[float, float] | None = None
        self._history: collections.deque = collections.deque()
        self._step_cost = self._budget
        self._queue: queue.Queue = queue.Queue()
        self._lock = threading.Lock()
        self._latest: BodiesSnapshot | None = None
        self._thread: threading.Thread | None = None
        self._stopping = False
        self._publish_now()

    # ---- any thread (post, latest, sync: Mailbox)

    def start(self) -> BodiesLoop:
        self._thread = threading.Thread(target=self._loop, name="floatsim-bodies", daemon=True)
        self._thread.start()
        return self

    def stop(self, timeout: float = 5.0) -> None:
        self._stopping = True
        for job in self._jobs.values():
            if isinstance(job, Compiler):
                job.stop()
        self.post("_wake")
        if self._thread is not None:
            self._thread.join(timeout)
        if self._thread is None or not self._thread.is_alive():
            self.run.close()  # MoorDyn's lines, if any

    # ---- the simulation thread

    def _loop(self) -> None:
        with np.errstate(all="ignore"):  # a blow-up is caught as a non-finite state (SimulationDiverged), said in a notice
            next_tick = time.monotonic()
            while not self._stopping:
                try:
                    commands = [self._queue.get(timeout=max(0.0, next_tick - time.monotonic()))]
                except queue.Empty:
                    commands = []
                while not self._queue.empty():
                    commands.append(self._queue.get_nowait())
                barriers = [value for name, value in commands if name == "_sync"]
                for name, value in commands:
                    if name in ("pause", "step", "reset", "speed", "notice"):
                        getattr(self, f"_cmd_{name}")(value)
                for name, field in SHOWN.items():  # once per batch, after its last value (app/loop.py: _show_used)
                    if any(n == name for n, _ in commands):
                        self._tell(field, getattr(self, f"_{field}"))
                self._ensure_kernels()
                now = time.monotonic()
                if now >= next_tick:
                    next_tick = now + self.period
                    try:
                        self._advance(now)
                    except Exception as e:  # noqa: BLE001 -- the thread must survive anything: pause and say why
                        self._pause()
                        self._raise(f"Paused: the step failed: {type(e).__name__}: {e}")
                    self._publish_now()
                elif barriers:
                    self._publish_now()
                for event in barriers:
                    event.set()

    def _advance(self, now: float) -> None:
        if self._paused:
            self._anchor = None
            self._history.clear()
            return
        t = self.run.state.t
        if self._anchor is None:
            self._anchor = (now, t)
            return
        target = self._anchor[1] + (now - self._anchor[0]) * self._speed
        n, started = round((target - t) / self.run.dt), time.perf_counter()
        while n > 0 and not self._paused and time.perf_counter() - started < self._budget:
            k = min(n, max(1, int(0.5 * self._budget / self._step_cost)))
            chunk = time.perf_counter()
            self._step(k)
            self._step_cost = 0.5 * self._step_cost + 0.5 * (time.perf_counter() - chunk) / k
            n -= k
        t = self.run.state.t
        if (target - t) / self._speed > 1.0:  # fell behind: drop the debt
            self._anchor = (now, t)
        self._history.append((now, t))
        while len(self._history) > 2 and now - self._history[0][0] > 2.0:
            self._history.popleft()

    def _step(self, n: int) -> None:
        try:
            self.run.step(n)
            self._steps += n
        except SimulationDiverged as e:
            self._diverged = True
            self._pause()
            self._raise(f"Paused: {e}. Press Reset.")

    def _ensure_kernels(self) -> None:
        """The bodies' compiled loads where this machine has them (loaded on a thread), else compiled by a child
        while the numpy reference runs; the run moves to them between two steps once all are loaded."""
        if not self._background or not self.run.system.has_twin or self.run.compiled:
            return
        for spec, job in list(self._jobs.items()):
            if not job.done:
                continue
            del self._jobs[spec]
            if not job.ok:
                self._failed.add(spec)
                self._raise(f"The fast kernels did not compile ({job.failure()}); the run stays on the numpy reference.")
            elif isinstance(job, Compiler):
                self._jobs[spec] = Loader(spec, compiled_in=job.seconds)
            else:
                self._loaded.add(spec)
        for spec in self.run.system.specs:
            if spec in self._loaded or spec in self._failed or spec in self._jobs:
                continue
            if kernels_ready(spec):
                self._jobs[spec] = Loader(spec)
            else:
                self._jobs[spec] = Compiler(spec)
                print(f"floatsim: compiling the bodies' fast kernels ({spec.describe()}) in the background, once for this machine; "
                      "until then the run goes on the numpy reference", file=sys.stderr, flush=True)  # fmt: skip
            break  # one at a time
        if set(self.run.system.specs) <= self._loaded:
            self.run.use_backend("numba")
            self._step_cost = self._budget
            self._anchor = None
            self._raise("The fast kernels are ready: the run goes on with them.")

    def engine(self) -> str:
        if self.run.compiled:
            return "compiled"
        compiling = [job for job in self._jobs.values() if isinstance(job, Compiler)]
        if compiling:
            return f"numpy reference (the fast kernels are compiling in the background: {time.monotonic() - compiling[0].started:.0f} s so far)"
        return "numpy reference (loading the fast kernels)" if self._jobs else "numpy reference"

    def _pause(self) -> None:
        """A pause the loop makes (a step, a divergence): the GUI is told."""
        self._paused = True
        self._tell("paused", True)

    def _tell(self, field: str, value) -> None:
        if self.on_setting is not None:
            try:
                self.on_setting(field, value)
            except Exception as e:  # noqa: BLE001 -- a drawing failure must not stop the run
                print(f"floatsim viewer: showing {field} failed: {type(e).__name__}: {e}", file=sys.stderr)

    def _cmd_pause(self, value) -> None:
        self._paused = value is True  # the gate lets only yes/no through; anything else runs
        self._anchor = None

    def _cmd_step(self, _value) -> None:
        self._pause()
        if not self._diverged:
            self._step(1)

    def _cmd_reset(self, _value) -> None:
        self.run.reset()
        self._diverged, self._anchor = False, None
        self._epoch += 1
        self._history.clear()

    def _cmd_speed(self, value) -> None:
        self._speed, note = SPEED.clamp(value, self._speed)
        if note:
            self._raise(note)
        self._anchor = None

    def _cmd_notice(self, value) -> None:
        self._raise(str(value))

    def _raise(self, text: str) -> None:
        self._notice, self._notice_id = text, self._notice_id + 1

    def _rate(self) -> float:
        h = self._history
        if len(h) < 2 or h[-1][0] - h[0][0] < 0.5:
            return math.nan
        return (h[-1][1] - h[0][1]) / (h[-1][0] - h[0][0])

    def _publish_now(self) -> None:
        snap = BodiesSnapshot(self.run.frame(), self.scene_name, self._speed, self._paused, self._rate(), self._notice, self._notice_id,
                              self._diverged, self._epoch, self.engine(), self.run.system.water)  # fmt: skip
        with self._lock:
            self._latest = snap
        if self.publish is not None:
            try:
                self.publish(snap)
            except Exception as e:  # noqa: BLE001 -- a drawing failure must not stop the run
                print(f"floatsim viewer: drawing failed: {type(e).__name__}: {e}", file=sys.stderr)


class BodiesScene:
    """The 3D nodes of a system: each body's frame and mesh, the joints' axes, the mooring lines, the water. `show`
    moves them to a snapshot (the live viewer's, a recording's: replay=True keeps every pose exactly and counts the
    throttles in the time given)."""

    def __init__(self, server: viser.ViserServer, system, replay: bool = False):
        self.server, self.replay = server, replay
        bodies = [m.body for m in system.members]
        size = max(max(float(np.ptp(b.mesh_vertices, axis=0).max()) for b in bodies), 2.0)
        self.water = WaterView(server, 2.0 * size, lighter=replay)
        self.frames = []
        for k, m in enumerate(system.members):
            self.frames.append(
                server.scene.add_frame(f"/bodies/{m.name}", axes_length=0.3 * m.body.radius, axes_radius=0.01 * m.body.radius)
            )
            server.scene.add_mesh_simple(f"/bodies/{m.name}/mesh", m.body.mesh_vertices, m.body.mesh_faces, color=BODY_COLOURS[k % len(BODY_COLOURS)],
                                         flat_shading=True)  # fmt: skip
        self._reach = 0.6 * size
        self.joints = self.lines = None
        self._lines_time = -math.inf
        self.tension = TensionScale()
        self.legend = None if replay else TensionLegend(server)
        """The lines' colour bar in the panel (app/tension.py; a recording keeps no panel)."""
        server.initial_camera.position = (1.6 * size, -2.2 * size, 0.9 * size)
        server.initial_camera.look_at = (0.0, 0.0, -0.25 * size)

    def show(self, snap: BodiesSnapshot, now: float | None = None) -> None:
        now = time.monotonic() if now is None else now
        frame = snap.frame
        with self.server.atomic():
            for node, body in zip(self.frames, frame.bodies):
                if self.replay:  # viser skips a pose within 1e-5 of the last one sent: a replay keeps every pose exactly
                    node._impl.position[:] = np.nan
                    node._impl.wxyz[:] = np.nan
                node.position, node.wxyz = body["x"], body["q"]
            if frame.joint_axes:
                segments = np.array([[p - self._reach * a, p + self._reach * a] for p, a in frame.joint_axes], np.float32)
                if self.joints is None:
                    self.joints = self.server.scene.add_line_segments("/joints", segments, JOINT_COLOUR, thickness=0.04)
                else:
                    self.joints.points = segments
            self.water.opacity = LINED_OPACITY if frame.lines else WAVE_OPACITY
            if frame.lines and now - self._lines_time >= 1.0 / LINES_HZ:  # the mooring lines, throttled
                self._lines_time = now
                self.tension.take(frame.line_tensions, frame.t)
                segments = np.concatenate([np.stack([p[:-1], p[1:]], axis=1) for p in frame.lines]).astype(np.float32)
                colours = segment_colours(frame.line_tensions, self.tension.low, self.tension.high)
                if self.lines is None:
                    self.lines = self.server.scene.add_line_segments(
                        "/moorings", segments, colours, thickness=THICKNESS, thickness_units="screen"
                    )
                else:
                    self.lines.points = segments
                    if not np.array_equal(self.lines.colors, colours):
                        self.lines.colors = colours
                if self.legend is not None:
                    self.legend.show(self.tension)
            self.water.show(snap.water, frame.t, np.mean([b["x"] for b in frame.bodies], axis=0), True, now)


class BodiesTake(Take):
    """A recording of a system's run: its snapshots on the take clock (app/take.py), the run's CSV, and its scene for a
    replay page or a video (app/replay.py, app/video.py)."""

    def __init__(self, system, columns: list[str], limit: int = MAX_SHOTS):
        super().__init__(limit)
        self.system, self.columns = system, columns

    def add(self, snap: BodiesSnapshot) -> bool:
        if len(self._shots) >= self.limit:
            return False
        if self._tick(snap.frame.t):
            self._shots.append(snap)
        return True

    def __getitem__(self, i: int) -> BodiesSnapshot:
        return self._shots[i]

    def csv(self) -> str:
        rows = [",".join(self.columns)] + [",".join(f"{v:.12g}" for v in shot.frame.row()) for shot in self._shots]
        return "\n".join(rows) + "\n"

    def stage(self, server: viser.ViserServer) -> BodiesScene:
        view = BodiesScene(server, self.system, replay=True)
        view.show(self[0], now=0.0)
        return view


class BodiesControls(Bound):
    """Pause, Step, Reset and Speed: a page's update posts a command; `show_setting` shows what the loop chose."""

    def __init__(self, gui, post):
        super().__init__(post)
        with gui.add_folder("Run"):
            self.paused = gui.add_checkbox("Pause", False, hint="Freeze the simulation (the view stays live)")
            self.step = gui.add_button("Step", hint="Advance one time step")
            self.reset = gui.add_button("Reset", hint="Back to the scene's initial state")
            self.speed = _control(gui, SPEED, 1.0)
        self._bind("paused", "pause")
        self._bind("speed", "speed")
        self.step.on_click(lambda _: post("step"))
        self.reset.on_click(lambda _: post("reset"))


class BodiesView:
    """The live viewer's scene and panel for a BodiesLoop; `show` runs on the simulation thread."""

    def __init__(self, server: viser.ViserServer, loop: BodiesLoop):
        self.server = server
        system = loop.run.system
        self.scene = BodiesScene(server, system)
        gui = server.gui
        self.controls = BodiesControls(gui, loop.post)
        loop.on_setting = self.controls.show_setting
        self.text = gui.add_markdown("")
        names = [g.name for g in system.joints if g.damping > 0]  # the joints with a take-off's damper
        self.takeoffs = names
        self.plot = gui.add_uplot((np.zeros(1),) + tuple(np.zeros(1) for _ in names),
                                  ({"label": "t (s)"}, *({"label": f"take-off {n} power (kW)", "stroke": c, "width": 1.5}
                                                          for n, c in zip(names, ("#d62728", "#1f77b4", "#2ca02c", "#9467bd")))),
                                  scales={"x": {"time": False}}, legend={"show": True}, aspect=2.2, visible=bool(names))  # fmt: skip
        self.recorder = RecordPanel(server, lambda text, client=None, error=False: loop.post("notice", text),
                                    new_take=lambda: BodiesTake(system, loop.run.columns()))  # fmt: skip
        self._history: collections.deque = collections.deque(maxlen=WINDOW)
        self._plotted, self._epoch, self._notice_id = -math.inf, -1, 0

    def show(self, snap: BodiesSnapshot) -> None:
        self.recorder.capture(snap)
        with self.server.atomic():
            self.scene.show(snap)
            self._readouts(snap)
        if snap.notice_id != self._notice_id:
            self._notice_id = snap.notice_id
            for client in self.server.get_clients().values():
                client.add_notification("floatsim", snap.notice, color="red" if snap.diverged else "yellow", auto_close_seconds=8.0)

    def _readouts(self, snap: BodiesSnapshot) -> None:
        now = time.monotonic()
        if now - self._plotted < 1.0 / PLOT_HZ:
            return
        self._plotted = now
        self.text.content = describe(snap, self.takeoffs)
        frame = snap.frame
        if snap.epoch != self._epoch:
            self._epoch = snap.epoch
            self._history.clear()
        if self.takeoffs and (not self._history or self._history[-1][0] != frame.t):
            self._history.append((frame.t, *(p / 1e3 for name, _, _, p, _ in frame.joints if name in self.takeoffs)))
            data = np.array(self._history, dtype=float).T
            self.plot.data = tuple(data)


def describe(snap: BodiesSnapshot, takeoffs: list[str]) -> str:
    """The panel's numbers: time, speed, engine; each body's height and speed; each joint's stroke, and the power and
    energy of those with a take-off (`takeoffs`)."""
    f = snap.frame
    rate = "paused" if snap.paused else ("-" if math.isnan(snap.real_time_factor) else f"{snap.real_time_factor:.2f}x real time")
    lines = [f"**{snap.scene_name}** &nbsp; t = {f.t:.2f} s ({rate}; {snap.engine})", ""]
    lines += [f"- {b['name']}: z = {b['x'][2]:+.3f} m, |u| = {np.linalg.norm(b['u']):.3f} m/s" for b in f.bodies]
    if f.mooring:
        lines += [
            f"- mooring lines: pull {np.linalg.norm(f.mooring[:3]) / 1e3:.2f} kN, largest fairlead tension {f.mooring[3] / 1e3:.2f} kN"
        ]
    for name, theta, _, p, e in f.joints:
        taken = (
            f", take-off power {p / 1e3:.1f} kW, absorbed {e / 1e6:.3f} MJ ({e / f.t / 1e3 if f.t > 0 else 0:.1f} kW mean)"
            if name in takeoffs
            else ""
        )
        lines.append(f"- joint {name}: stroke {theta:+.3f}{taken}")
    if snap.notice:
        lines += ["", f"_{snap.notice}_"]
    return "\n".join(lines)


class BodiesApp:
    """A running viewer of several bodies: the server, the loop and the view (start_bodies), behind the same gate
    as the one-body viewer (app/gate.py)."""

    def __init__(self, server: viser.ViserServer, loop: BodiesLoop, host: str, token: str | None = None, share: bool = False):
        self.server, self.loop, self.token = server, loop, token
        self.gate = Gate(server, lambda text: loop.post("notice", text), token=token, share=share)
        self.port = server.get_port()
        self.host, self.url = host, viewer_address(host, self.port)
        server.gui.configure_theme(show_share_button=share)
        self.view = BodiesView(server, loop)
        self.controls, self.recorder = self.view.controls, self.view.recorder
        loop.publish = self.view.show
        loop.start()

    def address(self) -> str:
        """The link the banner prints: with a token, the page it opens may drive the run."""
        return viewer_address(self.host, self.port, self.token)

    def latest(self) -> BodiesSnapshot:
        return self.loop.latest()

    def sync(self, timeout: float = 10.0) -> BodiesSnapshot:
        return self.loop.sync(timeout)

    def stop(self) -> None:
        self.gate.stop()
        self.loop.stop()
        self.server.stop()

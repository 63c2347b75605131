"""The simulation thread: owns the Simulation, applies queued commands between steps, paces to wall time, publishes snapshots.

ARCHITECTURE rule 6: GUI callbacks only `post`; this one thread changes the simulation. No viser
here, so the tests drive it without a browser or a server.
"""

from __future__ import annotations

import collections
import math
import queue
import sys
import threading
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

import sim
from sim.bodies.body import printable
from sim.bodies.rotation import quat_to_matrix
from sim.bodies.state import initial_state
from sim.compiling import Compiler, Loader, default_backend, kernels_ready
from sim.hydro.bem import no_solves
from sim.hydro.hydrostatics import at_rest, describe_rest, hydrostatics, sampled_model_warning
from sim.parameters import Param
from sim.scene.config import ENTRY_KEYS, IN_EFFECT, MESH_FORCES, PARAMS, available_scenes, body_own, entry_value, in_effect, load_scene

NOTICE_SECONDS = 10.0
"""How long a note about a clamped value stays in the GUI (a divergence note stays until Reset or Resume)."""

SPEED = Param("viewer", "speed", 1.0, "Simulated seconds per wall-clock second asked for", "×", lo=0.01, hi=100.0, label="Speed",
              gui=(0.1, 10.0, 0.1))  # fmt: skip
NO_SOLVE = (
    "a minute or more, which the live viewer does not run: run the scene with it once from the command line "
    "(python -m sim run), after which it is cached"
)
STEP_SECONDS = 0.25
"""Most wall time one step of an adaptive method may take here: the thread must get back to Pause and Reset."""
CONTROLLED = {p.key: p for p in PARAMS.values() if p.gui is not None}
"""Scene parameters with a live control, by key (the command that changes each is its key)."""
_QUALNAME = {p.key: qualname for qualname, p in PARAMS.items()}
DERIVED = {PARAMS[q].key for q in IN_EFFECT} & CONTROLLED.keys()
"""Controls whose value in effect other parameters decide: shown again after every batch of commands."""
SHOWN = {"speed": "speed", "pause": "paused"}
"""The viewer's own commands whose control shows the value the run uses after each batch, as the scene parameters' do
(command -> the setting's field): a clamp written back at once could land after the page's next valid value."""
SLOWEST = 0.1
"""The slowest one page's value may make the shared run: a tenth of real time (issue 59; the time step's cost)."""


@dataclass(frozen=True)
class Settings:
    """What the viewer shows in its controls: the running scene (`Simulation.scene`, never copied)
    plus what only the viewer has (preset name, speed, pause). Read any scene parameter by its key."""

    scene_name: str
    config: sim.SceneConfig
    body: sim.Body
    """The chosen body (the one body of a one-body scene): the Body folder's controls show and change its parameters."""
    speed: float = 1.0
    """Simulated seconds per wall-clock second asked for."""
    paused: bool = False
    focus: str = "body"
    """The chosen body's name (config.body_names): `body` in a one-body scene."""

    @property
    def scene(self) -> str:
        return self.scene_name

    @property
    def density(self) -> float:
        return self.body.mass / self.body.volume

    def __getattr__(self, key: str):
        if key in ENTRY_KEYS and self.config.bodies:  # a body's own parameter: the chosen body's
            return entry_value(self.config, next(e for e in self.config.bodies if e.name == self.focus), key)
        if key in _QUALNAME:
            return in_effect(self.config, _QUALNAME[key])
        raise AttributeError(key)

    def value(self, key: str):
        return getattr(self, key)


class Posed:
    """What the scene draws needs `frame` and `body`; this adds their calm-water hydrostatics (B, M, GM),
    computed once and only when asked (the markers and readouts, while shown)."""

    @cached_property
    def hydrostatics(self):
        return hydrostatics(self.body, self.frame.x_world, quat_to_matrix(self.frame.q_world_body))


@dataclass(frozen=True, eq=False)
class Part(Posed):
    """One body as the viewer draws it: its name, its Body and its one-body Frame."""

    name: str
    body: sim.Body
    frame: sim.Frame


@dataclass(frozen=True, eq=False)
class Snapshot(Posed):
    """One published state of the run: what the viewer draws and what tests read. `frame` and `body` are the chosen
    body's (the one body's: the run's own frame); `parts` every body's, `run` the run's own frame (its CSV row)."""

    frame: sim.Frame
    settings: Settings
    body: sim.Body
    water: object
    """The running simulation's Water (the viewer draws its surface)."""
    real_time_factor: float
    """Simulated seconds per wall second over the last ~2 s (nan while paused or just started)."""
    behind: bool
    """The machine cannot keep up with the asked speed (steps were dropped or the rate is low)."""
    notice: str
    """A note for the user ('' when none): a clamped value, a divergence, a failed command."""
    notice_id: int
    """Counts notices raised, so a viewer can tell a new note from the same one."""
    diverged: bool
    epoch: int
    """Counts resets, scene loads and body rebuilds (plots restart their history when it changes)."""
    steps: int
    """Steps taken since the loop started."""
    advice: str = ""
    """A standing warning about the running model for this body, a sentence ('' when none): the points model in its bad band."""
    engine: str = ""
    """What steps the run when not the compiled kernels ('numpy reference', with the compile's progress), else ''."""
    parts: tuple = ()
    """Every body (Part), in the scene's order (one body: itself)."""
    run_frame: object = None
    """The run's own frame where it is not `frame`: a scene of several bodies' (its Frame of them all)."""

    @property
    def run(self):
        """The run's own frame: its CSV row, the mooring lines, the joints' axes."""
        return self.frame if self.run_frame is None else self.run_frame

    @property
    def system(self) -> bool:
        """Whether the run is a scene of several bodies."""
        return self.run_frame is not None

    @property
    def params(self):
        """The running scene's [fluid] table."""
        return self.settings.config.fluid

    @property
    def density(self) -> float:
        return self.settings.density

    @property
    def damping(self) -> float:
        """The chosen body's damping coefficient (its own where its [[bodies]] entry gives one)."""
        return self.settings.damping


class Mailbox:
    """A simulation thread's side facing the others: commands go in a queue it applies between steps, snapshots come
    out under a lock. The subclass makes `_queue`, `_lock` and `_latest`, and answers `_sync` with its event."""

    def post(self, name: str, value: Any = None) -> None:
        """Queue a command for the simulation thread."""
        self._queue.put((name, value))

    def latest(self):
        """The last published snapshot."""
        with self._lock:
            assert self._latest is not None
            return self._latest

    def sync(self, timeout: float = 10.0):
        """Wait until every command posted before this call is applied, and return a fresh snapshot."""
        done = threading.Event()
        self.post("_sync", done)
        if not done.wait(timeout):
            raise TimeoutError(f"the simulation thread did not answer within {timeout} s")
        return self.latest()


class SimLoop(Mailbox):
    """Runs one Simulation on its own thread in (scaled) real time.

    `post(name, value)` queues a command (thread-safe, never blocks); the thread applies queued
    commands between steps. Hooks set with `attach`: `publish(snapshot)` is called on the thread
    at `publish_hz`; `on_setting(field, value)` when the loop itself changes a setting (a clamp, a scene load,
    a pause on divergence) so the GUI can show the value actually used.
    """

    def __init__(
        self,
        scene: sim.SceneConfig,
        scene_name: str,
        *,
        publish_hz: float = 30.0,
        budget: float = 0.7,
        resync_after: float = 1.0,
        fp_raise: bool = False,
        scene_options: tuple[str, ...] = (),
        background_compile: bool = False,
        kernels: bool = True,
    ):
        self._publish: Callable[[Snapshot], None] | None = None
        self._on_setting: Callable[[str, Any], None] | None = None
        self.period = 1.0 / float(publish_hz)
        self._budget = budget * self.period
        self._resync_after = resync_after
        self._fp = {"all": "raise", "under": "ignore"} if fp_raise else {"all": "ignore"}
        self.scene_options = tuple(scene_options) or tuple(available_scenes())

        self._background = background_compile and kernels and default_backend() == "numba"
        """Whether a scene whose kernels this machine has not compiled runs on the numpy reference while a child compiles them."""
        self._compiler: Compiler | None = None
        """The kernels compiling in a child process (sim/compiling.py); until it is done the numpy reference runs."""
        self._loader: Loader | None = None
        """The kernels loading from the disk cache on a thread."""
        self._loaded: set = set()  # the kernels.Spec this process has loaded
        self._failed: set = set()  # and those that did not compile: not tried again
        self._compiled_in: float | None = None  # seconds the last compile took, for the notice once its kernels are loaded
        self._backend = "numpy" if self._background or not kernels else None  # None: the default (compiled where there is a twin)
        self.sim = self._simulation(scene)
        self._scene_name, self._speed, self._paused = scene_name, 1.0, False
        self._focus = 0  # the chosen body's index (Settings.focus)
        self._queue: queue.Queue = queue.Queue()
        self._lock = threading.Lock()
        self._latest: Snapshot | None = None
        self._thread: threading.Thread | None = None
        self._stopping = False

        self._anchor: tuple[float, float] | None = None  # (wall, sim t) that pacing counts from
        self._history: collections.deque = collections.deque()  # (wall, sim t) for the real-time factor
        self._behind_until = 0.0
        self._step_cost = self._budget  # seconds per step, running estimate (unknown yet: one-step chunks)
        self._steps = 0
        self._epoch = 0
        self._diverged = False
        self._notice, self._notice_id, self._notice_until = "", 0, 0.0
        self._advice_key, self._advice_text = None, ""
        self._errors_logged: set[str] = set()
        self._ensure_kernels()
        self._publish_now()

    def attach(self, publish: Callable[[Snapshot], None] | None, on_setting: Callable[[str, Any], None] | None = None) -> None:
        """Set the viewer's hooks (before `start`): they run on the simulation thread."""
        self._publish, self._on_setting = publish, on_setting

    @property
    def settings(self) -> Settings:
        """The controls' values: a view of the running simulation's scene plus the viewer's own."""
        return Settings(self._scene_name, self.sim.scene, self.sim.bodies[self._focus], self._speed, self._paused,
                        self.sim.body_names[self._focus])  # fmt: skip

    # ---- any thread (post, latest, sync: Mailbox) ------------------------------------------

    def start(self) -> SimLoop:
        self._thread = threading.Thread(target=self._run, name="floatsim-sim", daemon=True)
        self._thread.start()
        return self

    def stop(self, timeout: float = 5.0) -> None:
        self._stopping = True
        if self._compiler is not None:
            self._compiler.stop()
        self.post("_wake")
        if self._thread is not None:
            self._thread.join(timeout)
        if not self.is_alive():
            self.sim.close()  # MoorDyn's lines, if any

    def is_alive(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    # ---- the simulation thread -------------------------------------------------------------

    def _run(self) -> None:
        with np.errstate(**self._fp):
            next_tick = time.monotonic()
            while not self._stopping:
                try:
                    commands = [self._queue.get(timeout=max(0.0, next_tick - time.monotonic()))]
                except queue.Empty:
                    commands = []
                while True:
                    try:
                        commands.append(self._queue.get_nowait())
                    except queue.Empty:
                        break
                barriers = []
                for name, value in commands:
                    if name == "_sync":
                        barriers.append(value)
                    elif name != "_wake":
                        self._apply(name, value)
                self._show_used({name for name, _ in commands if name in CONTROLLED or name in SHOWN})
                self._ensure_kernels()
                now = time.monotonic()
                if now >= next_tick:
                    next_tick = now + self.period
                    self._guarded("advance", lambda now=now: self._advance(now))
                    self._publish_now()
                elif barriers:
                    self._publish_now()
                for event in barriers:
                    event.set()

    def _ensure_kernels(self) -> None:
        """Between two steps: run the scene on its compiled kernels where this machine has them (loaded from the
        disk cache on a thread), else on the numpy reference while a child compiles them; switch when they are
        loaded (the same state vector; only the backend changes). A scene change may need other kernels: the same again.
        Nothing here waits for numba: the simulation thread must answer Pause, Reset and the tests' sync at once."""
        if not self._background or not self.sim.has_twin:
            return
        specs = self.sim.specs  # one; a scene of several bodies: one per kind of body and the system step's
        self._collect_kernels(specs)
        busy = set(self._compiler.specs) if self._compiler is not None else set()
        if self._loader is not None:
            busy.add(self._loader.spec)
        todo = [spec for spec in specs if spec not in self._loaded and spec not in self._failed]
        if todo and todo[0] not in busy:
            if kernels_ready(todo[0]):
                if self._loader is None:  # one load at a time; the next check starts the next one
                    self._loader = Loader(todo[0], compiled_in=self._compiled_in)
            elif self._compiler is None or not set(self._compiler.specs) <= set(specs):
                if self._compiler is not None:
                    self._compiler.stop()  # compiling kernels the scene no longer needs
                self._compiler = Compiler([spec for spec in todo if not kernels_ready(spec)])
                print(f"floatsim: compiling the fast kernels for this scene ({'; '.join(s.describe() for s in self._compiler.specs)}) in the "
                      f"background, once for this machine (about {self._compiler.expected:.0f} s here); until then it runs on the numpy reference",
                      file=sys.stderr, flush=True)  # fmt: skip
        self._backend = default_backend() if all(spec in self._loaded for spec in specs) else "numpy"
        if self.sim.backend != self._backend:
            self.sim.use_backend(self._backend)
            self._cost_unknown()
            self._restart_clock()

    def _collect_kernels(self, specs: list) -> None:
        """Take the result of a compile or a load that ended: a compile is followed by a load of its kernels."""
        compiler = self._compiler
        if compiler is not None and compiler.done:  # its kernels then load from the disk cache, one after the other
            self._compiler = None
            if not compiler.ok:
                self._failed.update(compiler.specs)
                self._raise_notice(f"The fast kernels did not compile ({compiler.failure()}); the run stays on the numpy reference.")
            self._compiled_in = compiler.seconds
        loader = self._loader
        if loader is not None and loader.done:
            self._loader = None
            if not loader.ok:
                self._failed.add(loader.spec)
                self._log("loading the compiled kernels", loader.error)
                self._raise_notice(f"The fast kernels did not load ({loader.failure()}); the run stays on the numpy reference.")
                return
            self._loaded.add(loader.spec)
            if loader.compiled_in is not None and loader.spec in specs and all(s in self._loaded for s in specs):
                self._compiled_in = None
                self._raise_notice(
                    f"The fast kernels are ready (compiled in {loader.compiled_in:.0f} s in the background): the run goes on with them."
                )

    def engine(self) -> str:
        """What steps the run, for the readouts: '' on the compiled kernels."""
        if self.sim.compiled:
            return ""
        if self._compiler is not None and set(self._compiler.specs) & set(self.sim.specs):
            c = self._compiler
            return f"numpy reference (the fast kernels are compiling in the background: {time.monotonic() - c.started:.0f} s of about {c.expected:.0f} s)"
        if self._loader is not None and self._loader.spec in self.sim.specs:
            return "numpy reference (loading the fast kernels)"
        return "numpy reference"

    def _guarded(self, what: str, fn: Callable[[], None]) -> None:
        """Run fn; on any error pause the run with a note instead of killing the thread."""
        try:
            fn()
        except Exception as e:  # noqa: BLE001 - the thread must survive anything
            self._log(what, e)
            self._set("paused", True)
            self._raise_notice(f"Paused: {what} failed: {type(e).__name__}: {e}", sticky=True)

    def _log(self, what: str, e: Exception) -> None:
        key = f"{what}:{type(e).__name__}"
        if key not in self._errors_logged:  # once per kind, or a bad frame would flood the terminal
            self._errors_logged.add(key)
            print(f"floatsim viewer: {what} failed:", file=sys.stderr)
            traceback.print_exception(e, file=sys.stderr)

    def _publish_now(self) -> None:
        try:
            run, frames = self.sim.frame(), self.sim.parts()
        except Exception as e:  # noqa: BLE001
            self._log("observe", e)
            return
        now = time.monotonic()
        if self._notice and not self._diverged and now > self._notice_until:
            self._notice = ""
        advice = self._advice()  # before the notice is read: it raises one when it starts to apply
        parts = tuple(Part(name, body, f) for name, body, f in zip(self.sim.body_names, self.sim.bodies, frames))
        snap = Snapshot(
            frame=parts[self._focus].frame,
            settings=self.settings,
            body=parts[self._focus].body,
            water=self.sim.water,
            real_time_factor=self._rate(),
            behind=(not self.settings.paused) and (now < self._behind_until or self._rate() < 0.85 * self.settings.speed),
            notice=self._notice,
            notice_id=self._notice_id,
            diverged=self._diverged,
            epoch=self._epoch,
            steps=self._steps,
            advice=advice,
            engine=self.engine(),
            parts=parts,
            run_frame=None if run is parts[0].frame else run,
        )
        with self._lock:
            self._latest = snap
        if self._publish is not None:
            try:
                self._publish(snap)
            except Exception as e:  # noqa: BLE001
                self._log("publish", e)

    def _simulation(self, scene) -> sim.Simulation:
        out = sim.Simulation(scene, backend=self._backend)
        out.step_seconds = STEP_SECONDS
        return out

    def _advice(self) -> str:
        """sampled_model_warning for the running body and fluid, computed again only when either changes."""
        key = (self.sim.bodies[self._focus], self.sim.params)
        if self._advice_key != key:
            try:
                text = sampled_model_warning(*key) or ""
            except Exception as e:  # noqa: BLE001 -- advice must never stop the run
                self._log("advice", e)
                text = ""
            text = text and text[0].upper() + text[1:] + "."  # a sentence, for the notice and the readouts
            if text and text != self._advice_text:
                self._raise_notice(text)  # once, when it starts to apply; the readouts keep it
            self._advice_key, self._advice_text = key, text
        return self._advice_text

    def _rate(self) -> float:
        h = self._history
        if len(h) < 2 or h[-1][0] - h[0][0] < 0.5:
            return math.nan
        return (h[-1][1] - h[0][1]) / (h[-1][0] - h[0][0])

    def _restart_clock(self) -> None:
        """Pacing starts afresh (after a pause, a reset, a new speed or dt)."""
        self._anchor = None
        self._history.clear()

    def _advance(self, now: float) -> None:
        """Take the steps that wall time x speed asks for, at most a tick's CPU budget of them."""
        s = self.settings
        if s.paused:
            self._restart_clock()
            return
        t = self.sim.state.t
        if self._anchor is None:
            self._anchor = (now, t)
            self._history.append((now, t))
            return
        wall0, t0 = self._anchor
        target = t0 + (now - wall0) * s.speed
        n = round((target - t) / self.sim.dt)
        if n > 0:
            self._step_within_budget(n)
        t = self.sim.state.t
        if (target - t) / s.speed > self._resync_after:  # fell far behind: drop the debt, say so
            self._anchor = (now, t)
            self._behind_until = now + 3.0
        self._history.append((now, t))
        while len(self._history) > 2 and now - self._history[0][0] > 2.0:
            self._history.popleft()

    def _step_within_budget(self, n: int) -> None:
        """Up to n steps in chunks that fill what is left of the tick's budget; stop once it is spent.

        One chunk a tick where the estimate holds: each chunk ends with the simulation's blow-up check (a
        frame of diagnostics, which the publish then reuses), as dear as a step at high resolution in waves,
        so the step's cost is measured without it.
        The chunk size comes from the measured cost per step, which a new integrator or body makes
        wrong: `_cost_unknown` starts those with one-step chunks, so a slow scheme cannot stall a tick.
        """
        started = time.perf_counter()
        done = 0
        while done < n and not self._paused:
            left = self._budget - (time.perf_counter() - started) - self.sim.check_seconds  # the last chunk's check
            k = min(n - done, max(1, int(left / self._step_cost)))
            chunk_started = time.perf_counter()
            self._step(k)
            done += k
            cost = max(time.perf_counter() - chunk_started - self.sim.check_seconds, 1e-9) / k  # a step's own, without the check
            self._step_cost = cost if k == 1 else 0.5 * self._step_cost + 0.5 * cost
            if time.perf_counter() - started > self._budget:
                break

    def _cost_unknown(self) -> None:
        """After a new integrator or body: measure the cost afresh, and start pacing afresh (no debt from the old one)."""
        self._step_cost = self._budget
        self._restart_clock()

    def _step(self, n: int) -> None:
        try:
            self.sim.step(n)
            self._steps += n
        except (sim.SimulationDiverged, FloatingPointError) as e:
            message = str(e)
            if isinstance(e, FloatingPointError):
                message = (f"simulation diverged at t = {self.sim.state.t:.6g} s: floating-point {e}; "
                           "likely cause: the time step is too large for this damping or integrator: try a smaller dt or 'implicit'")  # fmt: skip
            message = message.replace("--integrator", "integrator").replace("--dt", "time step")  # GUI words for the CLI flags
            self._diverged = True
            self._set("paused", True)
            self._restart_clock()
            self._raise_notice(f"Paused: {message}. Change the setting it names, then press Reset.", sticky=True)

    def _raise_notice(self, text: str, sticky: bool = False) -> None:
        self._notice = text
        self._notice_id += 1
        self._notice_until = math.inf if sticky else time.monotonic() + NOTICE_SECONDS

    def _set(self, field: str, value: Any, tell: bool = True) -> None:
        """Change a viewer setting (speed, paused); `tell` the GUI when the loop, not the user, chose it."""
        setattr(self, f"_{field}", value)
        if tell:
            self._tell(field, value)

    def _tell(self, field: str, value: Any) -> None:
        """Show the GUI a value the loop chose (a clamp, a preset's value, a pause on divergence)."""
        if self._on_setting is not None:
            try:
                self._on_setting(field, value)
            except Exception as e:  # noqa: BLE001
                self._log("GUI update", e)

    def _show_used(self, keys: set[str]) -> None:
        """After a batch of commands, every control it touched shows the value the run uses (a clamp, a
        refusal): unless a newer command for it is already queued. Each command's own write-back raced
        the page's next update (a clamp written after the next valid value showed it, which then ran
        unseen), so this runs once per batch, after the last command, and the GUI writes only a change."""
        if not keys:
            return
        keys = keys | DERIVED | ({"samples"} if "points_per_edge" in keys else set())  # (a mesh refined by points per edge: its samples)
        with self._queue.mutex:
            pending = {name for name, _ in self._queue.queue}
        for key in keys - pending:
            field = SHOWN.get(key, key)
            self._tell(field, self.settings.value(field))

    def _apply(self, name: str, value: Any) -> None:
        handler = getattr(self, f"_cmd_{name}", None)
        if handler is None and name in CONTROLLED:
            handler = lambda v: self._set_param(CONTROLLED[name], v)  # noqa: E731
        if handler is None:
            self._raise_notice(f"Unknown command {name[:24]!r} ignored.")
            return
        try:
            with no_solves(NO_SOLVE):
                handler(value)
        except Exception as e:  # noqa: BLE001 - a bad command must not stop the run
            self._log(f"command {name}", e)
            self._raise_notice(f"Could not apply {name}: {type(e).__name__}: {str(e)[:200]}")

    # ---- commands ----------------------------------------------------------------------------

    def _set_param(self, param: Param, value: Any) -> None:
        """Any scene parameter with a control: clamped by its declaration, applied between steps
        through `Simulation.update` (which rebuilds only what it touches); the scene stays current."""
        current = self.settings.value(param.key)
        used, note = param.clamp(value, current)
        if note:
            self._raise_notice(note)
        if param.key == "dt" and (refusal := self._too_slow(used, current)):
            self._raise_notice(refusal)
            return
        old_body, old_integrator = self.sim.bodies[self._focus], self.sim.integrator
        named = self.sim.body_names[self._focus] if body_own(param) else param.section  # a body's own: the chosen one's
        change = {f"{named}__{param.key}": used}
        if param.key == "points_per_edge" and self.settings.value("shape") == "mesh":
            change = {f"{named}__samples": 6 * used * used}  # a mesh is refined to about as many samples as a cube of N per edge
        try:
            self.sim.update(**change)
        except sim.ConfigError as e:
            self._raise_notice(f"{param.label or param.what}: {e}; kept {param.describe(current)}.")
            used = current
        if param.key in ("points_per_edge", "samples"):
            self._epoch += 1  # a rebuilt body: new history for the plots
        if self.sim.bodies[self._focus] is not old_body or self.sim.integrator is not old_integrator:
            self._cost_unknown()
        if param.key == "dt":
            self._restart_clock()

    def _too_slow(self, dt: float, current: float) -> str:
        """Why a time step of dt is refused, or "": one page's value may not slow the shared run below SLOWEST of real
        time at this machine's measured cost of a step (unknown right after a new body or integrator: not refused)."""
        cost = self._step_cost
        if dt >= current or cost >= self._budget or dt / cost >= SLOWEST:
            return ""
        return (f"Time step {dt:g} s would run at {dt / cost:.2g}x real time here ({cost * 1e6:.3g} µs a step), for every page: "
                f"kept {current:g} s (the shortest that keeps {SLOWEST:g}x real time: {SLOWEST * cost:.2g} s).")  # fmt: skip

    def _cmd_notice(self, value) -> None:
        """A note from another thread (a refused upload, a link not understood) shown like the loop's own."""
        self._raise_notice(str(value)[:400])

    def _cmd_speed(self, value) -> None:
        used, note = SPEED.clamp(value, self._speed)
        if note:
            self._raise_notice(note)
        self._set("speed", used, tell=False)  # shown after the batch (_show_used)
        self._restart_clock()

    def _cmd_pause(self, value) -> None:
        paused = bool(value)
        if not paused:
            self._diverged = False
            if self._notice_until == math.inf:
                self._notice = ""
        self._set("paused", paused, tell=False)
        self._restart_clock()

    def _cmd_step(self, _value=None) -> None:
        self._diverged = False
        self._step(1)

    def _cmd_reset(self, _value=None) -> None:
        """The scene's initial pose and velocities (its initial omega included), with the current parameters."""
        self.sim.reset()
        if self._diverged:  # the run was paused by the divergence, not by the user: resume
            self._diverged = False
            self._set("paused", False)
        if self._notice_until == math.inf:
            self._notice = ""
        self._epoch += 1
        self._restart_clock()

    def _cmd_focus(self, value) -> None:
        """Choose the body the Body, Joint and Start controls show and change, the camera follows and the readouts describe."""
        names = self.sim.body_names
        if value not in names:
            self._raise_notice(f"Body: {str(value)[:40]!r} is not one of {', '.join(names)}; kept {names[self._focus]}.")
            self._tell("focus", names[self._focus])
            return
        old = self.settings
        self._focus = names.index(value)
        self._tell_changes(old)

    def _cmd_scene(self, value) -> None:
        """Load another preset with its own parameters (speed and pause are kept)."""
        if value not in self.scene_options:
            self._raise_notice(f"Scene: {str(value)[:40]!r} is not one of {', '.join(self.scene_options)}; kept {self._scene_name}.")
            self._tell("scene", self._scene_name)
            return
        old = self.settings
        new = self._simulation(load_scene(value))
        self.sim.close()
        self.sim, self._focus = new, 0
        self._scene_name = value
        self._tell_changes(old)
        self._diverged = False
        self._epoch += 1
        self._cost_unknown()

    def _cmd_mesh(self, value) -> None:
        """A checked mesh file (app/live/upload.py) becomes the body, with the running parameters; it starts
        a quarter of its height above where it floats, so the user sees it settle. All or nothing: the
        new simulation is built and started whole before it replaces the running one, which any
        failure leaves running, with a note saying why."""
        path, unit = value
        old = self.settings
        try:
            new, note = self._mesh_simulation(path, unit)
        except Exception as e:  # noqa: BLE001 -- a bad body (ConfigError, SimulationDiverged, 0/0 in strict mode): the old one runs on
            why = str(e) if isinstance(e, sim.ConfigError) else f"{type(e).__name__}: {e}"
            self._raise_notice(f"Mesh not loaded: {why[:300]}. The running body is unchanged.")
            return
        self.sim.close()
        self.sim = new
        self._tell_changes(old)
        body = new.bodies[self._focus]
        self._raise_notice(f"Loaded {printable(Path(path).name.rsplit('-', 1)[0])}: {describe_rest(body, new.params)}." + note)
        self._diverged = False
        self._epoch += 1
        self._cost_unknown()

    def _mesh_simulation(self, path: str, unit: str) -> tuple[sim.Simulation, str]:
        """The running scene with the mesh as its body, set a quarter of its height above rest and
        reset; and the note that goes with it."""
        name = self.sim.body_names[self._focus]
        change = {f"{name}__shape": "mesh", f"{name}__mesh": path, f"{name}__mesh_unit": unit}
        note = ""
        if self.sim.scene.fluid.radiation != "none":  # a new body would need a boundary-element solve: not on this thread
            change["fluid__radiation"] = "none"
            note = " Radiation is off for it (solve its coefficients with `floatsim decay --mesh FILE --radiation bem`)."
        if self.sim.scene.bodies:  # one of several: it takes the chosen body's place on its joint; the scene starts again
            change[f"{name}__forces"] = MESH_FORCES
            new = self._simulation(sim.with_overrides(self.sim.scene, **change))
            new.frame()
            return new, note + " The scene started again with it in the place of " + name + "."
        new = self._simulation(sim.with_overrides(self.sim.scene, **change))
        body = new.body
        R = initial_state(body, new.scene).R_world_body
        height = float(np.ptp((body.mesh_vertices @ R.T)[:, 2]))
        try:
            z = at_rest(body, new.params, R)[0] + 0.25 * height
        except sim.ConfigError:  # it sinks: drop it from just under the surface, and say so
            z = -0.5 * height
            note += " It is heavier than the water it displaces: it sinks."
        if new.params.forces != self.sim.params.forces:
            note += f" Force model: {new.params.forces} (exact on a mesh; the samples' midpoint rule would turn it slowly)."
        new.update(initial__position=(0.0, 0.0, z))
        new.reset()
        new.frame()  # what every publish asks of it: fails here, not on the next tick
        return new, note

    def _tell_changes(self, old: Settings) -> None:
        new = self.settings
        if (old.focus, old.config.bodies) != (new.focus, new.config.bodies):
            self._tell("bodies", (tuple(self.sim.body_names), new.focus))
        for key in CONTROLLED:
            if old.value(key) != new.value(key):
                self._tell(key, new.value(key))

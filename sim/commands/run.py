"""`python -m sim run`: a scene headless to CSV, with a progress bar. Its flags come from the parameter declarations."""

from __future__ import annotations

import dataclasses
import math
import shlex
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated

import numpy as np
import tyro

from sim.compile_estimate import compile_wall
from sim.compiling import cached, compile_all, default_backend
from sim.errors import WriteFailed
from sim.hydro.hydrostatics import describe_rest
from sim.hydro.radiation import misfit_note
from sim.io import netcdf
from sim.limits import MAX_HOURS, SETUP_NOTE_SECONDS, duration
from sim.scene.config import PARAMS, ConfigError, SceneConfig, available_scenes, load_scene, scene_cost, validate, with_overrides
from sim.scene.gauges import added
from sim.simulation import Simulation, SimulationDiverged

from . import FROM_SCENE, declared_flags, overrides
from .interrupt import CHECK_SECONDS, EXIT, StopOnCtrlC, stop_if_asked
from .output import LineFile, NetcdfFile
from .progress import progress_bar

STEP_SECONDS = 30.0
"""Wall time an adaptive method may spend on one output step before the run stops naming a better integrator."""
MAX_STEPS = 100_000_000
"""Most steps `run` takes unless asked for more (about 5 min compiled for the default cube; hours for a fine mesh)."""


@dataclass
class _RunBase:
    """Run a scene headless and write its trajectory to CSV. Flags override the scene."""

    scene: Annotated[
        str, tyro.conf.arg(metavar="NAME|FILE", help=f"Preset name ({', '.join(available_scenes())}) or path to a scene .toml.")
    ] = "drop"
    """Preset name or path to a scene .toml (the presets are listed in --help)."""
    z0: Annotated[float | None, tyro.conf.arg(metavar="FLOAT", help_behavior_hint=FROM_SCENE)] = None
    """Initial height of the centre of mass, m."""
    q0: Annotated[tuple[float, float, float, float] | None, tyro.conf.arg(metavar="QW QX QY QZ", help_behavior_hint=FROM_SCENE)] = None
    """Initial orientation, unit quaternion (scalar first; within 1e-3 of unit norm is normalised)."""
    u0: Annotated[tuple[float, float, float] | None, tyro.conf.arg(metavar="UX UY UZ", help_behavior_hint=FROM_SCENE)] = None
    """Initial velocity, world frame, m/s."""
    omega0: Annotated[tuple[float, float, float] | None, tyro.conf.arg(metavar="WX WY WZ", help_behavior_hint=FROM_SCENE)] = None
    """Initial angular velocity, world frame, rad/s."""
    every: int = 10
    """Write one CSV row every K steps."""
    out: Annotated[str | None, tyro.conf.arg(metavar="FILE", help_behavior_hint="(default: none, a summary only)")] = None
    """CSV file to write (written aside and renamed when done: a reader never sees half of it), or netCDF for a name
    ending in .nc (the same columns with their units and the scene in its attributes; the netcdf extra). An earlier
    run's file there is replaced, and the summary says so; another existing file only with --overwrite."""
    overwrite: bool = False
    """Replace an existing --out file that is not an earlier run's CSV or netCDF."""
    progress: Annotated[
        bool | None, tyro.conf.arg(metavar="{True,False}", help_behavior_hint="(default: only on a terminal, never under CI)")
    ] = None
    """Show a progress bar."""
    step_budget: float = STEP_SECONDS
    """Wall seconds an adaptive integrator (rk45, dop853, radau) may spend on one output step before the run stops, naming a better one."""
    max_steps: int = MAX_STEPS
    """Refuse a run of more steps than this (t_end / dt): a typo such as --dt 1e-30 would run for ever."""
    max_hours: float = MAX_HOURS
    """Refuse a run estimated to take longer than this on one core (its bodies' samples and degrees of freedom, its steps)."""
    gauge: Annotated[tuple[tuple[float, float], ...], tyro.conf.UseAppendAction, tyro.conf.arg(metavar="X Y")] = ()
    """A wave gauge at (X, Y), m, repeatable: a column eta_gN of the water's elevation there (besides the scene's [[gauges]])."""


RunArgs = declared_flags("RunArgs", _RunBase, PARAMS.values())


def scene_from_args(args: RunArgs) -> SceneConfig:
    """The scene file with every flag given applied on top, validated."""
    scene = load_scene(args.scene)
    position = scene.initial.position
    if args.z0 is not None:
        position = (position[0], position[1], args.z0)
    given = overrides(args, PARAMS.values())
    if given.get("body__mesh"):  # a path typed here is the shell's, not the scene file's folder's
        given["body__mesh"] = str(Path(given["body__mesh"]).expanduser().absolute())
    if args.gauge:
        scene = validate(dataclasses.replace(scene, gauges=added(scene.gauges, args.gauge)))
    return with_overrides(scene, **given, initial__position=position, initial__orientation=args.q0, initial__velocity=args.u0,
                          initial__omega=args.omega0)  # fmt: skip


def numpy_seconds(sim: Simulation, n_steps: int) -> float:
    """The numpy reference's wall time for n_steps of this scene, from a few steps of a copy."""
    probe = Simulation(sim.scene, backend="numpy")
    probe.step_seconds = sim.step_seconds
    try:
        probe.step(1)
        started = time.perf_counter()
        probe.step(3)
    except SimulationDiverged:  # the run stops as soon: no compile is worth it
        return 0.0
    finally:
        probe.close()
    return (time.perf_counter() - started) / 3 * n_steps


def announce_compile(sim: Simulation, n_steps: int) -> None:
    """The compiled kernels build once per machine (then load from the disk cache): say so before the wait.
    `sim` is built on the numpy reference: where its kernels are not built yet (kernels_ready), a run the numpy reference
    finishes before they would compile stays there, saying so; a longer one moves to the kernels, which compile first.
    Both times are measured on this machine now (sim/compile_estimate.py), so the choice does not follow its load."""

    if sim.has_twin and not sim.compiled and default_backend() == "numba":
        todo = [spec for spec in sim.specs if not cached(spec)]
        wait = compile_wall(todo) if todo else 0.0  # (its probe takes 60 ms: only when something is to compile)
        if todo and (estimate := numpy_seconds(sim, n_steps)) < wait:
            print(f"floatsim: note: the fast kernels for this scene are not compiled on this machine yet (about {wait:.0f} s here, once); "
                  f"this run takes about {max(estimate, 1):.0f} s on the numpy reference, so it runs there (a longer run, or "
                  "`python -m sim.commands.compile`, compiles them)", file=sys.stderr)  # fmt: skip
        else:
            if todo:  # say so before the wait, not after it
                print(f"floatsim: compiling the fast kernels for this scene ({'; '.join(spec.describe() for spec in todo)}), once for this "
                      f"machine (about {wait:.0f} s here; cached on disk afterwards)...", file=sys.stderr, flush=True)  # fmt: skip
            seconds = compile_all(sim.specs)
            sim.use_backend(default_backend())
            if seconds > 5.0:  # loading from the cache takes under a second; compiling, minutes
                print(f"floatsim: compiled the fast kernels in {seconds:.1f} s (cached on disk for next runs)", file=sys.stderr)
    for note in sim.notes:
        print(f"floatsim: note: {note}", file=sys.stderr)


SAMPLES_NOTE = "a mesh's triangles are split by halving every edge over a length, or kept one sample each when more"


def inertia_source(scene, body) -> str:
    """Where the body's inertia comes from, as the run's summary says it."""
    source = "as given" if scene.body.inertia is not None else "exact (mesh shell)" if body.exact_inertia else "of the samples"
    return source + (" about the given centre of mass" if scene.body.centre_of_mass is not None else "")


def describe_terms(sim: Simulation) -> str:
    """The terms in use with their declared parameters, e.g. 'gravity+pressure+damping(damping = 100 N s/m^3)'."""
    parts = []
    for term in sim.model.terms:
        values = ", ".join(f"{p.key} = {p.describe(getattr(sim.params, p.key))}" for p in term.params)
        parts.append(f"{term.name}({values})" if values else term.name)
    return "+".join(parts)


INPUTS = (".toml", ".stl", ".obj", ".ply", ".py", ".md")
"""Suffixes of files a run reads or a user keeps: never overwritten by an output flag."""


def written_by_run(path: Path) -> bool:
    """Whether a file is empty or holds a run's CSV (its header: t first, E_total among the columns): what rerunning a
    command over its own output replaces without asking."""
    try:
        with open(path, "rb") as f:
            head = f.read(65536)
    except OSError:
        return False
    first = head.split(b"\n", 1)[0].split(b",")
    netcdf_run = head.startswith(b"CDF") and (b"floatsim_scene" in head or b"floatsim_sweep" in head)  # (its attributes' names)
    return not head or netcdf_run or (first[0] == b"t" and any(c.endswith(b"E_total") for c in first))


def check_output(path: str | None, flag: str = "out", suffix: str | None = None, inputs: tuple = (), overwrite: bool = True) -> None:
    """Refuse, before any work, an output file that cannot be written, or that is one of the run's
    `inputs` (its scene or mesh file) or an existing file of an input's kind: one line naming why.
    Without `overwrite`, an existing file a run did not write is refused too (written_by_run)."""
    if path is None:
        return
    p = Path(path)
    if p.suffix.lower() == ".nc":
        netcdf.check_extra()
    if suffix and p.suffix.lower() != suffix:
        raise ConfigError(f"--{flag} must name a {suffix} file, got {path!r}")
    if any(p.resolve() == Path(i).resolve() for i in inputs if i):
        raise ConfigError(f"--{flag} {path}: that is this run's own input file; give another name (the run would overwrite it)")
    if p.is_file() and p.suffix.lower() in INPUTS:
        raise ConfigError(f"--{flag} {path}: an existing {p.suffix} file is not overwritten by an output; give another name")
    if p.is_dir():
        raise ConfigError(f"--{flag} {path}: is a folder, give a file name")
    if p.exists() and not p.is_file():
        raise ConfigError(f"--{flag} {path}: not a regular file")
    if p.is_file() and not overwrite and not written_by_run(p):
        raise ConfigError(f"--{flag} {path}: an existing file floatsim did not write; give --overwrite to replace it, or another name")
    if not p.parent.resolve().is_dir():
        raise ConfigError(f"--{flag} {path}: folder {str(p.parent)!r} does not exist")
    existed = p.exists()
    try:
        with open(p, "a"):
            pass
        if not existed:
            p.unlink()  # only a probe: a run refused later leaves no empty file behind
    except OSError as e:
        raise ConfigError(f"--{flag} {path}: cannot write there ({e.strerror})") from None


def run(args: RunArgs, watch=None) -> int:
    """`watch(sim)` (optional, with an int attribute `every`) also sees the run every `watch.every` steps
    and at the start: how the viewer's recorder takes its frames without sim knowing of it."""
    if args.every < 1:
        raise ConfigError(f"--every must be >= 1, got {args.every}")
    if not args.step_budget > 0:
        raise ConfigError(f"--step-budget must be > 0 s, got {args.step_budget}")
    if args.max_steps < 1:
        raise ConfigError(f"--max-steps must be >= 1, got {args.max_steps}")
    if not args.max_hours > 0:
        raise ConfigError(f"--max-hours must be > 0, got {args.max_hours}")
    check_output(args.out, inputs=(args.scene if Path(args.scene).is_file() else None, args.mesh), overwrite=args.overwrite)
    scene = scene_from_args(args)
    check_budget(scene, args)
    sim = Simulation(scene, backend="numpy")  # nothing compiles before we know the run needs it
    try:
        return _run(sim, args, watch)
    finally:
        sim.close()


def check_budget(scene: SceneConfig, args: RunArgs) -> None:
    """Refuse a run past its budgets (steps; estimated hours on one core), and announce a long set-up with its estimate,
    all before any body is built."""
    n_steps = max(0, round(scene.step.t_end / scene.step.dt))
    cost = scene_cost(scene)
    hours = (cost.setup_seconds + cost.step_seconds(n_steps)) / 3600
    if n_steps > args.max_steps:
        raise ConfigError(f"t_end / dt = {scene.step.t_end:g} s / {scene.step.dt:g} s is {n_steps:.3g} steps, more than --max-steps "
                          f"{args.max_steps:.3g} (about {hours:.3g} h on one core): give a larger --dt, or --max-steps to run it anyway")  # fmt: skip
    if hours > args.max_hours:
        raise ConfigError(f"{n_steps:,} steps of {cost.describe()} would take about {hours:.3g} h on one core, more than --max-hours "
                          f"{args.max_hours:g}: give a shorter --t-end, a larger --dt or fewer samples, or --max-hours to run it anyway")  # fmt: skip
    if cost.setup_seconds > SETUP_NOTE_SECONDS:
        print(f"floatsim: note: {cost.describe()}; Ctrl-C stops it", file=sys.stderr, flush=True)


def _run(sim: Simulation, args: RunArgs, watch=None) -> int:
    scene = sim.scene
    sim.step_seconds = args.step_budget  # an adaptive method stuck on one step stops with the viewer's message
    for warning in sim.warnings():
        print(f"floatsim: warning: {warning}", file=sys.stderr)
    n_steps = max(0, round(scene.step.t_end / sim.dt))
    stop_if_asked()  # a Ctrl-C during the set-up that a library swallowed (trimesh's imports): before the kernels load
    announce_compile(sim, n_steps)
    cost = scene_cost(scene)
    if (seconds := cost.step_seconds(n_steps)) > 600:
        print(f"floatsim: note: about {duration(seconds)} on one core ({cost.samples:,} samples x {n_steps:,} steps); "
              "Ctrl-C stops it keeping the rows so far", file=sys.stderr)  # fmt: skip
    first = sim.frame()
    started = time.perf_counter()
    error, rows, stepping, replaced = stream(sim, sim.columns(), args, n_steps, watch)
    if error in (WRITE_FAILED, INTERRUPTED):
        return 2 if error == WRITE_FAILED else EXIT
    for note in sim.validity_notes():
        print(f"floatsim: note: {note}", file=sys.stderr)
    wall = time.perf_counter() - started
    last = sim.frame()
    (summarise_bodies if scene.bodies else summarise)(sim, first, last)
    steps = round(last.t / sim.dt)
    print(
        speeds(steps, last.t, wall, stepping, rows if args.out else None, checked=not scene.bodies)
        + (f" -> {args.out}" if args.out else "")
        + (f" (replaced {replaced})" if replaced else "")
    )
    return 3 if error else 0


def summarise(sim: Simulation, first, last) -> None:
    """The summary of a one-body run: the body, its scheme and forces, its rest, where it ended, its joint and lines."""
    scene = sim.scene
    drift = last.E_total - first.E_total
    asked = (
        f" ({scene.body.samples} asked: {SAMPLES_NOTE})" if scene.body.shape == "mesh" and sim.body.n_samples != scene.body.samples else ""
    )
    print(f"scene {scene.name}: {sim.body.name} with {sim.body.n_samples} samples{asked}, mass {sim.body.mass:.6g} kg, "
          f"integrator {sim.integrator.name}, dt {sim.dt:g} s, forces {describe_terms(sim)}, "
          f"inertia {inertia_source(scene, sim.body)}")  # fmt: skip
    print(f"at rest: {describe_rest(sim.body, sim.params)}")

    if sim.model.radiation is not None and (note := misfit_note(sim.model.radiation.memory)):
        print(note)
    print(f"t = {last.t:.6g} s: z = {last.x_world[2]:.6f} m, |u| = {np.linalg.norm(last.u_world):.3g} m/s, "
          f"|F| = {np.linalg.norm(last.force_world):.3g} N, |L| = {np.linalg.norm(last.L_world):.6g} kg m^2/s, "
          f"E_total = {last.E_total:.6g} J (change {drift:+.3g} J)" + (f", E_rad = {last.E_rad:.6g} J radiated" if sim.model.radiation else ""))  # fmt: skip
    if sim.joint is not None:
        j = sim.joint
        print(f"joint: {j.kind} to the seabed, take-off k {j.stiffness:g}, c {j.damping:g}")
    if sim.model.radiation is not None and (drifting := sim.model.radiation.drift) is not None:
        Fx, Fy, Mz = drifting.mean
        held = " on the held body, what a model test measures" if sim.joint is not None and sim.joint.dofs == 0 else ""
        print(f"wave drift: mean Fx = {Fx:.6g} N, Fy = {Fy:.6g} N, Mz = {Mz:.6g} N m{held} (the sea at full height, Newman: "
              "sum a_i^2 D_i; in the CSV's Fx, Fy and Tz)")  # fmt: skip
    summarise_readings(first, last, last.E_total + last.E_pto - first.E_total - first.E_pto)


def summarise_readings(first, last, body_change: float) -> None:
    """What every scene's run reads at its end (system/frame.Readings): each joint's take-off, the mooring lines' pull and
    energy; body_change is the bodies' and take-offs' energy change over the run."""
    for name, theta, _, _, absorbed, *_ in last.joints:
        print(
            f"joint {name}: coordinate {theta:.6g}, take-off absorbed {absorbed:.6g} J ({absorbed / last.t if last.t > 0 else 0.0:.4g} W on average)"
        )
    if last.mooring:
        n = len(last.mooring) - 4
        print(f"moorings: {n} line{'s' if n != 1 else ''} (MoorDyn), pull now {np.linalg.norm(last.mooring[:3]):.4g} N, largest fairlead "
              f"tension {last.mooring[3]:.4g} N")  # fmt: skip
    if last.line_energy:
        print(line_energy_summary(first, last, body_change))


def line_energy_summary(first, last, body_change: float) -> str:
    """The energy balance of bodies and lines in a line: what the lines store and dissipated, and the sum's change."""
    (e0, _), (e1, d1) = first.line_energy, last.line_energy
    return (
        f"lines' energy: stored {e1 - e0:+.4g} J, dissipated {d1:.4g} J; bodies, take-offs and lines together {body_change + e1 - e0 + d1:+.3g} J "
        "(zero in still water without the bodies' damping, drag or radiation)"
    )


def summarise_bodies(sim: Simulation, first, last) -> None:
    """The summary of a run of several bodies: each body, the tree, how it was stepped, where each ended, each take-off."""
    system = sim.system
    names = ", ".join(f"{m.name} ({m.body.mass:.6g} kg, {m.body.n_samples} samples)" for m in system.members)
    print(f"scene {sim.scene.name}: {len(system.members)} bodies: {names}; {len(system.groups)} rigid groups, {system.n_dofs} degrees of freedom; "
          "{}, dt {:g} s; the bodies' loads {}".format(*how_stepped(sim)))  # fmt: skip

    if system.radiation is not None and (note := misfit_note(system.radiation.memory)):
        print(note)
    for b in last.bodies:
        print(f"t = {last.t:.6g} s: {b.name} at z = {b.x_world[2]:.6f} m, |u| = {np.linalg.norm(b.u_world):.3g} m/s")
    if system.radiation is not None and (drifting := system.radiation.wave_drift) is not None:
        Fx, Fy, Mz = drifting.mean
        source = (
            "the bem_file's mean drift, its run's body moving as it did there"
            if system.radiation.coefficients.mean_drift is not None
            else "the solve's far field"
        )
        print(f"wave drift: mean Fx = {Fx:.6g} N, Fy = {Fy:.6g} N, Mz = {Mz:.6g} N m on {system.members[system.radiation.drift_root].name} "
              f"(the sea at full height, Newman: sum a_i^2 D_i, from {source})")  # fmt: skip
    drift = (last.E_total + last.E_pto) - (first.E_total + first.E_pto)
    print(f"E_total = {last.E_total:.6g} J, with the take-offs' {last.E_pto:.6g} J: change {drift:+.3g} J")
    summarise_readings(first, last, drift)


def how_stepped(sim: Simulation) -> tuple[str, float, str]:
    """(the scheme, dt, where the bodies' loads come from), as a several-body summary says them."""
    loads = "linear" if sim.scene.fluid.hydro == "linear" else "compiled" if sim.compiled else "on the numpy reference"
    return "stepped exactly (a linear system)" if sim.exact is not None else "Stormer-Verlet", sim.dt, loads


def speeds(steps: int, t: float, wall: float, stepping: float, rows: int | None, checked: bool = True) -> str:
    """The summary's speed line: the whole run (its rows' frames and writes, the energy check after every batch of steps
    when `checked`, the progress bar) and the stepping alone, each as x real time. `python -m sim bench` times the
    stepping alone, in long batches (docs/performance.md)."""
    x = lambda seconds: f"{t / seconds:.3g}x real time" if seconds > 0 else "too fast to time"  # noqa: E731
    us = stepping / steps * 1e6 if steps else 0.0
    per = (f"{us:.3g}" if us < 1000 else f"{us:,.0f}") + " us a step, " if us > 0 else ""
    rest = (("the energy check after every batch of steps" + (" and writing the rows" if rows is not None else ""))
            if checked else "each row's frame and write" if rows is not None else "")  # fmt: skip
    return (f"{steps} steps in {wall:.3g} s wall: {x(wall)} for the whole run{f' with its {rows} rows' if rows is not None else ''}; "
            f"stepping alone {stepping:.3g} s ({per}{x(stepping)}{f'; the rest: {rest}' if rest else ''})")  # fmt: skip


INTERRUPTED = "interrupted"
WRITE_FAILED = "write failed"


def stream(sim, columns, args, n_steps: int, watch=None) -> tuple[str | None, int, float, str]:
    """Step `sim` (a Simulation, or anything with step, frame and state.t) to n_steps, writing `columns` and a row
    every args.every steps to args.out (if given), with a progress bar. (error, rows, stepping): error is the divergence
    message, INTERRUPTED after Ctrl-C or WRITE_FAILED (said here, with the rows kept), or None. `rows` counts the
    whole rows in the file: a write that fails (a full disk) cuts it back to the last of them. `stepping`: wall seconds
    spent stepping alone (in `sim.step`, less its energy check after each call), without the rows, the bar and the rest.
    `replaced`: what the file replaced under its name (LineFile.replaced)."""
    out = open_output(args.out, sim.scene) if args.out else None
    bar = progress_bar(n_steps, flag=args.progress)
    clock = [0.0]

    def write(frame):
        if out:
            out.row(frame.row())

    try:  # numpy's overflow warnings would only repeat what the divergence message says better
        if out:
            out.header(columns)
        write(sim.frame())
        if watch is not None:
            watch(sim)
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"), StopOnCtrlC() as stop:
            error = _advance(sim, n_steps, args.every, bar, write if out else None, watch, stop, clock)
        if out:
            out.close()  # the last rows reach the disk here: this can fail too
    except WriteFailed as e:
        print(f"floatsim: {e} ({kept_rows(out)})", file=sys.stderr)
        return WRITE_FAILED, data_rows(out), clock[0], out.replaced
    finally:
        bar.close()
        if out:
            out.abandon()
    if error == INTERRUPTED:
        said = f"kept {data_rows(out)} rows in {args.out}" if out else "nothing written"
        print(f"floatsim: interrupted (Ctrl-C) at t = {sim.state.t:.6g} s of {n_steps * sim.dt:g} s: {said}", file=sys.stderr)
    elif error:
        print(f"floatsim: {error}" + (f" (kept {data_rows(out)} rows)" if out else ""), file=sys.stderr)
    return error, data_rows(out), clock[0], out.replaced if out else ""


def open_output(path: str, scene) -> LineFile | NetcdfFile:
    """The run's output file: netCDF for a name ending in .nc (with the scene and the command in its attributes), else
    CSV."""
    if Path(path).suffix.lower() != ".nc":
        return LineFile(path)
    return NetcdfFile(path, dataclasses.asdict(scene), "floatsim " + shlex.join(sys.argv[1:]))


def data_rows(out: LineFile | NetcdfFile | None) -> int:
    """Whole rows of data in the file (its first line is the header)."""
    return max(out.lines - 1, 0) if out else 0


def kept_rows(out: LineFile | NetcdfFile) -> str:
    if isinstance(out, NetcdfFile) and not out.lines:
        return f"its {out.rows} rows were not written; the file under that name is as it was"
    if not out.lines:
        return "kept nothing: the file is empty"
    return f"kept the header and {data_rows(out)} whole rows; the file ends with the last of them"


class Pace:
    """An honest estimate of the time left, from the pace so far: said once the run has taken PACE_AFTER
    seconds and still needs more than a minute, then again every PACE_EVERY seconds (a stiff adaptive
    run or a 4096-component sea is slow in ways no estimate before the run can know)."""

    PACE_AFTER, PACE_EVERY = 10.0, 300.0

    def __init__(self, n_steps: int):
        self.n_steps, self.started, self.next = n_steps, time.perf_counter(), self.PACE_AFTER

    def tell(self, done: int) -> None:
        spent = time.perf_counter() - self.started
        if spent < self.next or done >= self.n_steps:
            return
        self.next = spent + self.PACE_EVERY
        left = spent / done * (self.n_steps - done)
        if left > 60.0:
            print(f"floatsim: note: {done:,} of {self.n_steps:,} steps in {spent:.0f} s: at this pace about {_duration(left)} more; "
                  "Ctrl-C stops it keeping the rows so far", file=sys.stderr, flush=True)  # fmt: skip


def _duration(seconds: float) -> str:
    return f"{seconds / 60:.0f} min" if seconds < 5400 else f"{seconds / 3600:.1f} h"


def _advance(sim: Simulation, n_steps: int, every: int, bar, write, watch=None, stop=None, clock=None) -> str | None:
    """Step to n_steps, writing a frame every `every` steps (and calling `watch` every `watch.every`);
    the divergence message if the run blows up, INTERRUPTED after Ctrl-C (checked every CHECK_SECONDS
    of stepping at most). clock[0] sums the seconds of stepping alone (sim.step less its energy check)."""
    done = 0
    chunk = every if watch is None else math.gcd(every, watch.every)
    per_step = None  # seconds, measured
    pace = Pace(n_steps)
    try:
        while done < n_steps:
            if stop is not None and stop.asked:
                return INTERRUPTED
            k = min(chunk - done % chunk, n_steps - done)
            k = min(k, 1 if per_step is None else max(1, int(CHECK_SECONDS / per_step)))  # the first step measures
            began = time.perf_counter()
            sim.step(k)
            spent = time.perf_counter() - began
            per_step = max(spent / k, 1e-9)
            if clock is not None:
                clock[0] += max(spent - getattr(sim, "check_seconds", 0.0), 0.0)
            done += k
            bar.update(k)
            pace.tell(done)
            if write is not None and (done % every == 0 or done == n_steps):
                write(sim.frame())
            if stop is not None and stop.asked:
                return INTERRUPTED
            if watch is not None and (done % watch.every == 0 or done == n_steps):
                watch(sim)
    except SimulationDiverged as e:
        return str(e)
    return None

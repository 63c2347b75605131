"""`floatsim bench`: cost per step of each model, resolution and integrator, compiled vs numpy, in one run."""

from __future__ import annotations

import dataclasses
import importlib.util
import os
import statistics
import sys
import time
from dataclasses import dataclass

import numpy as np

from sim.commands.startup import startup
from sim.compile_estimate import compile_seconds
from sim.compiling import cached, warm_up
from sim.ensemble import Ensemble
from sim.errors import ConfigError
from sim.scene.config import load_scene, with_overrides
from sim.simulation import Simulation
from sim.sweeps.backends import run
from sim.sweeps.grid import Sweep, case_scene, chunks, parse_param

from .interrupt import stop_if_asked
from .progress import progress_bar
from .tables import machine, table


@dataclass
class BenchArgs:
    """Median cost per step on one core, and its ratio to the plain-numpy reference measured in the same run."""

    scene: str = "damped"
    """Scene whose initial state is stepped (damped: the cube dropped on the water line, spinning, d = 100)."""
    sizes: tuple[int, ...] = (10, 50, 100)
    """Points per edge N to time (6 N^2 samples)."""
    integrators: tuple[str, ...] = ("euler", "splitting", "implicit", "rk4")
    """Fixed-step integrators to time."""
    repeats: int = 5
    """Timed runs per cell; the median is reported."""
    budget: float = 0.05
    """Seconds of stepping per timed run (the step count adapts to it)."""
    ensemble: int = 100
    """Bodies in the ensemble row (0 to skip)."""
    radiation: bool = True
    """Also time each fixed-step integrator with radiation (added mass and memory, the cube's shipped coefficients) against without."""
    sweep_cases: int = 10_000
    """Cases in the sweep rows (0 to skip): the default cube over 100 densities x 100 orientations, 2 s each, on each backend."""
    waves: bool = True
    """Also time the sea states (still, a regular wave, a 64-component JONSWAP sea with and without drag) on
    both models, against the direct sum over components and the numpy reference."""
    moorings: bool = True
    """Also time the moored-buoy preset (3 lines x 20 segments on MoorDyn, a 64-component sea, radiation and diffraction):
    with its lines against without, and the split between the body's step and MoorDyn (needs the .[moorings] extra)."""
    systems: bool = True
    """Also time the rm3 preset (two bodies on slides, radiation 12 x 12 with the memory coupling them, diffraction) as
    shipped and in a 64-component sea at dt = 0.01 s, numpy and compiled, and the split between the bodies' loads
    (hydrodynamics), the radiation and the joints' stepping."""
    startup: bool = False
    """Instead of the above: how long `python -m sim run --scene NAME --t-end 1` takes in a fresh process from an
    empty kernel cache (a first run on a machine) and from the cache it left, for each preset (minutes each, cold)."""
    presets: tuple[str, ...] = ()
    """With --startup: the presets to time (all when empty)."""
    quick: bool = False
    """Only the first table at N = 10 (every model and integrator), in seconds: --sizes 10 --repeats 3 --ensemble 0
    --no-radiation --no-waves --no-moorings --no-systems --sweep-cases 0. Without it every table takes minutes."""


FULL_MINUTES = 6
"""Wall minutes of every table with the kernels compiled, on this project's 2-core machine when nothing else runs
(issue 39; 15.6 min measured with a load of 7-9 from other work: docs/performance.md)."""
QUICK_SECONDS = 10
"""Wall seconds of --quick there (9.2 s measured with the load of 7)."""


def announce(args: BenchArgs, base, cells) -> None:
    """Say, before the first row, how long the run takes and how to cut it: the whole benchmark is minutes of silence
    but for its progress bar. Kernels not compiled on this machine yet add their compile (counted for the first table)."""

    scenes = [
        with_overrides(base, fluid__forces=f, step__integrator=i, body__points_per_edge=n or base.body.points_per_edge) for f, n, i in cells
    ]
    missing = {spec for spec in (Simulation(scene, backend="numpy").spec for scene in scenes) if not cached(spec)}
    extra = (
        f"; first {len(missing)} of its kernels compile (about {compile_seconds(missing):.0f} s here, once for this machine)"
        if missing
        else ""
    )
    said = (f"the first table at N = 10 only (--quick): about {QUICK_SECONDS} s" if args.quick else
            f"every table, about {FULL_MINUTES} min on a free 2-core machine (longer on a busy one)" if args.ensemble and args.radiation and args.waves and args.moorings
            and args.systems and args.sweep_cases else f"the tables asked (every table: about {FULL_MINUTES} min on a free 2-core machine)")  # fmt: skip
    hint = "" if args.quick else f"; --quick: the first table at N = 10 in about {QUICK_SECONDS} s; --help: each table's switch"
    print(f"bench: {said} with the kernels compiled{extra}{hint}", file=sys.stderr, flush=True)


def _median_step_seconds(sim: Simulation, repeats: int, budget: float) -> float:
    stop_if_asked()  # a Ctrl-C a library swallowed while this case set up (trimesh's imports): before its timed steps
    start = sim.state
    sim.step(1)
    t0 = time.perf_counter()
    sim.step(1)
    one = max(time.perf_counter() - t0, 1e-7)
    n = max(1, int(budget / one))
    costs = []
    for _ in range(repeats):
        sim.reset(start)
        t0 = time.perf_counter()
        sim.step(n)
        costs.append((time.perf_counter() - t0) / n)
    return statistics.median(costs)


def bench(args: BenchArgs) -> int:
    if args.startup:
        return startup(args.presets, 1.0)

    if args.quick:
        args = dataclasses.replace(args, sizes=(10,), repeats=min(args.repeats, 3), ensemble=0, radiation=False, waves=False, moorings=False,
                                   systems=False, sweep_cases=0)  # fmt: skip
    compile_s = 0.0
    base = load_scene(args.scene)
    if base.bodies:  # the first tables time one body's samples and schemes; several bodies have their own rows
        raise ConfigError(f"bench --scene times one body's step (its samples and integrators): scene {args.scene!r} has several bodies; "
                          "their rows are the table `--systems` prints (rm3, rm3-moored)")  # fmt: skip
    cells = ([("points", n, name) for n in args.sizes for name in args.integrators] + [("cells", n, "implicit") for n in args.sizes]
             + [("panels", 0, name) for name in args.integrators])  # fmt: skip
    announce(args, base, cells)
    bar = progress_bar(len(cells) + (len(args.integrators) if args.ensemble else 0) + (2 if args.waves else 0), unit="cell")
    rows = []
    for forces, n, name in cells:
        scene = with_overrides(base, fluid__forces=forces, step__integrator=name, body__points_per_edge=n or base.body.points_per_edge)
        fast = Simulation(scene, backend="numba")
        ref = Simulation(scene, backend="numpy")
        compile_s += warm_up(fast.spec) if fast.compiled else 0.0
        t_fast = _median_step_seconds(fast, args.repeats, args.budget)
        t_ref = _median_step_seconds(ref, max(1, args.repeats // 2), args.budget)
        samples = fast.body.n_samples
        sampled = forces != "panels"
        per = f"{t_fast * 1e9 / samples:.2f}" if sampled else f"{t_fast * 1e9 / len(fast.body.mesh_faces):.0f} / triangle"
        rows.append((forces, str(samples) if sampled else f"{len(fast.body.mesh_faces)} triangles", name,
                     f"{t_fast * 1e6:.2f}", per, f"{fast.dt / t_fast:.0f}", f"{t_ref * 1e6:.0f}", f"{t_ref / t_fast:.0f}"))  # fmt: skip
        bar.update()
    ens_rows = []
    if args.ensemble:
        for name in args.integrators:
            scenes = [with_overrides(base, step__integrator=name, body__density=float(v)) for v in np.linspace(300, 1500, args.ensemble)]
            ens = Ensemble(scenes)
            ens.step(1)
            costs = []
            for _ in range(args.repeats):
                t0 = time.perf_counter()
                ens.step(100)
                costs.append(time.perf_counter() - t0)
            ens_rows.append((name, f"{args.ensemble * 100 / statistics.median(costs):,.0f}"))
            bar.update()
    radiation_rows = _radiation_rows(base, args) if args.radiation else []
    wave_rows = _wave_rows(base, args, bar) if args.waves else []
    mooring_rows = _mooring_rows(args) if args.moorings else []
    system_rows = _system_rows(args) if args.systems else []
    bar.close()
    sweep_rows = _sweep_rows(args.sweep_cases) if args.sweep_cases else []
    print(f"machine: {machine()}; OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}")
    print(
        f"scene {base.name} (d = {base.fluid.damping:g} N s/m^3, dt = {base.step.dt:g} s); kernels compiled or loaded in {compile_s:.2f} s; medians of {args.repeats} runs"
    )
    table(("model", "samples", "integrator", "us/step", "ns/sample", "x real time", "numpy us/step", "speed-up"), rows)
    if ens_rows:
        table((f"ensemble of {args.ensemble} cubes, N = {base.body.points_per_edge}, densities 300-1500", "body-steps/s"), ens_rows)
    if radiation_rows:
        table(("radiation (N = 10)", "model", "integrator", "us/step without", "us/step with", "with / without"), radiation_rows)
    if sweep_rows:
        print()
        print(f"sweep of {args.sweep_cases} cases (damped cube, N = 10, implicit, dt 0.005 s, 2 s each, chunks of 64; no files); "
              "startup: until the first chunk starts (workers, kernels); idle: the rest of the wall time not spent computing chunks, "
              "over all workers; scheduling: the same without the workers' wait at the end for the last chunk")  # fmt: skip
        table(
            (
                "backend",
                "workers",
                "wall s",
                "startup s",
                "body-steps/s",
                "per core",
                "vs serial",
                "idle",
                "scheduling",
                "simulated h per core-h",
            ),
            sweep_rows,
        )
    if wave_rows:
        print()
        print(
            f"sea states, implicit, dt = {base.step.dt:g} s; direct sum: the kernels summing every component at every node (no expansion)"
        )
        table(("sea", "model", "us/step", "vs still water", "direct sum us/step", "direct / this", "numpy us/step"), wave_rows)
    if mooring_rows:
        print()
        print(
            "the moored-buoy preset (compiled, implicit, dt = 0.01 s): the body's step with and without its lines, and where a moored step's time goes"
        )
        table(("case", "us/step", "x real time", "body (hydrodynamics) us", "MoorDyn us", "coupling us"), mooring_rows)
    if system_rows:
        print()
        print("several bodies: the rm3 preset's step (radiation 12 x 12 with the memory coupling both bodies, diffraction, a take-off) and where "
              "its time goes; loads: the bodies' (numpy, compiled or linear), step: the kinematics, kicks, radiation memory and take-offs "
              "(numpy, or the compiled system step: kernels/system.py); vs numpy: against the case's all-numpy row in this run; direct sum: "
              "every component summed at every node instead of each part's series (the exact wet surface's cost before issue 41)")  # fmt: skip
        table(
            (
                "case",
                "loads",
                "step",
                "us/step",
                "x real time",
                "vs numpy",
                "hydrodynamics us",
                "ns per triangle x component",
                "radiation us",
                "MoorDyn us",
                "joints and stepping us",
            ),
            system_rows,
        )
    return 0


def _sweep_rows(cases: int) -> list[tuple[str, ...]]:
    """One sweep on each backend: throughput, its ratio to one core, and the share of wall time lost to scheduling."""

    side = max(1, round(cases**0.5))
    spec = Sweep("damped", (parse_param(f"density=300:1500:{side}"), parse_param(f"orientation_seed=0:{max(0, cases // side - 1)}:{cases // side}")),
                 (("step__t_end", 2.0),), chunk=64)  # fmt: skip
    base = spec.base()
    plan = list(enumerate(chunks(spec, [case_scene(base, c) for c in spec.cases()])))
    n = len(spec.cases())
    steps = n * round(2.0 / base.step.dt)
    rows, serial = [], None
    for backend, workers in (("serial", 1), ("local", os.cpu_count() or 1), ("dask", os.cpu_count() or 1)):
        started = time.perf_counter()
        stats = run(spec, plan, lambda *_: None, backend, workers)
        wall = time.perf_counter() - started
        serial = serial or wall
        running = wall - stats["startup"]
        # the last chunks: each worker's final result, after which it had nothing left to do
        tail = sum(wall - t for t in sorted(stats["finished"])[-workers:])
        sched = max(0.0, 1 - stats["busy"] / (workers * running - tail))
        rows.append((backend, str(workers), f"{wall:.2f}", f"{stats['startup']:.2f}", f"{steps / wall:,.0f}", f"{steps / wall / workers:,.0f}",
                     f"{serial / wall:.2f}x", f"{max(0.0, 1 - stats['busy'] / (workers * running)):.1%}", f"{sched:.2%}",
                     f"{n * 2.0 / (wall * workers):,.0f}"))  # fmt: skip
    return rows


def _mooring_rows(args: BenchArgs) -> list[tuple[str, ...]]:
    """The moored buoy with and without its lines; the moored step split into MoorDyn's part (timed inside
    moorings.advance), the body's own step (the unmoored cost) and the rest (the per-step coupling)."""

    base = load_scene("moored-buoy")
    try:
        moored = Simulation(base)
    except ConfigError as e:  # no MoorDyn here
        print(f"moorings: skipped ({e})")
        return []
    free = Simulation(with_overrides(base, moorings__lines=0))
    body = _median_step_seconds(free, args.repeats, args.budget)
    moored.step(1)
    moored.moorings.seconds = 0.0
    steps = max(1, int(args.budget / body))
    costs, lines = [], []
    for _ in range(args.repeats):
        before = moored.moorings.seconds
        t0 = time.perf_counter()
        moored.step(steps)
        costs.append((time.perf_counter() - t0) / steps)
        lines.append((moored.moorings.seconds - before) / steps)
    cost, line = statistics.median(costs), statistics.median(lines)
    dt = moored.dt
    return [("without lines", f"{body * 1e6:.0f}", f"{dt / body:.0f}", f"{body * 1e6:.0f}", "-", "-"),
            (f"{len(moored.moorings.lines())} lines x {base.moorings.segments} segments", f"{cost * 1e6:.0f}", f"{dt / cost:.0f}",
             f"{body * 1e6:.0f}", f"{line * 1e6:.0f}", f"{(cost - body - line) * 1e6:.0f}")]  # fmt: skip


def _system_rows(args: BenchArgs) -> list[tuple[str, ...]]:
    """The rm3 preset's step, as shipped (regular waves, dt 0.05 s) and in a 64-component sea at dt 0.01 s, on the numpy
    reference and with the bodies' loads compiled; split by timing its parts in place: each body's loads
    (hydrodynamics), the radiation memory and diffraction (radiation), and the rest (kinematics, the kicks'
    matrix exponentials)."""

    preset = load_scene("rm3")
    sea = with_overrides(preset, waves__kind="jonswap", waves__height=2.5, waves__period=8.0, waves__components=64, step__dt=0.01)
    cases = [("rm3, regular waves, dt 0.05 s", preset), ("rm3, JONSWAP, 64 components, dt 0.01 s", sea)]
    if importlib.util.find_spec("moordyn") is not None:
        cases.append(("rm3-moored (planar spar, 3 chains x 20 segments), dt 0.05 s", load_scene("rm3-moored")))
    linear = with_overrides(sea, fluid__hydro="linear")  # on slides: a linear system, stepped exactly
    spar = linear.bodies[0]
    planar = dataclasses.replace(spar, constraint=dataclasses.replace(spar.constraint, joint="planar", axis=(0.0, 1.0, 0.0)))
    planar_scene = dataclasses.replace(linear, bodies=(planar, *linear.bodies[1:]))
    latching = with_overrides(planar_scene, float__controller="latching", float__latch_time=1.0)  # a controller: a call back a step
    cases += [("rm3, JONSWAP, 64 components, dt 0.01 s", linear),
              ("rm3 (planar spar), JONSWAP, 64 components, dt 0.01 s", planar_scene),
              ("rm3 (planar spar), latching float, JONSWAP, 64 components, dt 0.01 s", latching)]  # fmt: skip
    rows = []
    for label, scene in cases:
        linear = scene.fluid.hydro == "linear"
        reference = None
        variants = ((True, True, True),) if linear else ((True, False, True), (True, True, False), (True, True, True))
        for loads_on, step_on, expand in ((False, False, True),) + variants:
            run = Simulation(scene, backend="numpy")
            if loads_on:
                run.use_backend("numba")  # the bodies' compiled loads and the compiled step
                run.stepper = run.stepper if step_on else None
                run.system.use_kernels(True, expand=expand)
            t, h, r, m = _system_split(run, args.repeats)
            run.close()
            reference = reference or t
            loads = ("linear, exact step" if run.exact else "linear") if linear else "compiled" if run.compiled else "numpy"
            loads += "" if expand or not run.compiled else " (direct sum)"
            step = "exact" if run.exact else "compiled" if run.stepper is not None else "numpy"
            inside = run.stepper is not None  # the radiation runs inside the compiled step (and the linear loads too)
            components = len(getattr(run.water, "omega", ()))  # the hydrodynamics' cost per triangle and wave component
            cost = h / (sum(len(b.mesh_faces) for b in run.bodies) * components) if components and not linear else 0.0
            rows.append((label, loads, step, f"{t * 1e6:.0f}", f"{run.dt / t:.1f}", f"{reference / t:.1f}x",
                         "in step" if inside and linear else f"{h * 1e6:.0f}", f"{cost * 1e9:.1f}" if cost else "-",
                         "in step" if inside else f"{r * 1e6:.0f}", f"{m * 1e6:.0f}" if run.moorings else "-",
                         f"{(t - h - r - m) * 1e6:.0f}"))  # fmt: skip
            if run.exact:
                break
    return rows


def _system_split(run, repeats: int) -> tuple[float, float, float, float]:
    """Median seconds a step, and of it in the bodies' loads, in the radiation and in MoorDyn."""
    system = run.system
    spent = {"hydro": 0.0, "radiation": 0.0}

    def timed(fn, key):
        def wrapper(*a, **k):
            t0 = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                spent[key] += time.perf_counter() - t0

        return wrapper

    system.loads = [timed(loads, "hydro") for loads in system.loads]
    rad = system.radiation
    rad.drift, rad.load = timed(rad.drift, "radiation"), timed(rad.load, "radiation")
    run.step(5)
    lines = lambda: run.moorings.seconds if run.moorings else 0.0  # noqa: E731
    totals, hydro, radiation, moordyn = [], [], [], []
    for _ in range(repeats):
        before, h0, r0, m0 = time.perf_counter(), spent["hydro"], spent["radiation"], lines()
        run.step(40)
        totals.append((time.perf_counter() - before) / 40)
        hydro.append((spent["hydro"] - h0) / 40)
        radiation.append((spent["radiation"] - r0) / 40)
        moordyn.append((lines() - m0) / 40)
    return statistics.median(totals), statistics.median(hydro), statistics.median(radiation), statistics.median(moordyn)


def _radiation_rows(base, args: BenchArgs) -> list[tuple[str, ...]]:
    """Cost per step with radiation = 'bem' against without, each integrator and model, in the same run."""
    rows = []
    for forces in ("points", "panels"):
        for name in args.integrators:
            scene = with_overrides(base, fluid__forces=forces, step__integrator=name, body__points_per_edge=10)
            off = _median_step_seconds(Simulation(scene), args.repeats, args.budget)
            on = _median_step_seconds(Simulation(with_overrides(scene, fluid__radiation="bem")), args.repeats, args.budget)
            rows.append(("cube at rest, 10 fitted entries", forces, name, f"{off * 1e6:.2f}", f"{on * 1e6:.2f}", f"{on / off:.2f}x"))
    return rows


SEAS = (("still", {}), ("regular (H 0.5 m, T 6 s)", {"waves__kind": "regular", "waves__height": 0.5, "waves__period": 6.0}),
        ("JONSWAP, 64 components", {"waves__kind": "jonswap", "waves__hs": 3.0, "waves__tp": 9.0, "waves__components": 64}),
        ("JONSWAP, 64 components, C_d 1 (storm)", {"waves__kind": "jonswap", "waves__hs": 3.0, "waves__tp": 9.0, "waves__components": 64,
                                                   "fluid__drag_coefficient": 1.0}))  # fmt: skip


def _wave_rows(base, args: BenchArgs, bar) -> list[tuple[str, ...]]:
    """Cost per step of each sea state on both models (N = 10 samples a side), its ratio to still water,
    and to the direct sum over components and the numpy reference, all in the same run."""
    rows = []
    for forces in ("points", "panels"):
        still = None
        for label, changes in SEAS:
            scene = with_overrides(base, fluid__forces=forces, step__integrator="implicit", body__points_per_edge=10, **changes)
            sim = Simulation(scene)
            direct = Simulation(scene)
            direct.expand_waves = False
            ref = Simulation(scene, backend="numpy")
            cost = _median_step_seconds(sim, args.repeats, args.budget)
            cost_direct = _median_step_seconds(direct, args.repeats, args.budget)
            cost_ref = _median_step_seconds(ref, max(1, args.repeats // 2), args.budget)
            still = still or cost
            rows.append((label, forces, f"{cost * 1e6:.1f}", f"{cost / still:.1f}x", f"{cost_direct * 1e6:.1f}", f"{cost_direct / cost:.1f}x",
                         f"{cost_ref * 1e6:.0f}"))  # fmt: skip
        bar.update()
    return rows

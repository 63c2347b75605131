"""`python -m sim compare`: error against cost of each integrator on a scene, versus a tight DOP853 reference, with
each integrator's observed order beside its declared one, the reference's own error (the floor under the errors) and
whether the scene's forces are smooth enough for the orders to show."""

from __future__ import annotations

import math
import statistics
import sys
import time
from dataclasses import dataclass
from typing import Annotated

import numpy as np
import tyro

from sim.dynamics.integrators import INTEGRATORS
from sim.errors import ConfigError
from sim.scene.config import PARAMS, load_scene, with_overrides
from sim.simulation import Simulation

from . import FROM_SCENE, declared_flags, overrides
from .interrupt import stop_if_asked
from .progress import progress_bar

REFERENCE_RTOL = 1e-11
"""The DOP853 reference's tolerance; a second run at 10x it measures the reference's own error."""
FLOOR_FACTOR = 10.0
"""An error under this many times the reference's own error gives no observed order (the reference's error is in it)."""


@dataclass
class _CompareBase:
    """Error at t_end (max over position and orientation, vs DOP853 at rtol 1e-11) against wall time per simulated
    second, and each integrator's observed order (the slope of log error against log dt) beside its declared one.
    Flags override the scene."""

    scene: str = "damped"
    """Preset name or path to a scene .toml."""
    t_end: float = 5.0
    """Simulated duration, s."""
    dts: tuple[float, ...] = (0.02, 0.01, 0.005)
    """Time steps to try, s (largest first: each row's order is measured against the row above)."""
    integrators: tuple[str, ...] = ("euler", "splitting", "implicit", "rk4")
    """Fixed-step integrators to compare."""
    repeats: int = 3
    """Timing repeats (the median is reported)."""
    z0: Annotated[float | None, tyro.conf.arg(metavar="FLOAT", help_behavior_hint=FROM_SCENE)] = None
    """Initial height of the centre of mass, m."""
    q0: Annotated[tuple[float, float, float, float] | None, tyro.conf.arg(metavar="QW QX QY QZ", help_behavior_hint=FROM_SCENE)] = None
    """Initial orientation, unit quaternion (scalar first)."""
    u0: Annotated[tuple[float, float, float] | None, tyro.conf.arg(metavar="UX UY UZ", help_behavior_hint=FROM_SCENE)] = None
    """Initial velocity, world frame, m/s."""
    omega0: Annotated[tuple[float, float, float] | None, tyro.conf.arg(metavar="WX WY WZ", help_behavior_hint=FROM_SCENE)] = None
    """Initial angular velocity, world frame, rad/s."""


SCENE_FLAGS = [p for p in PARAMS.values() if p.section != "step"]
"""Every scene parameter is a flag of compare too, except the step's (compare chooses the integrators, steps and duration)."""
CompareArgs = declared_flags("CompareArgs", _CompareBase, SCENE_FLAGS)


def scene_from_args(args: CompareArgs):
    """The scene file with every flag given applied on top, over args.t_end."""
    scene = load_scene(args.scene)
    if scene.bodies:  # its integrators and their orders are one body's (several bodies step by their own scheme)
        raise ConfigError(f"compare runs one body under each integrator: scene {args.scene!r} has several bodies, which step by their "
                          "own scheme (Stormer-Verlet; python -m sim run --scene NAME --dt DT to see its convergence)")  # fmt: skip
    position = scene.initial.position
    if args.z0 is not None:
        position = (position[0], position[1], args.z0)
    return with_overrides(scene, **overrides(args, SCENE_FLAGS), initial__position=position, initial__orientation=args.q0,
                          initial__velocity=args.u0, initial__omega=args.omega0, step__t_end=args.t_end)  # fmt: skip


def pose_vector(sim: Simulation) -> np.ndarray:
    q = sim.state.q_world_body
    return np.concatenate([sim.state.x_world, q * np.sign(q[0])])


def timed_run(scene, repeats: int = 1) -> tuple[np.ndarray, float]:
    """Final pose and median wall seconds per simulated second."""
    costs = []
    for _ in range(repeats):
        stop_if_asked()  # a Ctrl-C a library swallowed while the last one set up (trimesh's imports): before minutes of steps
        sim = Simulation(scene)
        stop_if_asked()
        start = time.perf_counter()
        sim.step(steps(scene.step.t_end, sim.dt))
        costs.append((time.perf_counter() - start) / scene.step.t_end)
    return pose_vector(sim), statistics.median(costs)


def kink_nodes(sim: Simulation) -> tuple[np.ndarray, str]:
    """The body-frame points whose crossing of the water line makes the force model's loads not smooth in time, and
    their name: the samples (points: the wet set changes), the cells' corners (cells) or the mesh's vertices (panels)."""
    body, forces = sim.body, sim.scene.fluid.forces
    if forces == "points":
        return body.r_body, "samples"
    if forces == "cells":
        return np.unique(body.cell_corners.reshape(-1, 3), axis=0), "cell corners"
    return body.mesh_vertices, "mesh vertices"


def water_line_crossings(scene, integrator: str, dt: float) -> tuple[int, str]:
    """How many times the scene's kink nodes cross the water surface over the run (counted step by step along a
    fixed-step run), and their name."""
    sim = Simulation(with_overrides(scene, step__integrator=integrator, step__dt=dt))
    if not sim.model.needs_wet:
        return 0, "nodes"
    nodes, name = kink_nodes(sim)

    def wet() -> np.ndarray:
        s = sim.state
        return sim.model.water.height_above_surface(s.x_world + nodes @ s.R_world_body.T, s.t) < 0.0

    before, count = wet(), 0
    for _ in range(steps(scene.step.t_end, dt)):
        sim.step(1)
        after = wet()
        count += int(np.count_nonzero(after != before))
        before = after
    return count, name


def smoothness_note(scene, crossings: int, nodes: str, t_end: float) -> str | None:
    """One line saying why the observed orders may fall short of the declared ones, or None on a smooth scene."""
    if not crossings:
        return None
    fluid = scene.fluid
    where = f"not smooth: {crossings} crossings of the water line by the {nodes} in {t_end:g} s"
    jumping = [name for name, on in (("damping", fluid.damping > 0), ("drag", fluid.drag_coefficient > 0)) if on]
    if fluid.forces == "points" and jumping:
        return (f"{where}, and the {' and '.join(jumping)} force jumps at each (a sample is wet or not): a step across one errs "
                f"O(dt), so every order falls towards 1 and scatters; --forces cells or panels is continuous")  # fmt: skip
    return (f"{where}, and the forces' slope jumps at each ({fluid.forces} model): an order above 2 falls towards 2 where "
            f"those errors dominate")  # fmt: skip


def observed_orders(rows: list[tuple[str, float, float, float]], floor: float) -> list[float | None]:
    """Each row's slope of log error against log dt from the row above (same integrator); None for an integrator's
    first row and where either error is under FLOOR_FACTOR times the reference's own error."""
    orders: list[float | None] = []
    for i, (name, dt, err, _) in enumerate(rows):
        above = rows[i - 1] if i and rows[i - 1][0] == name else None
        if above is None or min(err, above[2]) <= FLOOR_FACTOR * floor or err <= 0.0:
            orders.append(None)
        else:
            orders.append(math.log(above[2] / err) / math.log(above[1] / dt))
    return orders


def steps(t_end: float, dt: float) -> int:
    """The whole number of steps of dt that reach t_end, where the errors are measured (ConfigError if there is none)."""
    n = round(t_end / dt)
    if n < 1 or abs(n * dt - t_end) > 1e-9 * t_end:
        raise ConfigError(f"compare: dt {dt:g} does not divide t_end {t_end:g} (each run's error is measured at t_end)")
    return n


def compare(args: CompareArgs) -> int:
    base = scene_from_args(args)
    for dt in args.dts:
        steps(args.t_end, dt)
    every = args.t_end / max(1, round(args.t_end / 0.05))  # the reference's output interval (its steps are its own)
    jobs = [(name, dt) for name in args.integrators for dt in args.dts]
    print(f"compare: two DOP853 references, then {len(jobs)} runs of '{base.name}' over {args.t_end:g} s...", file=sys.stderr, flush=True)
    bar = progress_bar(len(jobs) + 3, unit="run")
    references = []
    for rtol in (REFERENCE_RTOL, 10 * REFERENCE_RTOL):
        pose, _ = timed_run(with_overrides(base, step__integrator="dop853", step__dt=every, step__rtol=rtol, step__atol=rtol * 1e-2))
        references.append(pose)
        bar.update()
    reference, floor = references[0], float(np.abs(references[1] - references[0]).max())
    most = max(args.integrators, key=lambda name: INTEGRATORS[name].order)  # the closest to the reference
    crossings, nodes = water_line_crossings(base, most, min(args.dts))
    bar.update()
    rows = []
    for name, dt in jobs:
        pose, cost = timed_run(with_overrides(base, step__integrator=name, step__dt=dt), args.repeats)
        rows.append((name, dt, float(np.abs(pose - reference).max()), cost))
        bar.update()
    bar.close()
    print(
        f"scene {base.name}, t_end {args.t_end:g} s, error = max |pose - DOP853 reference| at t_end, observed order = slope of log error "
        "against log dt from the row above, cost = median wall ms per simulated s"
    )
    print("| integrator | declared order | dt (s) | error (m) | observed order | cost (ms/s) |")
    print("|---|---|---|---|---|---|")
    for (name, dt, err, cost), order in zip(rows, observed_orders(rows, floor)):
        shown = f"{order:.2f}" if order is not None else ("floor" if err <= FLOOR_FACTOR * floor else "")
        print(f"| {name} | {INTEGRATORS[name].order} | {dt:g} | {err:.2e} | {shown} | {cost * 1e3:.3g} |")
    print(
        f"reference floor {floor:.1e} m (the DOP853 reference at rtol {REFERENCE_RTOL:g} against one at {10 * REFERENCE_RTOL:g}): "
        f"an error under {FLOOR_FACTOR:g}x it gives no order ('floor')"
    )
    note = smoothness_note(base, crossings, nodes, args.t_end)
    print(note or f"smooth: no {nodes} crossed the water line, so each order should match its declared one above the floor")
    return 0

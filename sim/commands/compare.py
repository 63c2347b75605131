"""`python -m sim compare`: error against cost of each integrator on a scene, versus a tight DOP853 reference."""

from __future__ import annotations

import statistics
import sys
import time
from dataclasses import dataclass

import numpy as np

from ..config import load_scene, with_overrides
from ..simulation import Simulation
from .progress import progress_bar


@dataclass
class CompareArgs:
    """Error at t_end (max over position and orientation, vs DOP853 at rtol 1e-11) against wall time per simulated second."""

    scene: str = "damped"
    """Preset name or path to a scene .toml."""
    t_end: float = 5.0
    """Simulated duration, s."""
    dts: tuple[float, ...] = (0.02, 0.01, 0.005)
    """Time steps to try, s."""
    integrators: tuple[str, ...] = ("euler", "splitting", "implicit", "rk4")
    """Fixed-step integrators to compare."""
    repeats: int = 3
    """Timing repeats (the median is reported)."""


def pose_vector(sim: Simulation) -> np.ndarray:
    q = sim.state.q_world_body
    return np.concatenate([sim.state.x_world, q * np.sign(q[0])])


def timed_run(scene, repeats: int = 1) -> tuple[np.ndarray, float]:
    """Final pose and median wall seconds per simulated second."""
    costs = []
    for _ in range(repeats):
        sim = Simulation(scene)
        start = time.perf_counter()
        sim.step(round(scene.step.t_end / sim.dt))
        costs.append((time.perf_counter() - start) / scene.step.t_end)
    return pose_vector(sim), statistics.median(costs)


def compare(args: CompareArgs) -> int:
    base = with_overrides(load_scene(args.scene), step__t_end=args.t_end)
    jobs = [(name, dt) for name in args.integrators for dt in args.dts]
    print(f"compare: a DOP853 reference, then {len(jobs)} runs of '{base.name}' over {args.t_end:g} s...", file=sys.stderr, flush=True)
    bar = progress_bar(len(jobs) + 1, unit="run")
    reference, _ = timed_run(with_overrides(base, step__integrator="dop853", step__dt=0.05, step__rtol=1e-11, step__atol=1e-13))
    bar.update()
    rows = []
    for name, dt in jobs:
        pose, cost = timed_run(with_overrides(base, step__integrator=name, step__dt=dt), args.repeats)
        rows.append((name, dt, float(np.abs(pose - reference).max()), cost))
        bar.update()
    bar.close()
    print(
        f"scene {base.name}, t_end {args.t_end:g} s, error = max |pose - DOP853 reference| at t_end, cost = median wall ms per simulated s"
    )
    print("| integrator | dt (s) | error (m) | cost (ms/s) |")
    print("|---|---|---|---|")
    for name, dt, err, cost in rows:
        print(f"| {name} | {dt:g} | {err:.2e} | {cost * 1e3:.3g} |")
    return 0

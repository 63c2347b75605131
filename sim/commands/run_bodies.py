"""`python -m sim run` on a scene of several bodies ([[bodies]]): its trajectory to CSV, with a progress bar."""

from __future__ import annotations

import math
import sys
import time

import numpy as np

from ..config import ConfigError, SceneConfig
from .interrupt import EXIT


def run_bodies(args, scene: SceneConfig) -> int:
    from ..system import Assembly
    from .run import INTERRUPTED, WRITE_FAILED, stream

    run = Assembly(scene)
    n_steps = max(0, round(scene.step.t_end / run.dt))
    if n_steps > args.max_steps:
        raise ConfigError(f"t_end / dt = {scene.step.t_end:g} s / {run.dt:g} s is {n_steps:.3g} steps, more than --max-steps {args.max_steps:.3g}: "
                          "give a larger --dt, or --max-steps to run it anyway")  # fmt: skip
    for note in run.notes:
        print(f"floatsim: note: {note}", file=sys.stderr)
    first = run.frame()
    started = time.perf_counter()
    error, rows = stream(run, run.columns(), args, n_steps)
    if error in (WRITE_FAILED, INTERRUPTED):
        return 2 if error == WRITE_FAILED else EXIT
    wall = time.perf_counter() - started
    last = run.frame()
    system = run.system
    names = ", ".join(f"{m.name} ({m.body.mass:.6g} kg, {m.body.n_samples} samples)" for m in system.members)
    print(f"scene {scene.name}: {len(system.members)} bodies: {names}; {len(system.groups)} rigid groups, {system.n_dofs} degrees of freedom; "
          f"Stormer-Verlet, dt {run.dt:g} s")  # fmt: skip
    for b in last.bodies:
        print(f"t = {last.t:.6g} s: {b['name']} at z = {b['x'][2]:.6f} m, |u| = {np.linalg.norm(b['u']):.3g} m/s")
    for name, theta, _, _, absorbed in last.joints:
        print(f"joint {name}: coordinate {theta:.6g}, take-off absorbed {absorbed:.6g} J ({absorbed / last.t if last.t > 0 else 0.0:.4g} W on average)")
    drift = (last.E_total + last.E_pto) - (first.E_total + first.E_pto)
    steps = round(last.t / run.dt)
    print(f"E_total = {last.E_total:.6g} J, with the take-offs' {last.E_pto:.6g} J: change {drift:+.3g} J; {steps} steps in {wall:.3g} s wall "
          f"({last.t / wall if wall > 0 else math.inf:.3g}x real time)" + (f"; {rows} rows -> {args.out}" if args.out else ""))  # fmt: skip
    return 3 if error else 0

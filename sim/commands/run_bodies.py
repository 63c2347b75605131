"""`python -m sim run` on a scene of several bodies ([[bodies]]): its trajectory to CSV, with a progress bar."""

from __future__ import annotations

import sys
import time

import numpy as np

from ..config import ConfigError, SceneConfig
from .interrupt import EXIT


def run_bodies(args, scene: SceneConfig) -> int:
    from ..system import Assembly
    from .run import INTERRUPTED, WRITE_FAILED, speeds, stream

    run = Assembly(scene)
    n_steps = max(0, round(scene.step.t_end / run.dt))
    if n_steps > args.max_steps:
        raise ConfigError(f"t_end / dt = {scene.step.t_end:g} s / {run.dt:g} s is {n_steps:.3g} steps, more than --max-steps {args.max_steps:.3g}: "
                          "give a larger --dt, or --max-steps to run it anyway")  # fmt: skip
    announce_compile(run, scene, n_steps)
    for note in run.notes:
        print(f"floatsim: note: {note}", file=sys.stderr)
    first = run.frame()
    started = time.perf_counter()
    error, rows, stepping = stream(run, run.columns(), args, n_steps)
    if error in (WRITE_FAILED, INTERRUPTED):
        return 2 if error == WRITE_FAILED else EXIT
    wall = time.perf_counter() - started
    last = run.frame()
    system = run.system
    names = ", ".join(f"{m.name} ({m.body.mass:.6g} kg, {m.body.n_samples} samples)" for m in system.members)
    print(f"scene {scene.name}: {len(system.members)} bodies: {names}; {len(system.groups)} rigid groups, {system.n_dofs} degrees of freedom; "
          "{}, dt {:g} s; the bodies' loads {}".format(*how_stepped(run)))  # fmt: skip
    for b in last.bodies:
        print(f"t = {last.t:.6g} s: {b['name']} at z = {b['x'][2]:.6f} m, |u| = {np.linalg.norm(b['u']):.3g} m/s")
    for name, theta, _, _, absorbed in last.joints:
        print(
            f"joint {name}: coordinate {theta:.6g}, take-off absorbed {absorbed:.6g} J ({absorbed / last.t if last.t > 0 else 0.0:.4g} W on average)"
        )
    drift = (last.E_total + last.E_pto) - (first.E_total + first.E_pto)
    steps = round(last.t / run.dt)
    print(f"E_total = {last.E_total:.6g} J, with the take-offs' {last.E_pto:.6g} J: change {drift:+.3g} J")
    print(speeds(steps, last.t, wall, stepping, rows if args.out else None, checked=False) + (f" -> {args.out}" if args.out else ""))
    return 3 if error else 0


def announce_compile(run, scene: SceneConfig, n_steps: int) -> None:
    """As run.announce_compile for one body: the bodies' compiled loads build once per machine; a run the numpy
    reference finishes within SHORT_RUN_SECONDS stays there (saying so), a longer one compiles them first (saying so)."""
    from ..simulation import default_backend
    from ..system import Assembly
    from .run import SHORT_RUN_SECONDS

    if run.compiled or default_backend() != "numba" or not run.system.has_twin:
        return
    if not run.kernels_ready:
        probe = Assembly(scene, backend="numpy")
        probe.step(1)
        started = time.perf_counter()
        probe.step(2)
        if (estimate := (time.perf_counter() - started) / 2 * n_steps) < SHORT_RUN_SECONDS:
            print(f"floatsim: note: the bodies' fast kernels are not compiled on this machine yet (under a minute, once); this short run takes about "
                  f"{max(estimate, 1):.0f} s on the numpy reference, so it runs there (a longer run compiles them)", file=sys.stderr)  # fmt: skip
            return
        specs = "; ".join(spec.describe() for spec in run.system.specs)
        print(f"floatsim: compiling the bodies' fast kernels ({specs}), once for this machine (under a minute; cached on disk afterwards)...",
              file=sys.stderr, flush=True)  # fmt: skip
    started = time.perf_counter()
    run.use_backend("numba")
    if (seconds := time.perf_counter() - started) > 5.0:
        print(f"floatsim: compiled the bodies' fast kernels in {seconds:.1f} s (cached on disk for next runs)", file=sys.stderr)


def how_stepped(run) -> tuple[str, float, str]:
    """(the scheme, dt, where the bodies' loads come from), as the summary says them."""
    loads = "linear" if run.scene.fluid.hydro == "linear" else "compiled" if run.compiled else "on the numpy reference"
    return "stepped exactly (a linear system)" if run.exact is not None else "Stormer-Verlet", run.dt, loads

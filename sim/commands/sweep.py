"""`floatsim sweep`: one scene run for many values of a parameter at once (an Ensemble), to CSV."""

from __future__ import annotations

import sys
from dataclasses import dataclass
from typing import Literal

from ..config import PARAMS, ConfigError, load_scene, with_overrides
from ..ensemble import Ensemble
from ..simulation import CSV_COLUMNS
from .progress import progress_bar

SWEPT = {p.key: p for p in PARAMS.values() if p.section in ("body", "fluid", "waves") and p.kind in ("float", "optional") and p.key not in ("mass", "size")}
"""Parameters a sweep can vary (every declared number of the body, the water and the waves, term coefficients included), plus z0."""


@dataclass
class SweepArgs:
    """Run many bodies of one shape together, one per value of a parameter; one CSV row per body."""

    param: Literal[tuple(SWEPT) + ("z0",)] = "density"  # type: ignore[valid-type]
    """Which parameter varies: a declared body or water parameter (density, damping, drag_coefficient, ...) or z0 (initial height, m)."""
    values: tuple[float, ...] = (500.0, 700.0, 900.0)
    """The values to run, one body each."""
    scene: str = "damped"
    """Preset name or path to a scene .toml (everything else comes from it)."""
    t_end: float | None = None
    """Simulated duration, s (default: the scene's)."""
    dt: float | None = None
    """Time step, s."""
    integrator: str | None = None
    """Integrator name (fixed-step ones run compiled)."""
    out: str = "sweep.csv"
    """CSV of final states: param, value, status, then the run columns."""
    history: str | None = None
    """Also write every body's time history here (long format: body, value, then the run columns)."""
    every: int = 100
    """History: one row per body every K steps."""
    progress: bool | None = None
    """Progress bar (default: only on a terminal, never under CI)."""


def sweep(args: SweepArgs) -> int:
    if not args.values:
        raise ConfigError("--values needs at least one value")
    if args.every < 1:
        raise ConfigError(f"--every must be >= 1, got {args.every}")
    base = with_overrides(load_scene(args.scene), step__t_end=args.t_end, step__dt=args.dt, step__integrator=args.integrator)
    key = f"{SWEPT[args.param].section}__{args.param}" if args.param in SWEPT else None
    scenes = []
    for v in args.values:
        if key:
            scenes.append(with_overrides(base, **{key: float(v)}))
        else:
            x, y, _ = base.initial.position
            scenes.append(with_overrides(base, initial__position=(x, y, float(v))))
    ensemble = Ensemble(scenes)
    n_steps = round(base.step.t_end / ensemble.dt)
    history = open(args.history, "w") if args.history else None
    bar = progress_bar(n_steps, flag=args.progress)
    try:
        if history:
            history.write("body,value," + ",".join(CSV_COLUMNS) + "\n")
        done = 0
        while True:
            if history and done % args.every == 0:
                for i, (v, f) in enumerate(zip(args.values, ensemble.frames())):
                    history.write(f"{i},{v:.12g}," + ",".join(f"{c:.12g}" for c in f.row()) + "\n")
            if done >= n_steps:
                break
            k = min(args.every, n_steps - done)
            ensemble.step(k)
            done += k
            bar.update(k)
    finally:
        bar.close()
        if history:
            history.close()
    with open(args.out, "w") as out:
        out.write("param,value,status," + ",".join(CSV_COLUMNS) + "\n")
        for v, f, why in zip(args.values, ensemble.frames(), ensemble.diverged):
            status = "diverged" if why else "ok"
            out.write(f"{args.param},{v:.12g},{status}," + ",".join(f"{c:.12g}" for c in f.row()) + "\n")
    for v, why in zip(args.values, ensemble.diverged):
        if why:
            print(f"floatsim: {args.param} = {v:g}: {why}", file=sys.stderr)
    print(f"{len(args.values)} bodies, {n_steps} steps each -> {args.out}" + (f" (history -> {args.history})" if history else ""))
    return 3 if any(ensemble.diverged) else 0

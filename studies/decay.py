"""`floatsim decay` (or `python -m studies decay`): a free-decay test of a scene, with its figure.

The body is released raised by --drop (heave) or heeled by --tilt (roll) from its floating
equilibrium, run by the same Simulation `floatsim run` uses, and its record analysed (sim/decay.py).
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sim.commands import declared_flags, overrides
from sim.commands.progress import progress_bar
from sim.decay import analyse, release, signal
from sim.limits import check_memory
from sim.scene.config import PARAMS, ConfigError, load_scene, with_overrides
from sim.simulation import Simulation


@dataclass
class _DecayBase:
    """Free-decay test: release the body from its floating equilibrium, raised (--drop) or heeled (--tilt), and
    report the damped period, the decay rate and the first trough, with a figure. Flags override the scene."""

    scene: str = "sphere"
    """Preset name (assets/scenes/NAME.toml) or path to a scene .toml."""
    drop: float = 0.05
    """Release height above the equilibrium, m (heave decay)."""
    tilt: float = 0.0
    """Release heel about the world x axis, degrees (roll decay; then --drop is usually 0)."""
    duration: float = 20.0
    """Simulated seconds to record."""
    out: str | None = None
    """Figure to write (PNG); default decay_SCENE_DOF.png in the current folder."""
    progress: bool | None = None
    """Show a progress bar (default: only on a terminal, never under CI)."""


DecayArgs = declared_flags("DecayArgs", _DecayBase, PARAMS.values())


def decay(args: DecayArgs) -> int:
    if not 0.0 < args.duration <= 1e5:
        raise ConfigError(f"--duration must be in (0, 1e5] s, got {args.duration}")
    if abs(args.tilt) >= 90.0:
        raise ConfigError(f"--tilt must be within (-90, 90) degrees, got {args.tilt}")
    scene = with_overrides(load_scene(args.scene), **overrides(args, PARAMS.values()))
    if scene.bodies:  # its release, period and decay are one body's (a system's modes are coupled: not built yet)
        raise ConfigError(f"the decay study releases one body from its rest: scene {scene.name!r} has several bodies "
                          "(run it with `python -m sim run` and read a joint's coordinate from the CSV)")  # fmt: skip
    sim = Simulation(scene)
    dof, z_rest = release(sim, args.drop, args.tilt)
    n = int(round(args.duration / sim.dt))
    check_memory(f"a record of {n + 1:,} steps", 16 * (n + 1), "--duration")
    t, y = np.empty(n + 1), np.empty(n + 1)
    t[0], y[0] = 0.0, signal(sim, dof, z_rest)
    chunk = max(1, n // 200)
    bar = progress_bar(n, unit="step", flag=args.progress)
    i = 0
    while i < n:  # small chunks: a record point per step
        sim.step(1)
        i += 1
        t[i], y[i] = sim.state.t, signal(sim, dof, z_rest)
        if i % chunk == 0:
            bar.update(chunk)
    bar.close()
    result = analyse(dof, t, y)
    unit = "m" if dof == "heave" else "deg"
    radiation = sim.scene.fluid.radiation
    print(f"{dof} decay of '{scene.name}' ({radiation} radiation, forces {sim.scene.fluid.forces}, integrator {sim.integrator.name}, "
          f"dt {sim.dt:g} s), released {args.drop if dof == 'heave' else args.tilt:g} {unit} from rest at z = {z_rest:.4f} m")  # fmt: skip
    print(
        f"| damped period | {result.period:.4f} s (median of {len(result.periods)} peak-to-peak intervals, spread {np.ptp(result.periods) if len(result.periods) else math.nan:.2g} s) |"
    )
    print(f"| decay rate sigma | {result.rate:.4f} 1/s (damping ratio {result.damping_ratio:.4f}) |")
    print(f"| first trough | {result.first_trough:.4g} {unit} at t = {result.first_trough_time:.3f} s |")
    out = Path(args.out or f"decay_{scene.name}_{dof}.png")
    _figure(out, t, y, result, unit, f"{scene.name}: {dof} decay ({radiation} radiation)")
    print(f"figure: {out}")
    if sim.model.radiation is not None and dof == "roll" and abs(args.tilt) > 15:
        print("note: radiation coefficients are linear about the rest pose; a heel this large is outside their range", file=sys.stderr)
    return 0


def _figure(path: Path, t, y, result, unit: str, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 3.5))
    ax.plot(t, y, lw=1.2, label="simulated")
    te, ye = result.extrema
    ax.plot(te, ye, "o", ms=3, label="extrema")
    if math.isfinite(result.rate) and len(te):
        amp = np.abs(ye[0]) * np.exp(-result.rate * (t - te[0]))
        ax.plot(t, amp, "k--", lw=0.8, label=f"envelope, sigma = {result.rate:.3g} 1/s")
        ax.plot(t, -amp, "k--", lw=0.8)
    ax.set_xlabel("t (s)")
    ax.set_ylabel(f"{result.dof} ({unit})")
    ax.set_title(f"{title}: period {result.period:.3f} s")
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)

"""The figures of the accuracy report's parts 8 (the radiation memory's passivity) and 9 (drifting bodies)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..common import pyplot, save
from .plot import DPI


def passivity(data, path: Path) -> None:
    """Left: min eig B_fit(omega) / peak B against omega / omega_top for each shipped solve (symlog y: a negative
    value would show), the BEM grids' extent shaded. Right: rm3 without a damper, kicked: its mechanical energy
    and E_total + E_pto + E_rad, each against the kick."""
    plt = pyplot()
    fig, axes = plt.subplots(1, 2 if data.rm3 is not None else 1, figsize=(13 if data.rm3 is not None else 7, 4.8), squeeze=False)
    ax = axes[0, 0]
    for k, s in enumerate(data.solves):
        colour = f"C{k}"
        ax.plot(s.omega / s.omega_top, s.low / s.peak, color=colour, lw=1.2,
                label=f"{s.name[:7]}: {s.bodies} bod{'ies' if s.bodies > 1 else 'y'}, {s.dofs} radiating dofs, {s.states} states")  # fmt: skip
        ax.axvspan(s.omega_low / s.omega_top, 1.0, color=colour, alpha=0.06)
    ax.axvline(1.0, color="k", ls=":", lw=1, label="top of the BEM grids (shaded: each grid)")
    ax.axhline(0.0, color="k", lw=0.8)
    ax.set_xscale("log")
    ax.set_yscale("symlog", linthresh=1e-12)
    ax.set(xlabel="ω / ω_top (the solve's top frequency)", ylabel="smallest eigenvalue of B_fit(ω) / peak B",
           title="the fitted damping is positive semi-definite")  # fmt: skip
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="lower center")
    if data.rm3 is not None:
        r, ax = data.rm3, axes[0, 1]
        ax.plot(r.t, r.energy / r.kick, color="C0", label="mechanical energy E_total - start")
        ax.plot(r.t, r.balance / r.kick, color="C3", ls="--", label="E_total + E_pto + E_rad - start")
        ax.axhline(0.0, color="k", lw=0.8)
        ax.set(xlabel="t (s)", ylabel="energy / the kick's", title=f"rm3 without a damper, kicked 0.5 m/s: {r.kick / 1e3:.4g} kJ")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=9)
    fig.tight_layout()
    save(fig, path, DPI)


def drifting(data, path: Path) -> None:
    """Left: the free sphere's heave RAO a quarter wave from its start, on a slide, and the frequency domain. Right:
    its surge started at rest, without a ramp and with the default one (per wave amplitude)."""
    plt = pyplot()
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(13, 4.8))
    periods, curve = data.curve
    ax1.plot(periods, curve, color="k", lw=1, label="frequency domain (with diffraction)")
    rows = sorted(data.rows, key=lambda r: r.period)
    ax1.plot([r.period for r in rows], [r.slide for r in rows], "s", color="C1", mfc="none", ms=9, label="on a vertical slide at its start")
    ax1.plot([r.period for r in rows], [r.free for r in rows], "o", color="C0", label="free, a quarter wave from its start")
    ax1.set(xlabel="wave period (s)", ylabel="|heave| per wave amplitude (m/m)", title="the sphere's heave after a drift")
    ax1.grid(True, alpha=0.3)
    ax1.legend(fontsize=9)
    a, T = data.amplitude, data.settings.ramp_period
    for s, colour in zip(data.starts, ("C3", "C0")):
        label = "no ramp (full height at t = 0)" if s.ramp == 0 else f"default ramp, {s.ramp:g} s"
        ax2.plot(s.t / T, s.x / a, color=colour, lw=0.8, label=f"x / a, {label}")
        ax2.plot(
            np.arange(len(s.odd)) + 0.5, s.odd / a, "o", color=colour, ms=4, mfc="none", label=f"the kick's part, period means, {label}"
        )
        if s.ramp > 0:
            ax2.axvline(s.ramp / T, color=colour, ls=":", lw=1)
    ax2.set(xlabel="t / wave period", ylabel="surge / wave amplitude",
            title=f"started at rest in {1000 * data.settings.ramp_height:g} mm waves, T = {T:g} s")  # fmt: skip
    ax2.grid(True, alpha=0.3)
    ax2.legend(fontsize=8)
    fig.tight_layout()
    save(fig, path, DPI)

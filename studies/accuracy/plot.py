"""The accuracy report's figures: matplotlib only, reading computed data and writing PNGs."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from sim import INTEGRATORS

from ..common import pyplot, save
from .compute import ADAPTIVE, FIXED, ModelError, Settings, StabilityMap, StiffRow, WPResult, physics_limit, upright
from .numbers import model_errors

STYLE = {  # colour, marker, line style per integrator, the same in every figure
    "euler": ("C0", "o", "-"), "splitting": ("C1", "s", "-"), "implicit": ("C2", "D", "--"), "rk4": ("C3", "^", "-"),
    "rk45": ("C4", "v", ":"), "dop853": ("C5", "P", ":"), "radau": ("C6", "X", ":"),
}  # fmt: skip
DPI = 110


def _method_label(name: str) -> str:
    return f"{name} (order {INTEGRATORS[name].order})"


def work_precision(wp: WPResult, path: Path, label: str) -> None:
    plt = pyplot()
    fig, (ax1, ax2, ax3) = plt.subplots(1, 3, figsize=(16, 5.2))
    for name in (*FIXED, *ADAPTIVE):
        c, m, ls = STYLE[name]
        pts = [p for p in wp.of(name) if np.isfinite(p.error)]
        if not pts:
            continue
        face = "none" if name == "implicit" else c
        ax1.loglog([p.cost for p in pts], [p.error for p in pts], ls=ls, marker=m, color=c, mfc=face, label=_method_label(name))
        if name in FIXED:
            ax2.loglog([p.setting for p in pts], [p.error for p in pts], ls=ls, marker=m, color=c, mfc=face,
                       label=f"{name}: observed {wp.orders[name][0]:.2f}, declared {INTEGRATORS[name].order}")  # fmt: skip
            small = min(pts, key=lambda p: p.setting)
            dts = np.array(sorted(p.setting for p in pts))
            ax2.loglog(dts, small.error * (dts / small.setting) ** INTEGRATORS[name].order, color=c, lw=0.8, alpha=0.5, ls=(0, (2, 2)))
        else:
            ax3.loglog([p.setting for p in pts], [p.error for p in pts], ls=ls, marker=m, color=c, label=name)
    for ax in (ax1, ax2, ax3):
        ax.axhline(wp.ref_error, color="k", lw=0.8, ls="--")
        ax.grid(True, which="major", alpha=0.3)
    ax1.text(0.02, wp.ref_error, "reference's own error", transform=ax1.get_yaxis_transform(), fontsize=8, va="bottom")
    ax1.set(xlabel="wall time per simulated second (s/s, median)", ylabel="max corner error over the horizon (m)", title="work-precision")
    ax2.set(xlabel="dt (s)", ylabel="max corner error (m)", title="fixed-step convergence (faint: declared slope)")
    ax3.set(xlabel="rtol (atol = rtol/100)", ylabel="max corner error (m)", title="adaptive: error vs tolerance")
    rt = np.array([1e-11, 1e-2])
    ax3.loglog(rt, rt, color="gray", lw=0.8, label="error = rtol")
    fixed_errors = [p.error for p in wp.points if p.method in FIXED and np.isfinite(p.error) and p.error > 0]
    if fixed_errors:
        ax2.set_ylim(min(min(fixed_errors), wp.ref_error) / 3, max(fixed_errors) * 3)
    ax1.legend(fontsize=8, loc="best")
    ax2.legend(fontsize=8, loc="lower right")
    ax3.legend(fontsize=8, loc="best")
    fig.suptitle(f"{wp.case.title}: error vs DOP853 (rtol 1e-11) over {label}", fontsize=11)
    fig.tight_layout()
    save(fig, path, DPI)


MODEL_GROUPS = (("equilibrium (tilted cube, 770 kg/m^3)", ["equilibrium depth (m)", "equilibrium tilt (rad)"]),
                ("heave period (edge-down cube, 600 kg/m^3, 2 cm)", ["heave period (relative)"]),
                ("trajectory (damped scene, max corner error)", ["trajectory (m)"]))  # fmt: skip


def _model_column(me: ModelError, top, bottom, title: str, keys: list[str], errs: dict) -> None:
    """One group of errors: against N (top) and against the points model's cost (bottom)."""
    from matplotlib.ticker import NullFormatter

    ns, cost = np.array(me.ns), np.array(me.cost_points)
    series = [(key, np.array(errs[key], float), marker, f"C{i}", "-") for i, (key, marker) in enumerate(zip(keys, "os"))]
    if keys == ["trajectory (m)"]:
        series.append(("sampled inertia: panels with it vs with the exact one", np.array(me.inertia_error), "x", "gray", "--"))
    for j, (key, e, marker, color, ls) in enumerate(series):
        ok = np.isfinite(e) & (e > 0)
        rate = me.rates.get(key, me.rates["inertia (trajectory, m)"])
        top.loglog(ns[ok], e[ok], marker=marker, color=color, ls=ls, label=f"{key}: error ~ N^-{rate:.2f}")
        bottom.loglog(cost[ok], e[ok], marker=marker, color=color, ls="none", label=key)
        if j == 0 or len(keys) > 1:
            for n, c, v in zip(ns[ok], cost[ok], e[ok]):
                bottom.annotate(f"N={n}", (c, v), textcoords="offset points", xytext=(4, 3), fontsize=7, color=color)
    if keys == ["trajectory (m)"]:
        for ax in (top, bottom):
            ax.axhline(me.traj_floor, color="k", lw=0.8, ls=":", label="integrator's share (panels rk4 vs DOP853)")
    n_line = np.array([ns[0], ns[-1]], float)
    first = series[0][1]
    if np.isfinite(first[-1]) and first[-1] > 0:
        top.loglog(n_line, first[-1] * (n_line / ns[-1]) ** -2.0, color="k", lw=0.7, alpha=0.4, label="slope N^-2")
    bottom.axvline(me.cost_panels, color="k", lw=0.8, ls="--", label=f"panels model cost ({me.cost_panels:.2g} s/s)")
    top.set(title=title, xlabel="N (samples per cube edge; 6 N^2 samples)", ylabel="error vs panels")
    top.set_xticks(ns, [str(n) for n in ns])
    top.minorticks_off()
    bottom.set(xlabel="points model: wall s per simulated s (median)", ylabel="error vs panels")
    bottom.xaxis.set_minor_formatter(NullFormatter())
    for ax in (top, bottom):
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)


def model_error(me: ModelError, path: Path, label: str) -> None:
    plt = pyplot()
    errs = model_errors(me)
    fig, axes = plt.subplots(2, 3, figsize=(16, 9.5))
    for col, (title, keys) in enumerate(MODEL_GROUPS):
        _model_column(me, axes[0, col], axes[1, col], title, keys, errs)
    fig.suptitle(f"sampled (points) vs exact (panels) forces as N grows; cost from the damped-scene trajectory runs; {label}", fontsize=11)
    fig.tight_layout()
    save(fig, path, DPI)


def stability(st: StabilityMap, cfg: Settings, path: Path) -> None:
    plt = pyplot()
    fig, axes = plt.subplots(1, len(st.density), figsize=(7.5 * len(st.density), 5.4), squeeze=False)
    xs = [d if d > 0 else 1.0 for d in st.damping]  # d = 0 drawn at 1
    for ax, density in zip(axes[0], st.density):
        u = upright(density)
        dd = np.logspace(0, math.log10(max(st.damping) * 3), 200)
        heave, _ = physics_limit(density, 1.0)
        ax.axhline(heave, color="gray", ls="--", lw=1, label=f"heave: dt = 2/omega = {heave:.3g} s")
        ax.loglog(
            dd, 2 * u["M"] / (dd * u["A_sub"]), color="gray", ls="-.", lw=1, label="damping: dt = 2 M / (d A_sub) (explicit Euler, linear)"
        )
        kappa = next((st.lam_max[density, d] / d for d in st.damping if d > 0), None)
        if kappa:
            ax.loglog(
                dd,
                2 / (kappa * dd),
                color="k",
                ls=(0, (1, 3)),
                lw=1.2,
                label=f"fastest damping mode: dt = 2/lambda_max, lambda_max = {kappa:.3g} d /s",
            )
        ax.axhline(cfg.stab_cap, color="k", ls=":", lw=0.8, label=f"cap {cfg.stab_cap:g} s")
        for method in FIXED:
            c, m, ls = STYLE[method]
            ys = [st.limits[method, density, d] for d in st.damping]
            ax.loglog(xs, ys, marker=m, color=c, ls=ls, mfc="none" if method == "implicit" else c, label=method)
        ax.set_ylim(min(1e-4, 0.3 * min(v for (m_, de, d), v in st.limits.items() if de == density and np.isfinite(v))), 3 * cfg.stab_cap)
        ax.set_xticks(xs)
        ax.set_xticklabels(["0" if d == 0 else f"{d:g}" for d in st.damping])
        ax.set(xlabel="damping d (N s/m^3; d = 0 drawn at 1)", ylabel="largest stable dt (s)",
               title=f"{density:g} kg/m^3: M = {u['M']:g} kg, A_sub = {u['A_sub']:.3g} m^2, omega = {u['omega']:.3g} rad/s", )  # fmt: skip
        ax.grid(True, alpha=0.3)
        handles, labels = ax.get_legend_handles_labels()
        first = len(handles) - len(FIXED)
        ax.legend(handles[:first], labels[:first], fontsize=8, loc="lower left")
    fig.legend(handles[first:], labels[first:], loc="lower center", ncol=len(FIXED), fontsize=9)
    fig.suptitle(
        "largest stable dt of the fixed-step integrators (panels model, upright cube near rest; markers at the cap = stable up to it)",
        fontsize=11,
    )
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    save(fig, path, DPI)


def creep(rows: list[StiffRow], path: Path) -> None:
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(8, 5))
    for i, r in enumerate(rows):
        t, gap = r.creep
        ax.semilogy(t, gap, color=f"C{i}", label=f"d = {r.d:g}: implicit dt = 0.01 s")
        ax.semilogy(t, gap[0] * np.exp(-r.creep_rate_physical * t), color=f"C{i}", ls="--", lw=1)
    ax.set(
        xlabel="t (s)",
        ylabel="height above rest depth, z + 0.4 (m)",
        title="creep back to rest depth: simulated (solid) vs physical slow mode (dashed)",
    )
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    save(fig, path, DPI)


def leak(data, path: Path) -> None:
    """Steady rocking (colour) and drift (x) of the points and cells models over density and N, with
    the exact model's transitions (GM = 0) drawn in; each mapped band of densities drawn on its own."""
    from matplotlib.colors import LogNorm

    from .leak import DRIFT, ROCKING, transitions

    plt = pyplot()
    cfg = data.settings
    densities = np.array(sorted(set(cfg.densities)))
    bands = np.split(densities, np.flatnonzero(np.diff(densities) > 50) + 1)
    fig, axes = plt.subplots(2, len(bands), figsize=(13, 6.5), sharey=True, squeeze=False)
    norm = LogNorm(ROCKING, 30.0, clip=True)
    mesh = None
    for row, forces in enumerate(("points", "cells")):
        for col, band in enumerate(bands):
            ax = axes[row, col]
            grid = np.array([[max(data.at(d, n, forces).rocking, ROCKING) for d in band] for n in cfg.ns])
            half = 0.5 * (np.diff(band).min() if len(band) > 1 else 10.0)
            edges = np.concatenate([[band[0] - half], 0.5 * (band[1:] + band[:-1]), [band[-1] + half]])
            mesh = ax.pcolormesh(edges, np.arange(len(cfg.ns) + 1) - 0.5, grid, norm=norm, cmap="magma_r")
            for j, n in enumerate(cfg.ns):
                drift = [d for d in band if data.at(d, n, forces).speed > DRIFT]
                ax.plot(drift, [j] * len(drift), "x", color="C0", ms=7, mew=1.5, label="drifts sideways" if j == 0 else None)
            for t in transitions():
                if band[0] <= t <= band[-1]:
                    ax.axvline(t, color="C2", ls="--", lw=1.2, label="exact GM = 0")
            ax.set_yticks(range(len(cfg.ns)), [str(n) for n in cfg.ns])
            ax.set_title(f"{forces}: final tilt range, {band[0]:g}-{band[-1]:g} kg/m$^3$", fontsize=10)
            if row == 1:
                ax.set_xlabel("cube density (kg/m$^3$)")
            if col == 0:
                ax.set_ylabel("points per edge N")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    if handles:
        fig.legend(handles, labels, loc="upper right", fontsize=9)
    fig.colorbar(mesh, ax=axes, label=f"tilt range (deg); at rest below {ROCKING:g}")
    save(fig, path, DPI)


def excitation(data, path: Path) -> None:
    """|RAO| per body and dof over the wavelength: frequency domain (lines) and time domain (markers), with
    the diffraction force and without it (Froude-Krylov only)."""
    from matplotlib.ticker import FormatStrFormatter, NullFormatter

    from .excitation import DOF_NAMES

    plt = pyplot()
    bodies = [b for b in data.settings.bodies if data.of(b.name)]
    cols = max(len(b.dofs) for b in bodies)
    fig, axes = plt.subplots(len(bodies), cols, figsize=(4.2 * cols, 3.4 * len(bodies)), squeeze=False)
    for row, b in enumerate(bodies):
        rs = sorted(data.of(b.name), key=lambda r: r.wavelength)
        lam = np.array([r.wavelength for r in rs])
        for col in range(cols):
            ax = axes[row, col]
            if col >= len(b.dofs):
                ax.set_visible(False)
                continue
            d = b.dofs[col]
            for attr_f, attr_t, colour, ls, marker, label in (("freq_full", "time_full", "C0", "-", "o", "with diffraction"),
                                                               ("freq_fk", "time_fk", "C1", "--", "s", "Froude-Krylov only")):  # fmt: skip
                ax.plot(lam, [abs(getattr(r, attr_f)[d]) for r in rs], color=colour, ls=ls, label=f"frequency domain, {label}")
                ax.plot(lam, [abs(getattr(r, attr_t)[d]) for r in rs], marker, color=colour, mfc="none", label=f"time domain, {label}")
            ax.set_xscale("log")
            ax.set_xticks([t for t in (1.5, 2, 3, 5, 10, 20) if lam.min() * 0.9 <= t <= lam.max() * 1.1], minor=False)
            ax.xaxis.set_major_formatter(FormatStrFormatter("%g"))
            ax.xaxis.set_minor_formatter(NullFormatter())
            unit = "m/m" if d < 3 else "rad/m"
            ax.set(
                xlabel="wavelength / body length", ylabel=f"|{DOF_NAMES[d]}| per wave amplitude ({unit})", title=f"{b.name}: {DOF_NAMES[d]}"
            )
            ax.grid(True, which="both", alpha=0.3)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=2, fontsize=9)
    fig.tight_layout(rect=(0, 0.13, 1, 1))
    save(fig, path, DPI)

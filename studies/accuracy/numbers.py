"""The numbers the accuracy report quotes, derived from the computed data: observed orders, convergence
fits, the verdict, and the measured figures each discussion cites. No runs, no formatting."""

from __future__ import annotations

import math

import numpy as np

from sim import load_scene

from .. import probes
from .compute import ADAPTIVE, FIXED, ModelError, Settings, StabilityMap, StiffRow, WPPoint, WPResult, upright

# ---- fits ---------------------------------------------------------------------------------------


def observed_order(dts, errors, floor: float, last: int = 4) -> tuple[float, float, float]:
    """Least-squares log-log slope of error against dt over the `last` smallest steps whose error is
    above `floor` (round-off/reference level), and the range of the slopes between neighbours there."""
    pts = sorted((dt, e) for dt, e in zip(dts, errors) if np.isfinite(e) and e > floor)[:last]
    if len(pts) < 2:
        return math.nan, math.nan, math.nan
    x, y = np.log([p[0] for p in pts]), np.log([p[1] for p in pts])
    local = np.diff(y) / np.diff(x)
    return float(np.polyfit(x, y, 1)[0]), float(local.min()), float(local.max())


def loglog_rate(ns, errors) -> float:
    """Convergence rate p in error ~ N^-p (least squares over the finite, positive errors at N >= 4)."""
    return loglog_fit(ns, errors)[0]


def loglog_fit(ns, errors) -> tuple[float, float]:
    """(rate p, rms scatter about the fitted line in decades) over the finite, positive errors at N >= 4."""
    pts = [(n, e) for n, e in zip(ns, errors) if n >= 4 and np.isfinite(e) and e > 0]
    if len(pts) < 2:
        return math.nan, math.nan
    x, y = np.log10([p[0] for p in pts]), np.log10([p[1] for p in pts])
    coef = np.polyfit(x, y, 1)
    return float(-coef[0]), float(np.sqrt(np.mean((np.polyval(coef, x) - y) ** 2)))


# ---- 1. work-precision --------------------------------------------------------------------------


def observed_orders(res: WPResult) -> dict[str, tuple[float, float, float]]:
    """Per fixed-step method: the observed order over errors above 20x the reference's own error."""
    floor = max(20 * res.ref_error, 1e-12)
    return {name: observed_order([p.setting for p in res.of(name)], [p.error for p in res.of(name)], floor) for name in FIXED}


def adaptive_error_ratios(res: WPResult) -> list[float]:
    """error / rtol of every finished adaptive run."""
    return [p.error / p.setting for p in res.points if p.method in ADAPTIVE and np.isfinite(p.error)]


def most_accurate(points: list[WPPoint]) -> WPPoint | None:
    return min((p for p in points if np.isfinite(p.error)), key=lambda p: p.error, default=None)


# ---- 2. model error -----------------------------------------------------------------------------


def model_errors(me: ModelError) -> dict[str, list[float]]:
    """Each measured error of the sampled model against the exact one, per N."""
    zp, tp = me.eq_panels
    return {
        "equilibrium depth (m)": [abs(z - zp) for z, _ in me.eq_points],
        "equilibrium tilt (rad)": [abs(t - tp) for _, t in me.eq_points],
        "heave period (relative)": [abs(p / me.period_panels - 1) for p in me.period_points],
        "trajectory (m)": me.traj_error,
    }


def model_rates(me: ModelError) -> dict[str, float]:
    """Convergence rate p (error ~ N^-p) of each error, and of the sampled inertia's effect."""
    rates = {k: loglog_rate(me.ns, v) for k, v in model_errors(me).items()}
    rates["inertia (trajectory, m)"] = loglog_rate(me.ns, me.inertia_error)
    return rates


def model_fits(me: ModelError) -> dict[str, tuple[float, float]]:
    """(rate, scatter in decades) of each error."""
    return {k: loglog_fit(me.ns, v) for k, v in model_errors(me).items()}


def tilted_found(me: ModelError) -> int:
    """For how many N the tilted equilibrium was found."""
    return sum(np.isfinite(z) for z, _ in me.eq_points)


def trajectory_over_inertia(me: ModelError) -> float:
    """At the largest N: the force quadrature's trajectory error over the sampled inertia's."""
    return me.traj_error[-1] / me.inertia_error[-1] if me.inertia_error[-1] > 0 else math.nan


# ---- 3. stability -------------------------------------------------------------------------------


def measured_limit_numbers(st: StabilityMap, cfg: Settings, method: str) -> tuple[list[float], list[float]]:
    """dt omega at the method's d = 0 limits, and dt lambda_max at its limits where damping dominates (below the cap)."""
    heave = [st.limits[method, de, d] * upright(de)["omega"] for de in st.density for d in st.damping
             if d == 0 and st.limits[method, de, d] < cfg.stab_cap]  # fmt: skip
    damp = [st.limits[method, de, d] * st.lam_max[de, d] for de in st.density for d in st.damping
            if st.damping_dominated(de, d) and st.limits[method, de, d] < cfg.stab_cap]  # fmt: skip
    return heave, damp


def fastest_mode_ratios(st: StabilityMap) -> list[float]:
    """lambda_max over PHYSICS.md's d A_sub / M, for every d > 0."""
    return [st.lam_max[de, d] / (d * upright(de)["A_sub"] / upright(de)["M"]) for de in st.density for d in st.damping if d > 0]


def smallest_implicit_limit(st: StabilityMap) -> float:
    return min(st.limits["implicit", de, d] for de in st.density for d in st.damping)


def linear_limits(method: str) -> tuple[float, float]:
    """The method's declared (linear theory) limits on dt omega_heave and dt lambda_max."""
    return probes.stability_limits(method)


# ---- 4. verdict ---------------------------------------------------------------------------------


def verdict(wp: list[WPResult], targets) -> dict[float, dict[str, WPPoint | None]]:
    """For each target and case: the cheapest measured run whose error is within the target."""
    out = {}
    for target in targets:
        out[target] = {}
        for res in wp:
            ok = [p for p in res.points if np.isfinite(p.error) and p.error <= target and np.isfinite(p.cost)]
            out[target][res.case.key] = min(ok, key=lambda p: p.cost) if ok else None
    return out


def wins(verdict: dict[float, dict[str, WPPoint | None]]) -> list[tuple[str, int]]:
    """Verdict cells won per method, most first."""
    count = {}
    for per in verdict.values():
        for p in per.values():
            if p is not None:
                count[p.method] = count.get(p.method, 0) + 1
    return sorted(count.items(), key=lambda kv: -kv[1])


def timing_noise(wp: list[WPResult]) -> list[float]:
    """Without damping 'implicit' and 'splitting' do identical work: their relative cost differences are the noise."""
    noise = []
    for res in wp:
        if res.case.damping is None and load_scene(res.case.scene).fluid.damping == 0:
            split = {p.setting: p.cost for p in res.of("splitting")}
            noise += [abs(p.cost / split[p.setting] - 1) for p in res.of("implicit") if p.setting in split]
    return noise


# ---- 5. stiff -----------------------------------------------------------------------------------


def creep_ratios(rows: list[StiffRow]) -> list[float]:
    """Measured creep rate over the physical slow rate, per d."""
    return [r.creep_rate / r.creep_rate_physical for r in rows]

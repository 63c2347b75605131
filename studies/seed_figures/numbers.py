"""The numbers the seed-figures page states, derived from the recorded runs and the static probes.

Each section's function returns the dict that goes into numbers.json under that section's key; the
text quotes from it.
"""

from __future__ import annotations

import math

import numpy as np

from .. import probes
from .compute import DAMPING_SCALE, SWEEP_N, Cube, DampedProbes, Trace, sampled_gm

# ---- geometry of a pose -----------------------------------------------------------------------------------


def upright_axis(R: np.ndarray) -> int:
    """The body axis closest to the world vertical."""
    return int(np.abs(R[2]).argmax())


def tilt(R: np.ndarray) -> float:
    """Angle (rad) between the world vertical and the nearest body axis: 0 when a face is level (accurate for tiny angles)."""
    i = upright_axis(R)
    return math.atan2(math.hypot(R[0, i], R[1, i]), abs(R[2, i]))


def yaw(R: np.ndarray) -> float:
    """Rotation (deg) about the vertical of the horizontal body axes, folded into [-45, 45) by the cube's symmetry."""
    i = upright_axis(R)
    j = (i + 1) % 3
    angle = math.degrees(math.atan2(R[1, j], R[0, j]))
    return float((angle + 45.0) % 90.0 - 45.0)


def face_up(R: np.ndarray) -> str:
    i = upright_axis(R)
    return f"body {'+' if R[2, i] > 0 else '-'}{'xyz'[i]} face up"


def tilts(trace: Trace) -> np.ndarray:
    return np.array([tilt(R) for R in trace.R])


def settle_time(trace: Trace, L_rel: float = 1e-3, F_rel: float = 1e-4) -> float | None:
    """First time after which |L| < L_rel |L(0)| and |F| < F_rel x weight for the rest of the run (None: never)."""
    ok = (trace.norm("L") < L_rel * max(np.linalg.norm(trace.L[0]), 1e-300)) & (trace.norm("F") < F_rel * trace.weight)
    bad = np.flatnonzero(~ok)
    if len(bad) == 0:
        return float(trace.t[0])
    return float(trace.t[bad[-1] + 1]) if bad[-1] + 1 < len(ok) else None


# ---- the sections -----------------------------------------------------------------------------------------


def samples(cube: Cube, rows: dict, sweep: dict, n_ex: int = 10) -> dict:
    """Figures 1-2: numbers.json keys grid, grid_righting_worst_N20_40, grid_area_deficit_N10 and its formula."""
    fine = [n for n in SWEEP_N if n >= 20]
    worst = {k: max(abs(sweep[n][k]["righting_ratio"] - 1) for n in fine) for k in ("ours", "report", "rescaled")}
    return {
        "grid_righting_worst_N20_40": worst,
        "grid": {str(n): v for n, v in rows.items()},
        "grid_area_deficit_N10": 6 * cube.s**2 * (1 - rows[n_ex]["report"]["area_ratio"]),
        "grid_area_deficit_formula_N10": 6 * cube.s**2 * (1 - ((n_ex - 2) / n_ex) ** 2),
    }


def rest(cube: Cube, ours: Trace, spun: Trace) -> dict:
    """Figure 3: the cube placed at rest, without and with the report's artificial spin."""
    dz = ours.z - cube.z_rest
    dz_spin = spun.z - cube.z_rest
    return {
        "max_dz": float(np.abs(dz).max()), "max_u": float(ours.norm("u").max()), "max_F_rel": float((ours.norm("F") / ours.weight).max()),
        "max_T": float(ours.norm("T").max()), "spin_dz_min": float(dz_spin.min()), "spin_dz_max": float(dz_spin.max()),
        "spin_max_tilt_deg": float(np.degrees(tilts(spun)).max()), "spin_omega": float(np.linalg.norm(spun.spec.config().initial.omega)),
    }  # fmt: skip


def spin(runs: list[Trace], free: Trace) -> dict:
    """Figures 4-5: |L| of the spinning cube per run against the implicit one (runs[2]), the torque-free control, dL = int T dt."""
    ref = runs[2]
    L0 = float(np.linalg.norm(ref.L[0]))
    n: dict = {"L0": L0, "runs": {}}
    for tr in runs:
        Ln = tr.norm("L")
        dev = np.abs(Ln - np.interp(tr.t, ref.t, ref.norm("L"))).max() if tr is not ref else 0.0
        n["runs"][tr.spec.key] = {"dt": tr.spec.config().step.dt, "min": float(Ln.min()), "max": float(Ln.max()),
                                  "max_dev_from_implicit": float(dev)}  # fmt: skip
    coarse, fine = n["runs"]["spin_euler_coarse"], n["runs"]["spin_euler_fine"]
    n["euler_dev_ratio"] = coarse["max_dev_from_implicit"] / fine["max_dev_from_implicit"]
    n["free_rel_dev"] = float(np.abs(free.norm("L") / np.linalg.norm(free.L[0]) - 1).max())
    # dL/dt = torque: the change of L is the time integral of the recorded torque (trapezoid rule).
    dt_rec = np.diff(ref.t)[:, None]
    integral = np.vstack([np.zeros(3), np.cumsum(0.5 * (ref.T[1:] + ref.T[:-1]) * dt_rec, axis=0)])
    n["torque_integral_rel"] = float(np.linalg.norm(ref.L - ref.L[0] - integral, axis=1).max() / L0)
    n["max_torque"] = float(ref.norm("T").max())
    omega0 = np.asarray(ref.spec.config().initial.omega, float)
    n["righting_per_rad"] = Cube().mass * probes.fluid(ref.sim).g * Cube().GM  # M g GM, N m per radian of tilt
    n["I_omega2"] = float(ref.body.inertia[0] * (omega0 @ omega0))
    return n


def force_at_rest(tr: Trace, grid10: dict) -> dict:
    """Figure 6: |F_total| of the cube at rest, and what the report's two grids give at the same pose (N = 10)."""
    rel = tr.norm("F") / tr.weight
    return {"max_F_rel": float(rel.max()), "max_F": float(tr.norm("F").max()), "weight": tr.weight,
            "report_grid_F_rel": grid10["report"]["rest_force_rel"], "rescaled_grid_F_rel": grid10["rescaled"]["rest_force_rel"]}  # fmt: skip


def unstable_band(cube: Cube) -> tuple[float, float]:
    """Densities between which face up is metacentrically unstable for the hollow cube."""
    return (3 - math.sqrt(3)) / 6 * cube.rho, (3 + math.sqrt(3)) / 6 * cube.rho


def _density_row(cube: Cube, tr: Trace) -> dict:
    density = tr.density
    c = Cube(cube.s, density, cube.rho, cube.g)
    row = {"density": density, "z_min": float(tr.z.min()), "z_max": float(tr.z.max()), "z_end": float(tr.z[-1]),
           "max_tilt_deg": float(np.degrees(tilts(tr)).max())}  # fmt: skip
    if density < cube.rho:
        row["z_eq"] = c.z_rest
        row["GM"] = c.GM
        row["bottom_max"] = float(tr.z.max() - c.s / 2)
        row["top_min"] = float(tr.z.min() + c.s / 2)
    else:
        row["accel_end"] = float(tr.F[-1, 2] / tr.body.mass)
        row["accel_exact"] = -(1 - cube.rho / density) * cube.g
    return row


def densities(cube: Cube, runs: list[Trace]) -> dict:
    """Density runs: per run its range of z, tilt and (sinking) acceleration; for the metacentrically unstable
    one, the tilt's growth rate from round-off against sqrt(M g |GM| / I)."""
    lo, hi = unstable_band(cube)
    n: dict = {"unstable_band": [lo, hi], "runs": {f"{tr.density:g}": _density_row(cube, tr) for tr in runs}}
    unstable = [tr for tr in runs if lo < tr.density < hi]
    if unstable:
        tr = unstable[0]
        gm = sampled_gm(tr.sim, Cube(cube.s, tr.density, cube.rho, cube.g).z_rest, tr.weight)
        n["unstable"] = {"density": tr.density, "GM_sampled": gm, "rate_predicted": math.sqrt(tr.weight * abs(gm) / tr.body.inertia[0])}
        th = tilts(tr)
        window = (th > 1e-9) & (th < 1e-3)
        if window.sum() >= 5:
            n["unstable"]["rate_measured"] = float(np.polyfit(tr.t[window], np.log(th[window]), 1)[0])
    return n


def damped(cube: Cube, traces: list[Trace], probe: DampedProbes) -> dict:
    """Figures 7-9: metacentric numbers, the yaw probe, and per run its damping ratios, settling time and final pose."""
    body = traces[0].body
    weight = body.mass * cube.g
    n: dict = {"BM": cube.BM, "BG": cube.BG, "GM": cube.GM, "GM_sampled": probe.gm_sampled, "BM_over_s": cube.BM / cube.s,
               "yaw_torque_rel": probe.yaw_torque_rel, "yaw_force_rel": probe.yaw_force_rel, "A_sub": probe.wet_area, "runs": {}}  # fmt: skip
    for tr in traces:
        d = probes.fluid(tr.sim).damping
        D = probe.damping[tr.spec.key]
        R = probes.rotation_matrix(tr.q[-1])
        n["runs"][tr.spec.key] = {
            "d": d, "report_d": d / DAMPING_SCALE, "settle": settle_time(tr), "t_end": float(tr.t[-1]),
            "zeta_heave": float(D[2, 2] / (2 * math.sqrt(cube.rho * cube.g * cube.s**2 * body.mass))),
            "zeta_roll": float(D[3, 3] / (2 * math.sqrt(weight * probe.gm_sampled * body.inertia[0]))),
            "z_end": float(tr.z[-1]), "tilt_end_deg": math.degrees(tilt(R)), "yaw_end_deg": yaw(R), "face": face_up(R),
            "L_end": float(tr.norm("L")[-1]), "F_end": float(tr.norm("F")[-1]), "L0": float(tr.norm("L")[0]), "q_end": [float(v) for v in tr.q[-1]],
        }  # fmt: skip
    return n


def heave_omega(cube: Cube, tr: Trace) -> float:
    """sqrt(rho g s^2 / M) of the run's body, rad/s."""
    return math.sqrt(cube.rho * cube.g * cube.s**2 / tr.body.mass)

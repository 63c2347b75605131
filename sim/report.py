"""`python -m sim report`: the accuracy report, OUT_DIR/accuracy.md with figures in OUT_DIR/accuracy/.

Five parts, every number computed here from runs made by this command (nothing hand-typed):
work-precision diagrams with observed orders, the sampled model's error against the exact panel
model as N grows, a stability map of the fixed-step integrators over damping and density, a verdict
table (cheapest method per target accuracy) and a table of stiff and extreme cases.

Only the public API is used (Simulation, its Frame, State, observe, load_scene, with_overrides, and
Model.wetted/damping_matrix for the fastest damping rate), so the report keeps working whichever
backend advances the steps. Wall-clock figures are medians of `repeats` runs, single-threaded.
"""

from __future__ import annotations

import ctypes
import datetime
import math
import os
import platform
import statistics
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .config import load_scene, with_overrides
from .integrators import INTEGRATORS
from .progress import progress_bar
from .simulation import Simulation, SimulationDiverged, observe
from .state import State


@dataclass
class ReportArgs:
    """Write the accuracy report (work-precision, model error, stability map, verdict, stiff and extreme cases)."""

    out_dir: str = "reports"
    """Folder for accuracy.md; the figures go to OUT_DIR/accuracy/."""
    quick: bool = False
    """A short setting (fewer and shorter runs, ~20 s) for the test suite; the numbers are coarser."""
    repeats: int = 3
    """Timing repeats per run (wall-clock figures are their median)."""


FIXED = ("euler", "splitting", "implicit", "rk4")
ADAPTIVE = ("rk45", "dop853", "radau")
STYLE = {  # colour, marker, line style per integrator, the same in every figure
    "euler": ("C0", "o", "-"), "splitting": ("C1", "s", "-"), "implicit": ("C2", "D", "--"), "rk4": ("C3", "^", "-"),
    "rk45": ("C4", "v", ":"), "dop853": ("C5", "P", ":"), "radau": ("C6", "X", ":"),
}  # fmt: skip
STAB_EXCITATION = 1e-5
"""Initial offset (m), velocities (m/s) and spin (rad/s) of the stability runs."""
STAB_GROWTH = 1e3
"""Excitation energy growth that counts as unstable."""
# Linear stability constants on the two PHYSICS.md scales: heave (dt*omega below it) and damping
# (dt*lambda below it, lambda the fastest damping rate). Symplectic Euler and Stoermer-Verlet: 2 on the
# oscillator; RK4: 2 sqrt 2 on the imaginary axis, 2.785 on the negative real axis; the splitting's
# damping substeps are explicit midpoint steps of dt/2, stable to dt*lambda = 4; 'implicit' solves damping exactly.
def limit_constants(method: str) -> tuple[float, float]:
    """The integrator's declared stability limits on dt omega_heave and dt lambda_max."""
    cls = INTEGRATORS[method]
    return cls.heave_limit, cls.damping_limit


@dataclass(frozen=True)
class Case:
    """One work-precision problem: a preset scene with a force model and maybe another damping."""

    key: str
    scene: str
    forces: str
    damping: float | None = None

    @property
    def title(self) -> str:
        d = f", d = {self.damping:g}" if self.damping is not None else ""
        return f"{self.scene}{d} ({self.forces})"


@dataclass(frozen=True)
class Settings:
    horizon: float
    """Work-precision horizon, s; errors are the maximum over checkpoints up to it."""
    every: float
    """Checkpoint interval, s (the adaptive methods' output interval)."""
    cases: tuple[Case, ...]
    fixed_dts: dict[str, tuple[float, ...]]
    rtols: dict[str, tuple[float, ...]]
    ns: tuple[int, ...]
    """Points per edge for the model-error study."""
    n_inertia: int
    """N of the panel run whose inertia stands for the exact shell's."""
    traj_dt: float
    period_time: float
    period_dt: float
    stab_damping: tuple[float, ...]
    stab_density: tuple[float, ...]
    stab_time: float
    stab_steps: tuple[int, int]
    stab_ratio: float
    stab_cap: float
    stiff_damping: tuple[float, ...]
    stiff_time: float
    ref_rtol: float = 1e-11
    check_rtol: float = 1e-12
    targets: tuple[float, ...] = (1e-2, 1e-4, 1e-6)


def _pow2(lo: int, hi: int) -> tuple[float, ...]:
    """Steps 2^-lo ... 2^-hi s: exact binary fractions that divide every checkpoint interval."""
    return tuple(2.0**-k for k in range(lo, hi + 1))


FULL = Settings(
    horizon=3.0,
    every=0.25,
    cases=(
        Case("panels-drop", "drop", "panels"),
        Case("panels-damped", "damped", "panels"),
        Case("panels-spin", "spin", "panels"),
        Case("points-drop-d100", "drop", "points", 100.0),
    ),
    fixed_dts={"euler": _pow2(4, 10), "splitting": _pow2(2, 10), "implicit": _pow2(2, 10), "rk4": _pow2(2, 9)},
    rtols={"rk45": (1e-3, 1e-5, 1e-7, 1e-9), "dop853": (1e-4, 1e-6, 1e-8, 1e-10), "radau": (1e-3, 1e-5, 1e-7)},
    ns=(2, 4, 8, 16, 32, 64),
    n_inertia=256,
    traj_dt=2.0**-10,
    period_time=3.0,
    period_dt=2.0**-9,
    stab_damping=(0.0, 10.0, 1e2, 1e3, 1e4, 1e5),
    stab_density=(50.0, 900.0),
    stab_time=3.0,
    stab_steps=(200, 2000),
    stab_ratio=1.06,
    stab_cap=1.0,
    stiff_damping=(1e4, 1e5, 1e6, 1e7),
    stiff_time=5.0,
)

QUICK = Settings(
    horizon=1.0,
    every=0.25,
    cases=(Case("panels-damped", "damped", "panels"),),
    fixed_dts={"euler": _pow2(5, 8), "splitting": _pow2(4, 8), "implicit": _pow2(4, 8), "rk4": _pow2(3, 7)},
    rtols={"rk45": (1e-4, 1e-7), "dop853": (1e-6, 1e-9), "radau": (1e-5,)},
    ns=(2, 4, 8, 16),
    n_inertia=64,
    traj_dt=2.0**-8,
    period_time=1.6,
    period_dt=2.0**-8,
    stab_damping=(0.0, 1e4),
    stab_density=(900.0,),
    stab_time=0.5,
    stab_steps=(100, 300),
    stab_ratio=1.25,
    stab_cap=1.0,
    stiff_damping=(1e4, 1e7),
    stiff_time=2.0,
)


# ----------------------------------------------------------------------------------------------
# Runs and measurements


def corners(sim: Simulation) -> np.ndarray:
    """World positions of the body's mesh vertices (the cube's corners), m."""
    s = sim.state
    return s.x_world + sim.body.mesh_vertices @ s.R_world_body.T


def pose_error(a: np.ndarray, b: np.ndarray) -> float:
    """Largest displacement of any corner at any checkpoint between two corner histories, m."""
    return float(np.linalg.norm(a - b, axis=-1).max())


@dataclass
class Run:
    corners: np.ndarray | None
    """(checkpoints, vertices, 3) corner positions from the first repeat, or None if it diverged."""
    cost: float
    """Median wall seconds per simulated second over the repeats (NaN if it diverged)."""
    diverged: str | None = None


def trajectory(scene, horizon: float, every: float, repeats: int = 1) -> Run:
    """Run `scene` to `horizon`, recording the corners every `every` seconds; time only the stepping.
    Adaptive integrators get `every` as their output interval."""
    adaptive = INTEGRATORS[scene.step.integrator].adaptive
    if adaptive:
        scene = with_overrides(scene, step__dt=every)
    costs, history = [], []
    for r in range(max(1, repeats)):
        sim = Simulation(scene)
        k = 1 if adaptive else round(every / sim.dt)
        wall, hist = 0.0, []
        try:
            for _ in range(round(horizon / every)):
                start = time.perf_counter()
                sim.step(k)
                wall += time.perf_counter() - start
                if r == 0:
                    hist.append(corners(sim))
        except SimulationDiverged as e:
            return Run(None, math.nan, str(e))
        if r == 0:
            history = hist
        costs.append(wall / horizon)
    return Run(np.array(history), statistics.median(costs))


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


# ----------------------------------------------------------------------------------------------
# 1. Work-precision


@dataclass
class WPPoint:
    method: str
    setting: float
    """dt (fixed-step) or rtol (adaptive)."""
    error: float
    cost: float
    diverged: str | None = None


@dataclass
class WPResult:
    case: Case
    ref_error: float
    """Estimated error of the reference: its distance from the same run at the check tolerance, m."""
    ref_cost: float
    points: list[WPPoint]
    initial_loads: tuple[float, float] = (math.nan, math.nan)
    """abs(F) (N) and abs(torque) (N m) at t = 0."""
    orders: dict[str, tuple[float, float, float]] = field(default_factory=dict)

    def of(self, method: str) -> list[WPPoint]:
        return [p for p in self.points if p.method == method]


def case_scene(case: Case):
    scene = with_overrides(load_scene(case.scene), fluid__forces=case.forces, fluid__damping=case.damping)
    return scene


def work_precision(case: Case, cfg: Settings, repeats: int, tick) -> WPResult:
    base = case_scene(case)
    T, every = cfg.horizon, cfg.every
    ref = trajectory(with_overrides(base, step__integrator="dop853", step__rtol=cfg.ref_rtol, step__atol=cfg.ref_rtol * 1e-2), T, every)
    check = trajectory(with_overrides(base, step__integrator="dop853", step__rtol=cfg.check_rtol, step__atol=cfg.check_rtol * 1e-2), T, every)
    tick(2)
    points = []
    for name in FIXED:
        for dt in cfg.fixed_dts[name]:
            run = trajectory(with_overrides(base, step__integrator=name, step__dt=dt), T, every, repeats)
            err = pose_error(run.corners, ref.corners) if run.corners is not None else math.nan
            points.append(WPPoint(name, dt, err, run.cost, run.diverged))
            tick()
    for name in ADAPTIVE:
        for rtol in cfg.rtols[name]:
            run = trajectory(with_overrides(base, step__integrator=name, step__rtol=rtol, step__atol=rtol * 1e-2), T, every, repeats)
            err = pose_error(run.corners, ref.corners) if run.corners is not None else math.nan
            points.append(WPPoint(name, rtol, err, run.cost, run.diverged))
            tick()
    f0 = Simulation(base).frame()
    loads = (float(np.linalg.norm(f0.force_world)), float(np.linalg.norm(f0.torque_world)))
    result = WPResult(case, pose_error(ref.corners, check.corners), ref.cost, points, loads)
    floor = max(20 * result.ref_error, 1e-12)
    for name in FIXED:
        pts = result.of(name)
        result.orders[name] = observed_order([p.setting for p in pts], [p.error for p in pts], floor)
    return result


# ----------------------------------------------------------------------------------------------
# 2. Model error: sampled (points) against exact (panels) forces


def quat_about_x(theta: float) -> np.ndarray:
    return np.array([math.cos(theta / 2), math.sin(theta / 2), 0.0, 0.0])


def cube_model(forces: str, n: int, density: float):
    scene = with_overrides(load_scene("rest"), fluid__forces=forces, body__points_per_edge=n, body__density=density)
    return Simulation(scene).model


def loads_at(model, z: float, theta: float):
    frame = observe(model, State(0.0, np.array([0.0, 0.0, z]), quat_about_x(theta), np.zeros(3), np.zeros(3)))
    return frame.force_world, frame.torque_world


def equilibrium_depth(model, theta: float) -> float:
    """Centre-of-mass height where the vertical force vanishes, the cube tilted by theta about x."""
    from scipy.optimize import brentq

    return brentq(lambda z: loads_at(model, z, theta)[0][2], -1.0, 1.0, xtol=1e-13)


def tilted_equilibrium(model, guess: float, window: float = math.radians(6.0)) -> tuple[float, float]:
    """(depth, tilt) of the equilibrium tilted about x nearest to `guess`: a grid scan of the torque
    (at the depth where the body floats) over guess +- window, then Brent's method on the sign change."""
    from scipy.optimize import brentq

    def torque(theta):
        return loads_at(model, equilibrium_depth(model, theta), theta)[1][0]

    grid = guess + np.linspace(-window, window, 13)
    values = np.array([torque(t) for t in grid])
    changes = np.flatnonzero(np.sign(values[:-1]) * np.sign(values[1:]) <= 0)
    if not len(changes):
        return math.nan, math.nan
    roots = [brentq(torque, grid[i], grid[i + 1], xtol=1e-12) for i in changes]
    theta = min(roots, key=lambda t: abs(t - guess))
    return equilibrium_depth(model, theta), theta


def heave_period(forces: str, n: int, cfg: Settings, density: float = 600.0, amplitude: float = 0.02) -> tuple[float, float, float]:
    """Period of a small heave oscillation of the cube floating edge-down (45 deg about x), from the
    turning points (sign changes of u_z, linearly interpolated: u'' = 0 there) of an rk4 run.
    Returns (period, equilibrium depth, water-line width = water-plane area per metre of the 1 m cube)."""
    theta = math.pi / 4
    model = cube_model(forces, n, density)
    z_eq = equilibrium_depth(model, theta)
    scene = with_overrides(load_scene("rest"), fluid__forces=forces, body__points_per_edge=n, body__density=density,
                           initial__position=(0.0, 0.0, z_eq + amplitude), initial__orientation=tuple(quat_about_x(theta)),
                           step__integrator="rk4", step__dt=cfg.period_dt)  # fmt: skip
    sim = Simulation(scene)
    t, u = [0.0], [0.0]
    for _ in range(round(cfg.period_time / sim.dt)):
        sim.step(1)
        t.append(sim.state.t)
        u.append(sim.state.u_world[2])
    t, u = np.array(t), np.array(u)
    i = np.flatnonzero(u[1:-1] * u[2:] < 0) + 1  # skip the start (u = 0 there by construction)
    crossings = t[i] - u[i] * (t[i + 1] - t[i]) / (u[i + 1] - u[i])
    period = 2 * (crossings[-1] - crossings[0]) / (len(crossings) - 1) if len(crossings) >= 2 else math.nan
    width = 2 * (math.sqrt(0.5) - abs(z_eq))  # the diamond's width at the water line (side 1 m)
    return period, z_eq, width


@dataclass
class ModelError:
    ns: tuple[int, ...]
    eq_panels: tuple[float, float]
    eq_points: list[tuple[float, float]]
    upright_depth_error: float
    period_panels: float
    period_linear: float
    period_points: list[float]
    traj_error: list[float]
    """Points(N) against panels(N): the force quadrature alone (same sampled inertia)."""
    inertia_error: list[float]
    """Panels(N) against panels(n_inertia): the sampled inertia's share."""
    inertia_rel: list[float]
    traj_floor: float
    """rk4 at traj_dt against DOP853, panels: the integrator's share in these trajectory errors."""
    cost_points: list[float]
    cost_panels: float
    n_inertia: int
    rates: dict[str, float] = field(default_factory=dict)

    def errors(self) -> dict[str, list[float]]:
        zp, tp = self.eq_panels
        return {
            "equilibrium depth (m)": [abs(z - zp) for z, _ in self.eq_points],
            "equilibrium tilt (rad)": [abs(t - tp) for _, t in self.eq_points],
            "heave period (relative)": [abs(p / self.period_panels - 1) for p in self.period_points],
            "trajectory (m)": self.traj_error,
        }


def model_error(cfg: Settings, repeats: int, tick) -> ModelError:
    eq_density, guess = 770.0, math.radians(20.0)
    panels_model = cube_model("panels", 10, eq_density)
    eq_panels = tilted_equilibrium(panels_model, guess)
    eq_points, upright = [], 0.0
    for n in cfg.ns:
        eq_points.append(tilted_equilibrium(cube_model("points", n, eq_density), eq_panels[1]))
        upright = max(upright, abs(equilibrium_depth(cube_model("points", n, 900.0), 0.0) + 0.4))
        tick()
    period_panels, _, width = heave_period("panels", 10, cfg)
    omega = math.sqrt(1000.0 * 9.81 * width / 600.0)
    period_points = []
    for n in cfg.ns:
        period_points.append(heave_period("points", n, cfg)[0])
        tick()
    T, every = cfg.horizon, cfg.every
    damped = with_overrides(load_scene("damped"), step__integrator="rk4", step__dt=cfg.traj_dt)
    ref = trajectory(with_overrides(damped, fluid__forces="panels", step__integrator="dop853", step__rtol=cfg.ref_rtol, step__atol=cfg.ref_rtol * 1e-2), T, every)
    panels10 = trajectory(with_overrides(damped, fluid__forces="panels"), T, every, repeats)
    exact_inertia = trajectory(with_overrides(damped, fluid__forces="panels", body__points_per_edge=cfg.n_inertia), T, every)
    I_exact = 5 / 18 * Simulation(damped).body.mass * damped.body.size**2  # thin-walled cube (PHYSICS.md)
    traj, inertia, inertia_rel, costs = [], [], [], []
    for n in cfg.ns:
        pan = trajectory(with_overrides(damped, fluid__forces="panels", body__points_per_edge=n), T, every)
        pts = trajectory(with_overrides(damped, fluid__forces="points", body__points_per_edge=n), T, every, repeats)
        traj.append(pose_error(pts.corners, pan.corners))
        inertia.append(pose_error(pan.corners, exact_inertia.corners))
        inertia_rel.append(Simulation(with_overrides(damped, body__points_per_edge=n)).body.inertia[0] / I_exact - 1)
        costs.append(pts.cost)
        tick()
    result = ModelError(cfg.ns, eq_panels, eq_points, upright, period_panels, 2 * math.pi / omega, period_points, traj, inertia,
                        inertia_rel, pose_error(panels10.corners, ref.corners), costs, panels10.cost, cfg.n_inertia)  # fmt: skip
    result.rates = {k: loglog_rate(cfg.ns, v) for k, v in result.errors().items()}
    result.rates["inertia (trajectory, m)"] = loglog_rate(cfg.ns, inertia)
    return result


# ----------------------------------------------------------------------------------------------
# 3. Stability map


def upright(density: float, s: float = 1.0, rho: float = 1000.0, g: float = 9.81) -> dict[str, float]:
    """Upright cube floating at rest: centre height, wetted area, mass and the two PHYSICS.md rates."""
    draft = s * density / rho
    mass = density * s**3
    return {"z": s / 2 - draft, "A_sub": s * s + 4 * s * draft, "M": mass, "omega": math.sqrt(rho * g * s * s / mass)}


def physics_limit(density: float, d: float) -> tuple[float, float]:
    """PHYSICS.md's explicit limits: heave dt < 2/omega, damping dt < 2 M / (d A_sub)."""
    u = upright(density)
    return 2 / u["omega"], (2 * u["M"] / (d * u["A_sub"]) if d > 0 else math.inf)


def fastest_damping_rate(density: float, d: float) -> float:
    """Largest eigenvalue of the 6x6 damping matrix against the mass matrix diag(M, M, M, I) for the
    upright cube at rest depth: the rate of the fastest damping mode. Sway and roll are coupled (the
    wet surface's centroid is below the centre of mass), so it exceeds PHYSICS.md's d A_sub / M."""
    from scipy.linalg import eigh

    if d <= 0:
        return 0.0
    sim = Simulation(with_overrides(stability_scene("implicit", density, d), initial__position=(0.0, 0.0, upright(density)["z"])))
    model, R = sim.model, sim.state.R_world_body
    D = model.damping_matrix(model.wetted(sim.state.x_world, R))
    inertia = R @ np.diag(model.body.inertia) @ R.T
    mass = np.zeros((6, 6))
    mass[:3, :3] = model.body.mass * np.eye(3)
    mass[3:, 3:] = inertia
    return float(eigh(D, mass, eigvals_only=True).max())


def stability_scene(method: str, density: float, d: float, eps: float = STAB_EXCITATION):
    """The upright cube (panels) eps below its rest depth, with velocities and spin of order eps: every mode excited."""
    u = upright(density)
    return with_overrides(load_scene("rest"), fluid__forces="panels", fluid__damping=d, body__density=density, step__integrator=method,
                          initial__position=(0.0, 0.0, u["z"] - eps), initial__velocity=(eps, eps / 2, 0.0),
                          initial__omega=(eps, -eps / 2, eps / 2))  # fmt: skip


def is_stable(scene, dt: float, cfg: Settings, e_rest: float) -> bool:
    """Steps over max(stab_time, min steps) (at most max steps) raise no SimulationDiverged, and the
    excitation energy E - E_rest never exceeds STAB_GROWTH times its start. The excitation is tiny, so a
    growing mode gets there long before the water line's nonlinearity (a light body leaving the water,
    a heavy one submerging) could cap its growth, while a stable symplectic scheme's bounded energy
    oscillation, (1 + dt omega/2) / (1 - dt omega/2) at most, stays below it up to 0.995 of its limit."""
    sim = Simulation(with_overrides(scene, step__dt=dt))
    lo, hi = cfg.stab_steps
    n = int(min(max(math.ceil(cfg.stab_time / dt), lo), hi))
    k = max(1, n // 40)
    energy = [sim.frame().E_total]
    try:
        for _ in range(n // k):
            sim.step(k)
            energy.append(sim.frame().E_total)
    except SimulationDiverged:
        return False
    e = np.array(energy) - e_rest
    return bool(np.isfinite(e).all() and e.max() <= STAB_GROWTH * e[0])


def largest_stable_dt(method: str, density: float, d: float, cfg: Settings) -> tuple[float, int]:
    """Bisection in log dt, started from the method's linear prediction, to a ratio of stab_ratio;
    returns (largest stable dt found, number of runs), dt = cap meaning stable up to the cap."""
    scene = stability_scene(method, density, d)
    u = upright(density)
    e_rest = Simulation(with_overrides(scene, initial__position=(0.0, 0.0, u["z"]), initial__velocity=(0.0, 0.0, 0.0),
                                       initial__omega=(0.0, 0.0, 0.0))).frame().E_total  # fmt: skip
    c_heave, c_damp = limit_constants(method)
    lam = d * u["A_sub"] / u["M"]
    guess = min(c_heave / u["omega"], c_damp / lam if lam > 0 else math.inf, cfg.stab_cap)
    runs = 0

    def stable(dt):
        nonlocal runs
        runs += 1
        return is_stable(scene, dt, cfg, e_rest)

    if stable(guess):
        lo, hi = guess, None
        while hi is None:
            if lo >= cfg.stab_cap:
                return cfg.stab_cap, runs
            trial = min(2 * lo, cfg.stab_cap)
            if stable(trial):
                lo = trial
            else:
                hi = trial
    else:
        lo, hi = None, guess
        while lo is None:
            trial = hi / 2
            if trial < 1e-6:
                return math.nan, runs
            if stable(trial):
                lo = trial
            else:
                hi = trial
    while hi / lo > cfg.stab_ratio:
        mid = math.sqrt(lo * hi)
        if stable(mid):
            lo = mid
        else:
            hi = mid
    return lo, runs


@dataclass
class StabilityMap:
    damping: tuple[float, ...]
    density: tuple[float, ...]
    limits: dict[tuple[str, float, float], float]
    lam_max: dict[tuple[float, float], float]
    """(density, d) -> rate of the fastest damping mode, 1/s."""
    runs: int

    def damping_dominated(self, density: float, d: float) -> bool:
        lam = self.lam_max[density, d]
        return lam > 0 and 2 / lam < 0.5 * 2 / upright(density)["omega"]


def stability_map(cfg: Settings, tick) -> StabilityMap:
    limits, runs = {}, 0
    lam = {(de, d): fastest_damping_rate(de, d) for de in cfg.stab_density for d in cfg.stab_damping}
    for method in FIXED:
        for density in cfg.stab_density:
            for d in cfg.stab_damping:
                limits[method, density, d], n = largest_stable_dt(method, density, d, cfg)
                runs += n
                tick()
    return StabilityMap(cfg.stab_damping, cfg.stab_density, limits, lam, runs)


# ----------------------------------------------------------------------------------------------
# 5. Stiff and extreme cases


@dataclass
class StiffRow:
    d: float
    rest_drift: float
    spin_ratio: float
    spin_stop_time: float
    creep_monotone: bool
    creep_rate: float
    creep_rate_physical: float
    creep_energy_rise: float
    creep: tuple[np.ndarray, np.ndarray]


def slow_rate(d: float, density: float = 900.0) -> tuple[float, float]:
    """Overdamped heave of the upright cube near rest: the physical slow rate, the root of
    M s^2 - c s + k = 0 with c = d A_sub, k = rho g s^2."""
    u = upright(density)
    c, k, M = d * u["A_sub"], 1000.0 * 9.81, u["M"]
    return (c - math.sqrt(c * c - 4 * k * M)) / (2 * M)


def stiff_rows(cfg: Settings, tick, dt: float = 0.01) -> list[StiffRow]:
    rows = []
    for d in cfg.stiff_damping:
        base = with_overrides(load_scene("rest"), fluid__forces="panels", fluid__damping=d, step__integrator="implicit", step__dt=dt)
        sim = Simulation(base)
        drift = 0.0
        for _ in range(round(cfg.stiff_time / dt / 10)):
            sim.step(10)
            drift = max(drift, abs(sim.state.x_world[2] + 0.4), float(np.abs(sim.state.u_world).max()))
        sim = Simulation(with_overrides(base, initial__omega=(-1.0, 1.0, 0.0)))
        w0 = float(np.linalg.norm(sim.frame().omega_world))
        stop = math.nan
        for _ in range(round(1.0 / dt)):
            sim.step(1)
            w = float(np.linalg.norm(sim.frame().omega_world))
            if math.isnan(stop) and w < 1e-3 * w0:
                stop = sim.state.t
        spin_ratio = w / w0
        sim = Simulation(with_overrides(base, initial__position=(0.0, 0.0, -0.38)))
        t, z, energy = [0.0], [-0.38], [sim.frame().E_total]
        for _ in range(round(cfg.stiff_time / dt)):
            sim.step(1)
            t.append(sim.state.t)
            z.append(sim.state.x_world[2])
            energy.append(sim.frame().E_total)
        t, z = np.array(t), np.array(z)
        monotone = bool(np.all(np.diff(z) <= 1e-12) and np.all(z > -0.4 - 1e-12))
        gap = z + 0.4
        ok = gap > 1e-9
        rate = float(-np.polyfit(t[ok], np.log(gap[ok]), 1)[0]) if ok.sum() > 2 else math.nan
        rows.append(StiffRow(d, drift, spin_ratio, stop, monotone, rate, slow_rate(d), float(np.diff(energy).max()), (t, gap)))
        tick()
    return rows


@dataclass
class Extreme:
    case: str
    setup: str
    measured: str
    expected: str
    ok: bool


def run_until(sim: Simulation, t_end: float, chunk: int, measure=None) -> tuple[list, str | None]:
    """Step `chunk` steps at a time up to t_end, collecting measure(sim) after each call; also the
    divergence message, if any (None when the run finished)."""
    samples = []
    try:
        while sim.state.t < t_end - 1e-9:
            sim.step(chunk)
            if measure is not None:
                samples.append(measure(sim))
    except SimulationDiverged as e:
        return samples, str(e)
    return samples, None


def extreme_cases(cfg: Settings, tick) -> tuple[list[Extreme], list[tuple[str, str]]]:
    rows, messages = [], []
    g = 9.81
    quick = cfg is QUICK

    # Light body: leaves the water and falls back; its apex is set by energy conservation.
    apex_errors = []
    for dt in (0.005, 0.005 / 4 if not quick else 0.0025):
        scene = with_overrides(load_scene("drop"), fluid__forces="panels", body__density=1.0, step__dt=dt)
        sim = Simulation(scene)
        f0 = sim.frame()
        apex_pred = f0.E_total / (sim.body.mass * g)
        samples, err = run_until(sim, 12.0, max(1, round(0.01 / dt)), lambda s: (s.state.t, s.state.x_world[2]))
        tt, z = np.array(samples).T
        out = np.flatnonzero(z - 0.5 > 0)
        t_leave = tt[out[0]] if len(out) else math.nan
        back = np.flatnonzero((z - 0.5 <= 0) & (tt > t_leave)) if len(out) else []
        t_back = tt[back[0]] if len(back) else math.nan
        apex_errors.append(z.max() / apex_pred - 1)
        omega = math.sqrt(1000.0 * 9.81 / sim.body.mass)
        rows.append(Extreme("light body, 1 kg/m^3", f"drop scene (centre on the water line), d = 0, implicit dt = {dt:g} s (dt omega = {dt * omega:.2g}), 12 s",
                            f"leaves the water at t = {t_leave:.3g} s, apex z = {z.max():.4g} m ({apex_errors[-1]:+.1e}), back in at t = {t_back:.3g} s"
                            + (f"; {err}" if err else ""),
                            f"apex E0/(M g) = {apex_pred:.4g} m (energy conservation), up to the splitting's O((dt omega)^2) energy error",
                            err is None and not math.isnan(t_back) and abs(apex_errors[-1]) < 0.1))  # fmt: skip
    tick()

    # Heavy body: sinks at the terminal speed its damping sets.
    d = 1e4
    scene = with_overrides(load_scene("rest"), fluid__forces="panels", body__density=10000.0, fluid__damping=d, initial__position=(0.0, 0.0, -1.0))
    sim = Simulation(scene)
    M, V = sim.body.mass, sim.body.volume
    _, err = run_until(sim, 3.0, 20)
    v = -sim.state.u_world[2]
    v_t = (M - 1000.0 * V) * g / (d * 6.0)
    rows.append(Extreme("heavy body, 10000 kg/m^3", f"fully submerged, d = {d:g}, implicit dt = {sim.dt:g} s, 3 s",
                        f"sinks at {v:.6g} m/s (depth {-sim.state.x_world[2]:.3g} m)",
                        f"v_t = (M - rho V) g / (d 6 s^2) = {v_t:.6g} m/s",
                        err is None and abs(v / v_t - 1) < 1e-3))  # fmt: skip
    tick()

    # Fast spin of an elongated box near its intermediate axis (Dzhanibekov flips), out of the water.
    w = 100 * np.array([0.02, 1.0, 0.02]) / np.linalg.norm([0.02, 1.0, 0.02])
    for method, dt in (("implicit", 0.005), ("implicit", 0.001), ("rk4", 0.001)):
        scene = with_overrides(load_scene("rest"), body__shape="box", body__extents=(2.0, 0.5, 0.25), fluid__rho=0.0, fluid__g=0.0,
                               initial__position=(0.0, 0.0, 10.0), initial__omega=tuple(w), step__integrator=method, step__dt=dt)  # fmt: skip
        sim = Simulation(scene)

        def spin_state(s):
            f = s.frame()
            return np.linalg.norm(f.L_world), f.E_kin, (s.state.R_world_body.T @ f.omega_world)[1]

        first = spin_state(sim)
        samples, err = run_until(sim, 2.0, max(1, round(0.005 / dt)), spin_state)
        L, K, wy = np.array([first, *samples]).T
        dL, dK = np.abs(L / L[0] - 1), np.abs(K / K[0] - 1)
        flips = int(np.sum(np.diff(np.sign(wy)) != 0))
        rows.append(Extreme("100 rad/s spin, box 2 x 0.5 x 0.25 m", f"near the intermediate axis, g = rho = 0, {method} dt = {dt:g} s, 2 s",
                            f"max rel. change: abs(L) {max(dL):.1e}, E_kin {max(dK):.1e}; {flips} flips" + (f"; {err}" if err else ""),
                            "abs(L) and E_kin constant (torque-free)", err is None and max(dL) < 1e-9 and max(dK) < 1e-2))  # fmt: skip
    tick()

    # dt = 0.1 s on the damped scene, every fixed-step integrator.
    for method in FIXED:
        scene = with_overrides(load_scene("damped"), fluid__forces="panels", step__integrator=method, step__dt=0.1)
        sim = Simulation(scene)
        e0 = sim.frame().E_total
        samples, err = run_until(sim, 30.0, 1, lambda s: s.frame().E_total)
        rise = float(np.diff([e0, *samples]).max())
        f = sim.frame()
        rows.append(Extreme(f"dt = 0.1 s, {method}", "damped scene (d = 100), 30 s",
                            (f"z(30 s) = {f.x_world[2]:.5f} m, abs(omega) = {np.linalg.norm(f.omega_world):.1e} rad/s, "
                             f"largest one-step energy rise {rise:.2g} J" + (f"; {err}" if err else "")),
                            "stable, settling toward z = -0.4 m", err is None and abs(f.x_world[2] + 0.4) < 0.05))  # fmt: skip
    tick()

    # Exactly at the water line: bottom face on z = 0, top face on z = 0.
    for forces in ("points", "panels"):
        for where, z0 in (("bottom face", 0.5), ("top face", -0.5)):
            scene = with_overrides(load_scene("rest"), fluid__forces=forces, initial__position=(0.0, 0.0, z0))
            sim = Simulation(scene)
            f0 = sim.frame()
            M, V = sim.body.mass, sim.body.volume
            expect = -M * g if z0 > 0 else (1000.0 * V - M) * g
            z, err = run_until(sim, 2.0, 10, lambda s: s.state.x_world[2])
            rows.append(Extreme(f"{where} exactly on z = 0 ({forces})", "900 kg/m^3 at rest, implicit dt = 0.005 s, 2 s",
                                f"F_z(0) = {f0.force_world[2]:.6g} N, wet area {f0.submerged_area:g} m^2; then z in [{min(z):.3f}, {max(z):.3f}] m"
                                + (f"; {err}" if err else ""),
                                f"F_z = {expect:.6g} N", err is None and abs(f0.force_world[2] - expect) < 1e-9 * M * g))  # fmt: skip
    tick()

    # Far above the water: free fall.
    z0 = 1000.0
    scene = with_overrides(load_scene("rest"), fluid__forces="panels", initial__position=(0.0, 0.0, z0))
    sim = Simulation(scene)
    dev, err = run_until(sim, 3.0, 50, lambda s: abs(s.state.x_world[2] - (z0 - g * s.state.t**2 / 2)))
    rows.append(Extreme("far above the water", f"z0 = {z0:g} m, implicit dt = 0.005 s, 3 s", f"max abs(z - parabola) = {max(dev):.1e} m",
                        "free-fall parabola (to round-off: the splitting is exact for constant force)", err is None and max(dev) < 1e-9 * z0))  # fmt: skip
    tick()

    # Explicit schemes past their limits stop with the divergence message (damping limit, then heave limit).
    cases = [("euler", 900.0, 1e5, 0.01, 20.0), ("splitting", 900.0, 1e5, 0.01, 20.0), ("rk4", 900.0, 1e5, 0.01, 20.0),
             ("euler", 50.0, 0.0, 0.5, 20.0), ("splitting", 900.0, 0.0, 0.7, 30.0 if quick else 200.0)]  # fmt: skip
    for method, density, d, dt, t_end in cases:
        scene = stability_scene(method, density, d, eps=0.01)
        sim = Simulation(with_overrides(scene, step__dt=dt))
        e_rest = Simulation(with_overrides(scene, initial__position=(0.0, 0.0, upright(density)["z"]), initial__velocity=(0.0, 0.0, 0.0),
                                          initial__omega=(0.0, 0.0, 0.0))).frame().E_total  # fmt: skip
        e0 = sim.frame().E_total - e_rest
        z, err = run_until(sim, t_end, 1, lambda s: s.state.x_world[2])
        z = [scene.initial.position[2], *z]
        u = upright(density)
        numbers = f"dt omega = {dt * u['omega']:.3g}, dt d A_sub / M = {dt * d * u['A_sub'] / u['M']:.3g}"
        measured = (f"SimulationDiverged (last good state kept, t = {sim.state.t:.3g} s)" if err else
                    f"no SimulationDiverged in {t_end:g} s: z wandered over [{min(z):.3g}, {max(z):.3g}] m, excitation energy "
                    f"{sim.frame().E_total - e_rest:.3g} J from {e0:.3g} J")  # fmt: skip
        rows.append(Extreme(f"{method} past its limit", f"{density:g} kg/m^3, d = {d:g}, dt = {dt:g} s ({numbers})", measured,
                            "stops with SimulationDiverged and its message", err is not None))  # fmt: skip
        if err:
            messages.append((f"{method}, {density:g} kg/m^3, d = {d:g}, dt = {dt:g} s", err))
    tick()
    return rows, messages


# ----------------------------------------------------------------------------------------------
# Machine and timing


def single_thread_blas() -> str:
    """Limit the loaded OpenBLAS libraries to one thread (numpy may be imported before this module,
    so the environment variable can be too late); say what was done."""
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    os.environ.setdefault("MKL_NUM_THREADS", "1")
    done = []
    try:
        with open("/proc/self/maps") as f:
            libs = sorted({line.split()[-1] for line in f if "openblas" in line.lower() and line.split()[-1].startswith("/")})
    except OSError:
        libs = []
    for path in libs:
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        for name in ("openblas_set_num_threads", "scipy_openblas_set_num_threads64_", "openblas_set_num_threads64_"):
            fn = getattr(lib, name, None)
            if fn is not None:
                fn(1)
                done.append(Path(path).name)
                break
    return f"set to 1 at run time in {', '.join(done)}" if done else f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}"


def machine(blas: str) -> dict[str, str]:
    cpu = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import scipy

    sim = Simulation(load_scene("rest"))
    backend = getattr(sim, "backend", "numpy")
    return {
        "CPU (/proc/cpuinfo)": cpu,
        "platform.processor()": platform.processor() or "(empty)",
        "machine": f"{platform.machine()}, {os.cpu_count()} logical CPUs, load average {' '.join(f'{x:.2f}' for x in os.getloadavg())} at start",
        "Python / numpy / scipy": f"{platform.python_version()} / {np.__version__} / {scipy.__version__}",
        "stepping backend": f"{backend} for the fixed-step integrators; adaptive ones are scipy solve_ivp (numpy forces)",
        "BLAS threads": blas,
    }


def warm_up() -> None:
    """One short run of each integrator and force model, so one-off compilation is not timed."""
    for forces in ("points", "panels"):
        for method in (*FIXED, *ADAPTIVE):
            sim = Simulation(with_overrides(load_scene("damped"), fluid__forces=forces, step__integrator=method, step__dt=0.01))
            sim.step(2)


# ----------------------------------------------------------------------------------------------
# Figures


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _method_label(name: str) -> str:
    return f"{name} (order {INTEGRATORS[name].order})"


def figure_work_precision(wp: WPResult, path: Path, label: str) -> None:
    plt = _plt()
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
    fig.savefig(path, dpi=110)
    plt.close(fig)


def figure_model_error(me: ModelError, path: Path, label: str) -> None:
    plt = _plt()
    from matplotlib.ticker import NullFormatter

    errs = me.errors()
    fig, axes = plt.subplots(2, 3, figsize=(16, 9.5))
    groups = (("equilibrium (tilted cube, 770 kg/m^3)", ["equilibrium depth (m)", "equilibrium tilt (rad)"]),
              ("heave period (edge-down cube, 600 kg/m^3, 2 cm)", ["heave period (relative)"]),
              ("trajectory (damped scene, max corner error)", ["trajectory (m)"]))  # fmt: skip
    ns, cost = np.array(me.ns), np.array(me.cost_points)
    for col, (title, keys) in enumerate(groups):
        top, bottom = axes[0, col], axes[1, col]
        series = [(key, np.array(errs[key], float), marker, f"C{i}", "-") for i, (key, marker) in enumerate(zip(keys, "os"))]
        if keys == ["trajectory (m)"]:
            series.append((f"sampled inertia: panels(N) vs panels(N={me.n_inertia})", np.array(me.inertia_error), "x", "gray", "--"))
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
    fig.suptitle(f"sampled (points) vs exact (panels) forces as N grows; cost from the damped-scene trajectory runs; {label}", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def figure_stability(st: StabilityMap, cfg: Settings, path: Path) -> None:
    plt = _plt()
    fig, axes = plt.subplots(1, len(st.density), figsize=(7.5 * len(st.density), 5.4), squeeze=False)
    xs = [d if d > 0 else 1.0 for d in st.damping]  # d = 0 drawn at 1
    for ax, density in zip(axes[0], st.density):
        u = upright(density)
        dd = np.logspace(0, math.log10(max(st.damping) * 3), 200)
        heave, _ = physics_limit(density, 1.0)
        ax.axhline(heave, color="gray", ls="--", lw=1, label=f"heave: dt = 2/omega = {heave:.3g} s")
        ax.loglog(dd, 2 * u["M"] / (dd * u["A_sub"]), color="gray", ls="-.", lw=1, label="damping: dt = 2 M / (d A_sub) (PHYSICS.md)")
        kappa = next((st.lam_max[density, d] / d for d in st.damping if d > 0), None)
        if kappa:
            ax.loglog(dd, 2 / (kappa * dd), color="k", ls=(0, (1, 3)), lw=1.2, label=f"fastest damping mode: dt = 2/lambda_max, lambda_max = {kappa:.3g} d /s")
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
    fig.suptitle("largest stable dt of the fixed-step integrators (panels model, upright cube near rest; markers at the cap = stable up to it)", fontsize=11)
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def figure_creep(rows: list[StiffRow], path: Path) -> None:
    plt = _plt()
    fig, ax = plt.subplots(figsize=(8, 5))
    for i, r in enumerate(rows):
        t, gap = r.creep
        ax.semilogy(t, gap, color=f"C{i}", label=f"d = {r.d:g}: implicit dt = 0.01 s")
        ax.semilogy(t, gap[0] * np.exp(-r.creep_rate_physical * t), color=f"C{i}", ls="--", lw=1)
    ax.set(xlabel="t (s)", ylabel="height above rest depth, z + 0.4 (m)", title="creep back to rest depth: simulated (solid) vs physical slow mode (dashed)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# ----------------------------------------------------------------------------------------------
# The report


@dataclass
class ReportData:
    settings: Settings
    machine: dict[str, str]
    wp: list[WPResult]
    model: ModelError
    stability: StabilityMap
    stiff: list[StiffRow]
    extremes: list[Extreme]
    messages: list[tuple[str, str]]
    verdict: dict[float, dict[str, WPPoint | None]]
    figures: list[str]
    seconds: float
    markdown: str = ""


def verdict(wp: list[WPResult], targets) -> dict[float, dict[str, WPPoint | None]]:
    """For each target and case: the cheapest measured run whose error is within the target."""
    out = {}
    for target in targets:
        out[target] = {}
        for res in wp:
            ok = [p for p in res.points if np.isfinite(p.error) and p.error <= target and np.isfinite(p.cost)]
            out[target][res.case.key] = min(ok, key=lambda p: p.cost) if ok else None
    return out


def _setting(p: WPPoint) -> str:
    if INTEGRATORS[p.method].adaptive:
        return f"{p.method} rtol {p.setting:.0e}"
    return f"{p.method} dt 2^{round(math.log2(p.setting))} = {p.setting:.4g} s"


def _fmt(x: float, spec: str = ".2e") -> str:
    return "n/a" if x is None or not np.isfinite(x) else format(x, spec)


def run_report(args: ReportArgs) -> ReportData:
    """Compute everything and write the markdown and figures; return the data (for tests)."""
    started = time.perf_counter()
    cfg = QUICK if args.quick else FULL
    out = Path(args.out_dir)
    fig_dir = out / "accuracy"
    fig_dir.mkdir(parents=True, exist_ok=True)
    blas = single_thread_blas()
    repeats = max(1, args.repeats)
    jobs = (sum(2 + sum(len(v) for v in cfg.fixed_dts.values()) + sum(len(v) for v in cfg.rtols.values()) for _ in cfg.cases)
            + 3 * len(cfg.ns) + len(FIXED) * len(cfg.stab_density) * len(cfg.stab_damping) + len(cfg.stiff_damping) + 7)  # fmt: skip
    bar = progress_bar(jobs, unit="run")

    def tick(n=1):
        bar.update(n)

    try:
        with np.errstate(over="ignore", invalid="ignore", divide="ignore", under="ignore"):
            info = machine(blas)
            warm_up()
            wp = [work_precision(case, cfg, repeats, tick) for case in cfg.cases]
            me = model_error(cfg, repeats, tick)
            st = stability_map(cfg, tick)
            stiff = stiff_rows(cfg, tick)
            extremes, messages = extreme_cases(cfg, tick)
    finally:
        bar.close()
    data = ReportData(cfg, info, wp, me, st, stiff, extremes, messages, verdict(wp, cfg.targets), [], 0.0)
    label = f"{cfg.horizon:g} s; {info['CPU (/proc/cpuinfo)']}, {repeats} repeats"
    for res in wp:
        name = f"wp_{res.case.key}.png"
        figure_work_precision(res, fig_dir / name, label)
        data.figures.append(name)
    figure_model_error(me, fig_dir / "model_error.png", f"{info['CPU (/proc/cpuinfo)']}, {repeats} repeats")
    figure_stability(st, cfg, fig_dir / "stability.png")
    figure_creep(stiff, fig_dir / "stiff_creep.png")
    data.figures += ["model_error.png", "stability.png", "stiff_creep.png"]
    data.seconds = time.perf_counter() - started
    data.markdown = markdown(data, args)
    (out / "accuracy.md").write_text(data.markdown)
    return data


def report(args: ReportArgs) -> int:
    data = run_report(args)
    print(f"wrote {Path(args.out_dir) / 'accuracy.md'} and {len(data.figures)} figures in {data.seconds:.0f} s")
    return 0


# ----------------------------------------------------------------------------------------------
# Markdown


def _table(header: list[str], rows: list[list[str]]) -> list[str]:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c).replace("|", "/") for c in row) + " |" for row in rows]
    return lines


def markdown(data: ReportData, args: ReportArgs) -> str:
    cfg, me, st = data.settings, data.model, data.stability
    rel = "accuracy"
    L = []
    add = L.append
    add("# floatsim accuracy report")
    add("")
    add(f"Generated by `python -m sim report{' --quick' if args.quick else ''}` "
        f"({'quick setting: coarse, for the tests' if args.quick else 'full setting'}) on {datetime.date.today().isoformat()} "
        f"in {data.seconds:.0f} s of wall time. Regenerate with `python -m sim report` (about as long; `--quick` for a short check). "
        "Every number below is computed by that command.")  # fmt: skip
    add("")
    add("**Machine.** Wall-clock figures are medians of "
        f"{args.repeats} runs in one process on one core (single-threaded: BLAS limited to one thread, no parallel code); "
        "the machine is shared, so absolute timings are noisy; their ratios are the useful part.")  # fmt: skip
    add("")
    L += _table(["", ""], [[k, v] for k, v in data.machine.items()])
    add("")
    add("**Error measure.** Against a reference run of the same model (DOP853, rtol "
        f"{cfg.ref_rtol:g}, atol rtol/100), the largest distance between corresponding cube corners "
        f"at any checkpoint (every {cfg.every:g} s up to the horizon of {cfg.horizon:g} s), in metres: "
        "position and orientation errors in one number. The reference's own error is its distance, in the same measure, "
        f"from a run at rtol {cfg.check_rtol:g}.")  # fmt: skip
    add("")

    # 1
    add("## 1. Work-precision")
    add("")
    add("Fixed-step integrators at dt = 2^-k s (exact binary fractions), adaptive ones (scipy `solve_ivp`, dt = output "
        f"interval {cfg.every:g} s) at several rtol with atol = rtol/100. Cost = wall time per simulated second, "
        "including the per-checkpoint `Simulation.step` call overhead (an energy check each call). "
        "Observed order = least-squares log-log slope of error against dt over the four smallest dt whose error is "
        "above 20x the reference's error; the range of neighbour-to-neighbour slopes there is given too.")  # fmt: skip
    add("")
    for res in data.wp:
        add(f"### {res.case.title}")
        add("")
        add(f"![work-precision {res.case.title}]({rel}/wp_{res.case.key}.png)")
        add("")
        add(f"Reference: DOP853 rtol {cfg.ref_rtol:g}, its estimated error {res.ref_error:.1e} m, cost {res.ref_cost:.3g} s/s.")
        add("")
        rows = []
        for name in FIXED:
            fit, lo, hi = res.orders[name]
            pts = res.of(name)
            div = [p for p in pts if p.diverged]
            best = min((p for p in pts if np.isfinite(p.error)), key=lambda p: p.error, default=None)
            rows.append([name, INTEGRATORS[name].order, _fmt(fit, ".2f"), f"{_fmt(lo, '.2f')} .. {_fmt(hi, '.2f')}",
                         _fmt(best.error if best else math.nan), ", ".join(f"{p.setting:g}" for p in div) or "none"])  # fmt: skip
        L += _table(["integrator", "declared order", "observed order", "local slopes", "smallest error (m)", "diverged at dt (s)"], rows)
        add("")
        rows = []
        for name in ADAPTIVE:
            for p in res.of(name):
                rows.append([name, f"{p.setting:.0e}", _fmt(p.error), _fmt(p.error / p.setting, ".2g"), _fmt(p.cost, ".3g")])
        L += _table(["adaptive", "rtol", "error (m)", "error / rtol", "cost (s/s)"], rows)
        add("")
    add("**Observed orders at a glance** (declared in brackets):")
    add("")
    L += _table(["case", *[f"{m} ({INTEGRATORS[m].order})" for m in FIXED]],
                [[res.case.title, *[_fmt(res.orders[m][0], ".2f") for m in FIXED]] for res in data.wp])  # fmt: skip
    add("")
    add(_wp_discussion(data))
    add("")

    # 2
    add("## 2. Model error: sampled (`points`) vs exact (`panels`) forces")
    add("")
    add(f"![model error]({rel}/model_error.png)")
    add("")
    zp, tp = me.eq_panels
    add(f"* **Equilibrium** (static, solved directly: vertical force zero by Brent's method in z, torque zero by a scan and "
        f"Brent's method in the tilt about x). A cube of 770 kg/m^3 has a tilted equilibrium: panels give depth "
        f"z = {zp:.6f} m, tilt {math.degrees(tp):.4f} deg. For the upright cube of 900 kg/m^3 the sampled depth is exact for every N "
        f"(largest deviation from -0.4 m over the N tried: {me.upright_depth_error:.1e} m) because only the horizontal faces carry "
        "vertical pressure and all their samples sit at one depth; the upright `drop`/`rest` heave is therefore no test of N.")  # fmt: skip
    add(f"* **Heave period** of the cube floating edge-down (45 deg about x, 600 kg/m^3; the water line crosses the inclined faces), "
        f"2 cm amplitude, rk4 dt = {cfg.period_dt:g} s: panels {me.period_panels:.6f} s; linear theory 2 pi / sqrt(rho g A_wp / M) "
        f"with the water-plane area at rest gives {me.period_linear:.6f} s (difference {abs(me.period_panels / me.period_linear - 1):.1e}, "
        "the amplitude's nonlinearity).")  # fmt: skip
    add(f"* **Trajectory**: the `damped` scene over {cfg.horizon:g} s, rk4 dt = {cfg.traj_dt:g} s, points(N) against panels with the "
        f"same N, so both have the same sampled inertia and only the force quadrature differs. The integrator's share "
        f"(panels rk4 vs DOP853) is {me.traj_floor:.1e} m. Separately, the inertia tensor itself is computed from the samples "
        f"for both models (relative to the thin shell's (5/18) M s^2: {me.inertia_rel[0]:+.2e} at N = {me.ns[0]}, {me.inertia_rel[-1]:+.2e} at N = {me.ns[-1]}, "
        f"i.e. about {me.inertia_rel[-1] * me.ns[-1] ** 2:.2f}/N^2); its effect on the trajectory (panels(N) against panels(N = {cfg.n_inertia})) "
        "is the grey line.")  # fmt: skip
    add("")
    errs = me.errors()
    header = ["N", "cost (s/s)", *errs.keys(), "inertia effect (m)"]
    rows = []
    for i, n in enumerate(me.ns):
        rows.append([n, _fmt(me.cost_points[i], ".3g"), *[_fmt(v[i]) for v in errs.values()], _fmt(me.inertia_error[i])])
    rows.append(["rate p (error ~ N^-p, N >= 4)", "", *[_fmt(me.rates[k], ".2f") for k in errs], _fmt(me.rates["inertia (trajectory, m)"], ".2f")])
    L += _table(header, rows)
    add("")
    add(f"Panels cost {me.cost_panels:.3g} s/s on the same trajectory (12 triangles whatever N). "
        + _model_discussion(me))  # fmt: skip
    add("")

    # 3
    add("## 3. Stability map")
    add("")
    add(f"![stability map]({rel}/stability.png)")
    add("")
    add("Largest stable dt, by bisection in log dt to a ratio of "
        f"{cfg.stab_ratio:g}, started from each method's linear prediction, capped at {cfg.stab_cap:g} s. Problem: the upright cube "
        f"(panels) {STAB_EXCITATION:g} m below its rest depth with velocities and spin of {STAB_EXCITATION:g} (m/s, rad/s), so every "
        f"mode is excited. Stable = `Simulation.step` over max({cfg.stab_time:g} s, {cfg.stab_steps[0]} steps) (at most "
        f"{cfg.stab_steps[1]} steps) raises no `SimulationDiverged` and the excitation energy E - E_rest never exceeds {STAB_GROWTH:g} "
        "times its start. The tiny start matters: a light body's heave instability saturates once it jumps clear of the water (and a "
        "heavy one's once it submerges), so a large initial excitation lets wrong but bounded motion pass for stable; "
        f"{STAB_GROWTH:g} is far above a stable symplectic scheme's energy oscillation ((1 + dt omega/2)/(1 - dt omega/2) at most) "
        "and far below saturation. "
        f"{st.runs} runs in all. PHYSICS.md's limits are drawn in: heave dt omega < 2 with omega = sqrt(rho g s^2 / M), damping "
        "dt d A_sub / M < 2. The constants are the explicit Euler's; the other schemes' linear limits differ: Stoermer-Verlet "
        "(the splitting's kick-drift-kick) 2 on the oscillator, its damping substeps (explicit midpoint over dt/2) 4; "
        "RK4 2.83 on the oscillator and 2.79 on pure decay; `implicit` has no damping limit, only the heave one.")  # fmt: skip
    add("")
    rows = []
    for density in st.density:
        for d in st.damping:
            heave, damp = physics_limit(density, d)
            lam = st.lam_max[density, d]
            row = [f"{density:g}", f"{d:g}", f"{heave:.3g}", _fmt(damp, ".3g") if np.isfinite(damp) else "-", f"{2 / lam:.3g}" if lam > 0 else "-"]
            for method in FIXED:
                v = st.limits[method, density, d]
                if not np.isfinite(v):
                    row.append("n/a")
                elif v >= cfg.stab_cap:
                    row.append(f">= {v:.3g} (cap)")
                else:
                    number = f"dt omega {v * upright(density)['omega']:.2f}" + (f", dt lambda_max {v * lam:.2f}" if lam > 0 else "")
                    row.append(f"{v:.3g} ({number})")
            rows.append(row)
    L += _table(["density (kg/m^3)", "d (N s/m^3)", "heave 2/omega (s)", "PHYSICS.md damping 2M/(d A_sub) (s)", "fastest mode 2/lambda_max (s)",
                 *[f"{m}: largest stable dt (s)" for m in FIXED]], rows)  # fmt: skip
    add("")
    add(_stability_discussion(data))
    add("")

    # 4
    add("## 4. Verdict: cheapest measured setting per target accuracy")
    add("")
    add(f"From the work-precision runs above: for each target (max corner error over the {cfg.horizon:g} s horizon) and scene, "
        "the measured run with the least wall time per simulated second among those within the target (no interpolation; "
        "'none' = no tried setting reached it).")  # fmt: skip
    add("")
    rows = []
    for target, per in data.verdict.items():
        row = [f"{target:g} m"]
        for res in data.wp:
            p = per[res.case.key]
            row.append("none" if p is None else f"{_setting(p)}: {p.cost:.2g} s/s (error {p.error:.1e})")
        rows.append(row)
    L += _table(["target", *[r.case.title for r in data.wp]], rows)
    add("")
    add(_verdict_discussion(data))
    add("")

    # 5
    add("## 5. Stiff and extreme cases")
    add("")
    add("Stiff damping, `implicit` at dt = 0.01 s, panels, upright 900 kg/m^3 cube: **rest** = started at rest depth "
        f"for {cfg.stiff_time:g} s (largest of abs(z + 0.4) and abs(u)); **spin** = started at rest depth spinning at (-1, 1, 0) rad/s "
        f"(abs(omega) after 1 s over its start, and when it fell below 1e-3 of it); **creep** = released 2 cm above rest depth "
        f"for {cfg.stiff_time:g} s: monotone approach, and the fitted exponential rate against the physical slow rate "
        "s = (c - sqrt(c^2 - 4 k M)) / (2 M), c = d A_sub, k = rho g s^2.")  # fmt: skip
    add("")
    rows = []
    for r in data.stiff:
        rows.append([f"{r.d:g}", f"{r.rest_drift:.1e}", f"{r.spin_ratio:.1e} (at t = {_fmt(r.spin_stop_time, '.2g')} s)",
                     "yes" if r.creep_monotone else "NO", f"{r.creep_energy_rise:.1e}", f"{r.creep_rate:.4g}", f"{r.creep_rate_physical:.4g}",
                     f"{r.creep_rate / r.creep_rate_physical:.3g}"])  # fmt: skip
    L += _table(["d (N s/m^3)", "rest: drift (m, m/s)", "spin: abs(omega) ratio after 1 s", "creep monotone",
                 "creep: largest one-step energy rise (J)", "creep rate (1/s)", "physical rate (1/s)", "ratio"], rows)  # fmt: skip
    add("")
    add(f"![creep]({rel}/stiff_creep.png)")
    add("")
    add(_stiff_discussion(data))
    add("")
    rows = [[e.case, e.setup, e.measured, e.expected, "yes" if e.ok else "NO"] for e in data.extremes]
    L += _table(["case", "setup", "measured", "expected", "as expected"], rows)
    add("")
    add(_extreme_discussion(data))
    add("")
    add("Divergence messages of the explicit schemes past their limits (verbatim):")
    add("")
    add("```")
    for what, msg in data.messages:
        add(f"[{what}]")
        add(msg)
    add("```")
    add("")
    return "\n".join(L)


def _wp_discussion(data: ReportData) -> str:
    parts = [("**Reading the orders.** Water-line crossings make the right-hand side non-smooth even for the exact `panels` model:"
             " when a whole face reaches the water at once (the upright `drop`: the top face submerges at z = -0.5 m) the"
             " water-plane area jumps, so the force has a kink (continuous, with a jump in its derivative); when single vertices cross"
             " (a tumbling cube: `damped`, `spin`) the force is smoother still but not infinitely smooth. A step that straddles such a"
             " point commits a local error of low order, so high-order methods lose order, and where the steps happen to land relative"
             " to the kink makes the error jump about (scattered local slopes). With `points` the damping switches on discontinuously as"
             " samples cross z = 0 (a jump in the force, not a kink), which holds every fixed-step method near first order. The adaptive"
             " methods' error estimates do not see a kink inside a step either, so their error is no longer proportional to rtol there"
             " (the error/rtol columns).")]  # fmt: skip
    for res in data.wp:
        o = res.orders
        text = f"{res.case.title}: observed " + ", ".join(f"{m} {_fmt(o[m][0], '.2f')}" for m in FIXED)
        ratios = [p.error / p.setting for p in res.points if p.method in ADAPTIVE and np.isfinite(p.error)]
        if ratios:
            text += f"; adaptive error/rtol {min(ratios):.2g} to {max(ratios):.2g}"
        parts.append(text + ".")
        force, torque = res.initial_loads
        if o["euler"][0] > 1.7 and force + torque < 1e-9:
            parts.append(f"On {res.case.title} the loads vanish at t = 0 (abs(F) = {force:.1e} N, abs(torque) = {torque:.1e} N m): then "
                         "the report's drift-then-kick Euler produces the poses of the Stoermer-Verlet (leapfrog) scheme up to O(dt^2), "
                         "its velocities being leapfrog's half-step ones, so the pose error measured here is second order; with a "
                         "non-zero initial force the first drift is off by O(dt) and the order is 1.")  # fmt: skip
    return " ".join(parts)


def _model_discussion(me: ModelError) -> str:
    r = me.rates
    found = sum(np.isfinite(z) for z, _ in me.eq_points)
    ratio = me.traj_error[-1] / me.inertia_error[-1] if me.inertia_error[-1] > 0 else math.nan
    fits = {k: loglog_fit(me.ns, v) for k, v in me.errors().items()}
    regular = [f"{k} N^-{p:.2f}" for k, (p, scatter) in fits.items() if scatter <= 0.25]
    erratic = [f"{k} (fitted N^-{p:.2f}, scatter {scatter:.2f} decades)" for k, (p, scatter) in fits.items() if scatter > 0.25]
    text = (f"At N = {me.ns[-1]} the trajectory error is {ratio:.2g}x the effect of the sampled inertia, which falls as "
            f"N^-{r['inertia (trajectory, m)']:.2f} and which the panel model shares (both take the inertia from the samples). ")
    if regular:
        text += "Regular convergence (scatter about the fit at most 0.25 decades): " + ", ".join(regular) + " (midpoint quadrature: N^-2). "
    if erratic:
        text += ("Erratic: " + ", ".join(erratic) + ". The sampled force is piecewise linear in the pose, with a kink each time a row of "
                 "samples crosses the water line, so such errors depend on where the water line sits between rows, not only on N; "
                 "a static equilibrium near a tilt bifurcation (small restoring stiffness) magnifies small torque errors. ")
    return text + (f"The tilted equilibrium was found for {found} of {len(me.ns)} N values ('n/a': no torque sign change within 6 deg "
                   "of the exact tilt).")


def _span(values, spec: str = ".2f") -> str:
    lo, hi = min(values), max(values)
    return format(lo, spec) if format(lo, spec) == format(hi, spec) else f"{format(lo, spec)} to {format(hi, spec)}"


def _stability_discussion(data: ReportData) -> str:
    st, cfg = data.stability, data.settings
    imp = [st.limits["implicit", de, d] for de in st.density for d in st.damping]
    lines = [(f"`implicit` is stable at every tried (d, density) for every dt up to {min(imp):.3g} s, its smallest measured limit; "
              "its only limit is the heave one, independent of d.")]  # fmt: skip
    for method in FIXED:
        c_heave, c_damp = limit_constants(method)
        heave = [st.limits[method, de, d] * upright(de)["omega"] for de in st.density for d in st.damping
                 if d == 0 and st.limits[method, de, d] < cfg.stab_cap]  # fmt: skip
        damp = [st.limits[method, de, d] * st.lam_max[de, d] for de in st.density for d in st.damping
                if st.damping_dominated(de, d) and st.limits[method, de, d] < cfg.stab_cap]  # fmt: skip
        text = []
        if heave:
            text.append(f"dt omega = {_span(heave)} at its d = 0 limit (linear theory {c_heave:.3g})")
        if damp and math.isfinite(c_damp):
            text.append(f"dt lambda_max = {_span(damp)} where damping dominates (linear theory {c_damp:.3g})")
        if text:
            lines.append(f"{method}: " + "; ".join(text) + ".")
    ratio = [st.lam_max[de, d] / (d * upright(de)["A_sub"] / upright(de)["M"]) for de in st.density for d in st.damping if d > 0]
    if ratio:
        lines.append(f"The fastest damping mode is {_span(ratio)}x faster than PHYSICS.md's d A_sub / M (sway and roll "
                     "couple because the wet surface's centroid lies below the centre of mass), so PHYSICS.md's damping bound overestimates "
                     f"the explicit limit by that factor. The bisection's resolution is a factor {cfg.stab_ratio:g}.")  # fmt: skip
    return " ".join(lines)


def _verdict_discussion(data: ReportData) -> str:
    wins = {}
    for per in data.verdict.values():
        for p in per.values():
            if p is not None:
                wins[p.method] = wins.get(p.method, 0) + 1
    text = ", ".join(f"{m} {n}" for m, n in sorted(wins.items(), key=lambda kv: -kv[1]))
    # Without damping 'implicit' and 'splitting' do identical work: their timing difference is the noise.
    noise = []
    for res in data.wp:
        if res.case.damping is None and load_scene(res.case.scene).fluid.damping == 0:
            split = {p.setting: p.cost for p in res.of("splitting")}
            noise += [abs(p.cost / split[p.setting] - 1) for p in res.of("implicit") if p.setting in split]
    if noise:
        text += (f". Timing noise: 'implicit' and 'splitting' do identical work without damping, yet their measured costs differ by "
                 f"{np.median(noise):.0%} (median) and up to {max(noise):.0%}; cheaper-than differences smaller than that are not "
                 "significant, and at a few ms per simulated second the per-call overhead of `Simulation.step` dominates")
    return (f"Wins per method over all cells: {text or 'none'}. The fixed-step integrators run "
            f"on the '{data.machine['stepping backend'].split()[0]}' backend while the adaptive ones always call back into Python "
            "for every force evaluation, which weighs heavily in their cost; compare within each family before across.")


def _extreme_discussion(data: ReportData) -> str:
    parts = []
    spins = [e for e in data.extremes if e.case.startswith("100 rad/s spin")]
    if spins:
        parts.append("Torque-free, L is never changed by any scheme, so abs(L) is exact by construction; the kinetic energy error measures "
                     "the orientation's accuracy (the box is far from isotropic), and the Dzhanibekov flips show the motion is resolved.")
    silent = [e for e in data.extremes if e.case.endswith("past its limit") and not e.ok]
    for e in silent:
        parts.append(f"**Surprise:** {e.case} ({e.setup}) does not stop: {e.measured}. Past the heave limit the growth is not exponential "
                     "for long: once the body leaves the water or submerges, the buoyancy stops growing with the displacement, so the motion "
                     "stays bounded but wrong, and `Simulation`'s blow-up check (energy above its start plus 10x the body's energy scale) "
                     "does not fire. Only the stability numbers (dt omega > 2) give it away.")
    return " ".join(parts)


def _stiff_discussion(data: ReportData) -> str:
    rows = data.stiff
    if not rows:
        return ""
    ratios = [r.creep_rate / r.creep_rate_physical for r in rows]
    return ("`implicit` stays put at rest depth and kills a spin at every d, and the creep back to rest depth is monotone and at the "
            f"physical speed (measured over physical rate: {min(ratios):.3g} to {max(ratios):.3g}). It solves the pose-dependent loads and "
            "the damping together, exactly, at a frozen pose, so each half step relaxes the velocity to its exact terminal value instead "
            "of kicking it and then damping the kick away (an earlier version did that and crept up to 256x too fast at d = 1e7).")


__all__ = ["ReportArgs", "report", "run_report"]

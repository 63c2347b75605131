"""The accuracy report's runs: settings, then one function per part returning plain data objects.

Nothing here formats or draws; the numbers the text quotes are derived in `numbers`, the figures in
`plot`, the markdown in `text`. Wall-clock figures are medians of `repeats` runs, single-threaded.
"""

from __future__ import annotations

import math
import statistics
import time
from dataclasses import dataclass, field

import numpy as np

from sim import INTEGRATORS, Simulation, SimulationDiverged, State, load_scene, make_body, with_overrides

from .. import probes

FIXED = ("euler", "splitting", "implicit", "rk4")
ADAPTIVE = ("rk45", "dop853", "radau")
STAB_EXCITATION = 1e-5
"""Initial offset (m), velocities (m/s) and spin (rad/s) of the stability runs."""
STAB_GROWTH = 1e3
"""Excitation energy growth that counts as unstable."""
# Linear stability constants on the two PHYSICS.md scales: heave (dt*omega below it) and damping
# (dt*lambda below it, lambda the fastest damping rate). Symplectic Euler and Stoermer-Verlet: 2 on the
# oscillator; RK4: 2 sqrt 2 on the imaginary axis, 2.785 on the negative real axis; the splitting's
# damping substeps are explicit midpoint steps of dt/2, stable to dt*lambda = 4; 'implicit' solves damping exactly.
# Each integrator declares its own (probes.stability_limits).


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

    def jobs(self) -> int:
        """Progress-bar units: one per run group the parts tick for."""
        wp = sum(2 + sum(len(v) for v in self.fixed_dts.values()) + sum(len(v) for v in self.rtols.values()) for _ in self.cases)
        return wp + 3 * len(self.ns) + len(FIXED) * len(self.stab_density) * len(self.stab_damping) + len(self.stiff_damping) + 7


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
        Case("panels-waves", "waves", "panels"),
        Case("panels-storm", "storm", "panels"),
    ),
    fixed_dts={"euler": _pow2(4, 10), "splitting": _pow2(2, 10), "implicit": _pow2(2, 10), "rk4": _pow2(2, 9)},
    rtols={"rk45": (1e-3, 1e-5, 1e-7, 1e-9), "dop853": (1e-4, 1e-6, 1e-8, 1e-10), "radau": (1e-3, 1e-5, 1e-7)},
    ns=(2, 4, 8, 16, 32, 64),
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
    return s.x_world + probes.body(sim).mesh_vertices @ s.R_world_body.T


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


def trajectory(scene, horizon: float, every: float, repeats: int = 1, sampled_inertia: bool = False) -> Run:
    """Run `scene` to `horizon`, recording the corners every `every` seconds; time only the stepping.
    Adaptive integrators get `every` as their output interval. sampled_inertia: the body takes the
    samples' inertia even on panels (which otherwise take the mesh shell's exact one)."""
    adaptive = INTEGRATORS[scene.step.integrator].adaptive
    if adaptive:
        scene = with_overrides(scene, step__dt=every)
    costs, history = [], []
    for r in range(max(1, repeats)):
        sim = Simulation(scene, body=make_body(scene.body, scene.base_dir, exact_inertia=False) if sampled_inertia else None)
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
    """Observed order per fixed-step method (numbers.observed_orders): fit, smallest and largest local slope."""

    def of(self, method: str) -> list[WPPoint]:
        return [p for p in self.points if p.method == method]


def case_scene(case: Case):
    return with_overrides(load_scene(case.scene), fluid__forces=case.forces, fluid__damping=case.damping)


def _dop853(scene, rtol: float):
    return with_overrides(scene, step__integrator="dop853", step__rtol=rtol, step__atol=rtol * 1e-2)


def work_precision(case: Case, cfg: Settings, repeats: int, tick) -> WPResult:
    """Every fixed step and tolerance of `cfg` on `case`, measured against a tight DOP853 reference."""
    base = case_scene(case)
    T, every = cfg.horizon, cfg.every
    ref = trajectory(_dop853(base, cfg.ref_rtol), T, every)
    check = trajectory(_dop853(base, cfg.check_rtol), T, every)
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
    return WPResult(case, pose_error(ref.corners, check.corners), ref.cost, points, loads)


# ----------------------------------------------------------------------------------------------
# 2. Model error: sampled (points) against exact (panels) forces


def quat_about_x(theta: float) -> np.ndarray:
    return np.array([math.cos(theta / 2), math.sin(theta / 2), 0.0, 0.0])


def cube_model(forces: str, n: int, density: float) -> Simulation:
    """The `rest` cube with a force model, points per edge and density (only its loads are probed)."""
    return Simulation(with_overrides(load_scene("rest"), fluid__forces=forces, body__points_per_edge=n, body__density=density))


def loads_at(model: Simulation, z: float, theta: float):
    """Force and torque on the cube at rest with its centre at height z, tilted by theta about x."""
    frame = probes.frame_at(model, State(0.0, np.array([0.0, 0.0, z]), quat_about_x(theta), np.zeros(3), np.zeros(3)))
    return frame.force_world, frame.torque_world


def equilibrium_depth(model: Simulation, theta: float) -> float:
    """Centre-of-mass height where the vertical force vanishes, the cube tilted by theta about x."""
    from scipy.optimize import brentq

    return brentq(lambda z: loads_at(model, z, theta)[0][2], -1.0, 1.0, xtol=1e-13)


def tilted_equilibrium(model: Simulation, guess: float, window: float = math.radians(6.0)) -> tuple[float, float]:
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
    """Points(N) against panels(N) given the samples' inertia too: the force quadrature alone."""
    inertia_error: list[float]
    """Panels with the samples' inertia (N) against panels with the exact shell inertia: the sampled inertia's share."""
    inertia_rel: list[float]
    traj_floor: float
    """rk4 at traj_dt against DOP853, panels: the integrator's share in these trajectory errors."""
    cost_points: list[float]
    cost_panels: float
    rates: dict[str, float] = field(default_factory=dict)
    """Convergence rate per error (numbers.model_rates)."""


def _statics(cfg: Settings, tick, eq_density: float = 770.0, guess: float = math.radians(20.0)):
    """Tilted equilibrium (panels, then points per N) and the upright cube's worst depth error over N."""
    eq_panels = tilted_equilibrium(cube_model("panels", 10, eq_density), guess)
    eq_points, upright_error = [], 0.0
    for n in cfg.ns:
        eq_points.append(tilted_equilibrium(cube_model("points", n, eq_density), eq_panels[1]))
        upright_error = max(upright_error, abs(equilibrium_depth(cube_model("points", n, 900.0), 0.0) + 0.4))
        tick()
    return eq_panels, eq_points, upright_error


def model_error(cfg: Settings, repeats: int, tick) -> ModelError:
    eq_panels, eq_points, upright_error = _statics(cfg, tick)
    period_panels, _, width = heave_period("panels", 10, cfg)
    omega = math.sqrt(1000.0 * 9.81 * width / 600.0)
    period_points = []
    for n in cfg.ns:
        period_points.append(heave_period("points", n, cfg)[0])
        tick()
    T, every = cfg.horizon, cfg.every
    damped = with_overrides(load_scene("damped"), step__integrator="rk4", step__dt=cfg.traj_dt)
    panels = with_overrides(damped, fluid__forces="panels")
    ref = trajectory(_dop853(panels, cfg.ref_rtol), T, every)
    panels10 = trajectory(panels, T, every, repeats)
    I_exact = 5 / 18 * probes.body(Simulation(damped)).mass * damped.body.size**2  # thin-walled cube (PHYSICS.md)
    traj, inertia, inertia_rel, costs = [], [], [], []
    for n in cfg.ns:
        pan = trajectory(with_overrides(damped, fluid__forces="panels", body__points_per_edge=n), T, every, sampled_inertia=True)
        pts = trajectory(with_overrides(damped, fluid__forces="points", body__points_per_edge=n), T, every, repeats)
        traj.append(pose_error(pts.corners, pan.corners))
        inertia.append(pose_error(pan.corners, panels10.corners))  # panels10: the mesh shell's exact inertia
        inertia_rel.append(probes.body(Simulation(with_overrides(damped, body__points_per_edge=n))).inertia[0] / I_exact - 1)
        costs.append(pts.cost)
        tick()
    return ModelError(cfg.ns, eq_panels, eq_points, upright_error, period_panels, 2 * math.pi / omega, period_points, traj, inertia,
                      inertia_rel, pose_error(panels10.corners, ref.corners), costs, panels10.cost)  # fmt: skip


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
    body, R = probes.body(sim), sim.state.R_world_body
    D = probes.damping_matrix(sim, sim.state)
    mass = np.zeros((6, 6))
    mass[:3, :3] = body.mass * np.eye(3)
    mass[3:, 3:] = R @ np.diag(body.inertia) @ R.T
    return float(eigh(D, mass, eigvals_only=True).max())


def stability_scene(method: str, density: float, d: float, eps: float = STAB_EXCITATION):
    """The upright cube (panels) eps below its rest depth, with velocities and spin of order eps: every mode excited."""
    u = upright(density)
    return with_overrides(load_scene("rest"), fluid__forces="panels", fluid__damping=d, body__density=density, step__integrator=method,
                          initial__position=(0.0, 0.0, u["z"] - eps), initial__velocity=(eps, eps / 2, 0.0),
                          initial__omega=(eps, -eps / 2, eps / 2))  # fmt: skip


def rest_energy(scene, density: float) -> float:
    """Total energy of `scene`'s body at rest at the upright cube's rest depth."""
    at_rest = with_overrides(scene, initial__position=(0.0, 0.0, upright(density)["z"]), initial__velocity=(0.0, 0.0, 0.0),
                             initial__omega=(0.0, 0.0, 0.0))  # fmt: skip
    return Simulation(at_rest).frame().E_total


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
    e_rest = rest_energy(scene, density)
    c_heave, c_damp = probes.stability_limits(method)
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
# 5. Stiff cases


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


def _rest_drift(base, t_end: float, dt: float) -> float:
    """Started at rest depth: the largest abs(z + 0.4) and abs(u) over the run."""
    sim = Simulation(base)
    drift = 0.0
    for _ in range(round(t_end / dt / 10)):
        sim.step(10)
        drift = max(drift, abs(sim.state.x_world[2] + 0.4), float(np.abs(sim.state.u_world).max()))
    return drift


def _spin_down(base, dt: float) -> tuple[float, float]:
    """Started spinning at (-1, 1, 0) rad/s: abs(omega) after 1 s over its start, and when it fell below 1e-3 of it."""
    sim = Simulation(with_overrides(base, initial__omega=(-1.0, 1.0, 0.0)))
    w0 = float(np.linalg.norm(sim.frame().omega_world))
    stop = math.nan
    for _ in range(round(1.0 / dt)):
        sim.step(1)
        w = float(np.linalg.norm(sim.frame().omega_world))
        if math.isnan(stop) and w < 1e-3 * w0:
            stop = sim.state.t
    return w / w0, stop


def _creep(base, t_end: float, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Released 2 cm above rest depth: times, heights and total energies, one per step."""
    sim = Simulation(with_overrides(base, initial__position=(0.0, 0.0, -0.38)))
    t, z, energy = [0.0], [-0.38], [sim.frame().E_total]
    for _ in range(round(t_end / dt)):
        sim.step(1)
        t.append(sim.state.t)
        z.append(sim.state.x_world[2])
        energy.append(sim.frame().E_total)
    return np.array(t), np.array(z), np.array(energy)


def stiff_rows(cfg: Settings, tick, dt: float = 0.01) -> list[StiffRow]:
    rows = []
    for d in cfg.stiff_damping:
        base = with_overrides(load_scene("rest"), fluid__forces="panels", fluid__damping=d, step__integrator="implicit", step__dt=dt)
        drift = _rest_drift(base, cfg.stiff_time, dt)
        spin_ratio, stop = _spin_down(base, dt)
        t, z, energy = _creep(base, cfg.stiff_time, dt)
        monotone = bool(np.all(np.diff(z) <= 1e-12) and np.all(z > -0.4 - 1e-12))
        gap = z + 0.4
        ok = gap > 1e-9
        rate = float(-np.polyfit(t[ok], np.log(gap[ok]), 1)[0]) if ok.sum() > 2 else math.nan
        rows.append(StiffRow(d, drift, spin_ratio, stop, monotone, rate, slow_rate(d), float(np.diff(energy).max()), (t, gap)))
        tick()
    return rows


# ----------------------------------------------------------------------------------------------
# 5. Extreme cases


@dataclass
class Extreme:
    case: str
    setup: str
    measured: str
    expected: str
    ok: bool


G = 9.81


def _light_body(quick: bool) -> list[Extreme]:
    """Light body: leaves the water and falls back; its apex is set by energy conservation."""
    rows = []
    for dt in (0.005, 0.005 / 4 if not quick else 0.0025):
        scene = with_overrides(load_scene("drop"), fluid__forces="panels", body__density=1.0, step__dt=dt)
        sim = Simulation(scene)
        mass = probes.body(sim).mass
        apex_pred = sim.frame().E_total / (mass * G)
        samples, err = run_until(sim, 12.0, max(1, round(0.01 / dt)), lambda s: (s.state.t, s.state.x_world[2]))
        tt, z = np.array(samples).T
        out = np.flatnonzero(z - 0.5 > 0)
        t_leave = tt[out[0]] if len(out) else math.nan
        back = np.flatnonzero((z - 0.5 <= 0) & (tt > t_leave)) if len(out) else []
        t_back = tt[back[0]] if len(back) else math.nan
        apex_error = z.max() / apex_pred - 1
        omega = math.sqrt(1000.0 * 9.81 / mass)
        rows.append(Extreme("light body, 1 kg/m^3", f"drop scene (centre on the water line), d = 0, implicit dt = {dt:g} s (dt omega = {dt * omega:.2g}), 12 s",
                            f"leaves the water at t = {t_leave:.3g} s, apex z = {z.max():.4g} m ({apex_error:+.1e}), back in at t = {t_back:.3g} s"
                            + (f"; {err}" if err else ""),
                            f"apex E0/(M g) = {apex_pred:.4g} m (energy conservation), up to the splitting's O((dt omega)^2) energy error",
                            err is None and not math.isnan(t_back) and abs(apex_error) < 0.1))  # fmt: skip
    return rows


def _heavy_body() -> list[Extreme]:
    """Heavy body: sinks at the terminal speed its damping sets."""
    d = 1e4
    scene = with_overrides(
        load_scene("rest"), fluid__forces="panels", body__density=10000.0, fluid__damping=d, initial__position=(0.0, 0.0, -1.0)
    )
    sim = Simulation(scene)
    M, V = probes.body(sim).mass, probes.body(sim).volume
    _, err = run_until(sim, 3.0, 20)
    v = -sim.state.u_world[2]
    v_t = (M - 1000.0 * V) * G / (d * 6.0)
    return [Extreme("heavy body, 10000 kg/m^3", f"fully submerged, d = {d:g}, implicit dt = {sim.dt:g} s, 3 s",
                    f"sinks at {v:.6g} m/s (depth {-sim.state.x_world[2]:.3g} m)",
                    f"v_t = (M - rho V) g / (d 6 s^2) = {v_t:.6g} m/s",
                    err is None and abs(v / v_t - 1) < 1e-3)]  # fmt: skip


def _spin_state(sim: Simulation):
    f = sim.frame()
    return np.linalg.norm(f.L_world), f.E_kin, (sim.state.R_world_body.T @ f.omega_world)[1]


def _fast_spin() -> list[Extreme]:
    """Fast spin of an elongated box near its intermediate axis (Dzhanibekov flips), out of the water."""
    rows = []
    w = 100 * np.array([0.02, 1.0, 0.02]) / np.linalg.norm([0.02, 1.0, 0.02])
    for method, dt in (("implicit", 0.005), ("implicit", 0.001), ("rk4", 0.001)):
        scene = with_overrides(load_scene("rest"), body__shape="box", body__extents=(2.0, 0.5, 0.25), fluid__rho=0.0, fluid__g=0.0,
                               initial__position=(0.0, 0.0, 10.0), initial__omega=tuple(w), step__integrator=method, step__dt=dt)  # fmt: skip
        sim = Simulation(scene)
        first = _spin_state(sim)
        samples, err = run_until(sim, 2.0, max(1, round(0.005 / dt)), _spin_state)
        L, K, wy = np.array([first, *samples]).T
        dL, dK = np.abs(L / L[0] - 1), np.abs(K / K[0] - 1)
        flips = int(np.sum(np.diff(np.sign(wy)) != 0))
        rows.append(Extreme("100 rad/s spin, box 2 x 0.5 x 0.25 m", f"near the intermediate axis, g = rho = 0, {method} dt = {dt:g} s, 2 s",
                            f"max rel. change: abs(L) {max(dL):.1e}, E_kin {max(dK):.1e}; {flips} flips" + (f"; {err}" if err else ""),
                            "abs(L) and E_kin constant (torque-free)", err is None and max(dL) < 1e-9 and max(dK) < 1e-2))  # fmt: skip
    return rows


def _large_step() -> list[Extreme]:
    """dt = 0.1 s on the damped scene, every fixed-step integrator."""
    rows = []
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
    return rows


def _on_the_water_line() -> list[Extreme]:
    """Exactly at the water line: bottom face on z = 0, top face on z = 0."""
    rows = []
    for forces in ("points", "panels"):
        for where, z0 in (("bottom face", 0.5), ("top face", -0.5)):
            scene = with_overrides(load_scene("rest"), fluid__forces=forces, initial__position=(0.0, 0.0, z0))
            sim = Simulation(scene)
            f0 = sim.frame()
            M, V = probes.body(sim).mass, probes.body(sim).volume
            expect = -M * G if z0 > 0 else (1000.0 * V - M) * G
            z, err = run_until(sim, 2.0, 10, lambda s: s.state.x_world[2])
            rows.append(Extreme(f"{where} exactly on z = 0 ({forces})", "900 kg/m^3 at rest, implicit dt = 0.005 s, 2 s",
                                f"F_z(0) = {f0.force_world[2]:.6g} N, wet area {f0.submerged_area:g} m^2; then z in [{min(z):.3f}, {max(z):.3f}] m"
                                + (f"; {err}" if err else ""),
                                f"F_z = {expect:.6g} N", err is None and abs(f0.force_world[2] - expect) < 1e-9 * M * G))  # fmt: skip
    return rows


def _far_above() -> list[Extreme]:
    """Far above the water: free fall."""
    z0 = 1000.0
    sim = Simulation(with_overrides(load_scene("rest"), fluid__forces="panels", initial__position=(0.0, 0.0, z0)))
    dev, err = run_until(sim, 3.0, 50, lambda s: abs(s.state.x_world[2] - (z0 - G * s.state.t**2 / 2)))
    return [Extreme("far above the water", f"z0 = {z0:g} m, implicit dt = 0.005 s, 3 s", f"max abs(z - parabola) = {max(dev):.1e} m",
                    "free-fall parabola (to round-off: the splitting is exact for constant force)", err is None and max(dev) < 1e-9 * z0)]  # fmt: skip


def _past_limits(quick: bool) -> tuple[list[Extreme], list[tuple[str, str]]]:
    """Explicit schemes past their limits stop with the divergence message (damping limit, then heave limit)."""
    rows, messages = [], []
    cases = [("euler", 900.0, 1e5, 0.01, 20.0), ("splitting", 900.0, 1e5, 0.01, 20.0), ("rk4", 900.0, 1e5, 0.01, 20.0),
             ("euler", 50.0, 0.0, 0.5, 20.0), ("splitting", 900.0, 0.0, 0.7, 30.0 if quick else 200.0)]  # fmt: skip
    for method, density, d, dt, t_end in cases:
        scene = stability_scene(method, density, d, eps=0.01)
        sim = Simulation(with_overrides(scene, step__dt=dt))
        e_rest = rest_energy(scene, density)
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
    return rows, messages


def extreme_cases(cfg: Settings, tick) -> tuple[list[Extreme], list[tuple[str, str]]]:
    """Every extreme case (seven groups, one tick each) and the divergence messages of the explicit schemes past their limits."""
    quick = cfg is QUICK
    rows = []
    for group in (lambda: _light_body(quick), _heavy_body, _fast_spin, _large_step, _on_the_water_line, _far_above):
        rows += group()
        tick()
    past, messages = _past_limits(quick)
    tick()
    return rows + past, messages

"""The seed-figures page's runs and static force probes, returned as plain data.

The only physics written here is the source report's own point grid (`report_grid`), rebuilt for the
comparison of figures 1-2; its forces, like every other number here, come from `sim` (through
`studies.probes`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from sim import Simulation, State, load_scene, with_overrides

from .. import probes

DENSITIES = (200.0, 500.0, 900.0, 1100.0)
REPORT_DAMPING = (0.1, 0.25)
DAMPING_SCALE = 4000.0
"""Our d (N s/m^3) = 4000 x the report's constants: keeps their ratio 2.5 and brings the cube to rest in comparable times."""
YAW_SPIN = (-1.0, 1.0, 0.3)
"""The damped scene's spin plus a vertical component: the yaw it leaves behind is kept (yaw is neutral)."""
TILT_PROBE = math.radians(1.0)

# ---- the runs ---------------------------------------------------------------------------------------------

FLAGS = {
    "body__density": "--density", "fluid__damping": "--damping", "step__integrator": "--integrator", "step__dt": "--dt",
    "step__t_end": "--t-end", "body__points_per_edge": "--points-per-edge", "initial__omega": "--omega0",
}  # fmt: skip


@dataclass(frozen=True)
class Spec:
    """One simulation: a preset scene with overrides, recorded every `every` steps."""

    key: str
    scene: str
    changes: tuple
    """(with_overrides keyword, value) pairs."""
    every: int = 4

    def config(self):
        return with_overrides(load_scene(self.scene), **dict(self.changes))

    def steps(self) -> int:
        step = self.config().step
        return round(step.t_end / step.dt)

    def command(self) -> str:
        """The equivalent `python -m sim run` line (settings with no flag are named after it)."""
        words, extra = ["python -m sim run --scene", self.scene], []
        for key, value in self.changes:
            if key in FLAGS:
                words += [FLAGS[key], _flag_value(value)]
            else:
                extra.append(f"{key.replace('__', '.')} = {value:g}")
        line = "`" + " ".join(words) + "`"
        return line + (f" with {', '.join(extra)} in the scene file (no flag)" if extra else "")


def _flag_value(value) -> str:
    if isinstance(value, tuple):
        return " ".join(f"{v:g}" for v in value)
    return value if isinstance(value, str) else f"{value:g}"


@dataclass
class Trace:
    """A recorded run: arrays over the recorded frames, world frame, SI units."""

    spec: Spec
    sim: Simulation
    t: np.ndarray
    x: np.ndarray
    q: np.ndarray
    u: np.ndarray
    L: np.ndarray
    F: np.ndarray
    T: np.ndarray
    wall: float

    @property
    def body(self) -> probes.BodyView:
        return probes.body(self.sim)

    @property
    def weight(self) -> float:
        return self.body.mass * probes.fluid(self.sim).g

    @property
    def density(self) -> float:
        return self.body.mass / self.body.volume

    @property
    def z(self) -> np.ndarray:
        return self.x[:, 2]

    def norm(self, name: str) -> np.ndarray:
        return np.linalg.norm(getattr(self, name), axis=1)

    @property
    def R(self) -> np.ndarray:
        return np.array([probes.rotation_matrix(q) for q in self.q])


def plan(quick: bool, d_low: float, d_high: float) -> list[Spec]:
    """Every run the page uses. Full: the report's durations at dt 0.005 s; quick: a few seconds at dt 0.01 s."""
    dt = 0.01 if quick else 0.005

    def span(full, short):
        return ("step__t_end", short if quick else full)

    every = max(1, round(0.02 / dt))  # a frame every 0.02 s
    specs = [
        Spec("rest", "rest", (("step__integrator", "implicit"), ("step__dt", dt), span(10.0, 2.0)), every),
        Spec(
            "rest_spin",
            "rest",
            (("step__integrator", "euler"), ("step__dt", dt), span(10.0, 2.0), ("initial__omega", (1e-3, 0.0, 0.0))),
            every,
        ),
        Spec("spin_euler_coarse", "spin", (("step__integrator", "euler"), ("step__dt", 2 * dt), span(30.0, 6.0)), every // 2),
        Spec("spin_euler_fine", "spin", (("step__integrator", "euler"), ("step__dt", dt), span(30.0, 6.0)), every),
        Spec("spin_implicit", "spin", (("step__integrator", "implicit"), ("step__dt", dt), span(30.0, 6.0)), every),
        Spec("spin_free", "spin", (("step__integrator", "euler"), ("step__dt", 2 * dt), span(30.0, 6.0), ("fluid__g", 0.0)), every // 2),
    ]
    for density in DENSITIES:
        specs.append(
            Spec(
                f"drop_{density:g}",
                "drop",
                (("body__density", density), ("step__integrator", "implicit"), ("step__dt", dt), span(20.0, 4.0)),
                every,
            )
        )
    for key, d, omega in (("damped_low", d_low, None), ("damped_high", d_high, None), ("damped_yaw", d_low, YAW_SPIN)):
        changes = (("fluid__damping", d), ("step__integrator", "implicit"), ("step__dt", dt), span(30.0, 8.0))
        specs.append(Spec(key, "damped", changes + ((("initial__omega", omega),) if omega else ()), every))
    return specs


def record(spec: Spec, bar) -> Trace:
    sim = Simulation(spec.config())
    n = spec.steps()
    frames = [sim.frame()]
    started = time.perf_counter()
    done = 0
    while done < n:
        k = min(spec.every, n - done)
        sim.step(k)
        done += k
        bar.update(k)
        frames.append(sim.frame())
    wall = time.perf_counter() - started
    stack = {name: np.array([getattr(f, attr) for f in frames]) for name, attr in
             (("t", "t"), ("x", "x_world"), ("q", "q_world_body"), ("u", "u_world"), ("L", "L_world"), ("F", "force_world"), ("T", "torque_world"))}  # fmt: skip
    return Trace(spec=spec, sim=sim, wall=wall, **stack)


# ---- the report's cube ------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Cube:
    """The report's ice cube and the exact (continuum) numbers every grid is measured against."""

    s: float = 1.0
    density: float = 900.0
    rho: float = 1000.0
    g: float = 9.81

    @property
    def mass(self) -> float:
        return self.density * self.s**3

    @property
    def draft(self) -> float:
        return self.density / self.rho * self.s

    @property
    def z_rest(self) -> float:
        return self.s / 2 - self.draft

    @property
    def buoyancy(self) -> float:
        """rho g V_sub at the face-up rest pose, N."""
        return self.rho * self.g * self.draft * self.s**2

    @property
    def BM(self) -> float:
        """I_wp / V_sub = (s^4/12) / (draft s^2)."""
        return self.s**2 / (12 * self.draft)

    @property
    def BG(self) -> float:
        """Centre of gravity (the cube's centre) above the centre of buoyancy (half the draft)."""
        return self.s / 2 - self.draft / 2

    @property
    def GM(self) -> float:
        return self.BM - self.BG

    @property
    def inertia(self) -> float:
        """(5/18) M s^2: six thin square plates."""
        return 5 / 18 * self.mass * self.s**2


def pose_state(z: float, rotvec=(0.0, 0.0, 0.0)) -> State:
    """At rest at (0, 0, z), rotated by the world rotation vector `rotvec` (rad)."""
    return State(0.0, np.array([0.0, 0.0, z]), probes.quat_from_rotvec(rotvec), np.zeros(3), np.zeros(3))


def sampled_gm(sim: Simulation, z: float, weight: float) -> float:
    """GM of `sim`'s sampled body floating face up at height z: its righting moment at a 1 degree tilt over weight x sin(1 deg)."""
    tilted = probes.frame_at(sim, pose_state(z, (TILT_PROBE, 0.0, 0.0)))
    return -tilted.torque_world[0] / (weight * math.sin(TILT_PROBE))


# ---- figures 1-2: the report's grid against ours ----------------------------------------------------------


def report_grid(s: float, n_edge: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The report's cube (its section 1.1): on each face n_edge x n_edge points, edges and corners included
    (spacing s/(n_edge - 1)); the points on edges and corners are then dropped, and each kept point gets
    the area (s/n_edge)^2. Returns positions, outward normals, areas and the `kept` mask, over all
    6 n_edge^2 face points (the dropped ones with area 0, for plotting)."""
    if n_edge < 3:
        raise ValueError(f"the report's grid needs at least 3 points per edge to keep any, got {n_edge}")
    c = np.linspace(-s / 2, s / 2, n_edge)
    i, j = np.meshgrid(np.arange(n_edge), np.arange(n_edge), indexing="ij")
    interior = ((i > 0) & (i < n_edge - 1) & (j > 0) & (j < n_edge - 1)).ravel()
    pos, nor = [], []
    for axis in range(3):
        a, b = (axis + 1) % 3, (axis + 2) % 3
        for sign in (1.0, -1.0):
            p = np.zeros((n_edge * n_edge, 3))
            p[:, axis] = sign * s / 2
            p[:, a] = c[i.ravel()]
            p[:, b] = c[j.ravel()]
            normal = np.zeros(3)
            normal[axis] = sign
            pos.append(p)
            nor.append(np.tile(normal, (n_edge * n_edge, 1)))
    kept = np.tile(interior, 6)
    area = np.where(kept, (s / n_edge) ** 2, 0.0)
    return np.concatenate(pos), np.concatenate(nor), area, kept


def grid_body(r: np.ndarray, n: np.ndarray, area: np.ndarray, mass: float, like, name: str):
    """A sim body from bare samples (masses in proportion to area, as in sim's bodies), shown with `like`'s mesh."""
    m = mass * area / area.sum()
    inertia = np.einsum("k,k->", m, np.einsum("ki,ki->k", r, r)) * np.eye(3) - (r * m[:, None]).T @ r
    return probes.body_from_samples(r, n, area, mass, np.diag(inertia).copy(), like, name)


def grid_numbers(body, cube: Cube) -> dict:
    """What a grid gets right at the report's rest pose: area, buoyancy, righting moment at a 1 degree tilt, inertia."""
    view = probes.body(body)
    rest = probes.still_water_frame(body, cube.rho, cube.g, pose_state(cube.z_rest))
    bottom = view.n[:, 2] < -0.5
    tilted = probes.still_water_frame(body, cube.rho, cube.g, pose_state(cube.z_rest, (TILT_PROBE, 0.0, 0.0)))
    return {
        "samples": int(np.count_nonzero(view.area)),
        "area_ratio": float(view.area.sum() / (6 * cube.s**2)),
        "buoyancy_ratio": float((rest.force_world[2] + cube.mass * cube.g) / cube.buoyancy),
        "rest_force_rel": float(np.linalg.norm(rest.force_world) / (cube.mass * cube.g)),
        "righting_ratio": float(-tilted.torque_world[0] / (cube.buoyancy * cube.GM * math.sin(TILT_PROBE))),
        "waterplane_ratio": float(view.area[bottom] @ view.r[bottom, 1] ** 2 / (cube.s**4 / 12)),
        "inertia_ratio": float(view.inertia[0] / cube.inertia),
    }


def grids(cube: Cube, n_edge: int) -> dict:
    """The three grids compared: ours (cell centres), the report's, and the report's with areas rescaled to 6 s^2/n."""
    ours = probes.cube_body(cube.s, n_edge, cube.mass, "cube")
    r, n, a, kept = report_grid(cube.s, n_edge)
    report = grid_body(r[kept], n[kept], a[kept], cube.mass, ours, "report")
    rescaled = grid_body(r[kept], n[kept], np.full(kept.sum(), 6 * cube.s**2 / kept.sum()), cube.mass, ours, "report, rescaled")
    return {"ours": ours, "report": report, "rescaled": rescaled}


TABLE_N = (5, 10, 20)
SWEEP_N = np.arange(3, 41)


def grid_study(cube: Cube) -> tuple[dict, dict]:
    """grid_numbers of every grid: at the table's N, and over the sweep of N from 3 to 40."""
    rows = {n: {k: grid_numbers(b, cube) for k, b in grids(cube, n).items()} for n in TABLE_N}
    sweep = {n: {k: grid_numbers(b, cube) for k, b in grids(cube, int(n)).items()} for n in SWEEP_N}
    return rows, sweep


# ---- figures 7-9: static probes of the damped runs' model ---------------------------------------------------


@dataclass
class DampedProbes:
    gm_sampled: float
    yaw_torque_rel: float
    """abs(torque) at a 10 degree yaw over M g s."""
    yaw_force_rel: float
    """abs(F) at a 10 degree yaw over the weight."""
    wet_area: float
    """Wet area at the rest pose, m^2."""
    damping: dict[str, np.ndarray]
    """Run key -> 6x6 damping matrix at the rest pose."""


def damped_probes(runs: list[Trace], cube: Cube) -> DampedProbes:
    """The first run's model at the rest pose, tilted by 1 degree and yawed by 10; each run's damping matrix at rest."""
    base = Simulation(runs[0].spec.config())
    weight = probes.body(base).mass * cube.g
    rest = pose_state(cube.z_rest)
    yaw_probe = probes.frame_at(base, pose_state(cube.z_rest, (0.0, 0.0, math.radians(10.0))))
    return DampedProbes(
        gm_sampled=sampled_gm(base, cube.z_rest, weight),
        yaw_torque_rel=float(np.linalg.norm(yaw_probe.torque_world) / (weight * cube.s)),
        yaw_force_rel=float(np.linalg.norm(yaw_probe.force_world) / weight),
        wet_area=probes.frame_at(base, rest).submerged_area,
        damping={tr.spec.key: probes.damping_matrix(tr.sim, rest) for tr in runs},
    )

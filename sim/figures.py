"""`python -m sim figures`: the source report's figures reproduced with floatsim, and where the corrected model differs.

Writes OUT_DIR/seed-figures.md with its PNGs in OUT_DIR/seed-figures/, plus numbers.json there: every number
the page states, as computed by the runs below (nothing in the text is typed by hand). One section per
figure group of the report (`seed/000_069c8b0ce5e5c6f5.txt`). The only physics written here is the report's
own point grid (`report_grid`), rebuilt for the comparison of figures 1-2; its forces come from `sim`.
"""

from __future__ import annotations

import json
import math
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .body import Body, make_box
from .config import load_scene, with_overrides
from .forces import Model, Params, damping_matrix, wetted
from .progress import progress_bar
from .rotation import quat_multiply, quat_to_matrix, rotation_quat
from .simulation import Simulation, observe
from .state import State

SOURCE = "seed/000_069c8b0ce5e5c6f5.txt"
PAGE = "seed-figures.md"
ASSETS = "seed-figures"


@dataclass
class FiguresArgs:
    """Regenerate OUT_DIR/seed-figures.md: the source report's figures reproduced with floatsim, section by section."""

    out_dir: str = "reports"
    """Folder for seed-figures.md; the PNGs and numbers.json go to OUT_DIR/seed-figures/."""
    quick: bool = False
    """Short runs (a few simulated seconds, dt 0.01 s) and no browser render: the same sections in seconds, for tests."""
    viewer: bool = True
    """Render the resting cube in the live viewer (app/, headless chromium); a matplotlib render is used if that fails."""
    progress: bool | None = None
    """Show a progress bar (default: only on a terminal, never under CI)."""


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
    def weight(self) -> float:
        return self.sim.body.mass * self.sim.params.g

    @property
    def z(self) -> np.ndarray:
        return self.x[:, 2]

    def norm(self, name: str) -> np.ndarray:
        return np.linalg.norm(getattr(self, name), axis=1)

    @property
    def R(self) -> np.ndarray:
        return np.array([quat_to_matrix(q) for q in self.q])


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


DENSITIES = (200.0, 500.0, 900.0, 1100.0)
REPORT_DAMPING = (0.1, 0.25)
DAMPING_SCALE = 4000.0
"""Our d (N s/m^3) = 4000 x the report's constants: keeps their ratio 2.5 and brings the cube to rest in comparable times."""
YAW_SPIN = (-1.0, 1.0, 0.3)
"""The damped scene's spin plus a vertical component: the yaw it leaves behind is kept (yaw is neutral)."""


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


def pose_state(z: float, rotvec=(0.0, 0.0, 0.0)) -> State:
    """At rest at (0, 0, z), rotated by the world rotation vector `rotvec` (rad)."""
    return State(0.0, np.array([0.0, 0.0, z]), rotation_quat(np.asarray(rotvec, float)), np.zeros(3), np.zeros(3))


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


def grid_body(r: np.ndarray, n: np.ndarray, area: np.ndarray, mass: float, like: Body, name: str) -> Body:
    """A sim Body from bare samples (masses in proportion to area, as in sim.body), shown with `like`'s mesh."""
    m = mass * area / area.sum()
    inertia = np.einsum("k,k->", m, np.einsum("ki,ki->k", r, r)) * np.eye(3) - (r * m[:, None]).T @ r
    return Body(r_body=r, n_body=n, area=area, mass=mass, inertia=np.diag(inertia).copy(), volume=like.volume,
                radius=float(np.sqrt(np.einsum("ki,ki->k", r, r).max())), mesh_vertices=like.mesh_vertices,
                mesh_faces=like.mesh_faces, q_input_body=np.array([1.0, 0.0, 0.0, 0.0]), name=name)  # fmt: skip


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


TILT_PROBE = math.radians(1.0)


def grid_numbers(body: Body, cube: Cube) -> dict:
    """What a grid gets right at the report's rest pose: area, buoyancy, righting moment at a 1 degree tilt, inertia."""
    model = Model(body, Params(cube.rho, cube.g, 0.0))
    rest = observe(model, pose_state(cube.z_rest))
    bottom = body.n_body[:, 2] < -0.5
    tilted = observe(model, pose_state(cube.z_rest, (TILT_PROBE, 0.0, 0.0)))
    return {
        "samples": int(np.count_nonzero(body.area)),
        "area_ratio": float(body.area.sum() / (6 * cube.s**2)),
        "buoyancy_ratio": float((rest.force_world[2] + cube.mass * cube.g) / cube.buoyancy),
        "rest_force_rel": float(np.linalg.norm(rest.force_world) / (cube.mass * cube.g)),
        "righting_ratio": float(-tilted.torque_world[0] / (cube.buoyancy * cube.GM * math.sin(TILT_PROBE))),
        "waterplane_ratio": float(body.area[bottom] @ body.r_body[bottom, 1] ** 2 / (cube.s**4 / 12)),
        "inertia_ratio": float(body.inertia[0] / cube.inertia),
    }


def grids(cube: Cube, n_edge: int) -> dict[str, Body]:
    ours = make_box((cube.s,) * 3, n_edge, cube.mass, "cube")
    r, n, a, kept = report_grid(cube.s, n_edge)
    report = grid_body(r[kept], n[kept], a[kept], cube.mass, ours, "report")
    rescaled = grid_body(r[kept], n[kept], np.full(kept.sum(), 6 * cube.s**2 / kept.sum()), cube.mass, ours, "report, rescaled")
    return {"ours": ours, "report": report, "rescaled": rescaled}


GRID_NAMES = {"ours": "floatsim, cell centres", "report": "report, area (s/N)^2", "rescaled": "report, area 6 s^2/n"}


# ---- the viewer render ------------------------------------------------------------------------------------

VIEWS = {"side": ((1.3, -1.8, 1.0), (0.0, 0.0, -0.3), (0.0, 0.0, 1.0)), "top": ((0.0, 0.0, 2.4), (0.0, 0.0, -0.4), (0.0, 1.0, 0.0))}
"""Camera position, look-at point and up direction of each render (the top view has +y up, +x right)."""


def resting_scene_toml(trace: Trace) -> str:
    """A scene file holding the run's final pose at rest (what the viewer is asked to show)."""
    cfg, state = trace.spec.config(), trace.sim.state
    body = trace.sim.body
    q_input = quat_multiply(state.q_world_body, body.q_input_body * np.array([1.0, -1.0, -1.0, -1.0]))

    def vec(v) -> str:
        return "[" + ", ".join(f"{float(c):.17g}" for c in v) + "]"

    return (f'description = "Final pose of figures run {trace.spec.key}, at rest."\n\n[body]\nshape = "cube"\nsize = {cfg.body.size}\n'
            f"points_per_edge = {cfg.body.points_per_edge}\ndensity = {cfg.body.density}\n\n[fluid]\ndamping = {cfg.fluid.damping}\n\n"
            f"[initial]\nposition = {vec(state.x_world)}\norientation = {vec(q_input / np.linalg.norm(q_input))}\n\n[step]\ndt = {cfg.step.dt}\n")  # fmt: skip


def viewer_render(trace: Trace, paths: dict[str, Path]) -> str | None:
    """Pictures of the final pose from the live viewer, one per view in VIEWS. Returns None on success, else
    why not. The one place sim reaches for app/: optional and lazy, with a matplotlib render as the fallback."""
    try:
        from app.render import render_scene
    except Exception as e:  # noqa: BLE001 -- any import problem means the matplotlib render
        return f"the viewer could not be imported ({type(e).__name__}: {e})"
    with tempfile.TemporaryDirectory() as tmp:
        scene = Path(tmp) / "resting_pose.toml"
        scene.write_text(resting_scene_toml(trace))
        return render_scene(str(scene), VIEWS, paths)


# ---- the command ------------------------------------------------------------------------------------------


def figures(args: FiguresArgs) -> int:
    import matplotlib

    matplotlib.use("Agg")
    started = time.perf_counter()
    out = Path(args.out_dir)
    assets = out / ASSETS
    assets.mkdir(parents=True, exist_ok=True)
    d_low, d_high = (DAMPING_SCALE * c for c in REPORT_DAMPING)
    specs = plan(args.quick, d_low, d_high)
    bar = progress_bar(sum(s.steps() for s in specs), flag=args.progress)
    try:
        traces = {spec.key: record(spec, bar) for spec in specs}
    finally:
        bar.close()
    cube = Cube()
    nums: dict = {"quick": args.quick}
    page = Page(out, assets, nums)
    page.intro(args, cube, traces)
    page.samples(cube)
    page.rest(cube, traces)
    page.angular_momentum(traces)
    page.force_at_rest(traces)
    page.densities(cube, traces)
    page.damped(args, cube, traces)
    page.write()
    wall = time.perf_counter() - started
    sim_wall = sum(t.wall for t in traces.values())
    print(f"wrote {out / PAGE} with {len(page.images)} figures in {wall:.1f} s wall ({sim_wall:.1f} s simulating)")
    return 0


def fmt(x: float, digits: int = 3) -> str:
    """A number for the text: plain for ordinary magnitudes, a x 10^k otherwise."""
    if x == 0 or not math.isfinite(x):
        return f"{x:g}"
    if 1e-3 <= abs(x) < 1e5:
        text = f"{x:.{digits}g}"
        return f"{float(text):.0f}" if "e" in text else text
    mantissa, exponent = f"{x:.{digits - 1}e}".split("e")
    return f"{mantissa} x 10^{int(exponent)}"


def pct(x: float, digits: int = 3) -> str:
    return f"{fmt(100 * x, digits)} %"


class Page:
    """The markdown page, built section by section; figures are saved as they are made."""

    def __init__(self, out: Path, assets: Path, nums: dict):
        self.out, self.assets, self.nums = out, assets, nums
        self.parts: list[str] = []
        self.images: list[str] = []

    def add(self, text: str) -> None:
        self.parts.append(text.strip() + "\n")

    def save(self, fig, name: str, alt: str) -> str:
        import matplotlib.pyplot as plt

        with np.errstate(divide="ignore", invalid="ignore"):  # log axes of values that reach zero
            fig.savefig(self.assets / name, dpi=100, bbox_inches="tight")
        plt.close(fig)
        return self.image(name, alt)

    def image(self, name: str, alt: str) -> str:
        self.images.append(name)
        return f"![{alt}]({ASSETS}/{name})"

    def write(self) -> None:
        (self.out / PAGE).write_text("\n".join(self.parts))
        (self.assets / "numbers.json").write_text(json.dumps(self.nums, indent=1, sort_keys=True) + "\n")

    # ---- sections -----------------------------------------------------------------------------------------

    def intro(self, args: FiguresArgs, cube: Cube, traces: dict[str, Trace]) -> None:
        body = traces["rest"].sim.body
        quick = ("\n\n**This is the quick setting** (`--quick`: a few simulated seconds at dt = 0.01 s, no browser render), "
                 "made for the test; run `python -m sim figures` for the real page.") if args.quick else ""  # fmt: skip
        self.add(f"""
# The source report's figures, reproduced with floatsim

The source report (`{SOURCE}`, "Simulation of a Cubic Floating Body Suspended in Viscous Fluid") simulates a hollow
cube sampled by surface points in MATLAB. This page redoes each of its figures with floatsim's corrected model
(`PHYSICS.md`) and says where and why the results differ. It is generated, numbers included, by
`python -m sim figures{" --quick" if args.quick else ""}` (module `sim/figures.py`); the settings of every run are given as the
equivalent `python -m sim run` command.{quick}

Common to all runs: the report's ice cube, side s = {fmt(cube.s)} m, density {fmt(cube.density)} kg/m^3 (mass {fmt(cube.mass)} kg)
unless stated, water rho = {fmt(cube.rho)} kg/m^3, g = {fmt(cube.g)} m/s^2, sampled by floatsim's default
{body.n_samples} points (N = {traces["rest"].spec.config().body.points_per_edge} cells per edge on each face).
""")

    def samples(self, cube: Cube) -> None:
        import matplotlib.pyplot as plt
        from matplotlib.ticker import NullFormatter, ScalarFormatter

        table_n = (5, 10, 20)
        rows = {n: {k: grid_numbers(b, cube) for k, b in grids(cube, n).items()} for n in table_n}
        sweep_n = np.arange(3, 41)
        sweep = {n: {k: grid_numbers(b, cube) for k, b in grids(cube, int(n)).items()} for n in sweep_n}
        n_ex = 10
        r10 = rows[n_ex]
        fine = [n for n in sweep_n if n >= 20]
        worst = {k: max(abs(sweep[n][k]["righting_ratio"] - 1) for n in fine) for k in GRID_NAMES}
        self.nums["grid_righting_worst_N20_40"] = worst
        deficit = 6 * cube.s**2 * (1 - r10["report"]["area_ratio"])
        self.nums["grid"] = {str(n): v for n, v in rows.items()}
        self.nums["grid_area_deficit_N10"] = deficit
        self.nums["grid_area_deficit_formula_N10"] = 6 * cube.s**2 * (1 - ((n_ex - 2) / n_ex) ** 2)

        # Figure 1: the two grids in 3D, N = 5 (the report's own example).
        n_plot = 5
        r, nrm, _, kept = report_grid(cube.s, n_plot)
        ours = make_box((cube.s,) * 3, n_plot, cube.mass)
        fig = plt.figure(figsize=(11, 5.2))
        for k, (title, pts, normals, dropped) in enumerate((
            ((f"report: {n_plot} points per edge, edges and corners dropped\n{kept.sum()} points, total area "
              f"{fmt(kept.sum() * (cube.s / n_plot) ** 2)} m² of {fmt(6 * cube.s ** 2)} m²"), r[kept], nrm[kept], r[~kept]),
            ((f"floatsim: {n_plot} x {n_plot} cell centres per face\n{ours.n_samples} points, total area "
              f"{fmt(ours.area.sum())} m² of {fmt(6 * cube.s ** 2)} m²"), ours.r_body, ours.n_body, None),
        )):  # fmt: skip
            ax = fig.add_subplot(1, 2, k + 1, projection="3d")
            ax.scatter(*pts.T, s=12, color="tab:blue", depthshade=False, label="samples")
            ax.quiver(*pts.T, *(0.18 * normals).T, color="tab:red", linewidth=0.7, arrow_length_ratio=0.3, label="outward normals")
            if dropped is not None:
                ax.scatter(
                    *np.unique(dropped, axis=0).T, s=14, marker="x", color="0.55", depthshade=False, label="dropped (edges, corners)"
                )
            ax.set_title(title, fontsize=10)
            ax.set_box_aspect((1, 1, 1))
            ax.view_init(elev=22, azim=-58)
            ax.set_xlabel("x (m)")
            ax.set_ylabel("y (m)")
            ax.set_zlabel("z (m)")
            ax.legend(loc="upper left", fontsize=8)
        fig1 = self.save(fig, "fig1_samples.png", "Figure 1: the report's sample grid against floatsim's, with normals")

        # Figure 2: one face with each sample's area patch; errors against N.
        fig, axes = plt.subplots(1, 3, figsize=(14, 4.6), gridspec_kw={"width_ratios": [1, 1, 1.7]})
        h = cube.s / 2
        c_rep = np.linspace(-h, h, n_plot)
        c_our = (np.arange(n_plot) + 0.5) / n_plot * cube.s - h
        side = cube.s / n_plot
        for ax, title, centres, keep in (
            (
                axes[0],
                f"report, one face: {(n_plot - 2) ** 2} patches of (s/N)²\ncover {pct(((n_plot - 2) / n_plot) ** 2)} of it",
                c_rep,
                True,
            ),
            (axes[1], f"floatsim, one face: {n_plot**2} cells of (s/N)²\ncover 100 % of it", c_our, False),
        ):
            ax.add_patch(plt.Rectangle((-h, -h), cube.s, cube.s, fill=False, color="k", linewidth=1.5))
            for a in centres:
                for b in centres:
                    interior = not keep or (abs(a) < h - 1e-9 and abs(b) < h - 1e-9)
                    if interior:
                        ax.add_patch(plt.Rectangle((a - side / 2, b - side / 2), side, side, alpha=0.35, color="tab:blue", ec="tab:blue"))
                        ax.plot(a, b, "o", color="tab:blue", ms=4)
                    else:
                        ax.plot(a, b, "x", color="0.5", ms=6)
            ax.set_xlim(-0.62 * cube.s, 0.62 * cube.s)
            ax.set_ylim(-0.62 * cube.s, 0.62 * cube.s)
            ax.set_aspect("equal")
            ax.set_title(title, fontsize=10)
            ax.set_xlabel("m")
        ax = axes[2]
        colours = {"ours": "tab:orange", "report": "tab:blue", "rescaled": "tab:green"}
        for key, style, label in (("area_ratio", ":", "area deficit (= rest-buoyancy deficit)"), ("righting_ratio", "-", "righting-moment error, 1° tilt"),
                                  ("inertia_ratio", "--", "inertia error vs (5/18) M s²")):  # fmt: skip
            for grid in ("report", "rescaled", "ours"):
                if key == "area_ratio" and grid != "report":
                    continue  # exact (area) for the other two
                if key == "inertia_ratio" and grid == "rescaled":
                    continue  # same masses as the report's grid
                err = np.array([abs(sweep[n][grid][key] - 1) for n in sweep_n])
                ax.loglog(sweep_n, np.maximum(err, 1e-16), style, color=colours[grid], label=f"{grid}: {label}")
        ax.set_xticks([3, 5, 10, 20, 40])
        ax.xaxis.set_major_formatter(ScalarFormatter())
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.text(0.98, 0.97, "area: exact for floatsim and the rescaled grid", transform=ax.transAxes, ha="right", va="top", fontsize=8)
        ax.set_xlabel("N (points or cells per edge)")
        ax.set_ylabel("relative error")
        ax.set_ylim(1e-4, 2)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7.5, loc="lower left")
        ax.set_title("errors at the report's rest pose (draft 0.9 s)", fontsize=10)
        fig2 = self.save(fig, "fig2_area.png", "Figure 2: what each sample's area covers, and the errors against N")

        table = ["| grid | N | samples | total area / 6 s² | buoyancy at rest / rho g V_sub | water-plane moment / (s⁴/12) | righting moment at 1° / exact | I / ((5/18) M s²) |",
                 "|---|---|---|---|---|---|---|---|"]  # fmt: skip
        for grid in ("report", "rescaled", "ours"):
            for n in table_n:
                v = rows[n][grid]
                table.append(
                    f"| {GRID_NAMES[grid]} | {n} | {v['samples']} | {v['area_ratio']:.4f} | {v['buoyancy_ratio']:.4f} | {v['waterplane_ratio']:.4f} | {v['righting_ratio']:.4f} | {v['inertia_ratio']:.4f} |"
                )
        rep, res, our = r10["report"], r10["rescaled"], r10["ours"]
        self.add(f"""
## Figures 1-2: the point-sampled cube

**Settings.** No time stepping: each grid is turned into a `sim.Body` (the report's with `report_grid` in
`sim/figures.py`, ours with `sim.body.make_box`) and its forces at the report's rest pose (face up, centre at
z = {fmt(cube.z_rest)} m, draft {fmt(cube.draft)} m) and at a 1° tilt come from `sim.observe`. The exact values are
rho g V_sub = {fmt(cube.buoyancy, 5)} N, the righting moment rho g V_sub GM sin(1°) with GM = {fmt(cube.GM, 4)} m (see
figures 7-9), and the thin-shell inertia (5/18) M s^2 = {fmt(cube.inertia, 5)} kg m^2.

**The report.** N points per edge, edges and corners included; the edge and corner points are then dropped
("edge cases") and every kept point gets the area (s/N)^2, "ensuring that the sum of all individual areas equals
the cube's total surface area". Its introduction instead says each point's area is the total area divided by
the number of points. Figure 1 of the report plots the points, figure 2 the faces they represent.

**floatsim.** One sample at the centre of each of N x N square cells per face: every cell has area (s/N)^2 and
the cells tile the face, edges and corners included, so nothing has to be dropped.

{fig1}

{fig2}

{chr(10).join(table)}

**Where and why they differ.** Dropping the edge and corner points leaves (N-2)^2 of the N^2 points per face, so
the report's areas add up to 6 s^2 ((N-2)/N)^2, not 6 s^2: at N = {n_ex} the deficit is {fmt(deficit, 4)} m^2, exactly
6 s^2 (1 - ((N-2)/N)^2) = {fmt(self.nums["grid_area_deficit_formula_N10"], 4)} m^2 ({pct(1 - rep["area_ratio"])} of the surface).
The bottom face alone carries the buoyancy of a level cube, so the buoyancy falls short by the same fraction: at
the report's rest pose its grid gives {pct(rep["buoyancy_ratio"])} of rho g V_sub and a net force of {pct(rep["rest_force_rel"])} of the
weight, so the cube would not rest at z = {fmt(cube.z_rest)} m at all. Rescaling the areas to 6 s^2/n, as the
report's introduction says, restores the level cube's buoyancy ({pct(res["buoyancy_ratio"], 4)}) but not its stability.
The righting moment is rho g V_sub GM with GM = BM - BG, a small difference of two larger terms, and the kept points,
which stop one spacing s/(N-1) short of every edge, weigh both wrongly: the water-plane moment behind BM comes out
{pct(res["waterplane_ratio"])} of s^4/12 and the righting moment {pct(res["righting_ratio"])} of exact at N = {n_ex} (the uncorrected grid:
{pct(rep["righting_ratio"])}). floatsim's cell centres give the buoyancy to round-off ({pct(our["buoyancy_ratio"], 6)}), the water-plane
moment to the midpoint rule's 1 - 1/N^2 ({pct(our["waterplane_ratio"])}) and a righting moment of {pct(our["righting_ratio"])}. At N = {n_ex} the
water line falls on a cell boundary; for other N it cuts a row of samples, which either count as wet or not, so the
righting moment converges unevenly (figure 2, right): for N from 20 to 40 its error is at most {pct(worst["ours"])} for floatsim,
{pct(worst["report"])} and {pct(worst["rescaled"])} for the report's grid with its two area rules. The inertia is isotropic for every grid,
as the report says, but only floatsim's tends to (5/18) M s^2 ({fmt(our["inertia_ratio"], 4)} of it at N = {n_ex}, against
{fmt(rep["inertia_ratio"], 4)} for the report's grid, whose points crowd towards the face centres).
""")

    def rest(self, cube: Cube, traces: dict[str, Trace]) -> None:
        import matplotlib.pyplot as plt

        ours, spun = traces["rest"], traces["rest_spin"]
        dz = ours.z - cube.z_rest
        dz_spin = spun.z - cube.z_rest
        tilt_spin = np.degrees(tilts(spun))
        n = self.nums["rest"] = {
            "max_dz": float(np.abs(dz).max()), "max_u": float(ours.norm("u").max()), "max_F_rel": float((ours.norm("F") / ours.weight).max()),
            "max_T": float(ours.norm("T").max()), "spin_dz_min": float(dz_spin.min()), "spin_dz_max": float(dz_spin.max()),
            "spin_max_tilt_deg": float(tilt_spin.max()), "spin_omega": float(np.linalg.norm(spun.spec.config().initial.omega)),
        }  # fmt: skip
        fig, axes = plt.subplots(1, 2, figsize=(12, 4))
        ax = axes[0]
        ax.plot(ours.t, dz, color="tab:orange")
        ax.set_ylim(-1e-12, 1e-12)
        ax.set_title(f"floatsim ({ours.spec.config().step.integrator}), released at rest: no initial velocity", fontsize=10)
        ax.set_xlabel("t (s)")
        ax.set_ylabel("z(t) - (-0.4) (m)")
        ax.grid(alpha=0.3)
        ax = axes[1]
        ax.plot(spun.t, dz_spin, color="tab:blue", label="z(t) + 0.4")
        ax.set_xlabel("t (s)")
        ax.set_ylabel("z(t) - (-0.4) (m)", color="tab:blue")
        ax.ticklabel_format(axis="y", style="sci", scilimits=(-2, 2))
        ax2 = ax.twinx()
        ax2.plot(spun.t, tilt_spin, color="tab:red", lw=0.8)
        ax2.set_ylabel("tilt (deg)", color="tab:red")
        ax.set_title(f"with the report's trick: initial spin {fmt(n['spin_omega'])} rad/s about x, euler", fontsize=10)
        ax.grid(alpha=0.3)
        image = self.save(fig, "fig3_rest.png", "Figure 3: z(t) of the cube placed at rest at z = -0.4")
        self.add(f"""
## Figure 3: the cube placed at its resting depth

**Settings.** Left: {ours.spec.command()}. Right, the report's workaround: {spun.spec.command()}
(an angular velocity of {fmt(n["spin_omega"])} rad/s about x; the report does not give its value).

**The report.** Placed face up at z = -0.4 m (draft 0.9 m for density 900), the centre of mass shows "small
oscillations" about -0.4, caused by "a very small initial velocity [that] must be added to avoid division by zero
when calculating the rotation R".

**floatsim.** Released with no velocity at all, the cube stays put: |z + 0.4| stays below {fmt(n["max_dz"])} m, |u| below
{fmt(n["max_u"])} m/s, |F| below {fmt(n["max_F_rel"])} of the weight and |torque| below {fmt(n["max_T"])} N m over {fmt(ours.t[-1])} s (left, on a
±10^-12 m scale). With the report's artificial spin (right) the cube rocks by up to {fmt(n["spin_max_tilt_deg"])}° and its centre
moves between {fmt(n["spin_dz_min"])} and {fmt(n["spin_dz_max"])} m about -0.4.

{image}

**Where and why they differ.** The oscillation is the report's own doing, not physics: its rotation formula
divides by |Omega|, so it needed a non-zero spin, and the spin rocks the cube. Rocking changes the displaced volume
only at second order in the tilt, which is why z moves so little. floatsim's exact rotation uses a series for
small |Omega| dt (`sim.rotation.rotation_quat`), so w = 0 is an ordinary case and no trick is needed.
""")

    def angular_momentum(self, traces: dict[str, Trace]) -> None:
        import matplotlib.pyplot as plt

        runs = [traces[k] for k in ("spin_euler_coarse", "spin_euler_fine", "spin_implicit")]
        free = traces["spin_free"]
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
        body, omega0 = ref.sim.body, np.asarray(ref.spec.config().initial.omega, float)
        n["righting_per_rad"] = Cube().mass * ref.sim.params.g * Cube().GM  # M g GM, N m per radian of tilt
        n["I_omega2"] = float(body.inertia[0] * (omega0 @ omega0))
        self.nums["spin"] = n
        fig, axes = plt.subplots(1, 2, figsize=(12.5, 4.2))
        ax = axes[0]
        for tr, colour in zip(runs, ("tab:blue", "tab:cyan", "tab:orange")):
            cfg = tr.spec.config().step
            ax.plot(tr.t, tr.norm("L"), color=colour, lw=1.2 if tr is ref else 0.9, label=f"{cfg.integrator}, dt = {cfg.dt:g} s")
        ax.plot(free.t, free.norm("L"), "k--", lw=0.9, label="torque-free control (g = 0)")
        ax.set_xlabel("t (s)")
        ax.set_ylabel("|L| (kg m²/s)")
        ax.set_title("|L|(t), ice cube at z = -0.4 with ω = (-1, 1, 0) rad/s", fontsize=10)
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
        ax = axes[1]
        for tr, colour in zip(runs[:2], ("tab:blue", "tab:cyan")):
            cfg = tr.spec.config().step
            ax.plot(tr.t, tr.norm("L") - np.interp(tr.t, ref.t, ref.norm("L")), color=colour, lw=0.9, label=f"euler, dt = {cfg.dt:g} s")
        ax.set_xlabel("t (s)")
        ax.set_ylabel("|L| - |L| of implicit (kg m²/s)")
        ax.set_title("the report's scheme against implicit: a first-order error", fontsize=10)
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
        image = self.save(fig, "fig4_5_angular_momentum.png", "Figures 4-5: |L| against time for two time steps")
        cmds = "; ".join(tr.spec.command() for tr in runs)
        self.add(f"""
## Figures 4-5: |L| with an initial spin

**Settings.** {cmds}. Control: {free.spec.command()}.

**The report.** With Omega = (-1, 1, 0) rad/s at z = -0.4 it sets out to show that |L| "remains constant with
respect to time"; |L| "increases about halfway through, but only by a tiny amount", and less with a smaller time step.

**floatsim.** |L| starts at I |Omega| = {fmt(L0, 4)} kg m^2/s and is not constant: with the implicit scheme it ranges over
{fmt(ref.norm("L").min(), 4)}-{fmt(ref.norm("L").max(), 4)} kg m^2/s ({pct((ref.norm("L").max() - ref.norm("L").min()) / L0)} of |L(0)|) over {fmt(ref.t[-1])} s. The report's
scheme (euler) follows the same curve; its largest distance from the implicit one is {fmt(coarse["max_dev_from_implicit"])} kg m^2/s at
dt = {fmt(coarse["dt"])} s and {fmt(fine["max_dev_from_implicit"])} kg m^2/s at dt = {fmt(fine["dt"])} s, a ratio of {fmt(n["euler_dev_ratio"])} for halving dt:
first order, as the scheme is. The change of L is the torque's doing: L(t) - L(0) equals the time integral of the
recorded torque (peak {fmt(n["max_torque"], 4)} N m) to {fmt(n["torque_integral_rel"])} of |L(0)|. Without gravity (so without buoyancy
or torque) |L| keeps its value {"exactly" if n["free_rel_dev"] == 0 else f"to {fmt(n['free_rel_dev'])} relative"}.

{image}

**Where and why they differ.** |L| is conserved only without torque, and a spinning cube half in water is not
torque-free: as it rolls the submerged shape changes, the centre of buoyancy leaves the vertical through the
centre of mass and the hydrostatic pressure exerts a real torque that changes L, in direction and in size. The
report's expectation of constant |L| is the torque-free case (our control); with water, a change of |L| is physics,
not error, and what shrinks with dt is only the scheme's first-order error on top of it. (Why the report's change was
"tiny" cannot be told from the text: with a correct buoyancy the righting torque per radian of tilt, M g GM =
{fmt(n["righting_per_rad"])} N m, is comparable to I |Omega|^2 = {fmt(n["I_omega2"])} N m, so changes of order 10 % are to be expected.)
""")

    def force_at_rest(self, traces: dict[str, Trace]) -> None:
        import matplotlib.pyplot as plt

        tr = traces["rest"]
        rel = tr.norm("F") / tr.weight
        grid = self.nums["grid"]["10"]
        n = self.nums["force_at_rest"] = {"max_F_rel": float(rel.max()), "max_F": float(tr.norm("F").max()), "weight": tr.weight,
                                          "report_grid_F_rel": grid["report"]["rest_force_rel"], "rescaled_grid_F_rel": grid["rescaled"]["rest_force_rel"]}  # fmt: skip
        floor = 1e-18
        fig, ax = plt.subplots(figsize=(8, 3.8))
        ax.semilogy(tr.t, np.maximum(rel, floor), color="tab:orange", label="floatsim, cube at rest at z = -0.4")
        ax.axhline(n["report_grid_F_rel"], color="tab:blue", ls="--", label="report's grid (N = 10) at the same pose")
        ax.axhline(1e-9, color="0.5", ls=":", label="10^-9 of the weight")
        ax.set_ylim(floor / 2, 2)
        ax.set_xlabel("t (s)")
        ax.set_ylabel("|F_total| / weight")
        ax.set_title(f"|F_total| at rest (zeros drawn at {floor:g})", fontsize=10)
        ax.legend(fontsize=8, loc="center right")
        ax.grid(alpha=0.3, which="both")
        image = self.save(fig, "fig6_force_at_rest.png", "Figure 6: |F_total| of the cube at rest")
        self.add(f"""
## Figure 6: the total force at rest

**Settings.** The run of figure 3: {tr.spec.command()}.

**The report.** At the resting pose gravity should balance buoyancy and the horizontal pressure forces cancel;
its figure 6 shows "very tiny changes in ||F_total||".

**floatsim.** |F_total| stays below {fmt(n["max_F"])} N, {fmt(n["max_F_rel"])} of the weight ({fmt(n["weight"], 5)} N), for the whole run: round-off.

{image}

**Where and why they differ.** Both see a balance, but for the report it depends on which of its two area rules
the code used. With the areas of its section 1.1 the same pose is far from equilibrium: the net force is
{pct(n["report_grid_F_rel"])} of the weight at N = 10 (dashed line; figures 1-2). With the introduction's rescaled areas the level
cube balances ({fmt(n["rescaled_grid_F_rel"])} of the weight), so that is presumably what ran. floatsim's cell-centred grid
balances by construction at any N, and stays balanced because nothing moves.
""")

    def densities(self, cube: Cube, traces: dict[str, Trace]) -> None:
        import matplotlib.pyplot as plt

        runs = [traces[f"drop_{d:g}"] for d in DENSITIES]
        lo, hi = ((3 - math.sqrt(3)) / 6 * cube.rho, (3 + math.sqrt(3)) / 6 * cube.rho)
        rows, n = [], {"unstable_band": [lo, hi], "runs": {}}
        for tr in runs:
            density = tr.sim.body.mass / tr.sim.body.volume
            c = Cube(cube.s, density, cube.rho, cube.g)
            th = np.degrees(tilts(tr))
            row = {
                "density": density,
                "z_min": float(tr.z.min()),
                "z_max": float(tr.z.max()),
                "z_end": float(tr.z[-1]),
                "max_tilt_deg": float(th.max()),
            }
            if density < cube.rho:
                row["z_eq"] = c.z_rest
                row["GM"] = c.GM
                row["bottom_max"] = float(tr.z.max() - c.s / 2)
                row["top_min"] = float(tr.z.min() + c.s / 2)
            else:
                row["accel_end"] = float(tr.F[-1, 2] / tr.sim.body.mass)
                row["accel_exact"] = -(1 - cube.rho / density) * cube.g
            n["runs"][f"{density:g}"] = row
            if density >= cube.rho:
                what = (f"sinks: z = {fmt(row['z_end'])} m after {fmt(tr.t[-1])} s, accelerating at {fmt(row['accel_end'], 4)} m/s^2 once under "
                        f"(exact -(1 - rho/rho_b) g = {fmt(row['accel_exact'], 4)})")  # fmt: skip
            elif abs(row["z_max"] - row["z_min"]) < 1e-9:
                what = f"stays at its equilibrium z = {fmt(row['z_eq'])} m (released there)"
            else:
                what = f"bobs between z = {fmt(row['z_min'])} and {fmt(row['z_max'])} m about its equilibrium {fmt(row['z_eq'])} m"
                if row["bottom_max"] > 0:
                    what += f"; its bottom leaves the water by up to {fmt(row['bottom_max'])} m"
                if row["top_min"] < 0:
                    what += f"; it goes fully under, top down to {fmt(row['top_min'])} m"
            if density < cube.rho:
                stable = "stable" if row["GM"] > 0 else "unstable"
                what += f". Face up is {stable} (GM = {fmt(row['GM'], 3)} m); largest tilt {fmt(row['max_tilt_deg'])}°"
            rows.append(f"| {density:g} | {what} |")
        # the unstable one: tilt grows from round-off at the rate sqrt(M g |GM| / I)
        unstable = [tr for tr in runs if lo < tr.sim.body.mass / tr.sim.body.volume < hi]
        growth = ""
        if unstable:
            tr = unstable[0]
            density = tr.sim.body.mass / tr.sim.body.volume
            model = tr.sim.model
            c = Cube(cube.s, density, cube.rho, cube.g)
            tilted = observe(model, pose_state(c.z_rest, (TILT_PROBE, 0.0, 0.0)))
            gm_sampled = -tilted.torque_world[0] / (tr.weight * math.sin(TILT_PROBE))
            rate_pred = math.sqrt(tr.weight * abs(gm_sampled) / tr.sim.body.inertia[0])
            th = tilts(tr)
            window = (th > 1e-9) & (th < 1e-3)
            n["unstable"] = {"density": density, "GM_sampled": gm_sampled, "rate_predicted": rate_pred}
            if window.sum() >= 5:
                rate = float(np.polyfit(tr.t[window], np.log(th[window]), 1)[0])
                n["unstable"]["rate_measured"] = rate
                growth = (f" The {density:g} kg/m^3 cube is released exactly at its equilibrium and face up, which is unstable for it: "
                          f"a round-off tilt grows as exp({fmt(rate, 3)} t) (fit over tilts 10^-9 to 10^-3 rad), against sqrt(M g |GM| / I) = "
                          f"{fmt(rate_pred, 3)} /s with the sampled GM = {fmt(gm_sampled, 3)} m, until it is no longer small ({fmt(math.degrees(th.max()))}° by t = {fmt(tr.t[-1])} s, right). Its centre stays at z = 0 all the while: "
                          "any plane through a cube's centre halves its volume.")  # fmt: skip
            else:
                growth = (f" The {density:g} kg/m^3 cube is released exactly at its equilibrium and face up, which is unstable for it "
                          f"(sampled GM = {fmt(gm_sampled, 3)} m); a round-off tilt grows at sqrt(M g |GM| / I) = {fmt(rate_pred, 3)} /s, "
                          f"too slowly to show in this short run.")  # fmt: skip
        self.nums["densities"] = n
        fig, axes = plt.subplots(1, 2, figsize=(12.5, 4.2))
        colours = ("tab:green", "tab:purple", "tab:orange", "tab:brown")
        for tr, colour in zip(runs, colours):
            density = tr.sim.body.mass / tr.sim.body.volume
            axes[0].plot(tr.t, tr.z, color=colour, label=f"{density:g} kg/m³")
            axes[1].semilogy(tr.t, np.maximum(np.degrees(tilts(tr)), 1e-14), color=colour, label=f"{density:g} kg/m³")
        axes[0].axhline(0, color="tab:blue", lw=0.8, alpha=0.5)
        axes[0].set_ylim(-2.5, 1.2)
        axes[0].set_xlabel("t (s)")
        axes[0].set_ylabel("z of the centre of mass (m)")
        axes[0].set_title("released at rest with the centre on the water line (drop scene)", fontsize=10)
        axes[0].legend(fontsize=8, loc="lower left")
        axes[0].grid(alpha=0.3)
        axes[1].set_ylim(1e-14, 200)
        axes[1].set_xlabel("t (s)")
        axes[1].set_ylabel("tilt (deg, zeros drawn at 1e-14)")
        axes[1].set_title("tilt from face-up", fontsize=10)
        axes[1].grid(alpha=0.3, which="both")
        image = self.save(fig, "density.png", "z(t) for four densities")
        cmds = "; ".join(tr.spec.command() for tr in runs)
        self.add(f"""
## Density: sinking, bouncing out, bobbing

**Settings.** {cmds}.

**The report.** A denser cube sinks "and disappear[s] from view"; a lighter one bounces above the surface; at the
density of ice (900 kg/m^3) the motion resembles an ice cube dropped into water and, undamped, goes on until the
simulation times out.

**floatsim.** The same, cube by cube:

| density (kg/m^3) | what it does (released at rest with its centre at z = 0) |
|---|---|
{chr(10).join(rows)}

{image}

**Where and why they differ.** They agree. Two things the report does not mention: heave is not a small
oscillation here (the ice cube released at z = 0 overshoots until it is fully under, where the buoyancy stops
growing), and for a hollow cube, whose centre of gravity is its centre, face up is metacentrically stable only
for density below {fmt(lo, 3)} or above {fmt(hi, 3)} kg/m^3 (GM = s^2/(12 D) + D/2 - s/2 > 0 for draft D).{growth}
""")

    def damped(self, args: FiguresArgs, cube: Cube, traces: dict[str, Trace]) -> None:
        import matplotlib.pyplot as plt

        runs = [traces["damped_low"], traces["damped_high"]]
        yawed = traces["damped_yaw"]
        base = Simulation(runs[0].spec.config())
        body, model = base.body, base.model
        weight = body.mass * cube.g
        rest = pose_state(cube.z_rest)
        probe = observe(model, pose_state(cube.z_rest, (TILT_PROBE, 0.0, 0.0)))
        gm_sampled = -probe.torque_world[0] / (weight * math.sin(TILT_PROBE))
        yaw_probe = observe(model, pose_state(cube.z_rest, (0.0, 0.0, math.radians(10.0))))
        wet = wetted(body, rest.x_world, rest.R_world_body)
        omega_heave = math.sqrt(cube.rho * cube.g * cube.s**2 / body.mass)
        n: dict = {"BM": cube.BM, "BG": cube.BG, "GM": cube.GM, "GM_sampled": gm_sampled, "BM_over_s": cube.BM / cube.s,
                   "yaw_torque_rel": float(np.linalg.norm(yaw_probe.torque_world) / (weight * cube.s)),
                   "yaw_force_rel": float(np.linalg.norm(yaw_probe.force_world) / weight), "A_sub": wet.submerged_area, "runs": {}}  # fmt: skip
        for tr in runs + [yawed]:
            d = tr.sim.params.damping
            D = damping_matrix(Params(cube.rho, cube.g, d), wet)
            R = quat_to_matrix(tr.q[-1])
            n["runs"][tr.spec.key] = {
                "d": d, "report_d": d / DAMPING_SCALE, "settle": settle_time(tr), "t_end": float(tr.t[-1]),
                "zeta_heave": float(D[2, 2] / (2 * math.sqrt(cube.rho * cube.g * cube.s**2 * body.mass))),
                "zeta_roll": float(D[3, 3] / (2 * math.sqrt(weight * gm_sampled * body.inertia[0]))),
                "z_end": float(tr.z[-1]), "tilt_end_deg": math.degrees(tilt(R)), "yaw_end_deg": yaw(R), "face": face_up(R),
                "L_end": float(tr.norm("L")[-1]), "F_end": float(tr.norm("F")[-1]), "L0": float(tr.norm("L")[0]), "q_end": [float(v) for v in tr.q[-1]],
            }  # fmt: skip
        self.nums["damped"] = n
        lo, hi, yw = (n["runs"][k] for k in ("damped_low", "damped_high", "damped_yaw"))

        # Figure 7: the resting pose, from the viewer if it can be driven, else matplotlib.
        paths = {name: self.assets / f"fig7_resting_pose_{name}.png" for name in VIEWS}
        why = (
            "the quick setting skips the browser"
            if args.quick
            else ("--no-viewer was given" if not args.viewer else viewer_render(yawed, paths))
        )
        if why is None:
            source = ("the live viewer (`app/`, viser in headless chromium, `client.get_render`), paused at the run's final pose "
                      "(samples blue under water, orange above; the top view has +x to the right, +y up, and the water grid's lines along x and y)")  # fmt: skip
            images = [self.image(p.name, f"Figure 7: resting pose in the viewer, {name} view") for name, p in paths.items()]
        else:
            source = f"matplotlib (the viewer render was not used: {why})"
            images = [self.save(render_mpl(yawed, name), p.name, f"Figure 7: resting pose, {name} view") for name, p in paths.items()]
        self.nums["fig7_source"] = "viewer" if why is None else "matplotlib"

        fig, axes = plt.subplots(1, 2, figsize=(12.5, 4.2))
        for tr, colour in zip(runs + [yawed], ("tab:blue", "tab:red", "tab:blue")):
            style = "--" if tr is yawed else "-"
            label = f"d = {tr.sim.params.damping:g} N s/m³" + (f", ω0 = {YAW_SPIN}" if tr is yawed else "")
            axes[0].semilogy(tr.t, np.maximum(tr.norm("L"), 1e-14), style, color=colour, lw=0.9, label=label)
            axes[1].semilogy(tr.t, np.maximum(tr.norm("F"), 1e-14), style, color=colour, lw=0.9, label=label)
        for ax, what, name in zip(axes, ("|L| (kg m²/s)", "|F_total| (N)"), ("L", "F")):
            ax.set_xlabel("t (s)")
            ax.set_ylabel(what)
            ax.set_ylim(max(1e-12, min(tr.norm(name).min() for tr in runs + [yawed]) / 3), None)
            ax.grid(alpha=0.3, which="both")
            ax.legend(fontsize=8)
        axes[0].set_title("angular momentum", fontsize=10)
        axes[1].set_title("total force", fontsize=10)
        plot = self.save(fig, "fig8_9_damped.png", "Figures 8-9: |L| and |F| against time for two damping constants")

        def settled(v):
            return f"at rest after {fmt(v['settle'])} s" if v["settle"] is not None else f"not yet at rest at t = {fmt(v['t_end'])} s"

        def pose_row(tr, v):
            omega = ", ".join(f"{w:g}" for w in tr.spec.config().initial.omega)
            rest = fmt(v["settle"]) if v["settle"] is not None else f"not by {fmt(v['t_end'])}"
            return (f"| {fmt(v['d'])} | ({omega}) | {rest} | {v['face']} | {v['z_end']:.6f} | {fmt(v['tilt_end_deg'])} | {fmt(v['yaw_end_deg'], 4)} |"
                    f" {fmt(v['L_end'])} | {fmt(v['F_end'])} |")  # fmt: skip

        poses = "\n".join(["| d (N s/m^3) | initial spin (rad/s) | at rest after (s) | final pose | z (m) | tilt (°) | yaw (°, mod 90) | final abs(L) (kg m^2/s) | final abs(F) (N) |",
                           "|---|---|---|---|---|---|---|---|---|"] + [pose_row(tr, v) for tr, v in zip(runs + [yawed], (lo, hi, yw))])  # fmt: skip

        both = lo["settle"] is not None and hi["settle"] is not None
        speed = ""
        if both:
            speed = (": the heavier damping overdamps the roll, so it is no faster" if hi["settle"] >= 0.8 * lo["settle"]
                     else ": the heavier damping is faster")  # fmt: skip
        aligned = all(v["tilt_end_deg"] < 0.01 and abs(v["yaw_end_deg"]) < 0.01 for v in (lo, hi))
        ending = (("Both come to rest face up and back in the axes' alignment (table)." if aligned else "Both come to rest (table).")
                  if both else f"At t = {fmt(lo['t_end'])} s they are still moving (table).")  # fmt: skip
        turned = "."
        if yw["settle"] is not None:
            turned = (f", face up but turned by {fmt(yw['yaw_end_deg'], 3)}° about the vertical: the report's \"slightly rotated position\"."
                      if abs(yw["yaw_end_deg"]) > 0.5 else ", face up.")  # fmt: skip

        qw, qx, qy, qz = yw["q_end"]
        quaternion = f"Its final quaternion is (w, x, y, z) = ({qw:.6g}, {qx:.3g}, {qy:.3g}, {qz:.6g})"
        if math.hypot(qx, qy) < 1e-6:
            quaternion += (
                f": a turn about the vertical alone, by 2 atan2(|q_z|, |q_w|) = {fmt(math.degrees(2 * math.atan2(abs(qz), abs(qw))), 4)}°."
            )
        else:
            quaternion += "."
        cmds = "; ".join(tr.spec.command() for tr in runs)
        self.add(f"""
## Figures 7-9: damping brings the cube to rest

**Settings.** {cmds}. Figure 7 shows the end of {yawed.spec.command()}, the same with a vertical component added to
the initial spin. "At rest" means |L| < 10^-3 |L(0)| and |F| < 10^-4 of the weight from then on.

**The report.** With damping constants 0.1 and 0.25 (units not stated) the motion dies out and the cube "settled
in a slightly rotated position, offset from its initial alignment with the xyz-axes"; figures 8 and 9 plot
||L|| and ||F_total|| against time for the two constants.

**floatsim.** Our damping force on a wet sample is -d a_k v_k with d in N s/m^3, the report's F_damp = -d v area.
The report states neither its units nor how its masses and areas were scaled, so its constants cannot be
converted; we use d = {fmt(lo["d"])} and {fmt(hi["d"])} N s/m^3, {fmt(DAMPING_SCALE)} times its 0.1 and 0.25 (the same ratio). What carries
over between models is the damping ratio: at rest, with A_sub = {fmt(n["A_sub"])} m^2 wet, heave has zeta = d A_sub / (2 M omega) =
{fmt(lo["zeta_heave"])} and {fmt(hi["zeta_heave"])} (omega = {fmt(omega_heave, 4)} rad/s), rolling zeta = {fmt(lo["zeta_roll"])} and {fmt(hi["zeta_roll"])}. The cube is {settled(lo)}
with d = {fmt(lo["d"])} and {settled(hi)} with d = {fmt(hi["d"])}{speed}.

{plot}

{poses}

{ending} With the added vertical spin (last row) the cube is {settled(yw)}{turned}
{quaternion} Figure 7 shows that final pose, rendered by {source}.

{chr(10).join(images)}

**Why face up, and why "slightly rotated".** For the hollow cube of density 900 the centre of gravity G is the
centre, s/2 above the bottom; the centre of buoyancy B is at half the draft of {fmt(cube.draft / cube.s)} s, so BG = {fmt(cube.BG / cube.s)} s. The metacentre is
BM = I_wp / V_sub = (s^4/12) / (0.9 s^3) = s/{fmt(1 / n["BM_over_s"], 3)} = {fmt(cube.BM, 4)} m above B, so GM = BM - BG = {fmt(cube.GM, 4)} m > 0: a
tilt is righted, face up is stable. The sampled model agrees: a 1° tilt gives a righting moment M g GM sin(1°)
with GM = {fmt(gm_sampled, 4)} m (the midpoint rule's (1 - 1/N^2) on I_wp). Turning about the vertical changes nothing that
floats: at a 10° yaw the torque is {fmt(n["yaw_torque_rel"])} M g s and the force {fmt(n["yaw_force_rel"])} of the weight, round-off. Yaw is
neutral, so the damping stops it wherever the motion leaves it. The spin (-1, 1, 0) keeps the motion mirror-symmetric
about the vertical plane x = y, which allows only yaw 0 or 45° (mod 90°) (here {fmt(lo["yaw_end_deg"], 3)}° and {fmt(hi["yaw_end_deg"], 3)}°); a spin
with a vertical part breaks the symmetry and leaves {fmt(yw["yaw_end_deg"], 3)}°. The report's small rotation is such a neutral
yaw, left over from its motion; the text does not say which of its initial conditions or numerical errors set it.
""")


def render_mpl(trace: Trace, view: str):
    """The final pose's cube mesh with the water plane, by matplotlib (the fallback for figure 7)."""
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    body, state = trace.sim.body, trace.sim.state
    verts = body.mesh_vertices @ state.R_world_body.T + state.x_world
    fig = plt.figure(figsize=(6, 4.5))
    ax = fig.add_subplot(projection="3d")
    ax.computed_zorder = False  # drawn in order: cube, water, then every edge (a wireframe over both)
    w = 1.2
    water = np.array([[-w, -w, 0], [w, -w, 0], [w, w, 0], [-w, w, 0]]) + [state.x_world[0], state.x_world[1], 0]
    faces = body.mesh_faces
    ax.add_collection3d(Poly3DCollection([verts[f] for f in faces], facecolor=(0.84, 0.92, 0.98), linewidth=0, alpha=0.9))
    ax.add_collection3d(Poly3DCollection([water], facecolor=(0.2, 0.5, 0.85), alpha=0.35))
    # feature edges only (between triangles of different normals), not the triangulation's diagonals
    tri = body.mesh_vertices[faces]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    sides: dict = {}
    for k, f in enumerate(faces):
        for a, b in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0])):
            sides.setdefault((min(a, b), max(a, b)), []).append(k)
    for (a, b), ks in sides.items():
        if len(ks) != 2 or normal[ks[0]] @ normal[ks[1]] < 0.999:
            ax.plot(*verts[[a, b]].T, color="0.2", lw=1.0, zorder=3)
    c = state.x_world
    ax.set_xlim(c[0] - w, c[0] + w)
    ax.set_ylim(c[1] - w, c[1] + w)
    ax.set_zlim(-1.2, 1.2)
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(*((25, -55) if view == "side" else (88, -90)))
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    if view == "top":
        ax.set_zticks([])
    else:
        ax.set_zlabel("z (m)")
    ax.set_title(f"resting pose at t = {state.t:g} s, {view} view (water plane z = 0)", fontsize=9)
    return fig

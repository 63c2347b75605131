"""The seed-figures page's pictures: matplotlib figures from the runs, and figure 7 from the live viewer
(app/, headless chromium) with a matplotlib render as its fallback. Each function returns a figure; the
page saves it."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from .. import probes
from ..common import fmt, pct, pyplot
from .compute import SWEEP_N, YAW_SPIN, Cube, Trace, report_grid
from .numbers import tilts

GRID_COLOURS = {"ours": "tab:orange", "report": "tab:blue", "rescaled": "tab:green"}


def samples_3d(cube: Cube, n_plot: int = 5):
    """Figure 1: the two grids in 3D, N = 5 (the report's own example)."""
    plt = pyplot()
    r, nrm, _, kept = report_grid(cube.s, n_plot)
    ours = probes.body(probes.cube_body(cube.s, n_plot, cube.mass))
    fig = plt.figure(figsize=(11, 5.2))
    for k, (title, pts, normals, dropped) in enumerate((
        ((f"report: {n_plot} points per edge, edges and corners dropped\n{kept.sum()} points, total area "
          f"{fmt(kept.sum() * (cube.s / n_plot) ** 2)} m² of {fmt(6 * cube.s ** 2)} m²"), r[kept], nrm[kept], r[~kept]),
        ((f"floatsim: {n_plot} x {n_plot} cell centres per face\n{ours.n_samples} points, total area "
          f"{fmt(ours.area.sum())} m² of {fmt(6 * cube.s ** 2)} m²"), ours.r, ours.n, None),
    )):  # fmt: skip
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        ax.scatter(*pts.T, s=12, color="tab:blue", depthshade=False, label="samples")
        ax.quiver(*pts.T, *(0.18 * normals).T, color="tab:red", linewidth=0.7, arrow_length_ratio=0.3, label="outward normals")
        if dropped is not None:
            ax.scatter(*np.unique(dropped, axis=0).T, s=14, marker="x", color="0.55", depthshade=False, label="dropped (edges, corners)")
        ax.set_title(title, fontsize=10)
        ax.set_box_aspect((1, 1, 1))
        ax.view_init(elev=22, azim=-58)
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_zlabel("z (m)")
        ax.legend(loc="upper left", fontsize=8)
    return fig


def _face_patches(plt, ax, cube: Cube, title: str, centres, keep: bool, side: float) -> None:
    """One face with each sample's area patch (keep: the report's grid, whose edge and corner points are dropped)."""
    h = cube.s / 2
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


def sample_areas(cube: Cube, sweep: dict, n_plot: int = 5):
    """Figure 2: one face with each sample's area patch, both grids; the errors against N."""
    from matplotlib.ticker import NullFormatter, ScalarFormatter

    plt = pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.6), gridspec_kw={"width_ratios": [1, 1, 1.7]})
    h = cube.s / 2
    report_title = f"report, one face: {(n_plot - 2) ** 2} patches of (s/N)²\ncover {pct(((n_plot - 2) / n_plot) ** 2)} of it"
    _face_patches(plt, axes[0], cube, report_title, np.linspace(-h, h, n_plot), True, cube.s / n_plot)
    ours_title = f"floatsim, one face: {n_plot**2} cells of (s/N)²\ncover 100 % of it"
    _face_patches(plt, axes[1], cube, ours_title, (np.arange(n_plot) + 0.5) / n_plot * cube.s - h, False, cube.s / n_plot)
    ax = axes[2]
    for key, style, label in (("area_ratio", ":", "area deficit (= rest-buoyancy deficit)"), ("righting_ratio", "-", "righting-moment error, 1° tilt"),
                              ("inertia_ratio", "--", "inertia error vs (5/18) M s²")):  # fmt: skip
        for grid in ("report", "rescaled", "ours"):
            if key == "area_ratio" and grid != "report":
                continue  # exact (area) for the other two
            if key == "inertia_ratio" and grid == "rescaled":
                continue  # same masses as the report's grid
            err = np.array([abs(sweep[n][grid][key] - 1) for n in SWEEP_N])
            ax.loglog(SWEEP_N, np.maximum(err, 1e-16), style, color=GRID_COLOURS[grid], label=f"{grid}: {label}")
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
    return fig


def rest(cube: Cube, ours: Trace, spun: Trace, spin_omega: float):
    """Figure 3: z(t) of the cube placed at rest, without (left) and with (right) the report's initial spin."""
    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(12, 4))
    ax = axes[0]
    ax.plot(ours.t, ours.z - cube.z_rest, color="tab:orange")
    ax.set_ylim(-1e-12, 1e-12)
    ax.set_title(f"floatsim ({ours.spec.config().step.integrator}), released at rest: no initial velocity", fontsize=10)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("z(t) - (-0.4) (m)")
    ax.grid(alpha=0.3)
    ax = axes[1]
    ax.plot(spun.t, spun.z - cube.z_rest, color="tab:blue", label="z(t) + 0.4")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("z(t) - (-0.4) (m)", color="tab:blue")
    ax.ticklabel_format(axis="y", style="sci", scilimits=(-2, 2))
    ax2 = ax.twinx()
    ax2.plot(spun.t, np.degrees(tilts(spun)), color="tab:red", lw=0.8)
    ax2.set_ylabel("tilt (deg)", color="tab:red")
    ax.set_title(f"with the report's trick: initial spin {fmt(spin_omega)} rad/s about x, euler", fontsize=10)
    ax.grid(alpha=0.3)
    return fig


def angular_momentum(runs: list[Trace], free: Trace):
    """Figures 4-5: |L|(t) of the spinning cube per run and the torque-free control; euler minus implicit."""
    plt = pyplot()
    ref = runs[2]
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
    return fig


def force_at_rest(tr: Trace, report_grid_F_rel: float, floor: float = 1e-18):
    """Figure 6: |F_total| / weight of the cube at rest, with the report's grid's value at the same pose."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(8, 3.8))
    ax.semilogy(tr.t, np.maximum(tr.norm("F") / tr.weight, floor), color="tab:orange", label="floatsim, cube at rest at z = -0.4")
    ax.axhline(report_grid_F_rel, color="tab:blue", ls="--", label="report's grid (N = 10) at the same pose")
    ax.axhline(1e-9, color="0.5", ls=":", label="10^-9 of the weight")
    ax.set_ylim(floor / 2, 2)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("|F_total| / weight")
    ax.set_title(f"|F_total| at rest (zeros drawn at {floor:g})", fontsize=10)
    ax.legend(fontsize=8, loc="center right")
    ax.grid(alpha=0.3, which="both")
    return fig


def densities(runs: list[Trace]):
    """z(t) and tilt(t) of the cube released on the water line, one curve per density."""
    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(12.5, 4.2))
    colours = ("tab:green", "tab:purple", "tab:orange", "tab:brown")
    for tr, colour in zip(runs, colours):
        axes[0].plot(tr.t, tr.z, color=colour, label=f"{tr.density:g} kg/m³")
        axes[1].semilogy(tr.t, np.maximum(np.degrees(tilts(tr)), 1e-14), color=colour, label=f"{tr.density:g} kg/m³")
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
    return fig


def damped(runs: list[Trace], yawed: Trace):
    """Figures 8-9: |L| and |F| against time for the two damping constants and the yawed run."""
    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(12.5, 4.2))
    for tr, colour in zip(runs + [yawed], ("tab:blue", "tab:red", "tab:blue")):
        style = "--" if tr is yawed else "-"
        label = f"d = {probes.fluid(tr.sim).damping:g} N s/m³" + (f", ω0 = {YAW_SPIN}" if tr is yawed else "")
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
    return fig


# ---- figure 7: the resting pose ---------------------------------------------------------------------------

VIEWS = {"side": ((1.3, -1.8, 1.0), (0.0, 0.0, -0.3), (0.0, 0.0, 1.0)), "top": ((0.0, 0.0, 2.4), (0.0, 0.0, -0.4), (0.0, 1.0, 0.0))}
"""Camera position, look-at point and up direction of each render (the top view has +y up, +x right)."""


def resting_scene_toml(trace: Trace) -> str:
    """A scene file holding the run's final pose at rest (what the viewer is asked to show)."""
    cfg, state = trace.spec.config(), trace.sim.state
    q_input = probes.quat_product(state.q_world_body, trace.body.q_input * np.array([1.0, -1.0, -1.0, -1.0]))

    def vec(v) -> str:
        return "[" + ", ".join(f"{float(c):.17g}" for c in v) + "]"

    return (f'description = "Final pose of figures run {trace.spec.key}, at rest."\n\n[body]\nshape = "cube"\nsize = {cfg.body.size}\n'
            f"points_per_edge = {cfg.body.points_per_edge}\ndensity = {cfg.body.density}\n\n[fluid]\ndamping = {cfg.fluid.damping}\n\n"
            f"[initial]\nposition = {vec(state.x_world)}\norientation = {vec(q_input / np.linalg.norm(q_input))}\n\n[step]\ndt = {cfg.step.dt}\n")  # fmt: skip


def viewer_render(trace: Trace, paths: dict[str, Path]) -> str | None:
    """Pictures of the final pose from the live viewer, one per view in VIEWS. Returns None on success, else
    why not. Optional and lazy (chromium may be missing), with a matplotlib render as the fallback."""
    try:
        from app.tools.render import render_scene
    except Exception as e:  # noqa: BLE001 -- any import problem means the matplotlib render
        return f"the viewer could not be imported ({type(e).__name__}: {e})"
    with tempfile.TemporaryDirectory() as tmp:
        scene = Path(tmp) / "resting_pose.toml"
        scene.write_text(resting_scene_toml(trace))
        return render_scene(str(scene), VIEWS, paths)


def _feature_edges(vertices: np.ndarray, faces: np.ndarray) -> list[tuple[int, int]]:
    """Mesh edges between triangles of different normals (not the triangulation's diagonals)."""
    tri = vertices[faces]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    sides: dict = {}
    for k, f in enumerate(faces):
        for a, b in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0])):
            sides.setdefault((min(a, b), max(a, b)), []).append(k)
    return [(a, b) for (a, b), ks in sides.items() if len(ks) != 2 or normal[ks[0]] @ normal[ks[1]] < 0.999]


def render_mpl(trace: Trace, view: str):
    """The final pose's cube mesh with the water plane, by matplotlib (the fallback for figure 7)."""
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    plt = pyplot()
    body, state = trace.body, trace.sim.state
    verts = body.mesh_vertices @ state.R_world_body.T + state.x_world
    fig = plt.figure(figsize=(6, 4.5))
    ax = fig.add_subplot(projection="3d")
    ax.computed_zorder = False  # drawn in order: cube, water, then every edge (a wireframe over both)
    w = 1.2
    water = np.array([[-w, -w, 0], [w, -w, 0], [w, w, 0], [-w, w, 0]]) + [state.x_world[0], state.x_world[1], 0]
    faces = body.mesh_faces
    ax.add_collection3d(Poly3DCollection([verts[f] for f in faces], facecolor=(0.84, 0.92, 0.98), linewidth=0, alpha=0.9))
    ax.add_collection3d(Poly3DCollection([water], facecolor=(0.2, 0.5, 0.85), alpha=0.35))
    for a, b in _feature_edges(body.mesh_vertices, faces):
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

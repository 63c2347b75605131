"""The seed-figures page's markdown: one function per section of the source report, reading the runs and
the section's numbers, returning the section's text (its images come in as ready markdown links)."""

from __future__ import annotations

import math

from ..common import fmt, md_table, pct
from .compute import DAMPING_SCALE, TABLE_N, Cube, Trace
from .numbers import heave_omega, tilts

SOURCE = "seed/000_069c8b0ce5e5c6f5.txt"
GRID_NAMES = {"ours": "floatsim, cell centres", "report": "report, area (s/N)^2", "rescaled": "report, area 6 s^2/n"}


def intro(quick_setting: bool, cube: Cube, n_samples: int, points_per_edge: int) -> str:
    quick = ("\n\n**This is the quick setting** (`--quick`: a few simulated seconds at dt = 0.01 s, no browser render), "
             "made for the test; run `python -m studies figures` for the real page.") if quick_setting else ""  # fmt: skip
    return f"""
# The source report's figures, reproduced with floatsim

The source report (`{SOURCE}`, "Simulation of a Cubic Floating Body Suspended in Viscous Fluid") simulates a hollow
cube sampled by surface points in MATLAB. This page redoes each of its figures with floatsim's corrected model
(the README's *The model*) and says where and why the results differ. It is generated, numbers included, by
`python -m studies figures{" --quick" if quick_setting else ""}` (package `studies/seed_figures/`); the settings of every run are given as the
equivalent `python -m sim run` command.{quick}

Common to all runs: the report's ice cube, side s = {fmt(cube.s)} m, density {fmt(cube.density)} kg/m^3 (mass {fmt(cube.mass)} kg)
unless stated, water rho = {fmt(cube.rho)} kg/m^3, g = {fmt(cube.g)} m/s^2, sampled by floatsim's default
{n_samples} points (N = {points_per_edge} cells per edge on each face).
"""


def _grid_table(rows: dict) -> list[str]:
    header = ["grid", "N", "samples", "total area / 6 s²", "buoyancy at rest / rho g V_sub", "water-plane moment / (s⁴/12)",
              "righting moment at 1° / exact", "I / ((5/18) M s²)"]  # fmt: skip
    cells = [[GRID_NAMES[grid], n, v["samples"], *(f"{v[k]:.4f}" for k in ("area_ratio", "buoyancy_ratio", "waterplane_ratio", "righting_ratio", "inertia_ratio"))]
             for grid in ("report", "rescaled", "ours") for n in TABLE_N for v in [rows[n][grid]]]  # fmt: skip
    return md_table(header, cells)


def samples(cube: Cube, rows: dict, n: dict, fig1: str, fig2: str, n_ex: int = 10) -> str:
    """Figures 1-2: the report's sample grid against ours."""
    rep, res, our = (rows[n_ex][k] for k in ("report", "rescaled", "ours"))
    deficit, worst = n["grid_area_deficit_N10"], n["grid_righting_worst_N20_40"]
    table = _grid_table(rows)
    return f"""
## Figures 1-2: the point-sampled cube

**Settings.** No time stepping: each grid is turned into a `sim.Body` (the report's with `report_grid` in
`studies/seed_figures/compute.py`, ours with `sim.bodies.body.make_box`) and its forces at the report's rest pose (face up, centre at
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
6 s^2 (1 - ((N-2)/N)^2) = {fmt(n["grid_area_deficit_formula_N10"], 4)} m^2 ({pct(1 - rep["area_ratio"])} of the surface).
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
"""


def rest(ours: Trace, spun: Trace, n: dict, image: str) -> str:
    """Figure 3: the cube placed at its resting depth."""
    return f"""
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
small |Omega| dt (`sim.bodies.rotation.rotation_quat`), so w = 0 is an ordinary case and no trick is needed.
"""


def angular_momentum(runs: list[Trace], free: Trace, n: dict, image: str) -> str:
    """Figures 4-5: |L| with an initial spin."""
    ref = runs[2]
    L0 = n["L0"]
    coarse, fine = n["runs"]["spin_euler_coarse"], n["runs"]["spin_euler_fine"]
    cmds = "; ".join(tr.spec.command() for tr in runs)
    return f"""
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
"""


def force_at_rest(tr: Trace, n: dict, image: str) -> str:
    """Figure 6: the total force at rest."""
    return f"""
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
"""


def _density_effect(cube: Cube, row: dict, t_end: float) -> str:
    """What the cube of one density does, for the density table."""
    if row["density"] >= cube.rho:
        what = (f"sinks: z = {fmt(row['z_end'])} m after {fmt(t_end)} s, accelerating at {fmt(row['accel_end'], 4)} m/s^2 once under "
                f"(exact -(1 - rho/rho_b) g = {fmt(row['accel_exact'], 4)})")  # fmt: skip
    elif abs(row["z_max"] - row["z_min"]) < 1e-9:
        what = f"stays at its equilibrium z = {fmt(row['z_eq'])} m (released there)"
    else:
        what = f"bobs between z = {fmt(row['z_min'])} and {fmt(row['z_max'])} m about its equilibrium {fmt(row['z_eq'])} m"
        if row["bottom_max"] > 0:
            what += f"; its bottom leaves the water by up to {fmt(row['bottom_max'])} m"
        if row["top_min"] < 0:
            what += f"; it goes fully under, top down to {fmt(row['top_min'])} m"
    if row["density"] < cube.rho:
        stable = "stable" if row["GM"] > 0 else "unstable"
        what += f". Face up is {stable} (GM = {fmt(row['GM'], 3)} m); largest tilt {fmt(row['max_tilt_deg'])}°"
    return what


def _tilt_growth(n: dict, tr: Trace | None) -> str:
    """The metacentrically unstable density's tilt growth, if one was run."""
    if tr is None:
        return ""
    u = n["unstable"]
    density, gm_sampled, rate_pred = u["density"], u["GM_sampled"], u["rate_predicted"]
    if "rate_measured" in u:
        th = tilts(tr)
        return (f" The {density:g} kg/m^3 cube is released exactly at its equilibrium and face up, which is unstable for it: "
                f"a round-off tilt grows as exp({fmt(u['rate_measured'], 3)} t) (fit over tilts 10^-9 to 10^-3 rad), against sqrt(M g |GM| / I) = "
                f"{fmt(rate_pred, 3)} /s with the sampled GM = {fmt(gm_sampled, 3)} m, until it is no longer small ({fmt(math.degrees(th.max()))}° by t = {fmt(tr.t[-1])} s, right). Its centre stays at z = 0 all the while: "
                "any plane through a cube's centre halves its volume.")  # fmt: skip
    return (f" The {density:g} kg/m^3 cube is released exactly at its equilibrium and face up, which is unstable for it "
            f"(sampled GM = {fmt(gm_sampled, 3)} m); a round-off tilt grows at sqrt(M g |GM| / I) = {fmt(rate_pred, 3)} /s, "
            f"too slowly to show in this short run.")  # fmt: skip


def densities(cube: Cube, runs: list[Trace], n: dict, image: str) -> str:
    """Density: sinking, bouncing out, bobbing."""
    rows = [[f"{tr.density:g}", _density_effect(cube, n["runs"][f"{tr.density:g}"], tr.t[-1])] for tr in runs]
    table = "\n".join(md_table(["density (kg/m^3)", "what it does (released at rest with its centre at z = 0)"], rows))
    lo, hi = n["unstable_band"]
    unstable = next((tr for tr in runs if "unstable" in n and tr.density == n["unstable"]["density"]), None)
    growth = _tilt_growth(n, unstable)
    cmds = "; ".join(tr.spec.command() for tr in runs)
    return f"""
## Density: sinking, bouncing out, bobbing

**Settings.** {cmds}.

**The report.** A denser cube sinks "and disappear[s] from view"; a lighter one bounces above the surface; at the
density of ice (900 kg/m^3) the motion resembles an ice cube dropped into water and, undamped, goes on until the
simulation times out.

**floatsim.** The same, cube by cube:

{table}

{image}

**Where and why they differ.** They agree. Two things the report does not mention: heave is not a small
oscillation here (the ice cube released at z = 0 overshoots until it is fully under, where the buoyancy stops
growing), and for a hollow cube, whose centre of gravity is its centre, face up is metacentrically stable only
for density below {fmt(lo, 3)} or above {fmt(hi, 3)} kg/m^3 (GM = s^2/(12 D) + D/2 - s/2 > 0 for draft D).{growth}
"""


def settled(v: dict) -> str:
    return f"at rest after {fmt(v['settle'])} s" if v["settle"] is not None else f"not yet at rest at t = {fmt(v['t_end'])} s"


def _poses(traces: list[Trace], values: list[dict]) -> str:
    """The final pose of each damped run, as a table."""
    rows = []
    for tr, v in zip(traces, values):
        omega = ", ".join(f"{w:g}" for w in tr.spec.config().initial.omega)
        rest = fmt(v["settle"]) if v["settle"] is not None else f"not by {fmt(v['t_end'])}"
        rows.append([fmt(v["d"]), f"({omega})", rest, v["face"], f"{v['z_end']:.6f}", fmt(v["tilt_end_deg"]), fmt(v["yaw_end_deg"], 4),
                     fmt(v["L_end"]), fmt(v["F_end"])])  # fmt: skip
    return "\n".join(md_table(["d (N s/m^3)", "initial spin (rad/s)", "at rest after (s)", "final pose", "z (m)", "tilt (°)", "yaw (°, mod 90)",
                               "final abs(L) (kg m^2/s)", "final abs(F) (N)"], rows))  # fmt: skip


def _outcome(lo: dict, hi: dict, yw: dict) -> tuple[str, str, str]:
    """(speed, ending, turned): how the two damping constants compare, how both end, how the yawed run ends."""
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
    return speed, ending, turned


def _quaternion(q_end: list[float]) -> str:
    qw, qx, qy, qz = q_end
    quaternion = f"Its final quaternion is (w, x, y, z) = ({qw:.6g}, {qx:.3g}, {qy:.3g}, {qz:.6g})"
    if math.hypot(qx, qy) < 1e-6:
        return (
            quaternion
            + f": a turn about the vertical alone, by 2 atan2(|q_z|, |q_w|) = {fmt(math.degrees(2 * math.atan2(abs(qz), abs(qw))), 4)}°."
        )
    return quaternion + "."


def damped(cube: Cube, runs: list[Trace], yawed: Trace, n: dict, plot: str, images: list[str], source: str) -> str:
    """Figures 7-9: damping brings the cube to rest (`source` says what rendered figure 7)."""
    lo, hi, yw = (n["runs"][k] for k in ("damped_low", "damped_high", "damped_yaw"))
    gm_sampled = n["GM_sampled"]
    omega_heave = heave_omega(cube, runs[0])
    poses = _poses(runs + [yawed], [lo, hi, yw])
    speed, ending, turned = _outcome(lo, hi, yw)
    quaternion = _quaternion(yw["q_end"])
    cmds = "; ".join(tr.spec.command() for tr in runs)
    return f"""
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
"""

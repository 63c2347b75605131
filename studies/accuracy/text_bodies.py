"""The markdown of the accuracy report's parts 8 (the radiation memory's passivity) and 9 (drifting bodies)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..common import md_table

if TYPE_CHECKING:
    from . import ReportData

REL = "accuracy"


def passivity(data: ReportData) -> list[str]:
    """Part 8: the fitted damping's floor per shipped solve, and rm3 without a damper."""
    from .passivity import KICK, MISFITS, OLD_FIT, ROUND_OFF

    p = data.passivity
    L = ["## 8. Radiation that cannot create energy", ""]
    L.append("A body's radiation memory (the convolution of its past velocity with the retardation kernel) is fitted as a "
             "state space, K(s) = H (sI - F)^-1 G, to each BEM solve's damping B(ω) and added mass A(ω) (sim/hydro/memory_fit.py). "
             "The waves a body makes can only take energy from it when the fitted damping B_fit(ω) = Re K(iω) is positive "
             "semi-definite at every frequency, the grid's and beyond it: otherwise some motion pumps energy in. For every "
             f"shipped solve, the fit the scenes use: the smallest eigenvalue of B_fit(ω) over {2 * p.settings.points} frequencies "
             "(linear and logarithmic) from 0 to 10 times the solve's top frequency ω_top, against the solve's peak damping "
             "(over the dofs that radiate: the others' B_fit is zero); the fit's largest misfits of B and A on the grid, each "
             "entry that matters against its own peak; its states.")  # fmt: skip
    L.append("")
    rows = [[f"`{s.name}`", s.bodies, f"{s.frequencies}: {s.omega_low:.3g} to {s.omega_top:.3g}", s.dofs, s.states, f"{s.misfit_B:.2%}",
             f"{s.misfit_A:.2%}", f"{s.lowest:.2g}", f"{s.where / s.omega_top:.3g}"] for s in p.solves]  # fmt: skip
    L += md_table(["solve", "bodies", "frequencies (rad/s)", "radiating dofs", "states", "misfit B", "misfit A",
                   "min eig B_fit / peak B", "at ω / ω_top"], rows)  # fmt: skip
    L.append("")
    for s in p.solves:
        if s.name in MISFITS:
            L.append(f"`{s.name}` ({MISFITS[s.name][0]}) misses the 2 % misfit: a farm's cross terms oscillate with frequency, as "
                     "e^(ikd) with the spacing d, beyond what ten pole pairs follow. Its fit is passive and stable all the same, and a run "
                     "of it says how far off it is (docs/farms.md).")  # fmt: skip
            L.append("")
    worst = min(p.solves, key=lambda s: s.lowest)
    L.append(f"The lowest over every solve is {worst.lowest:.2g} of the peak (`{worst.name}`): "
             f"{'non-negative' if worst.lowest >= 0 else 'round-off'} (the check's bound is {-ROUND_OFF:g}).")  # fmt: skip
    L.append("")
    L.append(f"![the fitted damping's smallest eigenvalue]({REL}/passivity.png)")
    L.append("")
    if p.rm3 is not None:
        r = p.rm3
        L.append(f"**In time.** rm3 (float and spar) without its take-off's damper, in still water, the float kicked upwards at {KICK:g} m/s "
                 f"({r.kick / 1e3:.4g} kJ), linear hydro stepped exactly (sim/system/linear.py) for {r.t[-1]:.0f} s: the largest real part "
                 f"of an eigenvalue of the linear system is {r.eig_max:+.2g} 1/s; the mechanical energy "
                 + ("never rose above its start" if r.rise <= 0 else f"rose at most {r.rise / r.kick:.2g} of the kick above its start")
                 + f" and ended {r.energy[-1] / r.kick:+.3f} of the kick from it; the radiated waves "
                 f"took {r.E_rad / r.kick:.1%} of the kick, and E_total + E_pto + E_rad stayed the start's within {r.gap / r.kick:.1e} of the "
                 "kick (Simpson's integral of the radiated power).")  # fmt: skip
        L.append("")
    L.append(f"The fit before issue 38 (`python -m studies.passivity` against the parent of commit {OLD_FIT['commit'].rstrip('^')}: its "
             "code is not in this tree, so these two numbers are quoted from that run): rm3 without a damper had an eigenvalue with "
             f"real part {OLD_FIT['eig']:+.2g} 1/s and gained energy without bound ({OLD_FIT['energy']:.2g} J in {OLD_FIT['horizon']:g} s).")  # fmt: skip
    L.append("")
    return L


def drifting(data: ReportData) -> list[str]:
    """Part 9: the free sphere's heave after a drift against a slide, and the start-up with and without the ramp."""
    d = data.drifting
    cfg = d.settings
    L = ["## 9. Drifting bodies: excitation where the body is, and the wave ramp", ""]
    L.append("A body that drifts meets the wave's phase where it is: the diffraction force (sim/hydro/diffraction.py) is phased at the "
             "body's current position, as the Froude-Krylov pressure is. The sphere preset, placed a quarter wave down-wave of "
             f"where the scene starts it (before the waves rise, as a drift would carry it), free, in {cfg.height * 1000:g} mm waves: "
             "its heave RAO (the first harmonic of the last "
             f"{cfg.fit} of {cfg.run} periods after the ramp) against the same sphere on a vertical slide at its start (a prismatic "
             "joint) and the linear frequency-domain RAO of the same coefficients (interpolated linearly between the solve's "
             "frequencies). Before issue 38 the force was phased where the body started, which a drift of a quarter wave "
             "turns by 90 degrees.")  # fmt: skip
    L.append("")
    rows = [[f"{r.period:g}", f"{r.wavelength:.2f}", f"{r.free:.4f}", f"{r.slide:.4f}", f"{r.frequency:.4f}", f"{r.free / r.slide - 1:+.2%}",
             f"{r.free / r.frequency - 1:+.2%}", f"{r.slide / r.frequency - 1:+.2%}"] for r in sorted(d.rows, key=lambda r: r.period)]  # fmt: skip
    L += md_table(["T (s)", "λ (m)", "free (m/m)", "on the slide", "frequency domain", "free against slide", "free against frequency domain",
                   "slide against frequency domain"], rows)  # fmt: skip
    L.append("")
    L.append(f"![the drifting sphere's heave and its start-up]({REL}/drifting.png)")
    L.append("")
    a, T = d.amplitude, cfg.ramp_period
    default = max(s.ramp for s in d.starts)
    L.append(f"**The start-up.** The sphere started at rest in {cfg.ramp_height * 1000:g} mm waves (a = {a * 1000:g} mm, T = {T:g} s), "
             "once at x = 0 and once half a wave down-wave, where the wave's sign is flipped: half the difference of their period "
             "means is the part of the surge that flips with the wave, the first-order start-up kick (the rest, the mean wave force's "
             "drift, is second order). Waves at full height from t = 0 (`[waves] ramp = 0`, floatsim before the ramp) push it off at "
             f"once; the default ramp ({default / T:g} periods, a half-cosine: `[waves] ramp`) grows them from still water.")  # fmt: skip
    L.append("")
    rows = []
    for s in d.starts:
        rows.append(["0 (no ramp)" if s.ramp == 0 else f"{s.ramp:g} s (default)", f"{s.drift / a:+.3g} a ({s.drift * 1000:+.3g} mm)",
                     f"{abs(s.odd).max() / a:.3g} a", f"{s.odd[-1] / a:+.3g} a"])  # fmt: skip
    L += md_table(["ramp", "the kick's drift per period after the ramp", "its largest excursion", "where it ends"], rows)
    L.append("")
    return L

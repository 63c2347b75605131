"""`python -m studies.passivity [--nonlinear]`: the radiation memory's passivity and cost, in numbers (issue 38).

For each shipped BEM solve: the smallest eigenvalue of the fitted damping B_fit(omega) = Re K(i omega) on 40,000
frequencies from 0 to 10x the grid's top one (against the peak damping), the fit's misfits (B against B's peak per
entry, A against A's), its states and how long it took. For rm3 without a damper (and with a spring-only take-off),
linear hydro: the largest real part of an eigenvalue of the linear system, and the float kicked at 0.5 m/s in still
water for 3000 s, stepped exactly: how far the mechanical energy ever rose above the start and E_rad. With
--nonlinear also the default hydro (Stormer-Verlet, dt 0.05 s, minutes): the energy's largest rise and the float's
highest point. Then the memory's numpy cost per step (one body: advance and force; rm3: drift and load).

It uses only what the parent commit has too (fit_memory, response, exact_linear), so run against a checkout of it
(PYTHONPATH=that checkout) it prints the numbers before the passive fit.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

import numpy as np

from sim.hydro.bem import SHIPPED, Coefficients
from sim.hydro.radiation import fit_memory
from sim.scene.config import load_scene, with_overrides
from sim.system.linear import exact_linear
from sim.system.tree import build
from studies.accuracy.passivity import lowest_damping, misfits, scene_length, still_rm3


def residual_share(memory, c) -> str:
    """The largest diagonal of the residual mass dA against A_inf's, in %, and its dof (none before the passive fit)."""
    if not hasattr(memory, "residual_mass"):
        return "-"
    share = np.diag(memory.residual_mass) / np.maximum(np.diag(c.added_mass_inf), 1e-300)
    return f"{100 * share.max():.3g} % (dof {int(share.argmax())})"


def solves() -> None:
    print(
        "| solve | dofs | fit, s | states (one per entry; fewest) | misfit B, A | min eig B_fit / peak B | at omega, rad/s | dA / A_inf |"
    )
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for path in sorted(SHIPPED.glob("*.npz")):
        c = Coefficients.load(path)
        length = scene_length(c)
        started = time.perf_counter()
        memory = fit_memory(c, length=length)
        seconds = time.perf_counter() - started
        low, where = lowest_damping(memory, c.omega.max())
        fewest = len(memory.compact()[0]) if hasattr(memory, "compact") else memory.states
        misfit = ", ".join(f"{m:.4f}" for m in misfits(memory, c))
        print(
            f"| {path.stem} | {c.damping.shape[1]} | {seconds:.2f} | {memory.states}; {fewest} | {misfit} | {low / np.abs(c.damping).max():.3g} | {where:.4g} "
            f"| {residual_share(memory, c)} |"
        )


def rm3_linear() -> None:
    for stiffness in (0.0, 5e5):
        system, s = build(still_rm3("linear", stiffness))
        stepper = exact_linear(system, s)
        n = stepper.A.shape[0] - 1
        lam = np.linalg.eigvals(stepper.A[:n, :n])
        start, kick = sum(system.energies(s).values()), system.energies(s)["E_kin"]
        rise = -np.inf
        for _ in range(300):
            s = stepper.advance(s, 0.1, 100)
            e = sum(system.energies(s).values())
            rise = max(rise, e - start)
            if not np.isfinite(e):
                break
        print(
            f"rm3, linear hydro, take-off spring {stiffness:g} N/m, no damper: largest Re(eigenvalue) {lam.real.max():+.3g} 1/s; kicked "
            f"({kick:.4g} J), over {s.t:.0f} s the energy rose at most {rise:.3g} J above the start, E_rad {s.E_rad:.4g} J"
        )


def rm3_nonlinear() -> None:
    for stiffness in (0.0, 5e5):
        system, s = build(still_rm3("nonlinear", stiffness))
        start, kick = sum(system.energies(s).values()), system.energies(s)["E_kin"]
        rise, top, gap = -np.inf, -np.inf, 0.0
        for k in range(60000):
            s = system.step(s, 0.05)
            if k % 20 == 19:
                e = sum(system.energies(s).values())
                rise, gap = max(rise, e - start), max(gap, abs(e + s.absorbed.sum() + s.E_rad - start))
                top = max(top, float(system.pose(s).x[1][2]))
                if not np.isfinite(e) or top > 50:
                    break
        print(
            f"rm3, default hydro, spring {stiffness:g} N/m, no damper: over {s.t:.0f} s the energy rose at most {rise:.3g} J above the start "
            f"(kick {kick:.4g} J; E_total + E_pto + E_rad within {gap:.3g} J), the float's centre at most {top:.3g} m (starts at -0.7)"
        )


def cost() -> None:
    """Median numpy cost of the memory in one step: one body (the cube) advance + force; rm3 drift + load."""
    from sim import Simulation

    sim = Simulation(with_overrides(load_scene("rest"), fluid__radiation="bem"), backend="numpy")
    rad, R, x = sim.model.radiation, np.eye(3), np.zeros(sim.model.radiation.states)
    nu = np.full(6, 0.01)
    rad.advance(x, nu, 0.005)
    times = []
    for _ in range(7):
        t0 = time.perf_counter()
        for _ in range(2000):
            x = rad.advance(x, nu, 0.005)
            rad.force(R, x)
        times.append((time.perf_counter() - t0) / 2000)
    print(f"cube: {rad.states} memory states; advance and force {statistics.median(times) * 1e6:.2f} us a step (numpy)")
    system, s = build(with_overrides(load_scene("rm3"), waves__kind="still"))
    r = system.radiation
    after = system.step(s, 0.05)
    times, whole = [], []
    for _ in range(7):
        t0 = time.perf_counter()
        for _ in range(200):
            r.drift(system, s, after, 0.05)
        times.append((time.perf_counter() - t0) / 200)
        t0 = time.perf_counter()
        for _ in range(20):
            system.step(s, 0.05)
        whole.append((time.perf_counter() - t0) / 20)
    print(
        f"rm3: {r.states} memory states; the memory's drift {statistics.median(times) * 1e6:.1f} us a step, the whole step "
        f"{statistics.median(whole) * 1e3:.2f} ms (numpy)"
    )


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    print(f"sim from {Path(sys.modules['sim'].__file__).parent}")
    solves()
    rm3_linear()
    if "--nonlinear" in argv:
        rm3_nonlinear()
    cost()
    return 0


if __name__ == "__main__":
    sys.exit(main())

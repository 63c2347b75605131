"""The rm3 preset, a two-body point absorber, against linear theory with the same BEM coefficients (the shipped solve)."""

import dataclasses

import numpy as np
import pytest

from sim.scene.config import load_scene, with_overrides
from sim.system.frequency import response, steady_start
from sim.system.tree import build


@pytest.fixture(autouse=True)
def _shipped_only(monkeypatch, tmp_path):
    """The preset's coefficients come from the shipped file: no user cache, no solve."""
    import sim.hydro.bem as bem

    monkeypatch.setenv("FLOATSIM_BEM_CACHE", str(tmp_path))
    monkeypatch.setattr(bem, "solve_parts", lambda *a, **k: pytest.fail("the shipped rm3 coefficients were not found"))


def rm3_in(period: float, amplitude: float, joint: str = "prismatic"):
    """The rm3 preset in regular waves of this period (the solve's frequency nearest) and amplitude, its spar on a vertical
    slide (prismatic) or free to surge, heave and pitch (planar, WEC-Sim's floating constraint); (system, rest, i)."""
    base = load_scene("rm3")
    if joint == "planar":
        spar = base.bodies[0]
        spar = dataclasses.replace(spar, constraint=dataclasses.replace(spar.constraint, joint="planar", axis=(0.0, 1.0, 0.0)))
        base = dataclasses.replace(base, bodies=(spar, *base.bodies[1:]))
    system, _ = build(base)  # the coefficients come from the shipped file: no solve here
    c = system.radiation.coefficients
    i = int(np.argmin(abs(c.omega - 2 * np.pi / period)))
    scene = with_overrides(base, waves__height=2 * amplitude, waves__period=2 * np.pi / float(c.omega[i]), waves__ramp=0.0)  # (no ramp: the
    system, rest = build(scene)  # runs start on the steady state)
    return system, rest, i


def time_domain(system, start, omega: float, periods: int, per_period: int = 160):
    """(first harmonic of each joint coordinate (complex, e^(-i omega t)), mean take-off power) over `periods` periods."""
    T = 2 * np.pi / omega
    dt = T / per_period
    s = start
    times, coords = [], []
    for _ in range(periods * per_period):
        s = system.step(s, dt)
        times.append(s.t)
        coords.append(s.theta.copy())
    t, q = np.array(times), np.array(coords)
    basis = np.column_stack([np.ones_like(t), np.cos(omega * t), np.sin(omega * t)])
    coef, *_ = np.linalg.lstsq(basis, q, rcond=None)
    return coef[1] + 1j * coef[2], (s.absorbed - start.absorbed) / (s.t - start.t)


@pytest.mark.parametrize("joint", ["prismatic", pytest.param("planar", marks=pytest.mark.slow)])  # planar: over 4 s
@pytest.mark.parametrize("period", [8.0, pytest.param(6.0, marks=pytest.mark.slow)])
def test_rm3_take_off_power_and_relative_heave_match_the_frequency_domain(period, joint):
    """Started on the linear steady state, six wave periods of the two-body system (radiation memory coupling
    both bodies, diffraction, the exact clipped hydrostatics): the float's heave against the spar and the mean
    power its take-off absorbs match the 2-dof frequency-domain solution of the 12x12 impedance within 2 %."""
    a = 0.05
    system, rest, i = rm3_in(period, a, joint)
    c = system.radiation.coefficients
    w = float(c.omega[i])
    xi = response(system, rest, i)
    relative, power = time_domain(system, steady_start(system, rest, xi, w, a), w, periods=6)
    slide = next(g for g in system.joints if g.name == "float")
    k, d = slide.coordinate, slide.dofs.start  # its place among the coordinates and among the velocities
    expected_power = 0.5 * slide.damping * w * w * abs(a * xi[d]) ** 2
    errors = (abs(relative[k]) / abs(a * xi[d]) - 1, power[k] / expected_power - 1, np.angle(relative[k] / xi[d]))
    print(f"T = {2 * np.pi / w:.3f} s: relative heave {abs(a * xi[d]):.4g} m, power {expected_power:.4g} W; errors {errors}")
    assert abs(errors[0]) < 0.02 and abs(errors[1]) < 0.02 and abs(errors[2]) < 0.02
    assert expected_power > 100.0  # hundreds of watts from 10 cm waves: a real check, not of a body at rest


def kicked_float(**changes):
    """rm3 in still water with the float kicked upwards at 0.5 m/s from its rest."""
    scene = with_overrides(load_scene("rm3"), waves__kind="still", **changes)
    float_at = dataclasses.replace(scene.bodies[1], initial=dataclasses.replace(scene.bodies[1].initial, velocity=(0.0, 0.0, 0.5)))
    return dataclasses.replace(scene, bodies=(scene.bodies[0], float_at))


@pytest.mark.parametrize("hydro", ["nonlinear", "linear"])
def test_rm3_energy_closes_with_the_radiated_waves(hydro):
    """In still water, the float kicked upwards at 0.5 m/s from its rest: kinetic (with the added mass at infinite frequency),
    gravity, hydrostatic energy (the exact clipped one, or the linear model's potential about rest), what the take-off
    absorbed and what the radiated waves carried away add up to the start's, to second order in dt."""
    scene = kicked_float(fluid__hydro=hydro)
    errors = []
    for dt in (0.2, 0.1):
        system, s = build(scene)
        start, kinetic = sum(system.energies(s).values()), system.energies(s)["E_kin"]
        for _ in range(round(30.0 / dt)):
            s = system.step(s, dt)
        errors.append(abs(sum(system.energies(s).values()) + s.absorbed.sum() + s.E_rad - start))
        assert s.E_rad > 0.05 * s.absorbed.sum() > 0  # both took their share
    assert 3.0 < errors[0] / errors[1] < 5.5 and errors[1] < 0.005 * kinetic  # (252 J of the kick's 1.9e5 J at dt = 0.1 s)


def test_the_moored_rm3_starts_at_rest_on_its_lines():
    """rm3-moored in still water: the chains' hanging weight is what the spar's mass was reduced by, so the system
    starts in equilibrium: over 20 s nothing moves by more than 1 cm, the lines' pull staying within 1 % of its start."""
    pytest.importorskip("moordyn")
    from sim.simulation import Simulation

    run = Simulation(with_overrides(load_scene("rm3-moored"), waves__kind="still"), backend="numpy")
    try:
        start = run.frame()
        worst, pulls = 0.0, []
        for _ in range(20):
            run.step(20)
            frame = run.frame()
            worst = max(worst, *(np.abs(b.x_world - a.x_world).max() for a, b in zip(start.bodies, frame.bodies)))
            pulls.append(frame.mooring[2])
        assert worst < 0.01 and np.abs(np.array(pulls) / start.mooring[2] - 1).max() < 0.01
        assert start.mooring[2] < -2e5  # the chains do hang on it (228 kN)
    finally:
        run.close()


def test_the_moored_rm3_solve_reaches_below_its_slowest_swing():
    """rm3-moored has its own solve (shipped) whose grid starts below the surge natural frequency the chains give the
    two bodies swinging together, 2 pi / T with T = 2 pi sqrt((M + A_11(omega_n)) / k_11) (A_11 of both bodies' surge, k_11
    the chains' catenary stiffness): A_11 there is read inside the grid, not extrapolated (rm3's own grid starts at
    three times that frequency), and the fitted memory's surge added mass there meets the solve's within 1 %."""
    from sim.hydro.equilibrium import pull_stiffness

    scene = load_scene("rm3-moored")
    system, _ = build(scene)
    c, memory = system.radiation.coefficients, system.radiation.memory
    spar = scene.bodies[0]
    k = pull_stiffness(dataclasses.replace(scene, initial=spar.initial), np.asarray(spar.initial.position, float), np.eye(3))[0, 0]
    mass = sum(m.model.body.mass for m in system.members)
    surge = np.zeros(12)
    surge[[0, 6]] = 1.0  # both bodies' surge
    A11 = np.einsum("i,nij,j->n", surge, c.added_mass, surge)
    T = 2 * np.pi * np.sqrt(mass / k)
    for _ in range(30):
        T = 2 * np.pi * np.sqrt((mass + np.interp(2 * np.pi / T, c.omega, A11)) / k)
    w_n = 2 * np.pi / T
    free, _ = build(load_scene("rm3"))
    print(
        f"surge on the chains: T = {T:.1f} s, omega_n = {w_n:.4f} rad/s; grid from {c.omega[0]:.4f} (rm3's: {free.radiation.coefficients.omega[0]:.4f})"
    )
    assert c.omega[0] < w_n < c.omega[1] * 4 and free.radiation.coefficients.omega[0] > 2 * w_n
    fitted = surge @ (memory.added_mass_inf + memory.response(w_n)[0].imag / w_n) @ surge
    assert fitted == pytest.approx(np.interp(w_n, c.omega, A11), rel=0.01)

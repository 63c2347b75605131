"""Integrators: observed convergence orders, energy behaviour, torque-free invariants, free fall."""

import numpy as np
import pytest
from scenes import box_scene

from sim import INTEGRATORS, Simulation, SimulationDiverged, load_scene, with_overrides
from tests.covering import LINEAR, cases, waves


def final_state(scene, T=1.0, backend=None):
    sim = Simulation(scene, backend=backend)
    sim.step(round(T / sim.dt))
    s = sim.state
    return np.concatenate([s.x_world, s.u_world, s.L_world, s.q_world_body * np.sign(s.q_world_body[0])])


FIXED_STEP_DTS = {"euler": [0.02, 0.01, 0.005, 0.0025], "splitting": [0.04, 0.02, 0.01, 0.005],
                  "implicit": [0.04, 0.02, 0.01, 0.005], "rk4": [0.1, 0.05, 0.025, 0.0125]}  # fmt: skip


def test_every_integrator_is_tested():
    assert set(FIXED_STEP_DTS) | {n for n, c in INTEGRATORS.items() if c.adaptive} == set(INTEGRATORS)


@pytest.mark.parametrize("case", ["submerged-damped", "torque-free"])
@pytest.mark.parametrize("name", list(FIXED_STEP_DTS))
def test_observed_order_matches_declared_order(name, case):
    """Log-log slope of the error at t = 1 s against dt, on smooth nonlinear problems: an
    asymmetric box spinning fully under water with damping, and the same box in free space."""
    kw = {"damping": 50.0} if case == "submerged-damped" else {"damping": 0.0, "g": 0.0, "rho": 0.0, "z": 5.0}
    reference = final_state(box_scene("dop853", 0.05, **kw))
    dts = FIXED_STEP_DTS[name]
    errors = [np.abs(final_state(box_scene(name, dt, **kw)) - reference).max() for dt in dts]
    slope = np.polyfit(np.log(dts), np.log(errors), 1)[0]
    assert slope == pytest.approx(INTEGRATORS[name].order, abs=0.15), errors


@pytest.mark.parametrize("backend", ["numpy", *cases([("numba",)], lambda backend: waves("rk4", "points", LINEAR))])
def test_rk4_is_fourth_order_under_a_time_dependent_load(backend):
    """RK4's observed order is 4 on the submerged box in regular waves, a load depending on t (guards the stages' times)."""
    waves_4s = dict(waves__kind="regular", waves__height=1.0, waves__period=4.0)
    ends = [final_state(with_overrides(box_scene("rk4", dt), **waves_4s), backend=backend) for dt in (0.2, 0.1, 0.05, 0.025)]
    gaps = [np.abs(a - b).max() for a, b in zip(ends, ends[1:])]  # the order is log2 of their ratio (no reference needed)
    orders = np.log2(np.array(gaps[:-1]) / gaps[1:])  # k3 at t + dt instead of t + dt / 2: 0.3 and 0.9
    assert orders == pytest.approx([4.0, 4.0], abs=0.3), gaps


@pytest.mark.parametrize("name", [n for n, c in INTEGRATORS.items() if c.adaptive])
def test_adaptive_methods_meet_their_tolerance(name):
    reference = final_state(box_scene("rk4", 0.0025))  # rk4 error ~1e-11 here (see the order test)
    for tol in (1e-6, 1e-9):
        scene = box_scene(name, 0.1)
        scene = with_overrides(scene, step__rtol=tol, step__atol=tol)
        assert np.abs(final_state(scene) - reference).max() < 100 * tol


def energies(sim, steps, every=1):
    out = [sim.frame().E_total]
    for _ in range(steps // every):
        sim.step(every)
        out.append(sim.frame().E_total)
    return np.array(out)


def test_splitting_energy_error_is_bounded_and_second_order():
    """d = 0, the asymmetric box tumbling deep under water with gravity on (water as dense as the box,
    so it neither rises nor sinks out of the water in 200 s; its sampled forces are exactly
    conservative there): the splitting's energy error does not grow and falls ~4x when dt halves."""
    worst = []
    for dt in (0.02, 0.01):
        sim = Simulation(box_scene("splitting", dt, damping=0.0, g=9.81, rho=700.0, z=-50.0, omega=(0.3, 2.0, 0.1)))
        assert sim.frame().submerged_area > 0 and abs(sim.frame().force_world).max() < 1e-9 * sim.body.mass * 9.81  # wet, balanced
        e = energies(sim, round(200 / dt), every=round(0.5 / dt))
        err = np.abs(e - e[0])
        assert err[len(err) // 2 :].max() < 1.5 * err[: len(err) // 2].max()  # bounded: no secular drift
        worst.append(err.max() / abs(e[0]))
        assert sim.state.x_world[2] < -20.0  # still under water at the end
    assert worst[0] / worst[1] == pytest.approx(4.0, rel=0.15)
    assert worst[1] < 1e-4


@pytest.mark.parametrize("name", ["splitting", "implicit", "rk4"])
def test_damped_energy_never_rises(name):
    """d > 0 through the water line (the damped scene): total energy only falls, step after step."""
    sim = Simulation(with_overrides(load_scene("damped"), step__integrator=name))
    e = energies(sim, 2000)
    assert np.diff(e).max() < 1e-9 * e[0]
    assert e[-1] < 0.5 * e[0]


def test_torque_free_motion_keeps_L_and_cube_energy_exactly():
    """Out of the water with gravity off: |L| to round-off for the exact-rotation schemes, and the
    isotropic cube's kinetic energy exactly (its rotation is one exact exponential per step)."""
    for name in ("euler", "splitting", "implicit"):
        scene = with_overrides(load_scene("spin"), initial__position=(0.0, 0.0, 10.0), step__integrator=name, step__dt=0.05)
        scene = with_overrides(scene, fluid__g=0.0, initial__omega=(-3.0, 7.0, 2.0))
        sim = Simulation(scene)
        L0, E0 = np.linalg.norm(sim.state.L_world), sim.frame().E_kin
        sim.step(2000)
        assert np.linalg.norm(sim.state.L_world) == pytest.approx(L0, rel=1e-14)
        assert sim.frame().E_kin == pytest.approx(E0, rel=1e-12)
        assert np.linalg.norm(sim.state.q_world_body) == pytest.approx(1.0, abs=1e-14)


def test_torque_free_asymmetric_box_keeps_body_frame_L_norm():
    sim = Simulation(box_scene("splitting", 0.01, damping=0.0, g=0.0, rho=0.0, z=5.0, omega=(0.1, 5.0, 0.2)))
    L0 = np.linalg.norm(sim.state.L_world)
    for _ in range(20):
        sim.step(50)
        L_body = sim.state.R_world_body.T @ sim.state.L_world
        assert np.linalg.norm(L_body) == pytest.approx(L0, rel=1e-13)


@pytest.mark.parametrize("name", ["splitting", "implicit", "rk4"])
def test_free_fall_above_water_follows_the_parabola(name):
    scene = with_overrides(
        load_scene("drop"), initial__position=(0.0, 0.0, 200.0), initial__velocity=(1.0, -2.0, 3.0), step__integrator=name, step__dt=0.01
    )
    sim = Simulation(scene)
    sim.step(300)
    t = sim.state.t
    np.testing.assert_allclose(sim.state.x_world, [t, -2 * t, 200 + 3 * t - 0.5 * 9.81 * t * t], rtol=1e-12)
    np.testing.assert_allclose(sim.state.u_world, [1.0, -2.0, 3.0 - 9.81 * t], rtol=1e-12)


def test_euler_free_fall_error_is_first_order_and_exactly_as_predicted():
    """The report's scheme (drift, then kick) lags the parabola by g t dt / 2 exactly."""
    for dt in (0.01, 0.005):
        scene = with_overrides(load_scene("drop"), initial__position=(0.0, 0.0, 200.0), step__integrator="euler", step__dt=dt)
        sim = Simulation(scene)
        sim.step(round(3.0 / dt))
        exact = 200 - 0.5 * 9.81 * 9.0
        assert sim.state.x_world[2] - exact == pytest.approx(0.5 * 9.81 * 3.0 * dt, rel=1e-9)


@pytest.mark.parametrize("d", [1e4, 1e5, 1e7])
def test_implicit_damping_is_stable_for_any_coefficient(d):
    """Stiff damping at dt = 0.01 s: the implicit scheme stops a spin and does not move from rest."""
    scene = with_overrides(load_scene("spin"), fluid__damping=d, step__integrator="implicit", step__dt=0.01)
    sim = Simulation(scene)
    w0 = np.linalg.norm(sim.frame().omega_world)
    sim.step(200)
    frame = sim.frame()
    assert np.linalg.norm(frame.omega_world) < 1e-3 * w0
    assert abs(frame.x_world[2] + 0.4) < 0.01
    assert np.isfinite(frame.E_total)


def test_explicit_scheme_past_its_limit_stops_with_a_clear_message():
    scene = with_overrides(load_scene("damped"), fluid__damping=1e6, step__integrator="rk4", step__dt=0.01)
    sim = Simulation(scene)
    with pytest.raises(SimulationDiverged, match=r"diverged at t = .* too large for this damping .* --integrator implicit"):
        sim.step(1000)
    assert sim.state.is_finite()  # left at the last good step

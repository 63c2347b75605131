"""Stiff and extreme cases: enormous damping, very light and very heavy bodies, fast spin, big steps,
bodies at the water line or far above it. Each either stays stable and right, or stops clearly."""

import numpy as np
import pytest
from scenes import box_scene

from sim import Simulation, SimulationDiverged, load_scene, with_overrides


def trajectory(sim, steps, every=1):
    frames = []
    for _ in range(steps // every):
        sim.step(every)
        frames.append(sim.frame())
    return frames


@pytest.mark.parametrize("forces", ["points", "panels"])
@pytest.mark.parametrize("d", [1e4, 1e5, 1e6, 1e7])
def test_overdamped_cube_creeps_monotonically_to_its_rest_depth(d, forces):
    """Released with its centre on the water line under huge damping (implicit, dt = 0.01 s): it
    sinks without ever overshooting z = -0.4, and the energy only falls."""
    scene = with_overrides(load_scene("drop"), fluid__damping=d, fluid__forces=forces, step__integrator="implicit", step__dt=0.01)
    sim = Simulation(scene)
    frames = trajectory(sim, 300)
    z = np.array([f.x_world[2] for f in frames])
    energy = np.array([f.E_total for f in frames])
    assert np.all(np.diff(z) <= 1e-12)  # monotone descent
    assert z.min() >= -0.4 - 1e-9  # no overshoot
    assert np.diff(energy).max() <= 1e-9 * abs(energy[0])
    # the creep is slow when d is large: the heave time constant is d A / (rho g s^2), A ~ 1 + 4 draft
    assert z[-1] < -1e-4


@pytest.mark.parametrize("d", [1e4, 1e7])
def test_overdamped_cube_stays_exactly_at_rest_depth(d):
    sim = Simulation(with_overrides(load_scene("rest"), fluid__damping=d, step__integrator="implicit", step__dt=0.01))
    sim.step(500)
    assert abs(sim.state.x_world[2] + 0.4) < 1e-9
    assert np.linalg.norm(sim.state.u_world) < 1e-9


def test_very_light_body_jumps_out_of_the_water_and_falls_back():
    """Density 1 kg/m^3 released 1 m under water: buoyancy 1000x its weight throws it clear of the
    surface; with damping it then settles floating at a 1 mm draft."""
    scene = with_overrides(load_scene("drop"), body__density=1.0, fluid__damping=50.0, initial__position=(0.0, 0.0, -1.0),
                           step__integrator="implicit", step__dt=0.002)  # fmt: skip
    sim = Simulation(scene)
    frames = trajectory(sim, 20000, every=50)
    z = np.array([f.x_world[2] for f in frames])
    assert z.max() > 0.5 + 0.1  # the whole cube left the water
    airborne = np.flatnonzero(z > 0.5)
    assert airborne.size and z[airborne[-1] + 1 :].min() < 0.5  # and came back down
    assert z[-1] == pytest.approx(0.5 - 0.001, abs=2e-4)


def test_very_heavy_body_sinks_at_its_terminal_speed():
    """Density 10 000 kg/m^3, fully submerged: v_t = (M - rho V) g / (d A), A = 6 s^2."""
    d = 1000.0
    scene = with_overrides(load_scene("drop"), body__density=10_000.0, fluid__damping=d, initial__position=(0.0, 0.0, -1.0), step__dt=0.01)
    sim = Simulation(scene)
    sim.step(4000)  # 40 s = 24 time constants M / (d A): the transient is below e^-24
    v_terminal = (10_000.0 - 1000.0) * 9.81 / (d * 6.0)
    # the implicit scheme solves the velocity's relaxation exactly: only the e^-24 transient is left
    assert sim.state.u_world[2] == pytest.approx(-v_terminal, rel=1e-9)
    np.testing.assert_allclose(sim.state.u_world[:2], 0.0, atol=1e-9)


@pytest.mark.parametrize("d", [1e5, 1e6])
def test_overdamped_creep_has_the_physical_speed(d):
    """Released on the water line under stiff damping, the cube creeps down as slowly as the damping
    dictates: the implicit scheme at dt = 0.01 s follows a tight Radau reference (no fast creep from
    splitting the kick from the damping)."""
    base = with_overrides(load_scene("drop"), fluid__damping=d, step__dt=0.01)
    reference = Simulation(with_overrides(base, step__integrator="radau", step__rtol=1e-9, step__atol=1e-12))
    implicit = Simulation(base)
    for _ in range(10):
        reference.step(20)
        implicit.step(20)
        sunk = abs(reference.state.x_world[2])
        assert implicit.state.x_world[2] == pytest.approx(reference.state.x_world[2], rel=0.01, abs=1e-9)
    assert sunk > 1e-4  # it did creep


def test_fast_spin_of_an_elongated_box_keeps_its_invariants():
    """100 rad/s about the long (stable, least-inertia) axis with a wobble, in free space."""
    scene = box_scene("splitting", 0.0005, damping=0.0, g=0.0, rho=0.0, z=5.0, omega=(100.0, 2.0, 1.0))
    scene = with_overrides(scene, body__extents=(2.0, 0.5, 0.25))
    sim = Simulation(scene)
    L0, E0 = np.linalg.norm(sim.state.L_world), sim.frame().E_kin
    for _ in range(20):
        sim.step(100)
        assert np.linalg.norm(sim.state.R_world_body.T @ sim.state.L_world) == pytest.approx(L0, rel=1e-12)
        assert sim.frame().E_kin == pytest.approx(E0, rel=1e-4)


@pytest.mark.parametrize("forces", ["points", "panels"])
def test_big_time_step_stays_stable_with_the_implicit_scheme(forces):
    scene = with_overrides(load_scene("damped"), fluid__forces=forces, step__dt=0.1)
    sim = Simulation(scene)
    sim.step(600)  # 60 s
    assert sim.state.x_world[2] == pytest.approx(-0.4, abs=5e-3)
    assert np.linalg.norm(sim.frame().omega_world) < 1e-2


@pytest.mark.parametrize("forces", ["points", "panels"])
def test_body_resting_on_the_water_line_with_nothing_wet(forces):
    """Bottom face exactly at z = 0: nothing is wet (h = 0), so it falls in and bobs, no 0/0."""
    sim = Simulation(with_overrides(load_scene("drop"), fluid__forces=forces, initial__position=(0.0, 0.0, 0.5)))
    frame = sim.frame()
    assert frame.submerged_volume == 0.0
    assert frame.force_world[2] == pytest.approx(-sim.body.mass * 9.81)
    sim.step(400)
    assert sim.frame().submerged_volume > 0.5


def test_body_far_above_the_water_falls_freely():
    sim = Simulation(with_overrides(load_scene("drop"), initial__position=(0.0, 0.0, 1e6)))
    assert sim.model.wetted(sim.state.x_world, sim.state.R_world_body).weight.size == 0
    sim.step(100)
    t = sim.state.t
    assert sim.state.x_world[2] == pytest.approx(1e6 - 0.5 * 9.81 * t * t, rel=1e-15)


@pytest.mark.parametrize("name", ["euler", "splitting", "rk4"])
def test_explicit_schemes_past_their_limit_stop_clearly(name):
    scene = with_overrides(load_scene("damped"), fluid__damping=1e5, step__integrator=name, step__dt=0.01)
    sim = Simulation(scene)
    with pytest.raises(SimulationDiverged, match=r"diverged at t = [0-9.]+ s: .*too large for this damping"):
        for _ in range(100):
            sim.step(10)
    assert sim.state.is_finite() and sim.frame().E_total < 1e6


@pytest.mark.parametrize("forces", ["points", "panels"])
@pytest.mark.parametrize("d, dt", [(1e5, 0.0005), (1e7, 0.0005), (1e5, 0.01), (1e7, 0.01)])
def test_implicit_is_stable_for_light_spinning_tilted_bodies_at_any_damping(d, dt, forces):
    """Stable for any damping, also where rotation and damping couple hardest: a light cube (1 and 100
    kg/m^3) tilted and spinning at 50 rad/s, half in the water. The energy only falls and the spin dies."""
    from sim.bodies.rotation import rotation_quat

    for density in (1.0, 100.0):
        scene = with_overrides(load_scene("rest"), body__density=density, fluid__damping=d, fluid__forces=forces, step__dt=dt,
                               step__integrator="implicit", initial__position=(0.0, 0.0, 0.5 - density / 1000.0),
                               initial__orientation=tuple(rotation_quat(np.array([0.4, 0.3, 0.0]))), initial__omega=(50.0, -25.0, 50.0))  # fmt: skip
        sim = Simulation(scene)
        e0, w0 = sim.frame().E_total, np.linalg.norm(sim.frame().omega_world)
        sim.step(round(0.5 / dt))
        frame = sim.frame()
        assert sim.state.is_finite() and frame.E_total < e0
        assert np.linalg.norm(frame.omega_world) < 0.5 * w0


def test_an_adaptive_method_past_its_work_budget_stops_naming_a_better_one():
    """rk45 on a stiff setting takes ever smaller steps: past its evaluation cap (or the viewer's time
    budget) one step stops with SimulationDiverged, keeping the last good state, instead of hanging."""
    scene = with_overrides(load_scene("damped"), body__density=1.0, fluid__damping=1e7, step__integrator="rk45", step__dt=0.01)
    sim = Simulation(scene)
    sim.integrator.max_evaluations = 2000
    start = sim.state
    with pytest.raises(SimulationDiverged, match="more than 2,001 force evaluations .* use --integrator implicit, or radau"):
        sim.step(5)
    assert sim.state.t <= start.t + 5 * sim.dt and sim.state.is_finite()


def test_a_cube_riding_a_steep_twenty_metre_sea_is_not_stopped_as_a_blow_up():
    """The damped cube in regular waves 20 m high and 12 s long (steepness 0.089, inside the breaking limit): it rides
    them to the end, crest to trough, its energy against still water rising and falling by hundreds of kJ as the sea
    lifts and drops it (the guard counts what the sea can give: sim.simulation.sea_reach). Before, it stopped at
    30 s as 'the energy blew up'. A real blow-up still stops (test_explicit_schemes_past_their_limit_stop_clearly)."""
    sim = Simulation(with_overrides(load_scene("damped"), waves__kind="regular", waves__height=20.0, waves__period=12.0))
    z = [sim.frame().x_world[2]]
    for _ in range(120):
        sim.step(200)  # 120 s
        z.append(sim.frame().x_world[2])
    assert sim.state.t == pytest.approx(120.0)
    assert max(z) > 8.0 and min(z) < -8.0  # it follows the 10 m amplitude up and down

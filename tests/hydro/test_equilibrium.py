"""Hydrostatics: the report's resting cube, Archimedes, heave frequency, floating while spinning."""

import math

import numpy as np
import pytest

from sim import Simulation, load_scene, with_overrides
from sim.bodies.rotation import rotation_quat


def test_rest_scene_stays_put_without_any_initial_velocity():
    sim = Simulation(load_scene("rest"))
    assert not sim.state.u_world.any() and not sim.state.L_world.any()  # no artificial spin
    weight = sim.body.mass * 9.81
    for _ in range(100):  # 10 s in 0.1 s chunks
        sim.step(20)
        frame = sim.frame()
        assert abs(frame.x_world[2] + 0.4) < 1e-9
        assert np.linalg.norm(frame.force_world) < 1e-10 * weight
        assert np.linalg.norm(frame.torque_world) < 1e-10 * weight
    assert sim.state.t == pytest.approx(10.0)
    np.testing.assert_allclose(sim.state.x_world[:2], 0.0, atol=1e-12)
    np.testing.assert_allclose(np.abs(sim.state.q_world_body), [1, 0, 0, 0], atol=1e-12)


@pytest.mark.parametrize("draft", [0.05, 0.3, 0.9, 0.999])
def test_upright_cube_feels_archimedes_force_exactly(draft):
    sim = Simulation(with_overrides(load_scene("rest"), initial__position=(0.0, 0.0, 0.5 - draft)))
    frame = sim.frame()
    buoyancy = frame.force_world[2] + sim.body.mass * 9.81
    assert buoyancy == pytest.approx(1000 * 9.81 * draft, rel=1e-12)
    assert frame.submerged_volume == pytest.approx(draft, rel=1e-12)


def submerged_area_of_polygon(points: np.ndarray) -> float:
    """Area of a convex polygon (rows (y, z)) below z = 0: clip against the half-plane, then shoelace."""
    clipped = []
    for a, b in zip(points, np.roll(points, -1, axis=0)):
        if a[1] < 0:
            clipped.append(a)
        if (a[1] < 0) != (b[1] < 0):
            clipped.append(a + (b - a) * a[1] / (a[1] - b[1]))
    y, z = np.array(clipped).T
    return 0.5 * abs(y @ np.roll(z, -1) - z @ np.roll(y, -1))


def test_tilted_cube_buoyancy_converges_to_archimedes():
    """Tilted 30 degrees about x, the water line cuts faces obliquely: the sampled force tends to
    rho g V_sub (exact: the clipped square cross-section times the unit length) as N grows, and its
    line of action tends to the centre of buoyancy's."""
    angle, zc = np.radians(30), -0.1
    corners = np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]])
    c, s = np.cos(angle), np.sin(angle)
    world = corners @ np.array([[c, s], [-s, c]]) + [0.0, zc]
    exact = 1000 * 9.81 * submerged_area_of_polygon(world)
    errors = []
    for n in (4, 8, 16, 32, 64):
        scene = with_overrides(
            load_scene("rest"),
            body__points_per_edge=n,
            initial__position=(0.0, 0.0, zc),
            initial__orientation=tuple(rotation_quat(angle * np.array([1.0, 0.0, 0.0]))),
        )
        sim = Simulation(scene)
        frame = sim.frame()
        errors.append(abs(frame.force_world[2] + sim.body.mass * 9.81 - exact) / exact)
        assert abs(frame.force_world[0]) < 1e-9 * exact  # no sideways push from hydrostatics
    assert errors[-1] < 2e-4
    assert all(e2 < e1 for e1, e2 in zip(errors, errors[1:]))
    assert np.polyfit(np.log([4, 8, 16, 32, 64]), np.log(errors), 1)[0] < -1.0  # at least first order


def test_small_heave_oscillation_has_the_analytic_frequency():
    """omega = sqrt(rho g s^2 / M) for a face-up cube (no added mass in the model)."""
    sim = Simulation(with_overrides(load_scene("rest"), initial__position=(0.0, 0.0, -0.39), step__dt=0.002))
    t, z = [], []
    for _ in range(5000):
        sim.step()
        t.append(sim.state.t)
        z.append(sim.state.x_world[2] + 0.4)
    t, z = np.array(t), np.array(z)
    up = np.flatnonzero((z[:-1] < 0) & (z[1:] >= 0))
    crossings = t[up] - z[up] * (t[up + 1] - t[up]) / (z[up + 1] - z[up])
    omega = 2 * math.pi / np.diff(crossings).mean()
    assert len(crossings) >= 4
    assert omega == pytest.approx(math.sqrt(1000 * 9.81 * 1.0 / 900), rel=1e-4)
    assert np.abs(z).max() == pytest.approx(0.01, rel=1e-3)  # amplitude kept: no numerical damping


def test_spinning_cube_keeps_floating_at_its_depth():
    """The report's figures 4-5: spin (-1, 1, 0) rad/s at z = -0.4; the cube rolls but floats:
    its centre stays near the equilibrium depth, energy and |L| stay bounded (d = 0)."""
    sim = Simulation(with_overrides(load_scene("spin"), step__t_end=20.0))
    e0 = sim.frame().E_total
    L0 = np.linalg.norm(sim.state.L_world)
    z, energy = [], []
    for _ in range(200):
        sim.step(20)
        frame = sim.frame()
        z.append(frame.x_world[2])
        energy.append(frame.E_total)
    z = np.array(z)
    assert abs(z.mean() + 0.4) < 0.02
    assert np.abs(z + 0.4).max() < 0.1
    assert np.abs(np.array(energy) - e0).max() < 0.01 * e0
    assert np.linalg.norm(sim.state.L_world) < 3 * L0

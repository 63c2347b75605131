"""Quadratic drag: closed forms (terminal speed, the 2 cos^3 law, a spinning cube's torque), it never
does work on the body, every integrator reaches its fixed point, and it is a scene key, a flag and a control."""

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from sim import Simulation, load_scene, with_overrides
from sim.commands import main
from sim.hydro.forces import drag
from sim.scene.config import FluidConfig
from tests.covering import cases, still

RHO, G = 1000.0, 9.81
FIXED = ("euler", "splitting", "implicit", "rk4")


def submerged(forces="points", n=10, q=(1.0, 0.0, 0.0, 0.0), cd=1.0, density=2000.0, **step):
    """A 1 m cube deep under water (z = -5 m), at rest, with drag and nothing else but buoyancy and gravity."""
    return with_overrides(load_scene("rest"), fluid__forces=forces, fluid__drag_coefficient=cd, body__points_per_edge=n, body__density=density,
                          initial__position=(0.0, 0.0, -5.0), initial__orientation=q, **step)  # fmt: skip


def drag_load(sim: Simulation, twist) -> np.ndarray:
    """(force, torque) of the drag term alone at the simulation's pose and the given twist."""
    wet = sim.model.wetted(sim.state.x_world, sim.state.R_world_body)
    load = drag(sim.body, sim.model.water, sim.params, wet, np.asarray(twist, float), 0.0)
    return np.concatenate([load.force, load.torque])


@pytest.mark.parametrize(
    "integrator, forces",
    [
        *cases([(i, f) for f in ("points", "panels") for i in FIXED], still),
        *(pytest.param("rk45", f, marks=pytest.mark.slow) for f in ("points", "panels")),
    ],
)  # rk45: 6-9 s
def test_heavy_cube_sinks_at_the_terminal_speed(forces, integrator):
    """Face down, fully submerged: (1/2) rho C_d s^2 v^2 = (M - rho V) g, so v = sqrt(2 (M - rho V) g / (rho C_d s^2)).
    euler, rk4 and the implicit scheme (drag linearised about the current speed) keep it as their exact
    fixed point; the splitting's fixed point is off by O(dt^2) (drag and kick alternate), so it runs at a smaller dt."""
    cd, density = 1.2, 2000.0
    dt = 0.002 if integrator == "splitting" else 0.01
    sim = Simulation(submerged(forces, cd=cd, density=density, step__integrator=integrator, step__dt=dt))
    sim.step(round(12 / dt))
    v_exact = math.sqrt(2 * (density - RHO) * 1.0 * G / (RHO * cd * 1.0))
    assert sim.state.x_world[2] < -20.0  # it did fall, and stays far under the surface
    assert -sim.state.u_world[2] == pytest.approx(v_exact, rel=1e-6)
    np.testing.assert_allclose(sim.state.u_world[:2], 0.0, atol=1e-9)


def test_splitting_terminal_speed_error_is_second_order():
    errors = []
    for dt in (0.02, 0.01):
        sim = Simulation(submerged(cd=1.2, step__integrator="splitting", step__dt=dt))
        sim.step(round(12 / dt))
        errors.append(abs(-sim.state.u_world[2] - math.sqrt(2 * 1000.0 * G / (RHO * 1.2))))
    assert errors[0] / errors[1] == pytest.approx(4.0, rel=0.05)


@pytest.mark.parametrize("forces", ["points", "panels"])
def test_edge_on_drag_is_2_cos3_45_of_face_on(forces):
    v = 1.7
    face = Simulation(submerged(forces))
    edge = Simulation(submerged(forces, q=tuple(Rotation.from_euler("z", 45, degrees=True).as_quat(scalar_first=True))))
    f_face = drag_load(face, [v, 0, 0, 0, 0, 0])
    f_edge = drag_load(edge, [v, 0, 0, 0, 0, 0])
    np.testing.assert_allclose(f_face[:3], [-0.5 * RHO * 1.0 * 1.0 * v * v, 0, 0], rtol=1e-12, atol=1e-9)
    assert f_edge[0] / f_face[0] == pytest.approx(2 * math.cos(math.radians(45)) ** 3, rel=1e-12)
    np.testing.assert_allclose(f_edge[1:], 0.0, atol=1e-9)  # the two faces' sideways pushes cancel, and no torque


def test_spinning_cube_torque_is_exact_on_panels_and_converges_on_points():
    """Spinning about z at omega: half of each side face moves into the water with v.n = omega |y|, so
    T_z = -4 * (1/2) rho C_d omega^2 s * integral_0^{s/2} y^3 dy = -rho C_d omega^2 s^5 / 32.
    The panels clip each face at v.n = 0 and integrate the cubic exactly; the samples converge as N^-2."""
    w = 2.0
    exact = -RHO * 1.0 * w * w / 32
    panel = drag_load(Simulation(submerged("panels")), [0, 0, 0, 0, 0, w])
    assert panel[5] == pytest.approx(exact, rel=1e-12)
    np.testing.assert_allclose(np.r_[panel[:5]], 0.0, atol=1e-9)
    errors = [abs(drag_load(Simulation(submerged("points", n=n)), [0, 0, 0, 0, 0, w])[5] - exact) for n in (4, 8, 16, 32)]
    slopes = np.diff(np.log(errors)) / np.log(2)
    assert np.all(slopes < -1.9) and errors[-1] < 3e-3 * abs(exact)


@pytest.mark.parametrize("forces", ["points", "panels"])
def test_drag_never_does_positive_work(forces):
    """Power F.u + T.omega = -(1/2) rho C_d integral of (v.n)^3 over the advancing surface <= 0, at any pose and twist."""
    rng = np.random.default_rng(3)
    for q, z in zip(Rotation.random(8, random_state=5).as_quat(scalar_first=True), np.linspace(-0.6, 0.6, 8)):
        sim = Simulation(with_overrides(submerged(forces, n=6, q=tuple(q)), initial__position=(0.0, 0.0, z)))
        for _ in range(5):
            twist = rng.normal(size=6)
            load = drag_load(sim, twist)
            assert load @ twist <= 1e-12 * np.abs(load).max()
            assert load @ twist < 0 or np.abs(load).max() == 0


@pytest.mark.parametrize(
    "integrator, forces", cases([(i, f) for f in ("points", "panels") for i in ("splitting", "implicit", "rk4")], still)
)
def test_energy_never_rises_with_drag(forces, integrator):
    """The damped scene (through the water line, spinning) with drag added: energy only falls, step after step."""
    sim = Simulation(with_overrides(load_scene("damped"), fluid__drag_coefficient=1.0, fluid__forces=forces, step__integrator=integrator))
    e = [sim.frame().E_total]
    for _ in range(1000):
        sim.step(2)
        e.append(sim.frame().E_total)
    assert np.diff(e).max() < 1e-9 * e[0]
    assert e[-1] < 0.5 * e[0]


def test_implicit_drag_is_stable_far_past_the_explicit_limit():
    """A light cube with huge drag: explicit schemes blow up at this dt, the linearised implicit one
    relaxes monotonically to the terminal speed (here the body rises: buoyancy beats its weight)."""
    scene = with_overrides(submerged(cd=100.0, density=10.0, step__dt=0.5), initial__position=(0.0, 0.0, -100.0))
    sim = Simulation(with_overrides(scene, step__integrator="implicit"))
    speeds = []
    for _ in range(100):
        sim.step(1)
        speeds.append(sim.state.u_world[2])
    v_exact = math.sqrt(2 * (RHO - 10.0) * G / (RHO * 100.0))
    assert speeds[-1] == pytest.approx(v_exact, rel=1e-6)
    assert np.all(np.diff(speeds) >= -1e-15)  # no overshoot


def test_drag_is_a_scene_key_a_flag_and_only_in_scenes_that_use_it(tmp_path, capsys):
    assert FluidConfig().drag_coefficient == 0.0
    assert "drag" not in Simulation(load_scene("damped")).model.term_names  # left out when C_d = 0
    assert "drag" in Simulation(with_overrides(load_scene("damped"), fluid__drag_coefficient=0.5)).model.term_names
    scene = tmp_path / "s.toml"
    scene.write_text("[fluid]\ndrag_coefficient = 0.8\n[step]\nt_end = 0.1\n")
    assert main(["run", "--scene", str(scene)]) == 0
    assert "drag(drag_coefficient = 0.8)" in capsys.readouterr().out
    assert main(["run", "--scene", "drop", "--t-end", "0.1", "--drag-coefficient", "2.5"]) == 0
    assert "drag(drag_coefficient = 2.5)" in capsys.readouterr().out
    assert main(["run", "--drag-coefficient", "-1"]) == 2
    assert capsys.readouterr().err.strip() == "python -m sim: error: drag_coefficient must be >= 0, got -1.0"

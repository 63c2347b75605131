"""A body alone is a system of one (system/single.py): its system's kinematics and energies are the body's, and its step on
the system's state gives the one-body run's states bit for bit."""

import dataclasses

import numpy as np
import pytest

from sim.scene.config import load_scene, with_overrides
from sim.simulation import Simulation
from sim.system.frame import body_frames
from sim.system.single import Motion, from_system, to_system


def system_run(scene, backend: str):
    """A run, its body as a system of one, and the system's state at its start."""
    sim = Simulation(scene, backend=backend)
    return sim, sim.system, sim.state


def vectors(s) -> np.ndarray:
    return np.concatenate([s.x_free.ravel(), s.q_free.ravel(), s.theta, s.v, s.absorbed, s.memory, [s.t, s.E_rad]])


CASES = [
    ("drop", {}, "numpy"),
    ("drop", {"step__integrator": "rk4"}, "numpy"),
    ("waves", {}, "numba"),
    ("point-absorber", {}, "numpy"),
    ("moored-buoy", {}, "numba"),
]


@pytest.mark.parametrize("name,changes,backend", CASES, ids=[f"{c[0]}-{c[2]}{'-rk4' if c[1] else ''}" for c in CASES])
def test_a_system_of_one_steps_as_the_body_does(name, changes, backend):
    """The one-body run, and its step (Single.advance) driven through the system of one's state from another run of the
    same scene (its own lines and controller), the state made and read back between calls: the same states bit for bit,
    over calls of several steps."""
    scene = with_overrides(load_scene(name), **changes)
    reference = Simulation(scene, backend=backend)
    sim, system, s = system_run(scene, backend)
    sim.single.compiled = sim.compiled
    law = None if sim.controller is None else sim._next_law
    for n in (1, 7, 12):
        reference.step(n)
        s = to_system(system, sim.joint, sim.single.advance(from_system(system, sim.joint, s), n, sim.dt, law, sim.moorings))
        assert np.array_equal(vectors(s), vectors(reference.state))
    reference.close()
    sim.close()


@pytest.mark.parametrize("name", ["spin", "point-absorber"])
def test_the_systems_state_and_the_bodys_are_one_motion(name):
    """to_system then from_system gives the body's state back: exactly where the system's state keeps it, to round-off from
    the coordinates and velocities alone (a state made by hand, a reset's)."""
    sim, system, _ = system_run(load_scene(name), "numpy")
    sim.step(25)
    m = Motion(sim.body_state, sim.joint_theta, sim.pto_energy)
    s = to_system(system, sim.joint, m)
    assert from_system(system, sim.joint, s).state is m.state  # its body's own state, carried
    made = dataclasses.replace(s)  # a state made from another keeps no body of its own: its coordinates give it
    with pytest.raises(AttributeError):
        made.x_world
    back = from_system(system, sim.joint, made)
    assert back.state.t == m.state.t and back.theta == m.theta and back.absorbed == m.absorbed
    for a, b in zip(back.state.as_vector(), m.state.as_vector()):
        assert a == pytest.approx(b, rel=1e-12, abs=1e-12)


@pytest.mark.parametrize("name", ["spin", "waves", "point-absorber"])
def test_a_system_of_one_sees_the_body_where_it_is(name):
    """Its kinematics give the body's pose and twist, and its energies the run's: kinetic, gravity and the exact
    hydrostatic energy of the mesh clipped at the surface."""
    sim, system, _ = system_run(with_overrides(load_scene(name), fluid__radiation="none"), "numpy")
    sim.step(30)
    s, frame = sim.state, sim.frame()
    (b,) = body_frames(system, s)
    q = b.q_world_body * np.sign(b.q_world_body[0] * frame.q_world_body[0])
    for got, want in ((b.x_world, frame.x_world), (q, frame.q_world_body), (b.u_world, frame.u_world), (b.omega_world, frame.omega_world)):
        assert np.allclose(got, want, rtol=1e-12, atol=1e-12)
    energies = system.energies(s)
    assert energies["E_kin"] == pytest.approx(frame.E_kin, rel=1e-12, abs=1e-9)
    assert energies["E_grav"] == pytest.approx(frame.E_grav, rel=1e-12)
    assert energies["E_hyd"] == pytest.approx(frame.E_hyd, rel=1e-9)


def test_a_joint_of_one_is_the_systems_joint():
    """The hinge or slide of a body on a joint is the system's one joint: its axis, its take-off's spring and damper."""
    sim, system, s = system_run(load_scene("point-absorber"), "numpy")
    (joint,) = system.joints
    assert joint.kind == sim.joint.kind and np.array_equal(joint.axis, sim.joint.axis)
    assert (joint.stiffness, joint.damping) == (sim.joint.stiffness, sim.joint.damping)
    (point, direction) = system.joint_axes(s)[0]
    assert np.allclose(direction, sim.joint.axis) and abs(np.cross(point - sim.frame().joint_axis[0], direction)).max() < 1e-12
    assert dataclasses.replace(s).v.shape == (1,)


@pytest.mark.parametrize("name", ["spin", "point-absorber"])
def test_a_run_of_one_body_is_a_system_of_one(name):
    """The runner's state is the system's for a body alone too (its body's own state inside), its joints the system's,
    and a run reset to another's state goes on as that run does (the pose and twist to round-off)."""
    from sim.system.tree import SystemState

    run = Simulation(load_scene(name), backend="numpy")
    run.step(40)
    assert type(run.state) is SystemState and run.body_names == ["body"] and run.state.body is run.body_state
    assert [g.kind for g in run.system.joints] == ([run.joint.kind] if run.joint is not None else [])
    fresh = Simulation(load_scene(name), backend="numpy")
    fresh.reset(run.state)
    run.step(30)
    fresh.step(30)
    a, b = run.frame(), fresh.frame()
    for got, want in ((a.x_world, b.x_world), (a.q_world_body, b.q_world_body), (a.u_world, b.u_world), (a.omega_world, b.omega_world)):
        assert np.allclose(got, want, rtol=1e-10, atol=1e-12)
    assert a.t == b.t

"""The compiled system step (sim/kernels/system.py, kinematics.py, expm.py; sim/system/compiled.py) against the numpy
reference (sim/system/tree.py): each stage to round-off, then whole trajectories, and a run of several bodies switching between them."""

import dataclasses

import numpy as np
import pytest
import scipy.linalg

from sim.scene.config import load_scene, with_overrides
from sim.simulation import Simulation
from sim.system.compiled import CompiledStep
from sim.system.tree import build
from tests.system.test_system import CHAIN, MOORED, scene_file


def planar_rm3(hydro: str = "linear"):
    """rm3 with its spar on a planar joint (surge, heave, pitch) in a 16-component sea: turning Jacobians, a take-off,
    the radiation's memory coupling both bodies and diffraction."""
    scene = with_overrides(load_scene("rm3"), waves__kind="jonswap", waves__height=2.5, waves__period=8.0, waves__components=16,
                           step__dt=0.02, fluid__hydro=hydro)  # fmt: skip
    spar = scene.bodies[0]
    planar = dataclasses.replace(spar, constraint=dataclasses.replace(spar.constraint, joint="planar", axis=(0.0, 1.0, 0.0)))
    return dataclasses.replace(scene, bodies=(planar, *scene.bodies[1:]))


def close(a, b, tol: float) -> None:
    scale = max(np.abs(b).max(initial=0.0), 1e-300)
    assert np.abs(np.asarray(a) - np.asarray(b)).max(initial=0.0) <= tol * scale


def test_the_matrix_exponential_is_scipys():
    """Pade 3 to 13 with scaling and squaring against scipy.linalg.expm, over 1-norms from 1e-3 (degree 3) to 50 (13 with
    squarings), to 1e-13 relative."""
    from sim.kernels.expm import expm

    rng = np.random.default_rng(1)
    for scale in (1e-3, 0.03, 0.3, 1.0, 2.0, 5.0, 50.0):
        for _ in range(5):
            A = rng.standard_normal((10, 10))
            A *= scale / np.abs(A).sum(axis=0).max()
            close(expm(A), scipy.linalg.expm(A), 1e-13)


@pytest.fixture(scope="module")
def rm3_linear():
    run = Simulation(planar_rm3(), backend="numpy")
    return run.system, run.state, run.dt


def moved(system, s, steps: int = 40, dt: float = 0.02):
    for _ in range(steps):
        s = system.step(s, dt)
    return s


def test_each_stage_matches_the_reference(rm3_linear):
    """On the planar rm3 after 40 steps (moving, turning, the memory charged): each body's pose and twist Jacobian, the mass
    matrix with the added mass, b(v) and its Jacobian, the linear loads, the memory's load with diffraction, a kick (v and
    the take-off's energy) and the memory's drift, each to round-off."""
    from sim.kernels import kinematics
    from sim.kernels import system as kernels

    system, s0, dt = rm3_linear
    s = moved(system, s0)
    step = CompiledStep(system)
    mem = step.memory(dt)
    x, R, J, M, G, along = step.configuration(s, dt)
    pose = system.pose(s)
    for b in range(len(pose.x)):
        close(x[b], pose.x[b], 1e-14)
        close(R[b], pose.R[b], 1e-14)
        close(J[b], pose.J[b], 1e-14)
    close(M, system.inertia(pose), 1e-13)
    assert np.abs(J[0][3:]).max() > 0.5  # the spar pitches: a turning Jacobian
    b, B = kinematics.bias(step.tree, R, J, along, s.v)
    b0, B0 = system.bias(s, s.v)
    close(b, b0, 1e-9)  # the reference's central differences of J (round-off / 1e-5) against their analytic limit
    close(B, B0, 1e-9)
    f, D = kernels.linear_loads(step.linear, x, R, s.t)
    for k, loads in enumerate(system.loads):
        f0, D0 = loads(pose.x[k], pose.R[k], s.t, pose.J[k] @ s.v)
        close(f[k], f0, 1e-13)
        close(D[k], np.zeros((6, 6)) if D0 is None else D0, 1e-13)
    rad = system.radiation
    reference = pose.stacked.T @ rad.load(rad.frames(pose), s.memory, s.t, pose.x)
    close(kernels.radiation_load(mem, G, J, x, s.memory, s.t), reference, 1e-13)
    config = (x, R, J, M, G, along)
    v, absorbed = kernels.half_step(step.tree, mem, config, s.t, s.x_free, s.q_free, s.theta, s.v, s.absorbed, s.memory, s.E_rad, f, D, step.held(), dt,
                                    kernels.CLOSE)[4:6]  # fmt: skip
    kicked = system.kick(s, dt / 2)
    close(v, kicked.v, 1e-12)
    close(absorbed, kicked.absorbed, 1e-12)
    after = system.drifted(kicked, dt)
    G1 = step.configuration(after, dt)[4]
    memory, E_rad = kernels.memory_drift(mem, G, G1, kicked.v, s.memory, s.E_rad, dt)
    reference = rad.drift(system, kicked, after, dt)
    close(memory, reference.memory, 1e-13)
    assert E_rad == pytest.approx(reference.E_rad, rel=1e-12) and reference.E_rad > 0


def test_the_velocity_product_rates_are_the_limit_of_the_central_differences(tmp_path, rm3_linear):
    """dJ_b/dt along each turning unit velocity, from the forward kinematics differentiated (kinematics.rates), against the
    central differences of the compiled kinematics (System.bias's) to 1e-8: the planar rm3 pitching, and a free barge
    turning with a hinged flap and a slide on it."""
    from sim.kernels import kinematics

    system, s0, dt = rm3_linear
    chain, c0 = build(scene_file(tmp_path, CHAIN))
    for sys_, s, h in ((system, moved(system, s0), dt), (chain, moved(chain, c0, 100, 0.01), 0.01)):
        tree = CompiledStep(sys_).tree
        analytic = kinematics.rates(tree, s.x_free, s.q_free, s.theta)
        close(analytic, kinematics.rates_by_differences(tree, s.x_free, s.q_free, s.theta), 1e-8)
        assert np.abs(analytic[tree.turning]).max() > 0.1 and len(tree.turning) >= 2


def trajectory_gap(system, s0, dt: float, n: int) -> tuple[float, float]:
    """The largest gap between n compiled and n numpy steps, over the coordinates and velocities relative to their size, and
    of the take-offs' and the radiated energies; and how far the joints moved."""
    ref, out = s0, CompiledStep(system).step(s0, dt, n)[0]
    for _ in range(n):
        ref = system.step(ref, dt)
    gaps = [np.abs(getattr(out, f) - getattr(ref, f)).max(initial=0.0) / max(np.abs(getattr(ref, f)).max(initial=0.0), 1e-300)
            for f in ("x_free", "q_free", "theta", "v", "absorbed", "memory")]  # fmt: skip
    gaps.append(abs(out.E_rad - ref.E_rad) / max(abs(ref.E_rad), 1e-300))
    assert out.t == ref.t
    return max(gaps), float(np.abs(ref.theta - s0.theta).max(initial=0.0) + np.abs(ref.x_free - s0.x_free).max(initial=0.0))


def test_the_planar_rm3_in_a_sea_steps_as_the_reference(rm3_linear):
    """Linear loads, the whole step compiled (one call for 300 steps): the numpy trajectory to 1e-9."""
    system, s0, dt = rm3_linear
    gap, motion = trajectory_gap(system, s0, dt, 300)
    assert gap < 1e-9 and motion > 1e-3


def test_a_hinged_chain_steps_as_the_reference(tmp_path):
    """A free barge, a hinged flap and a sliding buoy (panels, the bodies' loads from numpy between compiled calls): 300 steps
    on both to 1e-9, the hinge turning."""
    system, s0 = build(scene_file(tmp_path, CHAIN))
    gap, motion = trajectory_gap(system, s0, 0.01, 300)
    assert gap < 1e-9 and motion > 0.05


def test_a_run_of_several_bodies_switches_between_backends_between_steps():
    """The same run stepped numpy, compiled, numpy: the all-numpy trajectory to 1e-9; the compiled step is what ran."""
    a, b = Simulation(planar_rm3(), backend="numpy"), Simulation(planar_rm3(), backend="numpy")
    a.step(60)
    a.use_backend("numba")
    assert a.stepper is not None
    a.step(60)
    a.use_backend("numpy")
    assert a.stepper is None
    a.step(60)
    b.step(180)
    close(a.state.theta, b.state.theta, 1e-9)
    close(a.state.v, b.state.v, 1e-9)
    assert a.state.t == pytest.approx(b.state.t)


@pytest.mark.slow
def test_rm3_with_its_compiled_loads_steps_as_the_reference():
    """The rm3 preset (panels, regular waves): each body's compiled loads from Python, the rest compiled, against the all-numpy
    run over 200 steps, to the sea expansion's bound (the loads' twin sums the sea differently: 1e-9)."""
    a, b = Simulation(load_scene("rm3"), backend="numpy"), Simulation(load_scene("rm3"), backend="numpy")
    a.use_backend("numba")
    a.step(200)
    b.step(200)
    close(a.state.theta, b.state.theta, 1e-8)
    close(a.state.absorbed, b.state.absorbed, 1e-8)
    assert np.abs(b.state.theta).max() > 0.1


@pytest.mark.slow
def test_moored_bodies_step_as_the_reference(tmp_path):
    """A moored pontoon (MoorDyn advanced between steps, its pull held) on the compiled step: the numpy run to 1e-9."""
    pytest.importorskip("moordyn")
    scene = scene_file(tmp_path, MOORED)
    runs = [Simulation(scene, backend="numpy") for _ in range(2)]
    try:
        runs[0].stepper = CompiledStep(runs[0].system)
        for run in runs:
            run.step(200)
        close(runs[0].state.theta, runs[1].state.theta, 1e-9)
        close(runs[0].state.absorbed, runs[1].state.absorbed, 1e-9)
        assert abs(runs[1].state.theta[0]) > 0.02  # pulled back towards the middle
    finally:
        for run in runs:
            run.close()


def test_joint_kinds_are_packed_as_the_reference_orders_them(tmp_path):
    """The packed tree: every group's kind, parent and columns as system.Group says, the bodies in the scene's order."""
    from sim.kernels.system_layout import KINDS, tree_pack

    system, _ = build(scene_file(tmp_path, CHAIN))
    tree = tree_pack(system)
    assert [KINDS[g.kind] for g in system.groups] == list(tree.kind)
    assert [g.parent for g in system.groups] == list(tree.parent) and tree.n_dofs == system.n_dofs == 8
    assert list(tree.turning) == system._turning_dofs and tree.needs_bias

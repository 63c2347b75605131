"""One world (issue 40): `Simulation` runs any scene, and a body's parameters are named the same way in every scene."""

import dataclasses
import re

import numpy as np
import pytest

from sim.scene.config import ConfigError, load_scene, with_overrides
from sim.simulation import Simulation
from tests.system.test_system import PAIR, SLIDE, scene_file


def poses(run) -> np.ndarray:
    """Every body's position, orientation, velocity and angular velocity, one row each."""
    return np.array([np.concatenate([b.x_world, b.q_world_body, b.u_world, b.omega_world]) for b in run.frame().bodies])


def test_simulation_runs_a_scene_of_several_bodies():
    run = Simulation(load_scene("rm3"), backend="numpy")
    assert type(run) is Simulation and run.single is None and run.body_names == ["spar", "float"]
    assert run.columns()[:2] == ["t", "spar_x"] and len(run.frame().row()) == len(run.columns())
    run.step(4)
    assert run.frame().t == pytest.approx(4 * run.dt)


def test_a_take_off_changed_mid_run_is_the_run_started_with_it(tmp_path):
    """float__pto_damping between steps: the next steps are those of a run built with the new damping from that state."""
    scene = scene_file(tmp_path, SLIDE.replace('name = "cube"', 'name = "float"'))
    run = Simulation(scene, backend="numpy")
    run.step(50)
    run.update(float__pto_damping=9000.0, float__pto_stiffness=100.0)
    assert run.scene.bodies[0].constraint.pto_damping == 9000.0
    fresh = Simulation(with_overrides(scene, float__pto_damping=9000.0, float__pto_stiffness=100.0), backend="numpy")
    fresh.reset(run.state)
    run.step(100)
    fresh.step(100)
    assert np.abs(poses(run) - poses(fresh)).max() < 1e-13
    assert run.frame().E_pto == pytest.approx(fresh.frame().E_pto, rel=1e-12) and run.frame().E_pto > 1.0


def test_a_mass_changed_mid_run_keeps_every_body_where_and_as_it_moves(tmp_path):
    """A welded member made heavier shifts its group's centre of mass: the bodies stay where they are, turning and
    moving as they were (generalised velocities kept), and then step as a run built with that mass."""
    scene = scene_file(tmp_path, PAIR)
    run = Simulation(scene, backend="numpy")
    run.step(20)
    before = poses(run)
    run.update(outrigger__density=900.0)
    assert np.abs(poses(run) - before).max() < 1e-12
    heavier = [m.body.mass for m in run.system.members]
    assert heavier[1] == pytest.approx(3 * Simulation(scene, backend="numpy").system.members[1].body.mass)
    fresh = Simulation(with_overrides(scene, outrigger__density=900.0), backend="numpy")
    fresh.reset(run.state)
    run.step(10)
    fresh.step(10)
    assert np.abs(poses(run) - poses(fresh)).max() < 1e-13


def test_the_one_body_of_a_scene_is_named_body():
    """body__pto_damping in a one-body scene is its [constraint] pto_damping, as float__pto_damping is a float's."""
    base = load_scene("damped")
    assert with_overrides(base, body__joint="prismatic", body__pto_damping=7.0) == with_overrides(
        base, constraint__joint="prismatic", constraint__pto_damping=7.0
    )
    assert with_overrides(base, body__position=(0.0, 0.0, 0.3)).initial.position == (0.0, 0.0, 0.3)


@pytest.mark.parametrize(
    "change, message",
    [
        ({"body__density": 500.0}, "this scene's bodies are its [[bodies]] (spar, float): name the body, e.g. float.density"),
        ({"buoy__density": 500.0}, "'buoy' is not a section or one of the bodies (spar, float)"),
        ({"float__colour": 1.0}, "unknown parameter 'colour' of body 'float'"),
        ({"float__density": -5.0}, "density"),
    ],
)
def test_a_wrong_body_parameter_is_one_line_and_leaves_the_run(change, message):
    run = Simulation(load_scene("rm3"), backend="numpy")
    run.step(2)
    state, scene = run.state, run.scene
    with pytest.raises(ConfigError, match=re.escape(message)) as e:
        run.update(**change)
    assert "\n" not in str(e.value)
    assert run.state is state and run.scene == scene


def test_an_unchanged_update_changes_nothing():
    run = Simulation(load_scene("rm3"), backend="numpy")
    system = run.system
    run.update(float__pto_damping=run.scene.bodies[1].constraint.pto_damping)
    assert run.system is system and dataclasses.replace(run.scene) == load_scene("rm3")


TWO_CUBES = """
    [fluid]
    forces = "panels"
    damping = {scene_damping}
    [[bodies]]
    name = "a"
    shape = "cube"
    density = 500.0
    position = [-2.0, 0.0, 0.1]
    {a_own}
    [[bodies]]
    name = "b"
    shape = "cube"
    density = 500.0
    position = [2.0, 0.0, 0.1]
    {b_own}
"""


def test_a_body_s_own_damping_is_its_alone(tmp_path):
    """A [[bodies]] entry's own term parameter (damping = 2000 for cube a) acts on that body alone and is exactly the
    scene's [fluid] value for it: the run equals one whose [fluid] damping is 2000 with cube b's own 0; a's heave dies
    out while b, undamped, keeps bobbing. Named by the body everywhere: update(b__damping=...) and its one-line errors."""
    own = scene_file(tmp_path, TWO_CUBES.format(scene_damping=0.0, a_own="damping = 2000.0", b_own=""), "own.toml")
    wide = scene_file(tmp_path, TWO_CUBES.format(scene_damping=2000.0, a_own="", b_own="damping = 0.0"), "wide.toml")
    assert [e.fluid_of(own.fluid).damping for e in own.bodies] == [2000.0, 0.0]
    runs = [Simulation(scene, backend="numpy") for scene in (own, wide)]
    heave = []
    for _ in range(120):  # 3 s: a's heave decays as exp(-d A t / 2 m) = exp(-2 t)
        for run in runs:
            run.step(5)
        heave.append(poses(runs[0])[:, 2])
        assert np.abs(poses(runs[0]) - poses(runs[1])).max() < 1e-12
    late = np.ptp(np.array(heave[-60:]), axis=0)  # the heave range of a and b over the last 1.5 s (a period)
    assert late[0] < 0.2 * late[1] and late[1] > 0.05, late
    runs[0].update(b__damping=200.0)
    assert [m.model.fluid.damping for m in runs[0].system.members] == [2000.0, 200.0]
    with pytest.raises(ConfigError, match=r"\[\[bodies\]\] b: damping must be >= 0"):
        runs[0].update(b__damping=-1.0)

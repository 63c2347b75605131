"""The heave damping term (forces.heave_damping: -B_33 w while wet, a linear damping matrix's heave entry) against the
damped oscillator's closed form, for a body alone and for one body of several, each with its own B_33."""

import math

import numpy as np

from sim import Simulation, load_scene, with_overrides
from tests.system.test_system import scene_file

RHO, G, SIDE, DENSITY, Z0, ZETA = 1000.0, 9.81, 1.0, 500.0, 0.1, 0.1
MASS = DENSITY * SIDE**3
K = RHO * G * SIDE**2  # a wall-sided body's heave stiffness, exact while its water line stays on the walls
OMEGA = math.sqrt(K / MASS)  # no added mass: no radiation here
B33 = 2.0 * ZETA * math.sqrt(K * MASS)
REST = -SIDE * (0.5 - DENSITY / RHO)  # the centre of mass at rest: the draft is half the side


def closed_form(t: np.ndarray) -> np.ndarray:
    """m z'' + B_33 z' + k z = 0 from z(0) = Z0 above rest, at rest: z0 e^(-zeta w t) (cos w_d t + zeta w / w_d sin w_d t)."""
    wd = OMEGA * math.sqrt(1.0 - ZETA**2)
    return REST + Z0 * np.exp(-ZETA * OMEGA * t) * (np.cos(wd * t) + ZETA * OMEGA / wd * np.sin(wd * t))


def heave_error(dt: float) -> float:
    """The largest gap to the closed form over two periods, a cube alone released Z0 above rest (panels: exact hydrostatics)."""
    scene = with_overrides(load_scene("rest"), fluid__forces="panels", fluid__heave_damping=B33, initial__position=(0.0, 0.0, REST + Z0),
                           body__density=DENSITY, step__dt=dt, step__integrator="implicit")  # fmt: skip
    sim = Simulation(scene, backend="numpy")
    every = round(0.05 / dt)
    times, z = [], []
    while sim.body_state.t < 4 * math.pi / OMEGA:
        sim.step(every)
        times.append(sim.body_state.t)
        z.append(sim.body_state.x_world[2])
    return float(np.abs(np.array(z) - closed_form(np.array(times))).max())


def test_a_cube_alone_decays_in_heave_as_the_damped_oscillator_at_second_order():
    coarse, fine = heave_error(0.01), heave_error(0.005)
    assert fine < 2e-4 * Z0
    assert 3.5 < coarse / fine < 4.5  # the implicit scheme's order, the term in it


PAIR = f"""
    [fluid]
    forces = "panels"
    [[bodies]]
    name = "damped"
    shape = "cube"
    size = {SIDE}
    density = {DENSITY}
    position = [0.0, 0.0, {REST + Z0}]
    heave_damping = {B33}
    [[bodies]]
    name = "free"
    shape = "cube"
    size = {SIDE}
    density = {DENSITY}
    position = [4.0, 0.0, {REST + Z0}]
    [step]
    dt = 0.005
"""


def test_each_body_of_several_feels_its_own_heave_damping(tmp_path):
    """Two cubes apart, one with B_33 (its [[bodies]] entry's heave_damping): it follows the damped closed form, the other
    keeps swinging with its amplitude (no damping of any kind on it)."""
    run = Simulation(scene_file(tmp_path, PAIR), backend="numpy")
    assert run.system.members[0].model.fluid.heave_damping == B33 and run.system.members[1].model.fluid.heave_damping == 0.0
    times, damped, free = [], [], []
    while run.state.t < 4 * math.pi / OMEGA:
        run.step(10)
        bodies = run.frame().bodies
        times.append(run.state.t)
        damped.append(bodies[0].x_world[2])
        free.append(bodies[1].x_world[2])
    assert np.abs(np.array(damped) - closed_form(np.array(times))).max() < 1e-3 * Z0
    assert np.max(free[len(free) // 2 :]) - REST > 0.99 * Z0

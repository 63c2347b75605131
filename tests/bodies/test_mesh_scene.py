"""A mesh body from a scene file: the log is unstable upright and must roll over to float on its side."""

import numpy as np
import pytest

from sim import Simulation, load_scene, with_overrides
from sim.bodies.rotation import quat_to_matrix


def metacentric_height_upright(radius=0.25, length=1.5, density=600.0):
    """GM = I_wp / V_sub - (z_G - z_B) for the upright cylinder (hollow: G at mid-length)."""
    draft = length * density / 1000.0
    return (np.pi * radius**4 / 4) / (np.pi * radius**2 * draft) - (length / 2 - draft / 2)


@pytest.mark.parametrize("forces", ["points", "panels"])
def test_log_rolls_over_and_floats_on_its_side(forces):
    assert metacentric_height_upright() < 0  # why it cannot stay upright
    sim = Simulation(with_overrides(load_scene("log"), fluid__forces=forces))
    sim.step(8000)  # 40 s
    frame = sim.frame()
    axis_body = quat_to_matrix(sim.body.q_input_body).T @ np.array([0.0, 0.0, 1.0])  # the mesh's z axis
    axis_world = sim.state.R_world_body @ axis_body
    assert abs(axis_world[2]) < 0.02  # lying flat
    assert frame.submerged_volume == pytest.approx(sim.body.mass / 1000.0, rel=1e-4)  # Archimedes
    assert np.linalg.norm(frame.omega_world) < 1e-2

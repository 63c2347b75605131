"""The shape of the code that the physics relies on: one declaration per parameter reaches every
place that needs it, water is asked rather than assumed, the scene describes what runs, and the
physics package imports no viewer, plotting or command-line library."""

import ast
import dataclasses
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from sim import PARAMS, TERMS, FluidConfig, Model, Simulation, StillWater, load_scene
from sim.bodies.body import make_box
from sim.commands.run import RunArgs
from sim.kernels.layout import coefficients, slot

SIM = Path(__file__).resolve().parent.parent / "sim"


def test_physics_package_imports_no_viewer_plotting_or_cli_library():
    code = "import sys, sim, sim.kernels, sim.ensemble; print(sorted(m for m in ('tyro', 'matplotlib', 'viser', 'app', 'studies') if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
    for path in SIM.rglob("*.py"):
        if "commands" in path.parts:
            continue  # the command line is the one subpackage that uses tyro
        for node in ast.walk(ast.parse(path.read_text())):
            names = (
                [a.name for a in node.names]
                if isinstance(node, ast.Import)
                else [node.module or ""]
                if isinstance(node, ast.ImportFrom)
                else []
            )
            for name in names:
                assert name.split(".")[0] not in ("tyro", "matplotlib", "viser", "app", "studies"), (path, name)


@pytest.mark.parametrize("term", TERMS, ids=lambda t: t.name)
def test_each_term_parameter_is_a_scene_key_a_flag_a_control_and_a_kernel_slot(term):
    from app.loop import CONTROLLED

    fields = {f.name for f in dataclasses.fields(FluidConfig)}
    flags = {f.name for f in dataclasses.fields(RunArgs)}
    for p in term.params:
        assert PARAMS[f"fluid.{p.key}"] is p and p.key in fields and p.key in flags
        assert (p.key in CONTROLLED) == (p.gui is not None)
        fluid = FluidConfig(**{p.key: 0.25})
        assert coefficients(fluid)[slot(p.key)] == 0.25
        assert not any(t.name == term.name for t in Model(make_box((1, 1, 1), 2, 1.0), StillWater(), FluidConfig(**{p.key: 0.0})).terms)


class RaisedWater(StillWater):
    """Calm water whose surface stands at z = 0.3 m instead of 0."""

    flat = False  # not the kernels' plane z = 0

    def elevation(self, xy, t):
        return np.full(np.shape(xy)[:-1], 0.3)

    def pressure(self, points, t):
        return -self.rho * self.g * (points[..., 2] - 0.3)


@pytest.mark.parametrize("forces", ["points", "panels"])
def test_wet_surface_and_pressure_come_from_the_water(forces):
    """The ice cube floats 0.9 m deep below whatever surface the water has: raised by 0.3 m, its rest
    height rises by 0.3 m; nothing assumes the plane z = 0."""
    body = make_box((1.0, 1.0, 1.0), 6, 900.0, "cube")
    fluid = FluidConfig(forces=forces)
    model = Model(body, RaisedWater(), fluid)
    wet = model.wetted(np.array([0.0, 0.0, -0.1]), np.eye(3))
    force, torque = model.pose_loads(wet)
    np.testing.assert_allclose(force, 0.0, atol=1e-9 * body.mass * 9.81)
    np.testing.assert_allclose(torque, 0.0, atol=1e-9)
    assert wet.submerged_area == pytest.approx(1.0 + 4 * (0.9 if forces == "panels" else 5 / 6))  # samples: 5 of 6 rows per side
    still = Model(body, StillWater(), fluid).pose_loads(Model(body, StillWater(), fluid).wetted(np.array([0.0, 0.0, -0.1]), np.eye(3)))
    assert still[0][2] == pytest.approx(1000 * 9.81 * 0.6 - 900 * 9.81)  # in still water that pose is not a rest


def test_scene_stays_current_and_describes_what_runs():
    """After changes between steps, a fresh Simulation built from `scene` continues identically."""
    sim = Simulation(load_scene("damped"), backend="numpy")
    sim.step(50)
    sim.set_density(700.0)
    sim.set_params(damping=250.0, drag_coefficient=0.4)
    sim.set_dt(0.004)
    sim.set_integrator("rk4")
    sim.update(body__points_per_edge=7)
    s = sim.scene
    assert (s.body.density, s.fluid.damping, s.fluid.drag_coefficient, s.step.dt, s.step.integrator, s.body.points_per_edge) == (
        700.0, 250.0, 0.4, 0.004, "rk4", 7)  # fmt: skip
    assert sim.body.mass == pytest.approx(700.0) and sim.body.n_samples == 6 * 49 and sim.model.term_names[-1] == "drag"
    twin = Simulation(sim.scene, backend="numpy")
    twin.reset(sim.state)
    sim.step(30)
    twin.step(30)
    np.testing.assert_array_equal(sim.state.as_vector(), twin.state.as_vector())

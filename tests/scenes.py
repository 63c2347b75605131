"""Small scene builders shared by the physics tests."""

import functools
from pathlib import Path

from sim.scene.config import BodyConfig, FluidConfig, InitialConfig, SceneConfig, StepConfig


def box_scene(integrator="splitting", dt=0.01, *, damping=50.0, g=9.81, rho=1000.0, z=-5.0, omega=(0.3, 2.0, 0.1), n=4, **step):
    """An asymmetric 1 x 0.6 x 0.3 m box (density 700) fully under water (or, with rho = g = 0, in
    free space): no sample crosses the water line, so the dynamics are smooth and nonlinear."""
    return SceneConfig(
        body=BodyConfig(shape="box", extents=(1.0, 0.6, 0.3), points_per_edge=n, density=700.0),
        fluid=FluidConfig(rho=rho, g=g, damping=damping),
        initial=InitialConfig(position=(0.0, 0.0, z), omega=omega, velocity=(0.2, 0.0, 0.1)),
        step=StepConfig(integrator=integrator, dt=dt, rtol=1e-12, atol=1e-12, **step),
    )


@functools.cache
def shipped_solve(scene: str) -> Path:
    """The shipped BEM file a one-body preset reads, found by its coefficients (no key typed in a test goes stale when
    the solves are redone: `python -m studies.ship_solves`)."""
    import numpy as np

    from sim import Simulation, load_scene
    from sim.hydro.bem import SHIPPED

    c = Simulation(load_scene(scene), backend="numpy").model.radiation.coefficients
    return next(p for p in sorted(SHIPPED.glob("*.npz")) if np.array_equal(np.load(p)["damping"], c.damping))


HEAVING_FARM = """[body]
shape = "cube"
size = 1.0
density = 900.0
[constraint]
joint = "prismatic"
axis = [0.0, 0.0, 1.0]
pto_damping = 2000.0
[initial]
position = [0.0, 0.0, -0.4]
[farm]
rows = {n}
columns = {n}
spacing = 10.0
"""


def heaving_farm(folder: Path, n: int) -> str:
    """A scene file of n x n cubes 10 m apart, each heaving on its slide with a take-off damper (600 samples and one
    degree of freedom each): a farm as large as a test needs, written into `folder`."""
    path = folder / f"farm{n}.toml"
    path.write_text(HEAVING_FARM.format(n=n))
    return str(path)

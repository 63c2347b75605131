"""Bring your own coefficients: your own Capytaine solve, saved as netCDF the way Capytaine's documentation does

`[fluid] bem_file = "sphere.nc"` reads a dataset of `BEMSolver().fill_dataset` saved by `capytaine.export_dataset`
(pip install -e ".[bem,netcdf]"). Here a script solves its own 0.5 m sphere (another mesh of it than floatsim's:
144 panels, 40 frequencies and infinity), and floatsim's sphere decay test, released 10 cm high, runs from it and
from floatsim's own solve of its preset: the two heaves agree.
"""

import logging
import tempfile
from dataclasses import dataclass
from pathlib import Path

import capytaine as cpt
import numpy as np
import tyro
import xarray as xr

from sim import Simulation, load_scene

SPHERE_MESH = Path(__file__).resolve().parent.parent / "assets" / "meshes" / "sphere.stl"


@dataclass
class Args:
    t_end: float = 10.0
    """Simulated seconds of the decay."""


def solve(path: Path) -> None:
    """The user's script: Capytaine's documented way, radiation and diffraction of its own sphere, saved as netCDF."""
    logging.getLogger("capytaine").setLevel(logging.ERROR)
    mesh = cpt.mesh_sphere(radius=0.5, center=(0, 0, 0), resolution=(12, 24)).immersed_part()
    body = cpt.FloatingBody(mesh=mesh, dofs=cpt.rigid_body_dofs(rotation_center=(0, 0, 0)), center_of_mass=(0, 0, 0), name="sphere")
    omegas = np.concatenate([np.linspace(0.5, 20.0, 40), [np.inf]])
    problems = xr.Dataset(coords={"omega": omegas, "wave_direction": [0.0], "radiating_dof": list(body.dofs), "rho": 1000.0,
                                  "water_depth": np.inf})  # fmt: skip
    cpt.export_dataset(str(path), cpt.BEMSolver().fill_dataset(problems, body))


SCENE = """
[fluid]
forces = "panels"
damping = 0.0
radiation = "bem"
bem_file = "{bem_file}"

[[bodies]]
name = "sphere"
shape = "mesh"
mesh = "{mesh}"
samples = 2000
density = 500.0
position = [0.0, 0.0, 0.1]

[step]
dt = 0.005
t_end = {t_end}
"""


def heave(scene: str, t_end: float) -> np.ndarray:
    sim = Simulation(load_scene(scene))
    z = []
    for _ in range(round(t_end / sim.dt)):
        sim.step(1)
        z.append(float(sim.frame().x_world[2]))
    sim.close()
    return np.array(z)


def main(args: Args) -> None:
    with tempfile.TemporaryDirectory() as folder:
        dataset = Path(folder) / "sphere.nc"
        solve(dataset)
        scene = Path(folder) / "sphere.toml"
        scene.write_text(SCENE.format(bem_file=dataset, mesh=SPHERE_MESH, t_end=args.t_end))
        theirs = heave(str(scene), args.t_end)
    ours = heave("sphere", args.t_end)  # the preset, floatsim's own solve
    apart = np.abs(theirs - ours).max()
    print(f"the sphere released 10 cm high, heave over {args.t_end:g} s: from your Capytaine solve and from floatsim's own at most "
          f"{apart * 1000:.2f} mm apart ({apart / 0.1:.2%} of the release)")  # fmt: skip


if __name__ == "__main__":
    main(tyro.cli(Args, description=__doc__))

"""Bring your own coefficients: a BEMIO .h5 file (WEC-Sim's and SEA-Stack's input), checked against SEA-Stack's own run

`[fluid] bem_file = "run.h5"` reads the file BEMIO writes (pip install -e ".[bemio]" for h5py). Here SEA-Stack's IEA
sphere (5 m in radius, half submerged, its coefficients a WAMIT run's in assets/coefficients/bemio, every 2nd
frequency) is released 1 m above rest on a vertical slide, as SEA-Stack's decay test released it, and its heave is
laid over SEA-Stack's own (Chrono with the same file, with nonlinear and with linear hydrostatics:
assets/reference/iea_sphere_decay.csv).
"""

import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh
import tyro

from sim import Simulation, load_scene

ROOT = Path(__file__).resolve().parent.parent
BEMIO = ROOT / "assets" / "coefficients" / "bemio" / "iea_sphere.h5"
REFERENCE = ROOT / "assets" / "reference" / "iea_sphere_decay.csv"


@dataclass
class Args:
    t_end: float = 40.0
    """Simulated seconds (SEA-Stack's run lasts 40)."""
    release: float = 1.0
    """Height above rest of the release, m (SEA-Stack's: 1)."""


SCENE = """
[fluid]
forces = "panels"
radiation = "bem"
bem_file = "{bem_file}"

[[bodies]]
name = "sphere"
shape = "mesh"
mesh = "sphere.stl"
mass = 261800.0
centre_of_mass = [0.0, 0.0, -2.0]  # the file's centre of gravity, 2 m below the sphere's centre
position = [0.0, 0.0, {start}]
joint = "prismatic"
axis = [0.0, 0.0, 1.0]

[step]
dt = 0.01
t_end = {t_end}
"""


def decay(args: Args) -> tuple[np.ndarray, np.ndarray]:
    with tempfile.TemporaryDirectory() as folder:
        trimesh.creation.icosphere(subdivisions=4, radius=5.0).export(Path(folder) / "sphere.stl")
        scene = Path(folder) / "iea_sphere.toml"
        scene.write_text(SCENE.format(bem_file=BEMIO, start=-2.0 + args.release, t_end=args.t_end))
        sim = Simulation(load_scene(str(scene)))
        t, z = [], []
        for _ in range(round(args.t_end / sim.dt)):
            sim.step(1)
            t.append(sim.state.t)
            z.append(float(sim.frame().x_world[2]))
        sim.close()
    return np.array(t), np.array(z)


def main(args: Args) -> None:
    t, z = decay(args)
    reference = np.genfromtxt(REFERENCE, delimiter=",", names=True, skip_header=1)
    within = reference["t"] <= t[-1]
    ours = np.interp(reference["t"][within], t, z)
    print(f"the IEA sphere released {args.release:g} m above rest, heave of its centre of gravity over {t[-1]:g} s:")
    for key, label in (("z_nonlinear", "nonlinear hydrostatics"), ("z_linear", "linear hydrostatics")):
        apart = np.abs(ours - reference[key][within]).max()
        print(f"  against SEA-Stack's run with {label}: at most {apart:.4f} m apart ({apart / args.release:.2%} of the release)")
    lowest = int(np.argmin(z))
    print(f"  floatsim's lowest point {z[lowest]:.4f} m at {t[lowest]:.2f} s, rest at -2 m")


if __name__ == "__main__":
    main(tyro.cli(Args, description=__doc__))

"""Bring your own coefficients: a NEMOH run (its Nemoh.cal and Results/*.tec), against WAMIT's run of the same body

`[fluid] bem_file = "Nemoh.cal"` reads a NEMOH run as WEC-Sim's readNEMOH takes it. Here WEC-Sim's NEMOH 2.3 run of
its half ellipsoid (assets/coefficients/nemoh/ellipsoid, every 4th frequency) and WAMIT's run of the same body
(assets/coefficients/wamit/ellipsoid.1) each drive the ellipsoid heaving on a slide in regular waves: two codes, two
meshes, one heave.
"""

import tempfile
from dataclasses import dataclass
from pathlib import Path

import trimesh
import tyro

from sim import Simulation, load_scene

COEFFICIENTS = Path(__file__).resolve().parent.parent / "assets" / "coefficients"
FILES = {"NEMOH": COEFFICIENTS / "nemoh" / "ellipsoid" / "Nemoh.cal", "WAMIT": COEFFICIENTS / "wamit" / "ellipsoid.1"}


@dataclass
class Args:
    t_end: float = 40.0
    """Simulated seconds."""
    period: float = 6.0
    """The waves' period, s (NEMOH's run keeps its irregular frequencies above 2.4 rad/s: periods under 2.6 s meet them)."""


SCENE = """
[fluid]
forces = "panels"
radiation = "bem"
bem_file = "{bem_file}"

[waves]
kind = "regular"
height = 1.0
period = {period}

[[bodies]]
name = "ellipsoid"
shape = "mesh"
mesh = "ellipsoid.stl"
mass = 76213.9
joint = "prismatic"
axis = [0.0, 0.0, 1.0]

[step]
dt = 0.05
t_end = {t_end}
"""


def heave(folder: Path, bem_file: Path, args: Args) -> list[float]:
    scene = folder / "ellipsoid.toml"
    scene.write_text(SCENE.format(bem_file=bem_file, period=args.period, t_end=args.t_end))
    sim = Simulation(load_scene(str(scene)))
    z = []
    for _ in range(round(args.t_end / sim.dt)):
        sim.step(1)
        z.append(float(sim.frame().x_world[2]))
    sim.close()
    return z


def main(args: Args) -> None:
    with tempfile.TemporaryDirectory() as folder:
        mesh = trimesh.creation.icosphere(subdivisions=4)
        mesh.apply_scale([4.5, 4.5, 1.8])  # WEC-Sim's ellipsoid, the upper half dry
        mesh.export(Path(folder) / "ellipsoid.stl")
        heaves = {code: heave(Path(folder), path, args) for code, path in FILES.items()}
    late = heaves["WAMIT"][len(heaves["WAMIT"]) // 2 :]
    amplitude = (max(late) - min(late)) / 2
    apart = max(abs(a - b) for a, b in zip(heaves["NEMOH"], heaves["WAMIT"]))
    print(f"heave amplitude in 0.5 m waves of {args.period:g} s from WAMIT's run: {amplitude:.4f} m; from NEMOH's it differs by at "
          f"most {apart:.4f} m ({apart / amplitude:.2%} of it)")  # fmt: skip


if __name__ == "__main__":
    main(tyro.cli(Args, description=__doc__))

"""Bring your own coefficients: a WAMIT run's numeric files (.1, .3, .hst) or its .out

A scene names its bodies' coefficients with `[fluid] bem_file` instead of solving them with Capytaine. Here WEC-Sim's
WAMIT run of a half ellipsoid 9 m across (assets/coefficients/wamit, a subset of its periods) drives the ellipsoid's
mesh in regular waves, heaving on a slide: once from the numeric files, once from the .out of the same run. The two
heaves agree to the .out's whole-degree phases, and both are the heave linear theory gives from the file's coefficients.
"""

import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh
import tyro

from sim import Simulation, load_scene
from sim.io.wamit_numeric import Assumed, read_numeric, stiffness

WAMIT = Path(__file__).resolve().parent.parent / "assets" / "coefficients" / "wamit"


@dataclass
class Args:
    t_end: float = 40.0
    """Simulated seconds."""
    period: float = 6.0
    """The waves' period, s."""


def scene_text(bem_file: Path, period: float, t_end: float) -> str:
    return f"""
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
    scene = folder / f"{bem_file.suffix[1:]}.toml"
    scene.write_text(scene_text(bem_file, args.period, args.t_end))
    sim = Simulation(load_scene(str(scene)))
    z = []
    for _ in range(round(args.t_end / sim.dt)):
        sim.step(1)
        z.append(float(sim.frame().x_world[2]))
    sim.close()
    return z


def linear_heave(period: float) -> float:
    """The heave amplitude per metre of wave that linear theory gives from the same files: |X3| / |C33 - w^2 (m + A33)
    - i w B33| at the waves' frequency (interpolated between the files' periods)."""
    run, _ = read_numeric(WAMIT / "ellipsoid.1", 1000.0, Assumed(9.81, np.inf, np.zeros((1, 3))))
    C33 = stiffness(WAMIT / "ellipsoid.1", run, 1000.0)[2, 2]
    w = 2 * np.pi / period
    A, B = (np.interp(w, run.omega, M[:, 2, 2]) for M in (run.added_mass, run.damping))
    X = np.interp(w, run.omega, np.abs(run.excitation[:, 0, 2]))
    return float(X / abs(C33 - w * w * (76213.9 + A) - 1j * w * B))


def main(args: Args) -> None:
    with tempfile.TemporaryDirectory() as folder:
        mesh = trimesh.creation.icosphere(subdivisions=4)
        mesh.apply_scale([4.5, 4.5, 1.8])  # WEC-Sim's WAMIT ellipsoid, the upper half dry
        mesh.export(Path(folder) / "ellipsoid.stl")
        numeric, out = (heave(Path(folder), WAMIT / name, args) for name in ("ellipsoid.1", "ellipsoid.out"))
    late = numeric[len(numeric) // 2 :]
    amplitude = (max(late) - min(late)) / 2
    apart = max(abs(a - b) for a, b in zip(numeric, out))
    print(f"heave amplitude in 0.5 m waves of {args.period:g} s: {amplitude:.4f} m from ellipsoid.1/.3 (linear theory from the same "
          f"files: {0.5 * linear_heave(args.period):.4f} m); the run from ellipsoid.out differs by at most {apart:.5f} m "
          f"({apart / amplitude:.2%} of it)")  # fmt: skip


if __name__ == "__main__":
    main(tyro.cli(Args, description=__doc__))

"""Float your own body: a mesh file or a trimesh object

Any watertight mesh (STL, OBJ, PLY, in m, cm, mm, in or ft) becomes the body, with the scene's other settings. Here a
capsule made by trimesh, half as dense as water: it floats on its side, half submerged.
"""

from dataclasses import dataclass

import trimesh
import tyro

from sim import Simulation, load_scene, with_overrides


@dataclass
class Args:
    mesh: str = ""
    """A mesh file to float (empty: a capsule 1.6 m long, 0.6 m across)."""
    density: float = 500.0
    """Its density, kg/m^3."""
    t_end: float = 20.0
    """Simulated seconds."""


def main(args: Args) -> None:
    scene = with_overrides(load_scene("rest"), body__density=args.density, fluid__damping=200.0, initial__position=(0.0, 0.0, 0.0))
    mesh = args.mesh or trimesh.creation.capsule(height=1.0, radius=0.3)
    sim = Simulation(scene, mesh=mesh)
    sim.step(round(args.t_end / sim.dt))
    f = sim.frame()
    print(
        f"{sim.body.name}: {sim.body.mass:.1f} kg, {sim.body.volume:.4f} m^3; after {f.t:.1f} s its centre is at z = {f.x_world[2]:.4f} m, "
        f"{f.submerged_volume / sim.body.volume:.1%} of it under water (Archimedes: {args.density / scene.fluid.rho:.1%})"
    )


if __name__ == "__main__":
    main(tyro.cli(Args, description=__doc__))

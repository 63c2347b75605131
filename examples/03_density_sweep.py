"""How deep a cube floats, against its density

A cube floating face up sinks until it displaces its own mass of water: its draft is its side times its density over
the water's. This sweep settles cubes of several densities and plots the draft they find against that line. Between
about 0.21 and 0.79 of the water's density a cube is unstable face up (the stability map in the docs): given time,
round-off tips it over, it settles tilted, and its centre is no longer at that depth (the 400 kg/m^3 point).
"""

from dataclasses import dataclass

import numpy as np
import tyro

from sim import Simulation, load_scene, with_overrides
from sim.sweeps.chunk import nearest_face_tilt


@dataclass
class Args:
    densities: tuple[float, ...] = (200.0, 400.0, 600.0, 800.0)
    """Cube densities, kg/m^3."""
    t_end: float = 30.0
    """Simulated seconds for each to settle."""
    plot: str = ""
    """Save draft against density to this PNG (empty: no plot)."""


def main(args: Args) -> None:
    drafts, water = [], load_scene("rest").fluid.rho
    for rho in args.densities:
        start = 0.5 - rho / water  # the centre near its draft, face up
        scene = with_overrides(load_scene("rest"), body__density=rho, fluid__damping=300.0, initial__position=(0.0, 0.0, start + 0.1))
        sim = Simulation(scene)
        sim.step(round(args.t_end / sim.dt))
        drafts.append(0.5 - sim.frame().x_world[2])  # the bottom face is 0.5 m below the centre
        tilt = nearest_face_tilt(sim.body, sim.state.q_world_body)
        print(f"density {rho:6.0f} kg/m^3: tilt {tilt:4.1f} deg, draft {drafts[-1]:.4f} m (Archimedes {rho / scene.fluid.rho:.4f} m)")
    if args.plot:
        import matplotlib.pyplot as plt

        rho = np.asarray(args.densities)
        plt.plot(rho, drafts, "o", label="floatsim")
        plt.plot(rho, rho / water, "-", label="Archimedes: s rho / rho_w")
        plt.xlabel("density (kg/m^3)"), plt.ylabel("draft (m)"), plt.legend(), plt.title("A 1 m cube's draft")
        plt.savefig(args.plot, dpi=120)


if __name__ == "__main__":
    main(tyro.cli(Args, description=__doc__))

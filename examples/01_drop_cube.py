"""Drop a cube into still water and watch it settle

The `drop` preset (the report's ice cube, 1 m, 900 kg/m^3, released with its centre on the water line) with some
damping: it bobs about its draft and settles at z = -0.4 m, where its weight equals the water it displaces.
"""

from dataclasses import dataclass

import tyro

from sim import Simulation, load_scene, with_overrides


@dataclass
class Args:
    t_end: float = 30.0
    """Simulated seconds."""
    damping: float = 100.0
    """Viscous damping on the wet surface, N s/m^3."""
    plot: str = ""
    """Save the height against time to this PNG (empty: no plot)."""


def main(args: Args) -> None:
    sim = Simulation(with_overrides(load_scene("drop"), fluid__damping=args.damping))
    times, heights = [0.0], [sim.frame().x_world[2]]
    while sim.state.t < args.t_end - 1e-9:
        sim.step(20)  # 0.1 s at the preset's dt = 0.005 s
        times.append(sim.state.t)
        heights.append(sim.frame().x_world[2])
    print(f"t = {sim.state.t:.1f} s: centre at z = {heights[-1]:.4f} m (Archimedes: -0.4000 m)")
    if args.plot:
        import matplotlib.pyplot as plt

        plt.plot(times, heights)
        plt.axhline(-0.4, color="grey", lw=0.8)
        plt.xlabel("t (s)"), plt.ylabel("centre height z (m)"), plt.title("A damped cube settles at its draft")
        plt.savefig(args.plot, dpi=120)


if __name__ == "__main__":
    main(tyro.cli(Args, description=__doc__))

"""Waves, and the waves a body makes: heave in a swell with and without radiation and diffraction

The ice cube (1 m, 900 kg/m^3, the exact panel model) in a regular swell, first with the Froude-Krylov pressure of
the undisturbed waves only, then with the waves it radiates (added mass and radiation damping) and diffracts, from
the cube's shipped Capytaine solve. For waves a few body lengths long the difference is a third or more.
"""

import sys
from dataclasses import dataclass

import tyro

from sim import Simulation, load_scene, with_overrides


@dataclass
class Args:
    period: float = 2.0
    """Wave period, s (2 s: waves 6.2 m long)."""
    height: float = 0.1
    """Wave height, m."""
    t_end: float = 30.0
    """Simulated seconds (the last third is measured)."""


def heave_amplitude(radiation: str, args: Args) -> float:
    scene = with_overrides(load_scene("waves"), fluid__forces="panels", fluid__damping=0.0, fluid__radiation=radiation,
                           waves__period=args.period, waves__height=args.height, step__dt=0.01)  # fmt: skip
    sim = Simulation(scene)
    z = []
    while sim.state.t < args.t_end - 1e-9:
        sim.step(5)
        if sim.state.t > 2 * args.t_end / 3:
            z.append(sim.state.x_world[2])
    return 0.5 * (max(z) - min(z))


def main(args: Args) -> None:
    if args.t_end < 3 * args.period:  # the last third must hold a whole wave period to measure an amplitude
        print(f"05_waves_and_radiation: error: --t-end {args.t_end:g} s is too short a run to measure: its last third must hold a "
              f"wave period (give --t-end {3 * args.period:g} or more)", file=sys.stderr)  # fmt: skip
        raise SystemExit(2)
    alone, with_water = heave_amplitude("none", args), heave_amplitude("bem", args)
    print(
        f"heave amplitude in {args.height:g} m waves of {args.period:g} s: {alone:.4f} m (Froude-Krylov only), {with_water:.4f} m "
        f"(with radiation and diffraction): x{with_water / alone:.2f}"
    )


if __name__ == "__main__":
    main(tyro.cli(Args, description=__doc__))

"""A decay test: a floating sphere rings down by the waves it radiates

The `sphere` preset: a sphere of radius 0.5 m, half submerged, released 10 cm high with no viscous damping. Its
heave period is longer than sqrt(m / k) because the water it moves adds mass, and its swing decays because it
radiates waves (added mass and radiation damping from the preset's shipped Capytaine solve).
"""

import math
from dataclasses import dataclass

import numpy as np
import tyro

from sim import Simulation, load_scene, with_overrides


@dataclass
class Args:
    t_end: float = 10.0
    """Simulated seconds."""


def main(args: Args) -> None:
    sim = Simulation(with_overrides(load_scene("sphere"), step__t_end=args.t_end))
    rest = -0.0  # its centre at rest: on the water line (half submerged)
    t, z = [], []
    while sim.state.t < args.t_end - 1e-9:
        sim.step(1)
        t.append(sim.state.t)
        z.append(sim.state.x_world[2] - rest)
    t, z = np.array(t), np.array(z)
    up = np.flatnonzero((z[:-1] < 0) & (z[1:] >= 0))  # upward crossings of the rest height
    crossings = t[up] - z[up] * (t[up + 1] - t[up]) / (z[up + 1] - z[up])
    body = sim.body
    k = sim.params.rho * sim.params.g * np.pi * 0.5**2  # the water plane's stiffness
    dry = 2 * np.pi * np.sqrt(body.mass / k)
    if len(crossings) < 2 or len(z) < 20:  # no whole period to measure: say so, not "nan"
        print(f"heave period: too short a run to measure ({len(crossings)} upward crossings in {args.t_end:g} s; it rings at over "
              f"{dry:.3f} s: give --t-end {math.ceil(3 * dry)} or more)")  # fmt: skip
        return
    print(
        f"heave period {np.diff(crossings).mean():.3f} s measured ({len(crossings) - 1} periods), "
        f"{dry:.3f} s without the added mass; "
        f"amplitude from {abs(z[: len(z) // 10]).max():.4f} m to {abs(z[-len(z) // 10 :]).max():.4f} m"
    )


if __name__ == "__main__":
    main(tyro.cli(Args, description=__doc__))

"""A force term of your own: a horizontal tether

A term is a function (body, water, fluid, wet, twist, t) -> Load and its line in `sim.hydro.forces.TERMS`; every model, the
CLI and the viewer then include it (docs: Developer guide, Adding a force term). Its compiled twin, the same function
in `sim/kernels/terms.py`, makes it fast; until it has one, a scene using it runs on the numpy reference and says so
(a force is never dropped silently). Here a tether pulls the body's centre back to the vertical through the origin
with stiffness k: the cube then surges with the period 2 pi sqrt(m / k).
"""

import math
from dataclasses import dataclass

import numpy as np
import tyro

import sim
from sim import Simulation, load_scene, with_overrides
from sim.hydro.forces import Load, Term


@dataclass
class Args:
    stiffness: float = 400.0
    """The tether's horizontal stiffness, N/m."""
    t_end: float = 30.0
    """Simulated seconds."""


def tether(k: float):
    def load(body, water, fluid, wet, twist, t) -> Load:
        """-k (x, y, 0) at the centre of mass."""
        return Load(np.array([-k * wet.x[0], -k * wet.x[1], 0.0]), np.zeros(3))

    return Term("tether", load, used=lambda fluid: True)


def main(args: Args) -> None:
    sim.hydro.forces.TERMS = (*sim.hydro.forces.TERMS, tether(args.stiffness))  # the registry line
    scene = with_overrides(load_scene("rest"), initial__position=(0.5, 0.0, -0.4), fluid__damping=0.0)
    run = Simulation(scene)
    print("; ".join(run.notes) or ("compiled" if run.compiled else "on the numpy reference"))
    x, t = [], []
    while run.state.t < args.t_end - 1e-9:
        run.step(4)
        t.append(run.state.t)
        x.append(run.state.x_world[0])
    x, t = np.array(x), np.array(t)
    up = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    closed = 2 * math.pi * math.sqrt(run.body.mass / args.stiffness)
    if len(up) > 1:
        print(f"surge period {np.diff(t[up]).mean():.3f} s on the tether; 2 pi sqrt(m / k) = {closed:.3f} s")
    else:  # no whole period to measure: say so, not "nan"
        print(f"surge period: too short a run to measure ({len(up)} upward crossings in {args.t_end:g} s); 2 pi sqrt(m / k) = {closed:.3f} s: "
              f"give --t-end {math.ceil(2 * closed)} or more")  # fmt: skip
    sim.hydro.forces.TERMS = sim.hydro.forces.TERMS[:-1]  # as it was


if __name__ == "__main__":
    main(tyro.cli(Args, description=__doc__))

"""Mooring lines alone: the OC4-DeepCwind semi's chains under a motion you give, against the elastic catenary

No body and no water loads: MoorDyn moves the three 835 m chains of the OC4 semi (OpenFAST's r-test file, shipped in
assets/moorings) with their fairleads on a platform that surges slowly from rest to an offset, and gives their
tensions (what `python -m sim lines` writes to CSV). A slow pull is quasi-static, so each fairlead's tension is the
elastic catenary's at that offset (sim.lines.catenary): printed side by side.
"""

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import tyro

from sim.lines.catenary import fairlead_tension
from sim.lines.lines_alone import Motion, coupled_points, rotation, run

LINES = Path(__file__).resolve().parents[1] / "assets" / "moorings" / "md_5MW_OC4Semi.dat"
ANCHORS = np.array([(418.8, 725.383, -200.0), (-837.6, 0.0, -200.0), (418.8, -725.383, -200.0)])
WEIGHT = (113.35 - 1025.0 * np.pi * 0.0766**2 / 4) * 9.80665
"""The chain's weight in water, N/m."""


@dataclass
class Args:
    offset: float = 8.0
    """The surge offset reached, m."""
    duration: float = 400.0
    """How long the pull takes, s (slow: quasi-static)."""


def main(args: Args) -> None:
    text = LINES.read_text()
    points = coupled_points(text)
    t = np.linspace(0.0, args.duration, 81)
    surge = 0.5 * args.offset * (1 - np.cos(np.pi * t / args.duration))  # from rest to rest
    positions = np.array([np.array([s, 0.0, 0.0]) + points @ rotation(0.0, 0.0, 0.0).T for s in surge])
    result = run(text, Motion(t, positions), dt=0.05, every=800)
    print(f"{'surge (m)':>10}" + "".join(f"{f'line {i} MoorDyn (kN)':>22}{'catenary':>10}" for i in (1, 2, 3)))
    for k, time in enumerate(result["t"]):
        s = float(np.interp(time, t, surge))
        row = f"{s:>10.2f}"
        for i in (1, 2, 3):
            gap = points[i - 1] + [s, 0.0, 0.0] - ANCHORS[i - 1]
            expected = fairlead_tension(float(np.hypot(*gap[:2])), float(gap[2]), 835.35, WEIGHT, 7.536e8)
            row += f"{result[f'T_fair_{i}'][k] / 1e3:>22.1f}{expected / 1e3:>10.1f}"
        print(row)


if __name__ == "__main__":
    main(tyro.cli(Args, description=__doc__))

"""A farm's power matrix: six point absorbers on a grid, swept over wave height and period

The `farm` preset copies the heaving cube with its take-off damper onto a 2 x 3 grid ([farm] rows, columns, spacing:
one scene of six bodies, d1 to d6). `floatsim sweep` runs it over wave heights and periods; each case's row holds
every device's mean take-off power over the run's second half (d1_power ... d6_power). Read back with pandas, they
give the farm's power matrix, W, heights down and periods across, and each device's share.
"""

import tempfile
from dataclasses import dataclass
from pathlib import Path

import pandas as pd
import tyro

from sim.commands import main as floatsim


@dataclass
class Args:
    heights: str = "0.05:0.15:3"
    """Wave heights, FROM:TO:COUNT, m."""
    periods: str = "1.8:2.6:3"
    """Wave periods, FROM:TO:COUNT, s."""
    t_end: float = 20.0
    """Simulated seconds per case (the second half is measured)."""
    backend: str = "local"
    """serial, local (one process per core) or dask."""
    out: str = ""
    """The results folder (empty: a temporary one)."""


def main(args: Args) -> None:
    out = args.out or tempfile.mkdtemp(prefix="floatsim-farm-")
    status = floatsim(["sweep", "--scene", "farm", "--param", f"height={args.heights}", "--param", f"period={args.periods}",
                       "--t-end", str(args.t_end), "--backend", args.backend, "--out", out])  # fmt: skip
    if status:
        raise SystemExit(status)
    rows = pd.concat(pd.read_parquet(p) for p in sorted(Path(out).glob("chunk-*.parquet")))
    devices = sorted((c for c in rows.columns if c.endswith("_power")), key=lambda c: int(c[1:].split("_")[0]))
    rows["farm"] = rows[devices].sum(axis=1)
    matrix = rows.pivot_table(index="height", columns="period", values="farm")
    print(f"the farm's mean power (W), {len(devices)} devices: wave height (m) down, period (s) across")
    print(matrix.to_string(float_format=lambda v: f"{v:.2f}"))
    share = rows[devices].div(rows["farm"], axis=0).mean()
    print("each device's share of the farm's power: " + ", ".join(f"{c.split('_')[0]} {v:.1%}" for c, v in share.items()))


if __name__ == "__main__":
    main(tyro.cli(Args, description=__doc__))

"""A sweep on a Dask cluster: the period of heave against the drop height

`floatsim sweep` runs the product of parameters as cases, in chunks, on this process, one process per core, or a Dask
cluster (`--backend dask`: a LocalCluster here, or `--scheduler ADDRESS` for yours), writing Parquet as the chunks
finish (a sweep interrupted and run again resumes). Here: the ice cube (draft 0.9 m, 0.1 m above the water) released
from five heights above its rest, read back with pandas: small drops bob with the linear period 2 pi sqrt(m / (rho g A)),
larger ones put its top under water and bob slower.
"""

import math
import tempfile
from dataclasses import dataclass
from pathlib import Path

import pandas as pd
import tyro

from sim.commands import main as floatsim


@dataclass
class Args:
    heights: str = "0.02:0.3:5"
    """Drop heights above the rest height, FROM:TO:COUNT, m."""
    t_end: float = 10.0
    """Simulated seconds per case."""
    backend: str = "dask"
    """serial, local (one process per core) or dask."""
    out: str = ""
    """The results folder (empty: a temporary one)."""


def main(args: Args) -> None:
    out = args.out or tempfile.mkdtemp(prefix="floatsim-sweep-")
    start, stop, count = (float(v) for v in args.heights.split(":"))
    status = floatsim(["sweep", "--scene", "rest", "--param", f"z0={-0.4 + start}:{-0.4 + stop}:{int(count)}", "--t-end", str(args.t_end),
                       "--backend", args.backend, "--out", out])  # fmt: skip
    if status:
        raise SystemExit(status)
    rows = pd.concat(pd.read_parquet(p) for p in sorted(Path(out).glob("chunk-*.parquet"))).sort_values("z0")
    linear = 2 * math.pi * math.sqrt(900.0 / (1000.0 * 9.81))  # m / (rho g A) for the 1 m cube: s rho_b / (rho_w g)
    for _, row in rows.iterrows():
        period = (f"{row['period']:.3f} s" if math.isfinite(row["period"])  # NaN: fewer than two bobs in the run, said so
                  else f"too short a run to measure (give --t-end {math.ceil(3 * linear)} or more)")  # fmt: skip
        print(f"dropped from {row['z0'] + 0.4:.3f} m above its rest: heave period {period} (linear: {linear:.3f} s)")


if __name__ == "__main__":
    main(tyro.cli(Args, description=__doc__))

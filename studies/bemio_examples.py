"""The BEMIO file the `.h5` reader is checked on: SEA-Stack's IEA sphere, a subset of its frequencies, and SEA-Stack's
own decay tests of it.

SEA-Stack (github.com/Project-SEA-Stack/SEA-Stack, MIT License, commit 4d1eae6) ships, in data/demos/run_seastack/
iea_sphere/, the IEA OES Task 10 heave benchmark's floating sphere (5 m in radius, half submerged, 261,800 kg, its
centre of gravity 2 m below its centre, on a heave-only joint):

- assets/hydroData/sphere.h5: BEMIO's file of a WAMIT run (written by WEC-Sim's writeBEMIOH5; rho 1000, g 9.81, 200 m
  of water, 240 frequencies 0.05 to 12 rad/s, heading 0), about the centre of gravity;
- decay_nl_1m/expected/baseline.h5 and decay/expected/baseline.h5: SEA-Stack's (Chrono's) free decays from 1 m above
  rest, 40 s at 0.01 s, with its nonlinear (the body's mesh) and its linear hydrostatics.

Kept here: assets/coefficients/bemio/iea_sphere.h5, every STRIDE-th frequency of the BEMIO file with the datasets
floatsim reads (as the file has them: names, shapes, normalisation), and assets/reference/iea_sphere_decay.csv, every
ROW_STRIDE-th row of the two decays' heave.

Run: python -m studies.bemio_examples PATH/TO/SEA-Stack/data/demos/run_seastack/iea_sphere
"""

from __future__ import annotations

import sys
from pathlib import Path

import h5py
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
COEFFICIENTS = ROOT / "assets" / "coefficients" / "bemio" / "iea_sphere.h5"
REFERENCE = ROOT / "assets" / "reference" / "iea_sphere_decay.csv"
STRIDE, ROW_STRIDE = 2, 5
"""120 of the 240 frequencies (0.1 rad/s apart); the decays every 0.05 s."""
KEPT = ("added_mass/all", "added_mass/inf_freq", "radiation_damping/all", "excitation/re", "excitation/im", "excitation/mag",
        "excitation/phase", "linear_restoring_stiffness")  # fmt: skip
PROPERTIES = ("cg", "cb", "disp_vol", "name", "body_number", "dof")
PARAMETERS = ("rho", "g", "water_depth", "wave_dir", "scaled")


def coefficients(source: Path, target: Path) -> None:
    """`source`'s datasets floatsim reads, at every STRIDE-th frequency."""
    target.parent.mkdir(parents=True, exist_ok=True)
    with h5py.File(source, "r") as f, h5py.File(target, "w") as out:
        out.attrs["source"] = "SEA-Stack (MIT License) commit 4d1eae6, data/demos/run_seastack/iea_sphere/assets/hydroData/sphere.h5"
        out["bem_data/code"] = f["bem_data/code"][()]
        for name in PARAMETERS:
            out[f"simulation_parameters/{name}"] = f[f"simulation_parameters/{name}"][()]
        for name in ("w", "T"):
            out[f"simulation_parameters/{name}"] = f[f"simulation_parameters/{name}"][()][::STRIDE]
        for name in PROPERTIES:
            out[f"body1/properties/{name}"] = f[f"body1/properties/{name}"][()]
        for name in KEPT:
            values = f[f"body1/hydro_coeffs/{name}"][()]
            out[f"body1/hydro_coeffs/{name}"] = values[..., ::STRIDE] if name.endswith(("all", "re", "im", "mag", "phase")) else values


def decays(folder: Path, target: Path) -> None:
    """The nonlinear and linear decays' heave of SEA-Stack's body (its centre of gravity), every ROW_STRIDE-th row."""
    columns = {}
    for case, name in (("decay_nl_1m", "z_nonlinear"), ("decay", "z_linear")):
        with h5py.File(folder / case / "expected" / "baseline.h5", "r") as f:
            columns["t"] = f["results/time/time"][()][ROW_STRIDE - 1 :: ROW_STRIDE]
            columns[name] = f["results/model/bodies/body1/position"][()][ROW_STRIDE - 1 :: ROW_STRIDE, 2]
    target.parent.mkdir(parents=True, exist_ok=True)
    header = ("# SEA-Stack (MIT License) commit 4d1eae6, data/demos/run_seastack/iea_sphere/{decay_nl_1m,decay}/expected/"
              "baseline.h5: the IEA sphere's heave (its centre of gravity, m) released 1 m above rest, with nonlinear and "
              "linear hydrostatics (python -m studies.bemio_examples)\n")  # fmt: skip
    rows = np.column_stack([columns["t"], columns["z_nonlinear"], columns["z_linear"]])
    target.write_text(header + "t,z_nonlinear,z_linear\n" + "\n".join(f"{t:.2f},{a:.6f},{b:.6f}" for t, a, b in rows) + "\n")


def main(folder: Path) -> None:
    coefficients(folder / "assets" / "hydroData" / "sphere.h5", COEFFICIENTS)
    decays(folder, REFERENCE)
    print(f"{COEFFICIENTS.relative_to(ROOT)} ({COEFFICIENTS.stat().st_size // 1024} KB), {REFERENCE.relative_to(ROOT)}")


if __name__ == "__main__":
    main(Path(sys.argv[1]))

"""The mean wave drift force from WAMIT's numeric files `.8` (momentum conservation: surge, sway and yaw only) and
`.9` (pressure integration: all six modes), the files BEMIO, HydroDyn (`MnDrift = 8` or `9`) and OrcaFlex read.

Their rows (WAMIT User Manual v7, section 4.7): `PER BETA1 BETA2 I Mod Pha Re Im` of the mean force per unit wave
amplitude squared in the bichromatic pair of headings (BETA1, BETA2), nondimensional: F = rho g L Fbar (forces),
rho g L^2 Fbar (moments), with L the run's ULEN. A unidirectional sea needs BETA1 = BETA2 only; the mean of a
regular wave is real, so Re is read (Im is zero to round-off). Negative modes (a `.9`'s -4, -5, -6: the moments about
another point some versions add) and rows at other heading pairs are left out.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sim.errors import ConfigError
from sim.io.wamit_numeric import rows

DRIFT = (".8", ".9")
MODES = {1: 0, 2: 1, 6: 2}
"""WAMIT's mode -> floatsim's drift component (F_x, F_y, M_z)."""


def read_drift(path: Path, rho: float, g: float, ulen: float = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(periods s, headings degrees, (n, m, 3) D: F_x, F_y in N/m², M_z in N m/m²) of a `.8` or `.9` at `path`: the mean
    drift per unit wave amplitude squared at each period and heading (BETA1 = BETA2), one body."""
    table = rows(path, (8,))
    same = np.isclose(table[:, 1], table[:, 2]) & np.isin(table[:, 3], list(MODES))
    table = table[same]
    if not len(table):
        raise ConfigError(f"[fluid] bem_file {str(path)!r}: no surge, sway or yaw drift at equal headings (a {path.suffix} file?)")
    periods, headings = np.unique(table[:, 0]), np.unique(table[:, 1])
    D = np.zeros((len(periods), len(headings), 3))
    n, m = np.searchsorted(periods, table[:, 0]), np.searchsorted(headings, table[:, 1])
    mode = np.array([MODES[int(i)] for i in table[:, 3]])
    scale = np.where(mode == 2, rho * g * ulen**2, rho * g * ulen)
    D[n, m, mode] = table[:, 6] * scale
    counts = np.bincount(n * len(headings) + m, minlength=len(periods) * len(headings))
    if counts.min() == 0:
        raise ConfigError(f"[fluid] bem_file {str(path)!r}: not every period has every heading ({len(headings)}) (a cut file?)")
    return periods, headings, D

"""The mean wave drift force from WAMIT's numeric files `.8` (momentum conservation: surge, sway and yaw only) and
`.9` (pressure integration: all six modes), the files BEMIO, HydroDyn (`MnDrift = 8` or `9`) and OrcaFlex read.

Their rows (WAMIT User Manual v7, section 4.7): `PER BETA1 BETA2 I Mod Pha Re Im` of the mean force per unit wave
amplitude squared in the bichromatic pair of headings (BETA1, BETA2), nondimensional: F = rho g L Fbar (forces),
rho g L^2 Fbar (moments), with L the run's ULEN. A unidirectional sea needs BETA1 = BETA2 only; the mean of a
regular wave is real, so Re is read (Im is zero to round-off). Negative modes (a `.9`'s -4, -5, -6: the moments about
another point some versions add) and rows at other heading pairs are left out. Several bodies' rows are modes 7, 8,
12 ... (the second body's surge, sway, yaw), each body's moment about its own origin XBODY.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sim.errors import ConfigError
from sim.io.wamit_numeric import rows

DRIFT = (".8", ".9")
MODES = {1: 0, 2: 1, 6: 2}
"""WAMIT's mode -> floatsim's drift component (F_x, F_y, M_z)."""


def read_drift(path: Path, rho: float, g: float, ulen: float = 1.0, bodies: int = 1) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(periods s, headings degrees, (n, m, bodies, 3) D: F_x, F_y in N/m², M_z in N m/m² about each body's origin) of a
    `.8` or `.9` at `path`: the mean drift per unit wave amplitude squared at each period and heading (BETA1 = BETA2)."""
    table = rows(path, (8,))
    body, local = (table[:, 3].astype(int) - 1) // 6, (table[:, 3].astype(int) - 1) % 6 + 1
    same = np.isclose(table[:, 1], table[:, 2]) & np.isin(local, list(MODES)) & (table[:, 3] > 0) & (body < bodies)
    table, body, local = table[same], body[same], local[same]
    if not len(table):
        raise ConfigError(f"[fluid] bem_file {str(path)!r}: no surge, sway or yaw drift at equal headings (a {path.suffix} file?)")
    periods, headings = np.unique(table[:, 0]), np.unique(table[:, 1])
    D = np.zeros((len(periods), len(headings), bodies, 3))
    n, m = np.searchsorted(periods, table[:, 0]), np.searchsorted(headings, table[:, 1])
    mode = np.array([MODES[int(i)] for i in local])
    scale = np.where(mode == 2, rho * g * ulen**2, rho * g * ulen)
    D[n, m, body, mode] = table[:, 6] * scale
    counts = np.bincount(n * len(headings) + m, minlength=len(periods) * len(headings))
    if counts.min() == 0:
        raise ConfigError(f"[fluid] bem_file {str(path)!r}: not every period has every heading ({len(headings)}) (a cut file?)")
    return periods, headings, D

"""Second-order wave forces from WAMIT's numeric files `.12d` (difference frequency) and `.12s` (sum frequency), the
quadratic transfer functions (QTFs) HydroDyn (`DiffQTF = 12`, `SumQTF = 12`), OrcaFlex and BEMIO read.

Their rows (WAMIT User Manual v7, section 4.10): `PER_i PER_j BETA_i BETA_j I Mod Pha Re Im`, the force in mode I per
unit amplitude of each wave of the bichromatic pair (periods PER_i, PER_j, headings BETA_i, BETA_j in degrees),
nondimensional: F = rho g L Fbar (forces), rho g L^2 Fbar (moments), L the run's ULEN. WAMIT's time factor is
e^(i omega t): the difference force is Re sum_ij a_i a_j^* T-_ij e^(i (omega_i - omega_j) t), the sum force
Re sum_ij a_i a_j T+_ij e^(i (omega_i + omega_j) t); in floatsim's e^(-i omega t) both are conjugated. A file holds one
triangle of the period pairs; the other follows: T-(j, i) = conj T-(i, j), T+(j, i) = T+(i, j) (each with its headings
swapped). The difference QTF's diagonal is the mean drift (`.8`/`.9`). Modes 7 to 12 ... are the next body's;
negative modes (moments about another point) are left out.

Read and kept for the second-order forces a scene will ask for (issue 61): no run reads them yet.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sim.errors import ConfigError
from sim.io.wamit_numeric import rows

QTF = {".12d": "difference", ".12s": "sum"}


@dataclass(frozen=True)
class Qtf:
    """One body's (or several bodies') quadratic transfer functions of one kind, dimensional, floatsim's time factor."""

    kind: str
    """"difference" or "sum"."""
    omega: np.ndarray
    """(n,) rad/s, ascending."""
    headings: np.ndarray
    """(m,) rad, ascending, in the file's own range (not wrapped to [0, 2 pi) as Coefficients.headings are)."""
    T: np.ndarray
    """(n, n, m, m, 6k) complex: N/m² (forces) and N m/m² (moments) per unit amplitude of each wave; T[i, j, a, b] for
    the waves omega_i from headings[a] and omega_j from headings[b]."""
    filled: np.ndarray
    """(n, n, m, m) bool: the entries the file gives, directly or by the other triangle's symmetry."""

    def mean_drift(self) -> np.ndarray:
        """(n, m, 6k) the mean force of a regular wave of each frequency and heading: the difference QTF's diagonal."""
        if self.kind != "difference":
            raise ValueError("the mean drift is the difference QTF's diagonal")
        n, m = len(self.omega), len(self.headings)
        return self.T[np.arange(n), np.arange(n)][:, np.arange(m), np.arange(m)].real


def read_qtf(path: Path, rho: float, g: float, ulen: float = 1.0) -> Qtf:
    """The `.12d` or `.12s` file at `path`: one-line ConfigError for a file that is not one or is cut."""
    kind = QTF.get(path.suffix.lower())
    if kind is None:
        raise ConfigError(f"{str(path)!r}: a QTF file is WAMIT's .12d (difference) or .12s (sum)")
    table = rows(path, (9,))
    table = table[table[:, 4] > 0]
    if not len(table):
        raise ConfigError(f"{str(path)!r} holds no second-order force rows")
    periods = np.unique(np.concatenate([table[:, 0], table[:, 1]]))
    if periods[0] <= 0:
        raise ConfigError(f"{str(path)!r}: a period of {periods[0]:g} s (the QTFs are at finite periods)")
    headings = np.unique(np.concatenate([table[:, 2], table[:, 3]]))
    modes = int(table[:, 4].max())
    bodies = math.ceil(modes / 6)
    order = np.argsort(2 * math.pi / periods)  # ascending frequency
    omega = (2 * math.pi / periods)[order]
    where = np.empty(len(periods), int)
    where[order] = np.arange(len(periods))
    i, j = where[np.searchsorted(periods, table[:, 0])], where[np.searchsorted(periods, table[:, 1])]
    a, b = np.searchsorted(headings, table[:, 2]), np.searchsorted(headings, table[:, 3])
    mode = table[:, 4].astype(int) - 1
    rotation = (mode % 6) >= 3
    value = np.conj(table[:, 7] + 1j * table[:, 8]) * rho * g * np.where(rotation, ulen**2, ulen)
    T = np.zeros((len(omega), len(omega), len(headings), len(headings), 6 * bodies), complex)
    filled = np.zeros(T.shape[:4], bool)
    mirrored = np.conj(value) if kind == "difference" else value
    T[j, i, b, a, mode] = mirrored  # the other triangle first: the file's own rows win on the diagonal
    T[i, j, a, b, mode] = value
    filled[j, i, b, a] = filled[i, j, a, b] = True
    _, per_pair = np.unique(np.minimum(i, j) * len(omega) + np.maximum(i, j), return_counts=True)
    if len(per_pair) != len(omega) * (len(omega) + 1) // 2:
        raise ConfigError(f"{str(path)!r}: {len(per_pair)} of the {len(omega) * (len(omega) + 1) // 2} pairs of its {len(omega)} periods "
                          "(a cut file?)")  # fmt: skip
    if per_pair.min() != per_pair.max():
        raise ConfigError(f"{str(path)!r}: some pairs of periods have {per_pair.min()} rows, others {per_pair.max()} (its heading pairs "
                          "and modes: a file cut inside a pair?)")  # fmt: skip
    return Qtf(kind, omega, np.radians(headings), T, filled)

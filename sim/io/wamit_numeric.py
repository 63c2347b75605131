"""Radiation and excitation coefficients from WAMIT's numeric output files: `.1` (added mass and damping), `.3`
(excitation) and `.hst` (hydrostatics), the files OpenFAST's HydroDyn, OrcaFlex and BEMIO read and Capytaine 3
(`capytaine.io.wamit.export_to_wamit`) and pyHAMS write.

Their rows (WAMIT User Manual v7, section 4.2), one coefficient each, nondimensional as in the `.out` (sim/io/wamit.py):

- `.1`: `PER I J Abar(I,J) Bbar(I,J)`; PER = -1 is the infinite period (A at zero frequency, no damping), PER = 0 the
  zero period (A at infinite frequency); A = rho L^k Abar, B = rho omega L^k Bbar (k = 3, 4, 5 as I and J are
  translations or rotations);
- `.3`: `PER BETA I Mod Pha Re Im` of Xbar per unit wave amplitude, time factor e^(i omega t): X = rho g L^m Xbar
  (m = 2 forces, 3 moments), conjugated to floatsim's e^(-i omega t); Re and Im are read (Pha has fewer digits);
- `.hst`: `I J Cbar(I,J)`, C = rho g L^k Cbar (k = 2 + the number of rotations among I and J).

Entries a file leaves out are zero. What the numeric files do not hold (g, the length scale ULEN, each body's
origin XBODY and centre of gravity, the depth, the panel count) is read from the run's `.out` beside them when there
is one; without it they are taken as WAMIT's defaults for one body: ULEN = 1, the scene's g and depth, the body's
origin at the world's origin, and its centre of gravity where the scene's body has its centre of mass.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sim.errors import ConfigError
from sim.io.wamit import WamitRun, read_out

NUMERIC = (".1", ".3", ".hst")


@dataclass
class Assumed:
    """What the numeric files do not say, when no `.out` says it."""

    g: float
    depth: float
    gravity_centers: np.ndarray
    """(k, 3) m."""


def rows(path: Path, columns: tuple[int, ...]) -> np.ndarray:
    """The numeric rows of `path` ((r, c) floats, each row one of `columns` long, shorter ones padded with NaN): a title
    line at the top is skipped; any other line that is not one is a one-line ConfigError naming it (a cut file)."""
    try:
        lines = path.read_text(errors="replace").splitlines()
    except OSError as e:
        raise ConfigError(f"[fluid] bem_file {str(path)!r}: {e.strerror or e}") from None
    width = max(columns)
    out = []
    for n, line in enumerate(lines, 1):
        words = line.replace("D", "E").replace("d", "e").split()
        if not words:
            continue
        try:
            values = [float(w) for w in words]
        except ValueError:
            if not out and n <= 2:
                continue  # a title ("WAMIT Numeric Output -- Filename ...")
            raise ConfigError(f"[fluid] bem_file {str(path)!r}, line {n}: not a row of numbers: {line.strip()[:60]!r}") from None
        if len(values) not in columns:
            raise ConfigError(f"[fluid] bem_file {str(path)!r}, line {n}: {len(values)} numbers, a {path.suffix} row has "
                              f"{' or '.join(map(str, columns))} (a cut or another file?)")  # fmt: skip
        out.append(values + [math.nan] * (width - len(values)))
    if not out:
        raise ConfigError(f"[fluid] bem_file {str(path)!r} holds no rows of numbers")
    return np.array(out)


def columns_of(path: Path) -> int:
    """How many numbers the first row of `path` holds: 4 or 5 for a `.1`, 7 for a `.3`, 3 for a `.hst` (0: none)."""
    try:
        with open(path, errors="replace") as f:
            for n, line in zip(range(50), f):
                if not line.split():
                    continue  # a blank line
                try:
                    return len([float(w) for w in line.replace("D", "E").split()])
                except ValueError:
                    continue
    except OSError:
        return 0
    return 0


def beside(path: Path, suffix: str) -> Path:
    """The file of the same WAMIT run as `path` with `suffix`: its whole name less its own suffix (cyl_0.5m.1 ->
    cyl_0.5m.3, not cyl_0.3)."""
    return path.with_name(path.stem + suffix)


def _powers(d: int, base: int) -> np.ndarray:
    """(d, d) the length scale's power of each entry: base + the number of rotations among I and J."""
    rotation = (np.arange(d) % 6) >= 3
    return base + rotation[:, None].astype(int) + rotation[None, :].astype(int)


def read_numeric(path: Path, rho: float, assumed: Assumed) -> tuple[WamitRun, bool]:
    """The coefficients of the WAMIT run whose `.1` (or `.3`, `.hst`) is `path`, and whether its `.out` was beside it.
    One-line ConfigError on a missing, cut or inconsistent file."""
    one, three, out = (beside(path, suffix) for suffix in (".1", ".3", ".out"))
    for need in (one, three):
        if not need.is_file():
            raise ConfigError(f"[fluid] bem_file {str(path)!r}: WAMIT's numeric files come as {one.name} (added mass and damping) "
                              f"and {three.name} (excitation); {need.name} is not beside it")  # fmt: skip
    meta = read_out(out, rho) if out.is_file() else None
    g = meta.g if meta else assumed.g
    L = meta.length if meta else 1.0
    A1 = rows(one, (4, 5))
    d = 6 * math.ceil(int(np.nanmax(A1[:, 1:3])) / 6)
    if meta is None and d > 6:
        raise ConfigError(f"[fluid] bem_file {str(path)!r} holds {d // 6} bodies: put the run's .out beside it (it says where each "
                          "body's origin is)")  # fmt: skip
    if meta is not None and meta.added_mass.shape[1] != d:
        raise ConfigError(f"[fluid] bem_file {str(path)!r} holds {d // 6} bodies, its {out.name} {meta.added_mass.shape[1] // 6}")
    period = A1[:, 0]
    periods = np.unique(period[period > 0])
    if not len(periods):
        raise ConfigError(f"[fluid] bem_file {str(one)!r} has no wave periods (only PER = -1 or 0 rows)")
    if not np.any(period == 0):
        raise ConfigError(f"[fluid] bem_file {str(one)!r} has no PER = 0 rows (the added mass at infinite frequency)")
    A_inf = _square(A1[period == 0], d, 3, one)
    A, B = np.zeros((len(periods), d, d)), np.zeros((len(periods), d, d))
    full = None
    for n, T in enumerate(periods):
        at = A1[period == T]
        if np.isnan(at[:, 4]).any():
            raise ConfigError(f"[fluid] bem_file {str(one)!r}: a row at T = {T:g} s without its damping")
        A[n], B[n] = _square(at, d, 3, one), _square(at, d, 4, one)
        pairs = {(int(i), int(j)) for i, j in at[:, 1:3]}
        full = pairs if full is None else full
        if pairs != full:
            raise ConfigError(f"[fluid] bem_file {str(one)!r}: T = {T:g} s has {len(pairs)} entries, the other periods "
                              f"{len(full)} (a cut file?)")  # fmt: skip
    headings, X = _excitation(three, periods, d)
    omega = 2 * math.pi / periods
    order = np.argsort(omega)
    omega = omega[order]
    k = _powers(d, 3)
    scale = rho * L**k
    turn = np.mod(np.radians(headings), 2 * math.pi)
    by_heading = np.argsort(turn)
    m = np.where((np.arange(d) % 6) < 3, 2, 3)
    X = np.conj(X[order][:, by_heading]) * rho * g * L**m
    if meta is not None:
        centers, gravity_centers, depth, panels = meta.centers, meta.gravity_centers, meta.depth, meta.panels
    else:
        centers, gravity_centers, depth, panels = np.zeros((1, 3)), assumed.gravity_centers, assumed.depth, 0
    run = WamitRun(omega, A[order] * scale, B[order] * scale * omega[:, None, None], A_inf * scale, turn[by_heading], X, centers,
                   gravity_centers, depth, g, panels, L)  # fmt: skip
    return run, meta is not None


def _square(at: np.ndarray, d: int, column: int, path: Path) -> np.ndarray:
    """(d, d) from rows `PER I J values...`: the values in `column`."""
    M = np.zeros((d, d))
    i, j = at[:, 1].astype(int) - 1, at[:, 2].astype(int) - 1
    if i.min() < 0 or j.min() < 0:
        raise ConfigError(f"[fluid] bem_file {str(path)!r}: a mode number below 1")
    M[i, j] = at[:, column]
    return M


def _excitation(path: Path, periods: np.ndarray, d: int) -> tuple[np.ndarray, np.ndarray]:
    """(headings in degrees, (n, m, d) complex as printed: e^(i omega t)) of the `.3` at `path`, at `periods`."""
    X3 = rows(path, (7,))
    headings = np.unique(X3[:, 1])
    missing = sorted(set(periods.tolist()) - set(X3[:, 0].tolist()))
    if missing:
        raise ConfigError(f"[fluid] bem_file {str(path)!r} lacks the excitation at {len(missing)} of the .1's periods "
                          f"(T = {missing[0]:g} s first): the files of two runs, or a cut file?")  # fmt: skip
    X = np.zeros((len(periods), len(headings), d), complex)
    n = np.searchsorted(periods, X3[:, 0])
    keep = (n < len(periods)) & (periods[np.minimum(n, len(periods) - 1)] == X3[:, 0])
    m = np.searchsorted(headings, X3[:, 1])
    i = X3[:, 2].astype(int) - 1
    if i.max() >= d:
        raise ConfigError(f"[fluid] bem_file {str(path)!r}: mode {i.max() + 1} with {d // 6} bodies in the .1")
    X[n[keep], m[keep], i[keep]] = X3[keep, 5] + 1j * X3[keep, 6]
    counts = np.bincount(n[keep] * len(headings) + m[keep], minlength=len(periods) * len(headings))
    if counts.min() == 0:
        raise ConfigError(f"[fluid] bem_file {str(path)!r}: not every period has every heading ({len(headings)}) (a cut file?)")
    if counts.min() != counts.max():
        raise ConfigError(f"[fluid] bem_file {str(path)!r}: {counts.min()} modes at one period and heading, {counts.max()} at another "
                          "(a cut file?)")  # fmt: skip
    return headings, X


def stiffness(path: Path, run: WamitRun, rho: float) -> np.ndarray | None:
    """(d, d) the hydrostatic stiffness in the `.hst` beside `path` of the run `run`, N/m, N and N m (None when there is
    none)."""
    d, g, L = run.added_mass.shape[1], run.g, run.length
    hst = beside(path, ".hst")
    if not hst.is_file():
        return None
    C = rows(hst, (3,))
    M = np.zeros((d, d))
    i, j = C[:, 0].astype(int) - 1, C[:, 1].astype(int) - 1
    if max(i.max(), j.max()) >= d:
        raise ConfigError(f"[fluid] bem_file {str(hst)!r}: mode {max(i.max(), j.max()) + 1} with {d // 6} bodies in the .1")
    M[i, j] = C[:, 2]
    return M * rho * g * L ** _powers(d, 2)

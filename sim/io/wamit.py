"""Radiation and excitation coefficients from WAMIT's output file (`.out`), the format WEC-Sim's BEMIO reads first.

A scene names such a file with `[fluid] bem_file` instead of letting Capytaine solve its bodies: a WAMIT user's own
run, or the one a cross-code check must share with the code it is compared with (WEC-Sim's RM3 in
docs/accuracy.md). What is read (WAMIT User Manual v7, chapter 4, "Output"):

- the body count and each body's origin (XBODY, YBODY, ZBODY: rotations are about it), the water depth, g and the
  length scale L;
- per wave period: ADDED-MASS AND DAMPING COEFFICIENTS (the 6k x 6k matrices, k bodies), and the excitation
  (DIFFRACTION EXCITING FORCES AND MOMENTS, else the HASKIND ones: either is the whole linear excitation, the
  incident wave's pressure and the scattered wave's) at every heading; the "Wave period = zero" block's added mass
  is A at infinite frequency (the "infinite" one, A at zero frequency, is not needed).

WAMIT prints them without dimensions, about each body's origin: A_ij = rho L^k Abar_ij and B_ij = rho omega L^k
Bbar_ij (k = 3, 4 or 5 as i and j are translations or rotations), X_i = rho g L^m Xbar_i per unit wave amplitude
(m = 2 for forces, 3 for moments). Its time factor is e^(i omega t), floatsim's (and Capytaine's) e^(-i omega t):
X is conjugated. Its phases are printed in whole degrees, so the excitation carries up to 0.9 % of rounding.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sim.errors import ConfigError

NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[EeDd][-+]?\d+)?"
_ROW = re.compile(rf"^\s*(\d+)\s+(\d+)\s+({NUMBER})(?:\s+({NUMBER}))?\s*$")
_FORCE = re.compile(rf"^\s*(\d+)\s+({NUMBER})\s+({NUMBER})\s*$")
_PERIOD = re.compile(rf"Wave period \(sec\)\s*=\s*({NUMBER})")
_BODY = re.compile(rf"XBODY\s*=\s*({NUMBER})\s+YBODY\s*=\s*({NUMBER})\s+ZBODY\s*=\s*({NUMBER})")
_CG = re.compile(rf"Center of Gravity\s*\(Xg,Yg,Zg\):\s*({NUMBER})\s+({NUMBER})\s+({NUMBER})")
_HEADING = re.compile(rf"Wave Heading \(deg\)\s*:\s*({NUMBER})")


@dataclass
class WamitRun:
    """One WAMIT run's coefficients, with dimensions (SI), frequencies increasing."""

    omega: np.ndarray
    """(n,) rad/s."""
    added_mass: np.ndarray
    """(n, 6k, 6k)."""
    damping: np.ndarray
    """(n, 6k, 6k)."""
    added_mass_inf: np.ndarray
    """(6k, 6k)."""
    headings: np.ndarray
    """(m,) rad, increasing in [0, 2 pi)."""
    excitation: np.ndarray
    """(n, m, 6k) complex, per unit wave amplitude, time factor e^(-i omega t), phase of the wave at the origin."""
    centers: np.ndarray
    """(k, 3) each body's origin XBODY (the point its rotations and moments are about), m."""
    gravity_centers: np.ndarray
    """(k, 3) each body's centre of gravity XBODY + (Xg, Yg, Zg), m (its body axes taken parallel to the world's)."""
    depth: float
    """m (inf: deep water)."""
    g: float
    panels: int
    """How many panels the bodies had, together."""
    length: float = 1.0
    """WAMIT's length scale ULEN, m (its nondimensional coefficients' L)."""


def read_out(path: Path, rho: float) -> WamitRun:
    """The coefficients in WAMIT's `.out` file at `path`, for water of density `rho` (WAMIT's own output has none):
    one-line ConfigError on a file that is not one."""
    try:
        text = Path(path).read_text(errors="replace")
    except OSError as e:
        raise ConfigError(f"[fluid] bem_file {str(path)!r}: {e.strerror or e}") from None
    try:
        return _parse(text, rho)
    except (ValueError, IndexError, KeyError) as e:
        raise ConfigError(f"[fluid] bem_file {str(path)!r} is not a WAMIT output file floatsim can read ({e})") from None


def _value(pattern: str, text: str, default=None) -> float:
    found = re.search(pattern, text)
    if found is None:
        if default is None:
            raise ValueError(f"no {pattern.split('[')[0].split('(')[0].strip()!r}")
        return default
    return float(found.group(1).replace("D", "E").replace("d", "e"))


def _parse(text: str, rho: float) -> WamitRun:
    g = _value(rf"Gravity:\s*({NUMBER})", text)
    L = _value(rf"Length scale:\s*({NUMBER})", text, 1.0)
    depth_text = re.search(r"Water depth:\s*(\S+)", text)
    depth = math.inf if depth_text is None or depth_text.group(1).lower().startswith("inf") else float(depth_text.group(1))
    centers = np.array([[float(v) for v in m.groups()] for m in _BODY.finditer(text)]) * L
    if not len(centers):
        raise ValueError("no body origins (XBODY)")
    cg = np.array([[float(v) for v in m.groups()] for m in _CG.finditer(text)]) * L
    gravity_centers = centers + (cg if cg.shape == centers.shape else 0.0)
    d = 6 * len(centers)
    translation = (np.arange(d) % 6) < 3
    power = np.where(translation[:, None] & translation[None, :], 3, np.where(~translation[:, None] & ~translation[None, :], 5, 4))
    moment = np.where(translation, 2, 3)
    blocks = re.split(r"\n\s*\*{20,}\s*\n", text)
    periods, A, B, X, headings, A_inf = [], [], [], [], None, None
    for block in blocks:
        if re.search(r"Wave period = zero", block):
            A_inf = _matrix(block, d, with_damping=False)
            continue
        found = _PERIOD.search(block)
        if found is None:
            continue
        T = float(found.group(1))
        a, b = _matrix(block, d, with_damping=True)
        beta, x = _excitation(block, d)
        if headings is None:
            headings = beta
        elif len(beta) != len(headings) or not np.allclose(beta, headings):
            raise ValueError(f"the headings differ between periods (at T = {T:g} s)")
        periods.append(T)
        A.append(a)
        B.append(b)
        X.append(x)
    if not periods:
        raise ValueError("no wave periods with added mass and damping")
    if A_inf is None:
        raise ValueError("no 'Wave period = zero' block (the added mass at infinite frequency)")
    omega = 2 * math.pi / np.array(periods)
    order = np.argsort(omega)
    if np.any(np.diff(omega[order]) <= 0):
        raise ValueError("a wave period given twice")
    omega = omega[order]
    A = np.array(A)[order] * rho * L**power
    B = np.array(B)[order] * rho * L**power * omega[:, None, None]
    turn = np.mod(np.radians(headings), 2 * math.pi)
    by_heading = np.argsort(turn)
    X = np.conj(np.array(X)[order][:, by_heading]) * rho * g * L**moment
    panels = sum(int(n) for n in re.findall(r"Total panels:\s*(\d+)", text))
    depth = depth * L if math.isfinite(depth) else depth
    return WamitRun(omega, A, B, A_inf * rho * L**power, turn[by_heading], X, centers, gravity_centers, depth, g, panels, L)


def _matrix(block: str, d: int, with_damping: bool):
    """The block's added mass (and damping) matrices, from their "I J A(I,J) [B(I,J)]" rows; entries WAMIT leaves out
    (below its print threshold) are zero."""
    start = block.find("ADDED-MASS")
    if start < 0:
        raise ValueError("a period without ADDED-MASS coefficients")
    a, b = np.zeros((d, d)), np.zeros((d, d))
    for line in block[start:].splitlines()[1:]:
        row = _ROW.match(line)
        if row is None:
            if re.search(r"[A-Za-z]{4}", line) and "A(I,J)" not in line:
                break  # the next section
            continue
        i, j = int(row.group(1)) - 1, int(row.group(2)) - 1
        if i >= d or j >= d:
            raise ValueError(f"mode {max(i, j) + 1} with {d // 6} bodies")
        a[i, j] = float(row.group(3))
        if with_damping:
            if row.group(4) is None:
                raise ValueError("an added-mass row without its damping")
            b[i, j] = float(row.group(4))
    return (a, b) if with_damping else a


def _excitation(block: str, d: int) -> tuple[np.ndarray, np.ndarray]:
    """(headings in degrees, (m, d) complex) of the block's DIFFRACTION (else HASKIND) exciting forces, as printed."""
    start = block.find("DIFFRACTION EXCITING FORCES")
    if start < 0:
        start = block.find("HASKIND EXCITING FORCES")
    if start < 0:
        raise ValueError("a period without DIFFRACTION or HASKIND exciting forces")
    headings, rows = [], []
    for line in block[start:].splitlines()[1:]:
        heading = _HEADING.search(line)
        if heading is not None:
            headings.append(float(heading.group(1)))
            rows.append(np.zeros(d, complex))
            continue
        force = _FORCE.match(line)
        if force is not None and rows:
            i = int(force.group(1)) - 1
            if i >= d:
                raise ValueError(f"mode {i + 1} with {d // 6} bodies")
            rows[-1][i] = float(force.group(2)) * np.exp(1j * math.radians(float(force.group(3))))
        elif re.search(r"[A-Za-z]{4}", line) and "Mod[" not in line and heading is None:
            break  # the next section (a RAO, drift forces, ...)
    if not headings:
        raise ValueError("exciting forces without a wave heading")
    return np.array(headings), np.array(rows)

"""Mooring lines alone: MoorDyn driven by a prescribed motion of its coupled points, giving the lines' tensions.

What OpenFAST's MoorDyn driver does with its time-series inputs (InputsMode 1), and what MoorDyn's own users ask for
(MoorDyn issue 363): no body, no water loads, only the lines under a motion you give. The lines are a MoorDyn v2 input
file; its Coupled (or Vessel) points are the ones moved. The motion is a table with a time column and either
- 6 columns: a rigid body's x, y, z (m) and roll, pitch, yaw (rad, R = Rz(yaw) Ry(pitch) Rx(roll)), the coupled points
  at their file positions when the body is at zero (OpenFAST's platform reference point), or
- 3 columns per coupled point (its world position, m, in the file's order).
Velocities are the derivative of a cubic spline through the positions (second order between samples). MoorDyn starts
from the lines' rest shape with the points held at the first sample (its Init, the static start OpenFAST's driver makes
too), then steps over each dt with the points at the spline's position and velocity at the step's start (as a coupled
run does, lines/moorings.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sim.errors import ConfigError
from sim.lines.moorings import Moorings


@dataclass(frozen=True)
class Motion:
    t: np.ndarray
    """(n,) s, increasing."""
    positions: np.ndarray
    """(n, k, 3) each coupled point's position, world, m."""

    def at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """((k, 3) positions, (k, 3) velocities) at t, from the cubic spline."""
        if not hasattr(self, "_spline"):
            from scipy.interpolate import CubicSpline

            object.__setattr__(self, "_spline", CubicSpline(self.t, self.positions.reshape(len(self.t), -1), axis=0))
        spline = self._spline
        return spline(t).reshape(-1, 3), spline(t, 1).reshape(-1, 3)


def rotation(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """R = Rz(yaw) Ry(pitch) Rx(roll): body to world."""
    cr, sr, cp, sp, cy, sy = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch), math.cos(yaw), math.sin(yaw)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])  # fmt: skip


def read_table(path: Path) -> np.ndarray:
    """The numeric rows of a whitespace- or comma-separated table (header and comment lines skipped), (n, m)."""
    rows = []
    for number, line in enumerate(Path(path).read_text().splitlines(), 1):
        fields = line.replace(",", " ").split()
        if not fields or line.lstrip().startswith("#"):
            continue
        try:
            rows.append([float(f) for f in fields])
        except ValueError:
            if rows:
                raise ConfigError(f"{path}: line {number} is not numbers after the table started: {line.strip()[:60]!r}") from None
    if len(rows) < 4 or len({len(r) for r in rows}) != 1:
        raise ConfigError(f"{path}: the motion needs at least 4 rows of the same number of columns (time first)")
    return np.array(rows)


def motion_of(table: np.ndarray, points: np.ndarray, where: str = "the motion") -> Motion:
    """The coupled points' motion from a table (time, then a body's 6 coordinates or 3 per point); `points` (k, 3) the
    points' positions in the lines file."""
    t, k = table[:, 0], len(points)
    if not np.all(np.diff(t) > 0):
        raise ConfigError(f"{where}: its times must increase")
    columns = table.shape[1] - 1
    if columns == 3 * k and (k != 2 or columns != 6):  # (two points and six columns would be ambiguous: a body's is meant)
        return Motion(t, table[:, 1:].reshape(len(t), k, 3))
    if columns == 6:
        positions = np.array([row[:3] + points @ rotation(*row[3:]).T for row in table[:, 1:]])
        return Motion(t, positions)
    raise ConfigError(f"{where}: {columns} columns after the time; give 6 (a body's x, y, z, roll, pitch, yaw) or {3 * k} "
                      f"(x, y, z of each of the lines' {k} coupled points)")  # fmt: skip


COUPLED = ("coupled", "vessel", "cpld")
"""MoorDyn's names for a point another program moves."""


def coupled_points(text: str) -> np.ndarray:
    """(k, 3) the Coupled (or Vessel) points' positions in a MoorDyn input file, in its order."""
    import re

    section = re.search(r"(?ims)^-+\s*(points|connection[s]?|node[s]?)\b[^\n]*\n(.*?)(?=^-+)", text)
    rows = []
    for line in [] if section is None else section.group(2).splitlines():
        fields = line.split()
        if len(fields) >= 5 and fields[1].lower() in COUPLED:
            rows.append([float(v) for v in fields[2:5]])
    if not rows:
        raise ConfigError("the lines file has no Coupled (or Vessel) points: nothing for the motion to move")
    return np.array(rows)


def run(text: str, motion: Motion, dt: float, t_end: float | None = None, every: int = 1, progress=None, energy: bool = False,
        folder: Path | None = None) -> dict[str, np.ndarray]:  # fmt: skip
    """The lines of MoorDyn input `text` under `motion`, stepped at dt from its first time to t_end (default its last):
    columns t, each coupled point's position and the lines' pull on it, each line's tension at its fairlead (end B)
    and anchor (end A) as OpenFAST's MoorDyn reports them (Moorings.end_forces), every `every` steps. `energy`: also
    E_lines (what the lines store), D_lines (what they have dissipated) and W_in (the work the moved points have done
    on them), J: W_in = E_lines - E_lines(start) + D_lines. `folder`: where the input came from (the files it names)."""

    start = float(motion.t[0])
    end = float(motion.t[-1]) if t_end is None else float(t_end)
    if not motion.t[0] < end <= motion.t[-1] + 1e-9:
        raise ConfigError(f"t_end {end:g} s must lie within the motion's times ({motion.t[0]:g} to {motion.t[-1]:g} s)")
    pos, vel = motion.at(start)
    lines = Moorings(text, np.zeros(3), np.eye(3), np.zeros(3), np.zeros(3), t0=start, start=(pos, np.zeros_like(vel)), folder=folder)
    lines.counting(energy)  # (settled at rest)
    names = range(1, len(pos) + 1)
    n_lines = len(lines.lines())
    columns = ["t", *(f"{p}{i}" for i in names for p in ("x_", "y_", "z_", "Fx_", "Fy_", "Fz_")),
               *(f"T_fair_{i}" for i in range(1, n_lines + 1)), *(f"T_anch_{i}" for i in range(1, n_lines + 1))]  # fmt: skip
    columns += ["E_lines", "D_lines", "W_in"] if energy else []
    rows = []

    def record(t: float, pos: np.ndarray) -> None:
        anchor, fairlead = lines.end_forces()
        rows.append(
            [
                t,
                *np.column_stack([pos, lines._forces]).ravel(),
                *fairlead,
                *anchor,
                *lines.energy_now(),
                *([lines.work_in] if energy else []),
            ]
        )

    steps = max(1, round((end - start) / dt))
    try:
        record(start, pos)
        for i in range(1, steps + 1):
            t = start + (i - 1) * dt
            pos, vel = motion.at(t)
            lines.pull(pos.ravel(), vel.ravel(), dt)
            if i % every == 0 or i == steps:
                record(start + i * dt, motion.at(start + i * dt)[0])
            if progress is not None:
                progress(i, steps)
    finally:
        lines.close()
    data = np.array(rows)
    return {c: data[:, j] for j, c in enumerate(columns)}

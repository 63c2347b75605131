"""The mooring lines' mechanical energy and the power they dissipate, summed node by node from MoorDyn's state.
MoorDyn reports neither; with them a moored system's energy closes (docs/lines.md).

Stored, J (`stored`):
- the inner nodes' kinetic energy, 1/2 v^T M v with the water's added mass in M (an end node's is not: a body moves
  it without feeling its inertia, as MoorDyn's coupling gives only forces), and each Free point's with its lines' ends;
- every node's and point's wet weight lifted, -W_z z;
- each stretched segment's strain, 1/2 EA (l - l0)^2 / l0;
- the seabed's spring under each node on it, 1/2 S^2 / (k_b d l0) with S = B_z + c_b d l0 z' its spring force.

Dissipated, W (`dissipation`):
- each node's drag, -D . v;
- each segment's internal damping, BA l'^2 / l0;
- the seabed's damping c_b d l0 z'^2 and its friction, -B_xy . v_xy;
- each point's drag, 1/2 rho CdA |v|^3.

Valid for lines of constant EA without bending stiffness, in still water (MoorDyn's own water kinematics off), between
Fixed, Free and Coupled points: no Rods or MoorDyn Bodies."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sim.errors import ConfigError
from sim.lines.moordyn_input import BODY_SECTIONS, POINT_SECTIONS, ROD_SECTIONS
from sim.lines.moordyn_input import sections as _sections
from sim.lines.moordyn_input import table as _table

DEFAULTS = {"g": 9.80665, "rho": 1025.0, "kb": 3.0e6, "cb": 3.0e5}
"""MoorDyn's defaults for the options read here (MoorDyn2.cpp)."""
OPTION_NAMES = {"g": "g", "gravity": "g", "rho": "rho", "wtrdnsty": "rho", "kbot": "kb", "kb": "kb", "cbot": "cb", "cb": "cb"}


@dataclass(frozen=True)
class LineType:
    diameter: float
    """m"""
    mass: float
    """kg/m in air"""
    EA: float
    """N"""
    BA: float
    """N s, or minus a damping ratio (MoorDyn's BA/-zeta)"""


@dataclass(frozen=True)
class Spec:
    """What MoorDyn's input file says and its API does not: each line's type, each point's own mass, volume and drag
    area, and the options."""

    types: list
    """Each line's LineType, in the file's order of lines."""
    points: dict
    """Each point's ID: (kind, mass kg, volume m^3, CdA m^2)."""
    options: dict
    """g, rho, kb, cb."""


def read_spec(text: str) -> Spec:
    """The Spec of a MoorDyn v2 input file (sections LINE TYPES, POINTS, LINES, OPTIONS; v1's names too)."""
    sections = _sections(text)
    if _table(sections, *BODY_SECTIONS) or _table(sections, *ROD_SECTIONS):
        raise ConfigError("the mooring file has MoorDyn bodies or rods: the lines' energy balance counts lines and points only")
    kinds = {}
    for row in _table(sections, "LINE TYPES", "LINE DICTIONARY"):
        try:
            kinds[row[0]] = LineType(*(float(v) for v in row[1:5]))
        except ValueError:  # a curve's file name in place of EA or BA
            raise ConfigError(f"the mooring line type {row[0]!r} has a nonlinear EA or BA: the lines' energy balance is for constant "
                              "ones only") from None  # fmt: skip
    try:
        types = [kinds[row[1]] for row in _table(sections, "LINES", "LINE PROPERTIES")]
    except KeyError as missing:
        raise ConfigError(f"the mooring file's LINES name a line type {missing} its LINE TYPES do not define") from None
    points = {}
    for row in _table(sections, *POINT_SECTIONS):
        points[int(row[0])] = (row[1].lower(), *(float(v) for v in row[5:8]))
    options = dict(DEFAULTS)
    for row in sections.get("OPTIONS", []) + sections.get("SOLVER OPTIONS", []):
        if len(row) >= 2 and row[1].lower() in OPTION_NAMES:
            options[OPTION_NAMES[row[1].lower()]] = float(row[0])
    return Spec(types, points, options)


def _damping(kind: LineType, segment: float) -> float:
    """The segments' internal damping BA, N s (MoorDyn's: a negative input is a damping ratio of the segment's axial mode)."""
    return -kind.BA * segment * math.sqrt(kind.EA * kind.mass) if kind.BA < 0 else kind.BA


class LineEnergy:
    """Stored energy and dissipated power of a MoorDyn system's lines and points, read node by node (slow: a few
    hundred API calls, so only where a scene asks for the energy balance)."""

    def __init__(self, md, system, lines: list, spec: Spec):
        self._md, self._lines, self._spec = md, lines, spec
        if len(spec.types) != len(lines):
            raise ConfigError(f"the mooring file lists {len(spec.types)} lines where MoorDyn read {len(lines)}: the energy balance needs the "
                              "file's LINE TYPES and LINES tables")  # fmt: skip
        self._points = [(md.GetPoint(system, pid), *spec.points[pid][1:]) for pid in spec.points if spec.points[pid][0] != "fixed"]
        self._free = [md.GetPointType(p) == md.POINT_TYPE_FREE for p, *_ in self._points]

    def _nodes(self, ln):
        md, n = self._md, self._md.GetLineN(ln)
        pos = np.array([md.GetLineNodePos(ln, i) for i in range(n + 1)])
        vel = np.array([md.GetLineNodeVel(ln, i) for i in range(n + 1)])
        bed = np.array([md.GetLineNodeSeabedForce(ln, i) for i in range(n + 1)])
        return n, pos, vel, bed

    def _segments(self, ln, n: int, pos: np.ndarray, vel: np.ndarray):
        """Each segment's unstretched length, stretched length and rate of stretch."""
        l0 = self._md.GetLineUnstretchedLength(ln) / n
        step = np.diff(pos, axis=0)
        length = np.linalg.norm(step, axis=1)
        rate = np.einsum("ij,ij->i", step / length[:, None], np.diff(vel, axis=0))
        return l0, length, rate

    def _node_length(self, n: int, l0: float) -> np.ndarray:
        """The line length each node stands for (MoorDyn's: half of each adjacent segment)."""
        out = np.full(n + 1, l0)
        out[[0, -1]] = 0.5 * l0
        return out

    def stored(self) -> dict[str, float]:
        """{kinetic, gravity, strain, seabed}: the energy the lines and points hold now, J."""
        md, o = self._md, self._spec.options
        out = dict.fromkeys(("kinetic", "gravity", "strain", "seabed"), 0.0)
        for ln, kind in zip(self._lines, self._spec.types):
            n, pos, vel, bed = self._nodes(ln)
            for i in range(n + 1):
                if 0 < i < n:  # an end's inertia is its Free point's (in GetPointM), or felt by nobody
                    out["kinetic"] += 0.5 * vel[i] @ np.array(md.GetLineNodeM(ln, i)) @ vel[i]
                out["gravity"] -= md.GetLineNodeWeight(ln, i)[2] * pos[i, 2]
            l0, length, _ = self._segments(ln, n, pos, vel)
            stretch = np.maximum(length - l0, 0.0)
            out["strain"] += 0.5 * kind.EA * float(stretch @ stretch) / l0
            support = o["cb"] * kind.diameter * self._node_length(n, l0)
            spring = np.where(bed[:, 2] != 0.0, bed[:, 2] + support * vel[:, 2], 0.0)
            out["seabed"] += 0.5 * float(np.sum(spring**2 / (o["kb"] * kind.diameter * self._node_length(n, l0))))
        for (p, mass, volume, _), free in zip(self._points, self._free):
            r, v = np.array(md.GetPointPos(p)), np.array(md.GetPointVel(p))
            out["gravity"] += o["g"] * (mass - o["rho"] * volume) * r[2]
            if free:
                out["kinetic"] += 0.5 * v @ np.array(md.GetPointM(p)) @ v
        return out

    def dissipation(self) -> float:
        """The power the lines and points dissipate now, W (drag, internal damping, the seabed's damping and friction)."""
        md, o = self._md, self._spec.options
        total = 0.0
        for ln, kind in zip(self._lines, self._spec.types):
            n, pos, vel, bed = self._nodes(ln)
            drag = np.array([md.GetLineNodeDrag(ln, i) for i in range(n + 1)])
            total -= float(np.einsum("ij,ij->", drag, vel))
            l0, _, rate = self._segments(ln, n, pos, vel)
            total += _damping(kind, l0) * float(rate @ rate) / l0
            on_bed = bed[:, 2] != 0.0
            support = o["cb"] * kind.diameter * self._node_length(n, l0)
            total += float(np.sum(np.where(on_bed, support * vel[:, 2] ** 2, 0.0)))
            total -= float(np.einsum("ij,ij->", bed[:, :2], vel[:, :2]))
        for p, _, _, area in self._points:
            v = np.array(md.GetPointVel(p))
            total += 0.5 * o["rho"] * area * float(np.linalg.norm(v)) ** 3
        return total

"""Reading MoorDyn v2 input files: their sections, and a Coupled body's points as Coupled points (the form floatsim
couples). WEC-Sim's and OpenFAST's files often hang the fairleads on a MoorDyn body of type Coupled, given its pose as
6 coordinates at each step; floatsim moves each fairlead with its own body instead, which is the same coupling when the
MoorDyn body carries nothing of its own (mass, volume, drag: the host's body has them)."""

from __future__ import annotations

import math
import re

import numpy as np

from sim.errors import ConfigError

HEADING = re.compile(r"^\s*-{2,}\s*(.*?)\s*-*\s*$")
BODY_SECTIONS = ("BODIES", "BODY LIST", "BODY PROPERTIES")
ROD_SECTIONS = ("RODS", "ROD LIST", "ROD PROPERTIES")
POINT_SECTIONS = ("POINTS", "POINT LIST", "POINT PROPERTIES", "CONNECTION PROPERTIES", "NODE PROPERTIES")
"""The names MoorDyn's v2 and v1 files give these sections."""


def sections(text: str) -> dict[str, list[list[str]]]:
    """Each '---- NAME ----' section's rows (split on whitespace), its two heading rows dropped for tables."""
    out, name = {}, None
    for raw in text.splitlines():
        found = HEADING.match(raw)
        if found:
            name = " ".join(found.group(1).upper().split())
            out[name] = []
        elif name is not None and raw.strip():
            out[name].append(raw.split())
    return out


def table(found: dict, *names: str) -> list[list[str]]:
    """The rows of the first section named (its two heading rows dropped), or none."""
    for name in names:
        if name in found:
            return found[name][2:]
    return []


def _rotation(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """MoorDyn's body orientation from its angles (radians): Rx(roll) Ry(pitch) Rz(yaw) (Misc.hpp, Euler2Quat)."""
    c, s = np.cos([roll, pitch, yaw]), np.sin([roll, pitch, yaw])
    rx = np.array([[1, 0, 0], [0, c[0], -s[0]], [0, s[0], c[0]]])
    ry = np.array([[c[1], 0, s[1]], [0, 1, 0], [-s[1], 0, c[1]]])
    rz = np.array([[c[2], -s[2], 0], [s[2], c[2], 0], [0, 0, 1]])
    return rx @ ry @ rz


def _numbers(field: str) -> list[float]:
    return [float(v) for v in field.split("|")]


def check_input(text: str, name: str) -> None:
    """A ConfigError unless `text` reads as MoorDyn input floatsim can couple: a LINES section with a line, and a Coupled
    point (or a Coupled body's points) among its POINTS. Cheap (no MoorDyn), so made before any solve, fit or compile."""
    found = sections(text)
    if not table(found, "LINES", "LINE LIST", "LINE PROPERTIES"):
        raise ConfigError(f"{name}: not a MoorDyn input file (no '---- LINES ----' section with a line)")
    points = table(found, *POINT_SECTIONS) + table(found, *BODY_SECTIONS)
    if not any(len(row) > 1 and row[1].lower().startswith(("coupled", "vessel", "cpld")) for row in points):
        raise ConfigError(f"{name}: the mooring input must couple the body through 'Coupled' points (its fairleads); it has none")


def coupled_bodies_as_points(text: str) -> str:
    """(coupled_points, with a one-line error for a number it cannot read.)"""
    try:
        return _coupled_points(text)
    except ValueError as e:
        raise ConfigError(f"the mooring file's Coupled body or its points: {e}") from None


def _coupled_points(text: str) -> str:
    """The input with each Coupled body's points ('Body<N>', relative to it) as Coupled points at their world positions
    and the body's row gone; unchanged without Coupled bodies. A Coupled body with its own mass, volume or drag, or with
    rods on it, is refused in one line: floatsim's body would count them twice, or not at all."""
    found = sections(text)
    coupled = {}
    for row in table(found, *BODY_SECTIONS):
        if len(row) < 2 or row[1].lower() != "coupled":
            continue
        if len(row) < 14:
            raise ConfigError(f"MoorDyn body {row[0]}: a Coupled body's row needs its 14 columns (ID Attachment X0 Y0 Z0 r0 p0 y0 Mass CG I "
                              "Volume CdA Ca)")  # fmt: skip
        own = [_numbers(row[8]), _numbers(row[11]), _numbers(row[12])]
        if any(v != 0.0 for values in own for v in values):
            raise ConfigError(f"MoorDyn body {row[0]} is Coupled with its own mass, volume or drag: floatsim's body carries those, so "
                              "give them 0 in the mooring file")  # fmt: skip
        place = np.array([float(v) for v in row[2:5]])
        coupled[row[0]] = (place, _rotation(*(math.radians(float(v)) for v in row[5:8])))
    if not coupled:
        return text
    for row in table(found, *ROD_SECTIONS):
        if len(row) > 2 and row[2].lower().removesuffix("pinned").removeprefix("body") in coupled:
            raise ConfigError(f"MoorDyn rod {row[0]} is on a Coupled body: floatsim couples lines through points only")
    out, section = [], None
    for raw in text.splitlines():
        heading = HEADING.match(raw)
        if heading:
            section = " ".join(heading.group(1).upper().split())
            out.append(raw)
            continue
        row = raw.split()
        if section in BODY_SECTIONS and len(row) > 1 and row[0] in coupled:
            continue  # the body itself: floatsim's
        if section in POINT_SECTIONS and len(row) > 4:
            owner = row[1].lower()
            if owner.startswith("body") and owner.removeprefix("body").removesuffix("pinned") in coupled:
                place, R = coupled[owner.removeprefix("body").removesuffix("pinned")]
                world = place + R @ np.array([float(v) for v in row[2:5]])
                raw = " ".join([row[0], "Coupled", *(f"{v:.12g}" for v in world), *row[5:]])
        out.append(raw)
    return "\n".join(out) + "\n"

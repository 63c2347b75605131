"""Valid ranges of the live controls, and the clamping of whatever a browser sends into them.

viser does not enforce a slider's min/max, so any client can send NaN, a negative or a huge
number, or the wrong type. The simulation thread passes every value through here before use.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Range:
    label: str
    lo: float
    hi: float
    unit: str = ""


# Wider than the sliders (a script or the number box may go further), narrow enough to stay sane.
RANGES = {
    "density": Range("Density", 1.0, 1.0e5, "kg/m³"),
    "damping": Range("Damping", 0.0, 1.0e7, "N·s/m³"),
    "dt": Range("Time step", 1.0e-5, 0.1, "s"),
    "speed": Range("Speed", 0.01, 100.0, "×"),
    "points_per_edge": Range("Points per edge", 1, 100),
    "omega0": Range("Initial ω", -100.0, 100.0, "rad/s"),
}


def _fmt(v: float, unit: str) -> str:
    return f"{v:g} {unit}".strip()


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def clamp(name: str, value, current: float) -> tuple[float, str | None]:
    """(value to use, note for the user or None). Non-numbers and NaN keep `current`; the rest is clipped to the range."""
    r = RANGES[name]
    if not _is_number(value) or math.isnan(value):
        return current, f"{r.label}: {value!r} is not a number; kept {_fmt(current, r.unit)}."
    if value < r.lo or value > r.hi:
        used = min(max(float(value), r.lo), r.hi)
        return used, f"{r.label}: {value:g} is outside {_fmt(r.lo, r.unit)} … {_fmt(r.hi, r.unit)}; using {_fmt(used, r.unit)}."
    return float(value), None


def clamp_int(name: str, value, current: int) -> tuple[int, str | None]:
    """Like `clamp`, then rounded to a whole number."""
    used, note = clamp(name, value, current)
    n = round(used)
    if note is None and n != used:
        note = f"{RANGES[name].label}: {value:g} is not a whole number; using {n}."
    return n, note


def clamp_vector3(name: str, value, current: tuple[float, float, float]) -> tuple[tuple[float, float, float], str | None]:
    """Three numbers, each clipped to the range; anything else keeps `current`."""
    r = RANGES[name]
    try:
        items = tuple(value)
    except TypeError:
        items = ()
    if len(items) != 3 or not all(_is_number(v) and not math.isnan(v) for v in items):
        return current, f"{r.label}: {value!r} is not three numbers; kept {current}."
    used = tuple(min(max(float(v), r.lo), r.hi) for v in items)
    note = None if used == tuple(float(v) for v in items) else f"{r.label}: components are limited to ±{r.hi:g} {r.unit}; using {used}."
    return used, note  # type: ignore[return-value]

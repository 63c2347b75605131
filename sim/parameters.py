"""One declaration per user-facing parameter: its section, key, default, unit, valid range, label and help.

Everything else reads these declarations: the TOML scene schema and its validation (scene/config.py), the
command-line flags (commands/run.py), the viewer's controls and their clamps (app/live/controls.py), and
the summary. A force term declares its own parameters next to its function (hydro/forces.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from sim.errors import ConfigError

KINDS = ("float", "int", "choice", "text", "vector", "optional", "switch", "points")
"""float: a finite number; int: a whole number; choice: one of `choices`; text: any string;
vector: `size` finite numbers (or None, unset, when that is its default); optional: a finite number or None (unset); switch: true or false (or None,
unset, when that is its default: the scene decides); points: a list of up to `size` points of three
finite numbers each (scene files only, no flag)."""


@dataclass(frozen=True)
class Param:
    section: str
    """Scene table it lives in: 'body', 'fluid', 'initial' or 'step'."""
    key: str
    """TOML key, Python field name and (with dashes) CLI flag."""
    default: Any
    help: str
    """One line: what it is and what it does (CLI --help, viewer hint)."""
    unit: str = ""
    """SI unit as text, e.g. 'N s/m^3' ('' for a pure number)."""
    lo: float = -math.inf
    """Smallest valid value (each component for a vector)."""
    hi: float = math.inf
    """Largest valid value."""
    lo_open: bool = False
    """Whether `lo` itself is excluded (> rather than >=)."""
    live: tuple[float, float] | None = None
    """(min, max) a live control clamps into when narrower than the valid range: an excluded lower
    bound needs a smallest usable value, and some valid values cost too much to apply interactively."""
    kind: str = "float"
    choices: tuple[str, ...] = ()
    size: int = 0
    """Length of a vector parameter."""
    name: str = ""
    """How error messages call it (default: the key)."""
    label: str = ""
    """The viewer's label (default: the name); only parameters with `gui` get a control."""
    gui: tuple | None = None
    """The viewer's control: (min, max, step) of a slider for a number, () for a choice's dropdown or a
    vector's three boxes; None: no live control."""
    flag: bool = True
    """Whether `run` and `sweep` take it as a command-line flag."""
    flag_name: str = ""
    """The flag's name with underscores (default: the key), e.g. 'wave_height' for [waves] height."""

    def __post_init__(self):
        if self.kind not in KINDS:
            raise TypeError(f"parameter {self.section}.{self.key}: kind {self.kind!r} is not one of {KINDS}")

    @property
    def cli(self) -> str:
        """The command-line flag's name, underscores for dashes (e.g. 'wave_height' for --wave-height)."""
        return self.flag_name or self.key

    @property
    def what(self) -> str:
        """How error messages call it."""
        return self.name or self.key

    @property
    def title(self) -> str:
        """The viewer's label with its unit."""
        text = self.label or self.what
        unit = self.unit.replace("^3", "³").replace("^2", "²").replace(" ", "·")
        return f"{text} ({unit})" if unit else text

    def describe(self, value) -> str:
        """A value as the summaries print it, with its unit ('100 N s/m^3', 'on')."""
        if self.kind == "switch":
            return {True: "on", False: "off", None: "auto"}.get(value, str(value))
        return f"{value:g} {self.unit}".strip() if isinstance(value, (int, float)) else str(value)

    def check(self, value) -> Any:
        """The value if valid (tuples for vectors), else ConfigError with a one-line message."""
        if value is None and (self.kind == "optional" or (self.kind == "vector" and self.default is None)):
            return None
        if self.kind == "switch":
            if value is None and self.default is None:
                return None
            if not isinstance(value, bool):
                raise ConfigError(f"{self.what} must be true or false, got {_short(value)}")
            return value
        if self.kind == "choice":
            if value not in self.choices:
                raise ConfigError(f"unknown {self.what} {_short(value)}; {self.what} must be one of: {', '.join(self.choices)}")
            return value
        if self.kind == "text":
            if not isinstance(value, str):
                raise ConfigError(f"{self.what} must be text, got {value!r}")
            return value
        if self.kind == "vector":
            if not isinstance(value, (tuple, list)) or len(value) != self.size:
                raise ConfigError(f"{self.what} must have {self.size} numbers, got {_short(value)}")
            return tuple(float(self._number(v)) for v in value)
        if self.kind == "points":
            if not isinstance(value, (tuple, list)) or len(value) > self.size:
                raise ConfigError(f"{self.what} must be a list of at most {self.size} points [x, y, z], got {_short(value)}")
            if not all(isinstance(p, (tuple, list)) and len(p) == 3 for p in value):
                raise ConfigError(f"{self.what}: each point must be three numbers [x, y, z], got {_short(value)}")
            return tuple(tuple(float(self._number(v)) for v in p) for p in value)
        return self._number(value)

    def _number(self, value) -> float | int:
        what = self.what
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(f"{what} must be a number, got {value!r}")
        if not math.isfinite(value):
            raise ConfigError(f"{what} must be finite, got {value}")
        if self.kind == "int" and int(value) != value:
            raise ConfigError(f"{what} must be a whole number, got {value}")
        if self.lo_open and value <= self.lo:
            raise ConfigError(f"{what} must be > {self.lo:g}, got {value}")
        if value < self.lo:
            raise ConfigError(f"{what} must be >= {self.lo:g}, got {value}")
        if value > self.hi:
            raise ConfigError(f"{what} must be <= {self.hi:g}, got {value}")
        return int(value) if self.kind == "int" else value

    def clamp(self, value, current) -> tuple[Any, str | None]:
        """(value to use, note for the user or None): what a live control does with any input.
        Non-numbers and NaN keep `current`; numbers are clipped into `live` (default: the valid
        range); whole-number parameters are rounded."""
        label = self.label or self.what
        if self.kind == "switch":
            if isinstance(value, bool):
                return value, None
            return current, f"{label}: {_short(value)} is not on or off; kept {current}."
        if self.kind == "choice":
            if value in self.choices:
                return value, None
            return current, f"{label}: {_short(value)} is not one of {', '.join(self.choices)}; kept {current}."
        if self.kind == "vector":
            try:
                items = tuple(value)
            except TypeError:
                items = ()
            if len(items) != self.size or not all(_is_number(v) and not math.isnan(v) for v in items):
                return current, f"{label}: {_short(value)} is not {self.size} numbers; kept {current}."
            used = tuple(min(max(float(v), self.lo), self.hi) for v in items)
            if used == tuple(float(v) for v in items):
                return used, None
            return used, f"{label}: components are limited to {self.lo:g} … {self.hi:g} {self.unit}; using {used}."
        if not _is_number(value) or math.isnan(value):
            return current, f"{label}: {_short(value)} is not a number; kept {self.describe(current)}."
        lo, hi = self.live or (self.lo, self.hi)
        note = None
        used = float(value)
        if used < lo or used > hi:
            used = min(max(used, lo), hi)
            note = f"{label}: {value:g} is outside {self.describe(lo)} … {self.describe(hi)}; using {self.describe(used)}."
        if self.kind == "int":
            n = round(used)
            if note is None and n != used:
                note = f"{label}: {value:g} is not a whole number; using {n}."
            return n, note
        return used, note


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _short(value, limit: int = 24) -> str:
    """A bounded repr for notices: never echo more than a few characters of a bad input."""
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 1] + "…"

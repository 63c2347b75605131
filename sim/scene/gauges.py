"""Wave gauges: points where a run writes the water's elevation (`[[gauges]] x, y`, or `--gauge X Y`).

Each gauge is a column `eta_NAME` of the run's outputs, m, the surface of the scene's sea at (x, y) at each row's time
(still water: 0): the incident sea, as the bodies feel it, without the waves they radiate or scatter. A gauge with
`at_record = true` stands where a measured record was taken ([waves] record_point) and adds `record_NAME`, the record
itself at each row's time (linearly between its samples, its mean removed as the sea has it): the record and the sea
made from it in one plot.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from sim.errors import ConfigError

NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]*")


@dataclass(frozen=True)
class Gauge:
    name: str
    x: float
    """m, world frame."""
    y: float
    at_record: bool = False
    """Where the scene's measured record was taken (x, y from [waves] record_point), with the record beside."""


def parse_gauges(value, where: str) -> tuple[Gauge, ...]:
    """[[gauges]] tables: x and y (or at_record = true), an optional name (g1, g2, ... by default): one-line
    ConfigError on anything else."""
    if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
        raise ConfigError(f"{where}: gauges must be an array of tables ([[gauges]] with x and y)")
    out = []
    for i, table in enumerate(value):
        at = f"{where} [[gauges]] #{i + 1}"
        unknown = set(table) - {"name", "x", "y", "at_record"}
        if unknown:
            raise ConfigError(f"{at}: unknown key '{sorted(unknown)[0]}' (known: at_record, name, x, y)")
        at_record = table.get("at_record", False)
        if not isinstance(at_record, bool):
            raise ConfigError(f"{at}: at_record must be true or false")
        if not at_record and not {"x", "y"} <= set(table):
            raise ConfigError(f"{at}: give the gauge's x and y (m), or at_record = true")
        x, y = (table.get(k, 0.0) for k in ("x", "y"))
        if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in (x, y)):
            raise ConfigError(f"{at}: x and y must be finite numbers (m)")
        out.append(Gauge(str(table.get("name", f"g{i + 1}")), float(x), float(y), at_record))
    return tuple(out)


def added(gauges: tuple[Gauge, ...], points) -> tuple[Gauge, ...]:
    """`gauges` and one more at each (x, y) of `points` (the --gauge flags), named on from the scene's."""
    return gauges + tuple(Gauge(f"g{len(gauges) + k + 1}", float(x), float(y)) for k, (x, y) in enumerate(points))


def check_gauges(gauges: tuple[Gauge, ...], record: bool, record_point) -> tuple[Gauge, ...]:
    """Names that make columns (a letter, then letters, digits, _), each once; an at_record gauge only with a measured
    record, placed at its point. Returns the gauges placed."""
    seen = set()
    placed = []
    for g in gauges:
        if not NAME.fullmatch(g.name):
            raise ConfigError(f"gauge name {g.name!r}: use a letter, then letters, digits or _ (it names the column eta_{g.name})")
        if g.name in seen:
            raise ConfigError(f"two gauges named {g.name!r}: give each its own name")
        seen.add(g.name)
        if not (math.isfinite(g.x) and math.isfinite(g.y)):
            raise ConfigError(f"gauge {g.name!r} at ({g.x:g}, {g.y:g}): its x and y must be finite numbers (m)")
        if g.at_record and not record:
            raise ConfigError(f'gauge {g.name!r} is at_record, but the scene\'s sea is not a measured record ([waves] kind = "record")')
        placed.append(Gauge(g.name, *map(float, record_point), True) if g.at_record else g)
    return tuple(placed)

"""`python -m sim lines`: mooring lines alone under a prescribed motion (lines/lines_alone.py): MoorDyn's tensions to CSV."""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sim.commands.output import write_whole
from sim.commands.progress import progress_bar
from sim.errors import ConfigError
from sim.lines.lines_alone import coupled_points, motion_of, read_table, run
from sim.lines.moordyn_input import coupled_bodies_as_points


@dataclass
class LinesArgs:
    """The tensions of mooring lines (a MoorDyn v2 input file) whose Coupled or Vessel points follow a motion you give:
    a table of time and a body's x, y, z, roll, pitch, yaw (its points rigidly on it) or each point's x, y, z."""

    lines: str
    """The MoorDyn input file."""
    motion: str
    """The motion table (whitespace or commas; header lines skipped): t and 6 columns, or t and 3 per coupled point."""
    dt: float = 0.0125
    """The coupling step, s (MoorDyn takes its own dtM steps within it)."""
    t_end: float | None = None
    """Stop here, s (default: the motion's last time)."""
    every: int = 1
    """Write one row every K steps."""
    out: str = ""
    """CSV file to write (default: a summary only)."""
    energy: bool = False
    """Add the lines' energy: E_lines (stored), D_lines (dissipated by drag, internal damping and the seabed) and W_in (the
    work the moved points did), J (docs/lines.md; a few hundred MoorDyn calls a step)."""


def lines(args: LinesArgs) -> int:

    for name, value in (("--lines", args.lines), ("--motion", args.motion)):
        if not Path(value).is_file():
            raise ConfigError(f"{name}: no such file: {value}")
    if not args.dt > 0 or args.every < 1:
        raise ConfigError("--dt must be > 0 and --every >= 1")
    text = coupled_bodies_as_points(Path(args.lines).read_text())
    motion = motion_of(read_table(Path(args.motion)), coupled_points(text), where=args.motion)
    end = float(motion.t[-1]) if args.t_end is None else args.t_end
    with progress_bar(round((end - motion.t[0]) / args.dt), "lines") as bar:
        result = run(text, motion, args.dt, args.t_end, args.every, lambda i, n: bar.update(1), args.energy, Path(args.lines).parent)
    names = list(result)
    if args.out:
        table = np.column_stack(list(result.values()))
        write_whole(args.out, lambda tmp: np.savetxt(tmp, table, delimiter=",", header=",".join(names), comments="", fmt="%.10g"))
    fair = [c for c in names if c.startswith("T_fair_")]
    print(f"{len(fair)} lines, {len(result['t'])} rows over {result['t'][0]:g}-{result['t'][-1]:g} s (dt {args.dt:g} s)"
          + (f" -> {args.out}" if args.out else ""))  # fmt: skip
    for c in fair:
        T = result[c]
        print(
            f"line {c.rsplit('_', 1)[1]}: fairlead tension mean {T.mean() / 1e3:.6g} kN, min {T.min() / 1e3:.6g}, max {T.max() / 1e3:.6g}"
        )
    if args.energy:
        stored, lost, done = result["E_lines"][-1] - result["E_lines"][0], result["D_lines"][-1], result["W_in"][-1]
        print(
            f"energy: the moved points did {done:.6g} J on the lines = {stored:+.6g} J stored + {lost:.6g} J dissipated, to {done - stored - lost:+.3g} J"
        )
    sys.stdout.flush()
    return 0

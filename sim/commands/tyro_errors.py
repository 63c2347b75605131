"""tyro's parse errors (a boxed panel of 5-15 lines) as one line: what is wrong, and with which flag."""

from __future__ import annotations

import contextlib
import io
import re
import sys
from collections.abc import Callable
from typing import TypeVar

T = TypeVar("T")
_BOX = "│╭╮╰╯"


def one_line(panel: str) -> str:
    """The gist of a tyro error panel: its first section, with a type error reduced to the flag and
    the reason, and an unknown flag to the nearest known one."""
    boxed = any(line.strip().startswith("│") for line in panel.splitlines())  # rich draws a box on a terminal-like stream
    rows = [line.strip().strip(_BOX).strip() for line in panel.splitlines() if not line.strip().startswith(("╭", "╰"))]
    rows = [row for row in rows if row] + [""]
    is_rule = lambda row: bool(row) and set(row) <= {"─", "-"}  # noqa: E731
    if not boxed and len(rows) > 1 and is_rule(rows[1]):  # a plain rendering: its title line first
        rows = rows[2:]
    sections, current = [], []
    for row in rows:
        if is_rule(row):
            sections.append(" ".join(current))
            current = []
        else:
            current.append(row)
    sections.append(" ".join(current))
    text = re.sub(r"\s+", " ", sections[0]).strip()
    text = re.sub(r"\[/?bold\]|`", "", text)
    if m := re.match(r"Error parsing (--[\w.-]+):", text):
        reasons = [r.strip() for r in re.findall(r"- (?!<class 'NoneType'>)[^:]+: (.*?)(?= - |$)", text)]
        return f"{m.group(1)}: {reasons[-1] if reasons else text[len(m.group(0)) :].strip()}"
    if text.startswith("Unrecognized options") and len(sections) > 1 and (m := re.search(r"Perhaps you meant: (--[\w.-]+)", sections[1])):
        return f"{text} (did you mean {m.group(1)}?)"
    return text or "could not parse the command line"


def parse(parser: Callable[[], T], prog: str) -> T:
    """Run a tyro parser; on a user mistake print `prog: error: <one line>` and exit 2. Help and
    everything that is not an error pass through unchanged."""
    captured = io.StringIO()
    try:
        with contextlib.redirect_stderr(captured):
            return parser()
    except SystemExit as e:
        if e.code in (0, None):
            sys.stderr.write(captured.getvalue())
            raise
        print(f"{prog}: error: {one_line(captured.getvalue())}", file=sys.stderr)
        raise SystemExit(2) from None

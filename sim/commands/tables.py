"""What the benchmark commands print besides their numbers: the machine they ran on, and markdown tables."""

from __future__ import annotations

import os
import platform

import numba
import numpy as np


def machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, numpy {np.__version__}, numba {numba.__version__}"


def table(header: tuple[str, ...], rows: list[tuple[str, ...]]) -> None:
    """A markdown table after a blank line."""
    print()
    for r in (header, ("---",) * len(header), *rows):
        print("| " + " | ".join(r) + " |")

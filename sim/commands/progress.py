"""Progress bars for long runs: shown on a terminal, never in CI logs or pipes."""

from __future__ import annotations

import os
import sys


def show_progress(flag: bool | None = None) -> bool:
    if flag is not None:
        return flag
    return sys.stderr.isatty() and not os.environ.get("CI")


def progress_bar(total: int, unit: str = "step", flag: bool | None = None):
    from tqdm import tqdm

    return tqdm(total=total, unit=unit, disable=not show_progress(flag), file=sys.stderr, smoothing=0.1)

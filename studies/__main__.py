"""`python -m studies report|figures ...`: write the generated documents (reports/ by default)."""

import sys

from .accuracy import ReportArgs, report
from .probes import dispatch
from .seed_figures import FiguresArgs, figures

COMMANDS = {"report": (ReportArgs, report), "figures": (FiguresArgs, figures)}


def main(argv: list[str] | None = None) -> int:
    return dispatch(COMMANDS, argv, prog="python -m studies")


if __name__ == "__main__":
    sys.exit(main())

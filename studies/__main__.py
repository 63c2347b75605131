"""`python -m studies report|figures|decay|stability ...`: write the generated documents (reports/ by default)."""

import sys

from .probes import dispatch

COMMANDS = {
    "report": "studies.accuracy:report",
    "figures": "studies.seed_figures:figures",
    "decay": "studies.decay:decay",
    "stability": "studies.stability:stability",
    "f3of": "studies.f3of:main",
    "rm3-mooring": "studies.rm3_mooring:main",
}


def main(argv: list[str] | None = None) -> int:
    return dispatch(COMMANDS, argv, prog="python -m studies")


if __name__ == "__main__":
    sys.exit(main())

"""`floatsim view`: the viewer as a subcommand of the `floatsim` console script (registered as a plugin in pyproject.toml)."""

from __future__ import annotations

import sys

from app.args import ViewArgs
from sim.commands import floatsim


def view(args: ViewArgs) -> int:
    from app.main import serve  # viser is imported here, only when viewing

    return serve(args)


if __name__ == "__main__":
    sys.exit(floatsim())

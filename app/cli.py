"""The `floatsim` command: the headless subcommands of `sim.cli` plus `view`, which alone imports viser."""

from __future__ import annotations

import sys

from sim.cli import COMMANDS, dispatch

from .args import ViewArgs


def view(args: ViewArgs) -> int:
    from .main import serve  # viser is imported here, only when viewing

    return serve(args)


def main(argv: list[str] | None = None) -> int:
    return dispatch({**COMMANDS, "view": (ViewArgs, view)}, argv, prog="floatsim")


if __name__ == "__main__":
    sys.exit(main())

"""`python -m app [--scene NAME|PATH] [--host H] [--port P]`: the live viewer, same as `floatsim view`."""

from __future__ import annotations

import sys

import tyro

from app.args import ViewArgs
from sim.commands.tyro_errors import parse
from sim.scene.config import ConfigError


def main(argv: list[str] | None = None, prog: str = "python -m app") -> int:
    args = parse(lambda: tyro.cli(ViewArgs, args=argv, prog=prog), prog)
    from app.main import serve  # viser is imported only once the flags parsed

    try:
        return serve(args)
    except ConfigError as e:  # a bad scene or address: one line, exit 2, before any server starts
        print(f"{prog}: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # Ctrl-C before the server is up (e.g. while the kernels compile)
        print(f"{prog}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())

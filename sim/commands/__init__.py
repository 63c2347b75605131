"""The command line: `python -m sim run|sweep|compare|bench|gains|lines`. Flags for scene parameters are generated
from their declarations (`parameters.Param`), so a new term's coefficient is a flag without an edit here."""

from __future__ import annotations

import dataclasses
import importlib
import os
import signal
import sys
import threading
import typing
from collections.abc import Iterable
from typing import Annotated

import tyro

from sim.commands.interrupt import EXIT, asked_before, interrupted_by_ctrl_c, listen, settled
from sim.errors import ConfigError
from sim.parameters import Param

from .tyro_errors import parse

_TYPES = {"float": float, "int": int, "choice": str, "text": str, "optional": float, "switch": bool}


def _flag_type(p: Param):
    if p.kind == "vector":
        return tuple[(float,) * p.size]  # type: ignore[misc]
    return _TYPES[p.kind]


FROM_SCENE = "(default: from the scene)"


def _metavar(p: Param) -> str:
    if p.choices:
        return "{" + ",".join(p.choices) + "}"
    if p.kind == "switch":
        return "{True,False}"
    word = {"float": "FLOAT", "optional": "FLOAT", "int": "INT", "text": "STR", "choice": "STR"}.get(p.kind, "FLOAT")
    return " ".join([word] * p.size) if p.kind == "vector" else word


def _flag_help(p: Param) -> str:
    extra = f"one of: {', '.join(p.choices)}" if p.choices else p.unit
    return f"{p.help}" + (f" ({extra})" if extra else "") + f" [scene: [{p.section}] {p.key}]"


def declared_flags(name: str, base: type, params: Iterable[Param]) -> type:
    """A dataclass `base` extended with one optional flag per declared parameter (None: keep the scene's)."""
    params = [p for p in params if p.flag]
    taken = {f.name for f in dataclasses.fields(base)}
    fields = []
    for p in params:
        if p.cli in taken:
            raise TypeError(f"flag --{p.cli} is declared twice")
        taken.add(p.cli)
        arg = tyro.conf.arg(help=_flag_help(p), metavar=_metavar(p), help_behavior_hint=FROM_SCENE)
        fields.append((p.cli, Annotated[_flag_type(p) | None, arg], dataclasses.field(default=None)))
    cls = dataclasses.make_dataclass(name, fields, bases=(base,))
    cls.__doc__ = base.__doc__
    return cls


def overrides(args, params: Iterable[Param]) -> dict:
    """{'section__key': value} for every declared flag that was given."""
    return {f"{p.section}__{p.key}": getattr(args, p.cli) for p in params if p.flag and getattr(args, p.cli, None) is not None}


COMMANDS = {
    "run": "sim.commands.run:run",
    "sweep": "sim.commands.sweep:sweep",
    "compare": "sim.commands.compare:compare",
    "bench": "sim.commands.bench:bench",
    "gains": "sim.commands.gains:gains",
    "lines": "sim.commands.lines:lines",
}
"""name -> 'module:function'; the function's `args` annotation is its dataclass of flags."""
PLUGINS = "floatsim.commands"
"""Entry-point group through which the packages above sim (the viewer, the studies) add subcommands to
`floatsim` without sim importing them: see pyproject.toml."""


def _load(target: str):
    module, name = target.split(":")
    fn = getattr(importlib.import_module(module), name)
    return typing.get_type_hints(fn)["args"], fn


def dispatch(commands: dict[str, str], argv: list[str] | None = None, prog: str = "floatsim") -> int:
    """Parse `argv` into one subcommand's dataclass and run it; user mistakes exit 2 with one line."""
    loaded = {name: _load(target) for name, target in commands.items()}  # (Ctrl-C until here: sim/__init__'s one line)
    classes = {name: cls for name, (cls, _) in loaded.items()}
    args = parse(lambda: tyro.extras.subcommand_cli_from_dict(classes, args=argv, prog=prog), prog)
    handler = next(fn for cls, fn in loaded.values() if isinstance(args, cls))
    before = signal.getsignal(signal.SIGINT)
    if threading.current_thread() is threading.main_thread():  # a shell starts background jobs with Ctrl-C ignored: take it back
        listen()
    try:
        return handler(args)
    except ConfigError as e:
        print(f"{prog}: error: {e}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # the reader went away (`... | head`): stop quietly, like any Unix tool
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141
    except BaseException as e:  # noqa: BLE001 - after a Ctrl-C, what its KeyboardInterrupt left behind too
        if not (interrupted_by_ctrl_c(e) or asked_before()) or isinstance(e, SystemExit):
            raise
        name = next((n for n, (cls, _) in loaded.items() if isinstance(args, cls)), "")
        print(f"{prog}: {name} interrupted (Ctrl-C) before writing its results", file=sys.stderr)
        return EXIT
    finally:
        settled()
        if threading.current_thread() is threading.main_thread():
            # the process's own command line ends next: said and written, a Ctrl-C in the teardown (a Dask cluster's)
            # changes nothing; a caller in-process (main([...])) gets its own handler back
            signal.signal(signal.SIGINT, signal.SIG_IGN if argv is None else (before or signal.default_int_handler))


def main(argv: list[str] | None = None) -> int:
    """`python -m sim`: the headless commands."""
    return dispatch(COMMANDS, argv, prog="python -m sim")


def floatsim(argv: list[str] | None = None) -> int:
    """The `floatsim` console script: the headless commands plus every installed plugin's (view, report, ...)."""
    from importlib.metadata import entry_points

    plugins = {ep.name: ep.value for ep in entry_points(group=PLUGINS)}
    return dispatch({**COMMANDS, **plugins}, argv, prog="floatsim")

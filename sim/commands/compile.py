"""`python -m sim.commands.compile PID [SPEC ...]`: the child that compiles kernels into the disk cache (compiling.Compiler
starts it; the tests' session start hands it specs on stdin). With no spec: every preset's.

Where a compile's CPU goes (FLOATSIM_COMPILE_PROFILE=FILE, as `floatsim bench --startup` asks): numba announces each
function it compiles ("numba:compile", nested: a kernel compiles the kernels it calls first); `Profile` takes each one's
CPU time less that of the compiles nested in it, so the shares add up to the whole, and each one's LLVM seconds with its
callees' from numba's own timers (its overload's `llvm_lock`: optimising, linking and emitting machine code)."""

from __future__ import annotations

import collections
import json
import os
import sys
import time

from numba.core import event

from sim.compiling import load, parse_spec, spec_argument
from sim.forked import die_with
from sim.scene.config import available_scenes, load_scene
from sim.simulation import Simulation

from .startup import PROFILE_ENV


def _name(dispatcher) -> str:
    f = dispatcher.py_func
    return f"{f.__module__.split('.')[-1]}.{f.__name__}"


class Profile(event.Listener):
    """Each compiled function's own CPU seconds (`own`), and each one's LLVM seconds with its callees' (`llvm`)."""

    def __init__(self):
        self.own: collections.Counter = collections.Counter()
        self.llvm: collections.Counter = collections.Counter()
        self._open: list = []
        self._seen: set = set()

    def on_start(self, ev) -> None:
        self._open.append([ev.data["dispatcher"], time.process_time(), 0.0])

    def on_end(self, ev) -> None:
        dispatcher, started, nested = self._open.pop()
        spent = time.process_time() - started
        name = _name(dispatcher)
        self.own[name] += spent - nested
        if self._open:
            self._open[-1][2] += spent
        self._seen.add(dispatcher)

    def __enter__(self):
        event.register("numba:compile", self)
        return self

    def __exit__(self, *exc) -> None:
        event.unregister("numba:compile", self)

    def write(self, path: str) -> None:
        for dispatcher in self._seen:  # (its timers are set once its compile has ended)
            for result in dispatcher.overloads.values():
                timers = (result.metadata or {}).get("timers", {})
                self.llvm[_name(dispatcher)] = max(self.llvm[_name(dispatcher)], timers.get("llvm_lock", 0.0))
        with open(path, "w") as out:
            json.dump({"own": dict(self.own), "llvm": dict(self.llvm)}, out)


def preset_specs() -> list:
    """The kernels.Spec of every preset scene with a compiled twin, as shipped (a scene of several bodies: its bodies'
    loads and the system step's)."""
    specs = []
    for name in available_scenes():
        sim = Simulation(load_scene(name), backend="numpy")
        if sim.has_twin:  # (a body on a joint alone runs on the reference)
            specs += [spec for spec in sim.specs if spec not in specs]
    return specs


def _main(parent: int, specs: list[str]) -> int:
    """Compile the kernels of each spec given (spec_argument), or of every preset scene; `-`: of each spec read from
    stdin, a line each, until it closes (so that a parent hands the next to whichever child is free)."""
    die_with(parent)  # a viewer stopped by SIGKILL leaves no compiler behind
    words = (line.strip() for line in sys.stdin) if specs == ["-"] else iter(specs or [spec_argument(s) for s in preset_specs()])
    with Profile() as profile:
        for word in words:
            spec = parse_spec(word)
            seconds = load(spec)
            print(f"floatsim: compiled the kernels for the {spec.describe()} in {seconds:.1f} s", flush=True)
    if os.environ.get(PROFILE_ENV):
        profile.write(os.environ[PROFILE_ENV])
    return 0


USAGE = """usage: python -m sim.commands.compile [PID [SPEC ...]]

Compile the numba kernels into the disk cache, once for this machine: with no argument, every preset's (as a first
run of each would); with PID, the kernels of each SPEC given (a word of sim.compiling.spec_argument), or of each read
from stdin with '-', stopping when the process PID stops."""


def main(argv: list[str]) -> int:
    if argv and argv[0] in ("-h", "--help"):
        print(USAGE)
        return 0
    if argv and (not argv[0].isdigit() or int(argv[0]) != os.getppid()):  # it stops with PID: only its parent's makes sense
        print(f"floatsim: {argv[0]!r} is not this command's parent's process id ({os.getppid()})\n{USAGE}", file=sys.stderr)
        return 2
    try:
        return _main(int(argv[0]) if argv else os.getppid(), argv[1:])
    except ValueError as e:  # a spec word that is not one
        print(f"floatsim: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))

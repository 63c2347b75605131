"""`python -m sim.commands.compile PID [SPEC ...]`: the child that compiles kernels into the disk cache (compiling.Compiler
starts it; the tests' session start hands it specs on stdin). With no spec: every preset's."""

from __future__ import annotations

import os
import sys

from sim.compiling import load, parse_spec, spec_argument
from sim.scene.config import available_scenes, load_scene
from sim.simulation import Simulation
from sim.sweeps.backends import die_with


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
    for word in words:
        spec = parse_spec(word)
        seconds = load(spec)
        print(f"floatsim: compiled the kernels for the {spec.describe()} in {seconds:.1f} s", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(_main(int(sys.argv[1]) if len(sys.argv) > 1 else os.getppid(), sys.argv[2:]))

"""`floatsim bench --startup`: how long a user waits before a preset runs, from an empty and from a warm kernel cache.

Each preset is run as a user runs it, `python -m sim run --scene NAME --t-end T`, in a fresh process: first
with an empty kernel cache of its own (a first run on a machine: a short run stays on the numpy reference),
then the kernels that preset needs are compiled into that cache in a fresh process, as the viewer's
background compiler and a longer run do (`python -m sim.commands.compile`), then the run again (every later run:
the kernels load from the cache). Wall time and the peak memory of each process are reported.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time

from sim.commands.tables import machine, table
from sim.compiling import spec_argument
from sim.scene.config import ConfigError, available_scenes, load_scene
from sim.simulation import Simulation


def timed_run(scene: str, t_end: float, cache: str) -> tuple[float, float, int, str]:
    """(wall seconds, peak MiB, exit status, the compile announcement if any) of one run in a fresh process."""
    return timed([sys.executable, "-m", "sim", "run", "--scene", scene, "--t-end", f"{t_end:g}", "--every", "1000000"], cache)


def timed_compile(scene: str, cache: str) -> tuple[float, float, int, str]:
    """timed_run of compiling the kernels the preset needs (its kernels.Spec) in a fresh process."""

    run = Simulation(load_scene(scene), backend="numpy")
    specs = run.specs if run.has_twin else []
    run.close()
    if not specs:  # nothing to compile (sim.compiling with no spec would compile every preset's)
        return 0.0, 0.0, 0, ""
    return timed([sys.executable, "-m", "sim.commands.compile", str(os.getpid()), *map(spec_argument, specs)], cache)


def timed(command: list[str], cache: str) -> tuple[float, float, int, str]:
    env = {**os.environ, "NUMBA_CACHE_DIR": cache}
    started = time.perf_counter()
    child = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env, text=True)
    err = child.stdout.read()
    _, status, usage = os.wait4(child.pid, 0)  # this child's own peak memory, not the largest so far
    wall = time.perf_counter() - started
    child.returncode = os.waitstatus_to_exitcode(status)
    said = next((line for line in err.splitlines() if "compil" in line), "")
    return wall, usage.ru_maxrss / 1024, child.returncode, said  # ru_maxrss: KiB on Linux


def how_it_ran(said: str) -> str:
    """What a cold run's announcement says, in a few words and whole parentheses (the note itself is long and
    holds parentheses of its own: cut at a fixed length it left one open)."""
    if "runs there" in said:
        return " (on the numpy reference: a short run does not wait for the compiler)"
    if "compil" in said:
        return " (compiled its kernels first)"
    return ""


def startup(presets: tuple[str, ...], t_end: float) -> int:
    names = presets or tuple(available_scenes())
    unknown = [n for n in names if n not in available_scenes()]
    if unknown:
        raise ConfigError(f"--presets: {', '.join(map(repr, unknown))} not among the presets ({', '.join(available_scenes())})")
    rows = []
    for name in names:
        with tempfile.TemporaryDirectory(prefix="floatsim-startup-") as cache:
            cold = timed_run(name, t_end, cache)
            compiled = timed_compile(name, cache)
            warm = timed_run(name, t_end, cache)
        rows.append(
            (name, f"{cold[0]:.1f}", f"{compiled[0]:.1f}", f"{compiled[1]:.0f}", f"{warm[0]:.1f}", str(cold[2] or compiled[2] or warm[2]))
        )
        print(
            f"  {name}: cold {cold[0]:.1f} s{how_it_ran(cold[3])}, compile {compiled[0]:.1f} s, warm {warm[0]:.1f} s",
            file=sys.stderr,
            flush=True,
        )

    print(f"machine: {machine()}")
    print(f"`python -m sim run --scene NAME --t-end {t_end:g}` in a fresh process. cold: an empty kernel cache; compile: the kernels "
          "the preset needs, into that cache, in a fresh process (what the viewer and a longer run wait for); warm: the run again")  # fmt: skip
    table(("preset", "cold run s", "compile s", "compile peak MiB", "warm run s", "exit"), rows)
    return 0

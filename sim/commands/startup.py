"""`floatsim bench --startup`: how long a user waits before a preset runs, from an empty and from a warm kernel cache.

Each preset is run as a user runs it, `python -m sim run --scene NAME --t-end T`, in a fresh process: first
with an empty kernel cache of its own (a first run on a machine: a short run stays on the numpy reference),
then the kernels that preset needs are compiled into that cache in a fresh process, as the viewer's
background compiler and a longer run do (`python -m sim.commands.compile`), then the run again (every later run:
the kernels load from the cache). Wall and CPU time and the peak memory of each process are reported, and the kernels
whose own compile took the most CPU (numba's compile events and LLVM timers: sim/commands/compile.py's Profile).
"""

from __future__ import annotations

import collections
import json
import os
import subprocess
import sys
import tempfile
import time
from typing import NamedTuple

from sim.commands.tables import machine, table
from sim.compile_estimate import compile_seconds, spec_cpu
from sim.compiling import spec_argument
from sim.scene.config import ConfigError, available_scenes, load_scene
from sim.simulation import Simulation

PROFILE_ENV = "FLOATSIM_COMPILE_PROFILE"
"""Where the compile child (sim/commands/compile.py) writes its profile: each kernel's own compile CPU, its LLVM's."""


def top(path: str, n: int = 3) -> str:
    """The n kernels whose own compile took the most CPU, from a written profile: "name 12.3 s (LLVM 8.1 s), ..."."""
    with open(path) as f:
        data = json.load(f)
    own, llvm = collections.Counter(data["own"]), data["llvm"]
    return ", ".join(f"{name} {s:.1f} s (LLVM {llvm.get(name, 0.0):.1f} s with callees)" for name, s in own.most_common(n))


class Timed(NamedTuple):
    wall: float
    """Seconds."""
    cpu: float
    """The process's user and system CPU seconds."""
    peak: float
    """Its peak resident memory, MiB."""
    status: int
    said: str
    """Its compile announcement, if any."""


def timed_run(scene: str, t_end: float, cache: str) -> Timed:
    """One run in a fresh process."""
    return timed([sys.executable, "-m", "sim", "run", "--scene", scene, "--t-end", f"{t_end:g}", "--every", "1000000"], cache)


def specs_of(scene: str) -> list:
    """The kernels.Spec the preset compiles (none when it has no compiled twin)."""
    run = Simulation(load_scene(scene), backend="numpy")
    specs = list(run.specs) if run.has_twin else []
    run.close()
    return specs


def timed_compile(scene: str | list, cache: str, profile: str | None = None) -> Timed:
    """Compiling the kernels the preset needs (its kernels.Spec; or these specs) in a fresh process; its compile profile
    into `profile`."""
    specs = specs_of(scene) if isinstance(scene, str) else scene
    if not specs:  # nothing to compile (sim.compiling with no spec would compile every preset's)
        return Timed(0.0, 0.0, 0.0, 0, "")
    return timed([sys.executable, "-m", "sim.commands.compile", str(os.getpid()), *map(spec_argument, specs)], cache,
                 {PROFILE_ENV: profile} if profile else {})  # fmt: skip


def timed(command: list[str], cache: str, env: dict | None = None) -> Timed:
    env = {**os.environ, "NUMBA_CACHE_DIR": cache, **(env or {})}
    started = time.perf_counter()
    child = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env, text=True)
    err = child.stdout.read()
    _, status, usage = os.wait4(child.pid, 0)  # this child's own peak memory, not the largest so far
    wall = time.perf_counter() - started
    child.returncode = os.waitstatus_to_exitcode(status)
    said = next((line for line in err.splitlines() if "compil" in line), "")
    return Timed(wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024, child.returncode, said)  # ru_maxrss: KiB on Linux


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
            profile = os.path.join(cache, "profile.json")
            cold = timed_run(name, t_end, cache)
            compiled = timed_compile(name, cache, profile)
            warm = timed_run(name, t_end, cache)
            most = top(profile) if os.path.exists(profile) else ""
        rows.append((name, f"{cold.wall:.1f}", f"{compiled.wall:.1f}", f"{compiled.cpu:.1f}", f"{compiled.peak:.0f}", f"{warm.wall:.1f}",
                     most, str(cold.status or compiled.status or warm.status)))  # fmt: skip
        print(f"  {name}: cold {cold.wall:.1f} s{how_it_ran(cold.said)}, compile {compiled.wall:.1f} s ({compiled.cpu:.1f} s CPU), "
              f"warm {warm.wall:.1f} s", file=sys.stderr, flush=True)  # fmt: skip

    print(f"machine: {machine()}")
    compiled = [(name, float(row[3])) for name, row in zip(names, rows) if float(row[3]) > 0]
    if len(compiled) > 1:
        print(together(tuple(name for name, _ in compiled), compiled[0][1]))
    print(f"`python -m sim run --scene NAME --t-end {t_end:g}` in a fresh process. cold: an empty kernel cache; compile: the kernels "
          "the preset needs, into that cache, in a fresh process (what the viewer and a longer run wait for), wall and CPU; warm: "
          "the run again; most CPU: the kernels whose own compile took the most (their callees' apart)")  # fmt: skip
    table(("preset", "cold run s", "compile s", "compile CPU s", "compile peak MiB", "warm run s", "most CPU", "exit"), rows)
    return 0


def together(names: tuple[str, ...], first_cpu: float) -> str:
    """The presets' kernels compiled in one fresh process from an empty cache, against compile_seconds (what they share
    counted once), at this machine's speed as the first preset's compile measured it: the check of SHARED_CPU. A timed
    test of it failed on a loaded machine (40.4 s taken, 31.0 said), so it is measured here, on a quiet one."""
    specs = list(dict.fromkeys(spec for name in names for spec in specs_of(name)))
    speed = first_cpu / sum(map(spec_cpu, specs_of(names[0])))
    with tempfile.TemporaryDirectory(prefix="floatsim-startup-") as cache:
        taken = timed_compile(specs, cache).cpu
    said, apart = compile_seconds(specs, factor=speed), sum(map(spec_cpu, specs)) * speed
    return (
        f"{' + '.join(names)} compiled in one process: {taken:.1f} s CPU; estimated {said:.1f} s with what they share "
        f"counted once ({taken / said:.2f}x), {apart:.1f} s counted for each ({taken / apart:.2f}x)"
    )

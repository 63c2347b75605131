"""`floatsim bench --startup`: how long a user waits before a preset runs, from an empty and from a warm kernel cache.

Each preset is run as a user runs it, `python -m sim run --scene NAME --t-end T`, in a fresh process: first
with an empty kernel cache of its own (a first run on a machine), then again with the cache that run left
(every later run). Wall time and the peak memory of that process are reported, with the compile each cold
run announced. Cold runs take minutes each on a small machine; `--presets` picks a few.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time

from ..config import ConfigError, available_scenes


def timed_run(scene: str, t_end: float, cache: str) -> tuple[float, float, int, str]:
    """(wall seconds, peak MiB, exit status, the compile announcement if any) of one run in a fresh process."""
    env = {**os.environ, "NUMBA_CACHE_DIR": cache}
    started = time.perf_counter()
    child = subprocess.Popen([sys.executable, "-m", "sim", "run", "--scene", scene, "--t-end", f"{t_end:g}", "--every", "1000000"],
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env, text=True)  # fmt: skip
    err = child.stderr.read()
    _, status, usage = os.wait4(child.pid, 0)  # this child's own peak memory, not the largest so far
    wall = time.perf_counter() - started
    child.returncode = os.waitstatus_to_exitcode(status)
    said = next((line for line in err.splitlines() if "compil" in line), "")
    return wall, usage.ru_maxrss / 1024, child.returncode, said  # ru_maxrss: KiB on Linux


def startup(presets: tuple[str, ...], t_end: float) -> int:
    names = presets or tuple(available_scenes())
    unknown = [n for n in names if n not in available_scenes()]
    if unknown:
        raise ConfigError(f"--presets: {', '.join(map(repr, unknown))} not among the presets ({', '.join(available_scenes())})")
    rows = []
    for name in names:
        with tempfile.TemporaryDirectory(prefix="floatsim-startup-") as cache:
            cold = timed_run(name, t_end, cache)
            warm = timed_run(name, t_end, cache)
        rows.append((name, f"{cold[0]:.1f}", f"{warm[0]:.1f}", f"{cold[1]:.0f}", str(cold[2] or warm[2]), cold[3][:90]))
        print(f"  {name}: cold {cold[0]:.1f} s, warm {warm[0]:.1f} s", file=sys.stderr, flush=True)
    from .bench import _table, machine

    print(f"machine: {machine()}")
    print(f"`python -m sim run --scene NAME --t-end {t_end:g}` in a fresh process; cold: an empty kernel cache; warm: the cache it left; "
          "peak: the cold run's largest resident memory")  # fmt: skip
    _table(("preset", "cold s", "warm s", "peak MiB", "exit", "what the cold run said"), rows)
    return 0

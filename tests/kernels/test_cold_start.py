"""Issue 39: what a newcomer sees when the README's test line starts on an empty kernel cache."""

import os
import selectors
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.slow  # a pytest inside a pytest, stopped once it has spoken
def test_a_cold_test_run_says_it_is_compiling_at_once(tmp_path):
    """The README's test line on an empty kernel cache: its first line of its own says it is compiling the presets'
    kernels, how many and where they are cached, before any test runs (3.4 s after the start here; the next lines count
    them off as each is done, a minute or two apart under load); the run is stopped there."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    started = time.monotonic()
    run = subprocess.Popen([sys.executable, "-m", "pytest", "-q", "-n", "2", "tests/bodies/test_body.py"], cwd=ROOT, env=env,
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, start_new_session=True)  # fmt: skip
    lines, first_seconds = [], None
    watch = selectors.DefaultSelector()
    watch.register(run.stdout, selectors.EVENT_READ)
    try:
        while time.monotonic() - started < 600 and first_seconds is None:
            if watch.select(timeout=5) and (line := run.stdout.readline()):
                lines.append(line.rstrip())
                if "floatsim" in line and first_seconds is None:
                    first_seconds = time.monotonic() - started
            elif run.poll() is not None:
                break
    finally:
        os.killpg(run.pid, signal.SIGKILL)
        run.wait()
    print(f"floatsim's first line after {first_seconds} s:", *lines[:4], sep="\n")
    said = [line for line in lines if "floatsim" in line]  # (an installed plugin may warn first: pytest-benchmark under xdist)
    assert said and said[0].startswith("floatsim: compiling the numba kernels of") and str(tmp_path) in said[0], lines
    assert run.returncode == -signal.SIGKILL  # still running when stopped: compiling, not failed


def test_kernels_compiled_from_another_checkout_do_not_count_as_compiled_here(tmp_path):
    """numba files a kernel's compiled code under a subfolder named after its source folder's path: a cache a clone
    elsewhere on this machine filled holds nothing this checkout can load, and a run that took it for compiled would
    compile in every process instead of once, up front (the tests' covering set, the viewer's switch)."""
    from numba.core.caching import UserProvidedCacheLocator

    import sim.kernels as kernels

    ours = UserProvidedCacheLocator.get_suitable_cache_subpath(str(Path(kernels.__file__).parent / "schemes.py"))
    theirs = UserProvidedCacheLocator.get_suitable_cache_subpath("/elsewhere/floatsim/sim/kernels/schemes.py")
    assert ours != theirs
    for sub in (theirs, ours):
        (tmp_path / sub).mkdir()
        (tmp_path / sub / "schemes.advance-250.py311.nbi").write_bytes(b"")
        assert kernels.compiled_here(str(tmp_path)) == ({"schemes.advance"} if sub == ours else set())

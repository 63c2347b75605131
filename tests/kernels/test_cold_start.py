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

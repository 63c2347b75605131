"""Issue 24: nobody waits for the compiler. On an empty kernel cache the viewer serves at once on the numpy
reference, says so in its readouts, and takes the compiled kernels between two steps once the child that
compiles them is done (here a child that copies this machine's warm cache after a few seconds, standing in
for the minutes of a real compile); the switch keeps the state vector as it is."""

from __future__ import annotations

import asyncio
import os
import re
import shlex
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import sim
from app.tools.page import Page

ROOT = Path(__file__).resolve().parents[2]
READOUT = re.compile(r"t = \*\*([-0-9.]+) s\*\*")


def _serve(env: dict) -> tuple[subprocess.Popen, int]:
    proc = subprocess.Popen([sys.executable, "-m", "app", "--port", "0", "--scene", "drop"], cwd=ROOT, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)  # fmt: skip
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        if line.startswith("floatsim viewer: http://127.0.0.1:"):
            return proc, int(line.split()[2].split(":")[2].split("/")[0])
        if not line and proc.poll() is not None:
            break
    proc.kill()
    pytest.fail(f"no viewer banner: {proc.stderr.read()[-2000:]}")


async def _watch(port: int, seconds: float) -> list[tuple[float, bool]]:
    """(t, on the numpy reference) from the readouts, as a page sees them, until the kernels took over and 2 s more."""
    seen: list[tuple[float, bool]] = []
    switched = None
    async with Page.open(port) as page:
        await page.camera()
        await page.read(1.0)  # the first page restarts the run: watch from after that
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline and (switched is None or time.monotonic() < switched + 2.0):
            await page.read(0.2)
            text = page.text("Speed:")
            if match := READOUT.search(text):
                numpy = "numpy reference" in text
                seen.append((float(match.group(1)), numpy))
                if not numpy and switched is None:
                    switched = time.monotonic()
    return seen


@pytest.mark.slow
def test_an_empty_kernel_cache_runs_on_numpy_at_once_then_on_the_kernels_without_a_restart(tmp_path):
    from sim.compiling import cached
    from sim.kernels import KERNEL_CACHE

    if not cached(sim.Simulation(sim.load_scene("drop")).spec):
        pytest.skip("needs this machine's compiled kernels to stand in for a compile")
    empty = tmp_path / "cache"
    target = empty / Path(KERNEL_CACHE).name
    copy = f"import shutil, time; time.sleep(4); shutil.copytree({KERNEL_CACHE!r}, {str(target)!r}, dirs_exist_ok=True)"
    env = {**os.environ, "NUMBA_CACHE_DIR": str(empty), "FLOATSIM_COMPILER": shlex.join([sys.executable, "-c", copy])}
    proc, port = _serve(env)
    try:
        seen = asyncio.run(_watch(port, 60.0))
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=20)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert "in the background" in err and "Traceback" not in err, err
    on_numpy = [t for t, numpy in seen if numpy]
    compiled = [t for t, numpy in seen if not numpy]
    assert on_numpy and on_numpy[-1] > on_numpy[0], "the body moved on the numpy reference while the kernels compiled"
    assert compiled, f"the kernels never took over: {seen[-3:]}"
    assert [numpy for _, numpy in seen] == sorted((numpy for _, numpy in seen), reverse=True), "numpy, then compiled, never back"
    times = [t for t, _ in seen]
    assert all(b >= a for a, b in zip(times, times[1:])), "time never went back: the switch restarted nothing"
    assert compiled[-1] > on_numpy[-1]


def test_switching_backend_between_steps_keeps_the_state():
    """numpy steps, then compiled steps from the same state, agree with numpy all the way to round-off."""
    scene = sim.load_scene("damped")
    reference = sim.Simulation(scene, backend="numpy")
    switched = sim.Simulation(scene, backend="numpy")
    reference.step(200)
    switched.step(100)
    before = switched.state.as_vector().copy()
    switched.use_backend("numba")
    assert switched.compiled and np.array_equal(switched.state.as_vector(), before)
    switched.step(100)
    scale = np.abs(reference.state.as_vector()).max()
    assert switched.state.t == pytest.approx(reference.state.t, abs=1e-12)
    np.testing.assert_allclose(switched.state.as_vector(), reference.state.as_vector(), rtol=0, atol=1e-9 * scale)


def test_a_short_cli_run_on_an_empty_kernel_cache_runs_on_numpy_and_says_so(tmp_path):
    """`python -m sim run --scene drop --t-end 1` compiled for minutes before its 200 steps; on an empty cache
    it now runs them on the numpy reference (it finishes before the kernels would compile: both estimates said, measured
    here and now), says so in one note, and prints what the compiled run prints."""

    def run(env: dict, out: Path) -> np.ndarray:
        done = subprocess.run([sys.executable, "-m", "sim", "run", "--scene", "drop", "--t-end", "1", "--every", "50", "--out", str(out)],
                              cwd=ROOT, env=env, capture_output=True, text=True, timeout=120, check=False)  # fmt: skip
        assert done.returncode == 0, done.stderr
        notes.append(done.stderr)
        return np.genfromtxt(out, delimiter=",", skip_header=1)

    notes: list[str] = []
    empty = tmp_path / "cache"
    cold = run({**os.environ, "NUMBA_CACHE_DIR": str(empty)}, tmp_path / "cold.csv")
    warm = run(dict(os.environ), tmp_path / "warm.csv")
    assert "numpy reference" in notes[0] and "compil" not in notes[1]
    said = re.search(r"not compiled on this machine yet \(about (\d+) s here, once\); this run takes about (\d+) s on the numpy", notes[0])
    assert said and int(said.group(2)) < int(said.group(1)), notes[0]  # both estimates said, numpy's the shorter
    assert not any(empty.rglob("*.nbi")), "nothing was compiled"
    assert cold.shape == warm.shape and cold.shape[0] == 5
    np.testing.assert_allclose(cold, warm, rtol=1e-9, atol=1e-9)

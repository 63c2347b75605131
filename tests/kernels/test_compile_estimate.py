"""Issue 57: honest compile estimates, from one measured table, and a run that does not wait for a compile it would
outlast on the numpy reference (both measured on this machine at the same moment: the choice does not follow its load)."""

import os
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

import sim
from sim import compiling
from sim.compile_estimate import shares_of, spec_cpu
from sim.compiling import parse_spec

ROOT = Path(__file__).resolve().parents[2]
DROP = "implicit,points,gravity+pressure+damping+heave_damping,0,0,0,0,0"
"""The drop preset's kernels (compiling.spec_argument)."""


def _compile_cpu(words: list[str], cache: Path) -> float:
    """CPU seconds of one fresh process compiling the kernels of `words` into the empty cache `cache`."""
    child = subprocess.Popen([sys.executable, "-m", "sim.commands.compile", str(os.getpid()), *words], cwd=ROOT,
                             env={**os.environ, "NUMBA_CACHE_DIR": str(cache)}, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)  # fmt: skip
    out = child.stdout.read()
    _, status, usage = os.wait4(child.pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0, out
    return usage.ru_utime + usage.ru_stime


@pytest.mark.slow  # a real compile from an empty cache: the table's honesty
def test_the_estimate_is_within_a_factor_two_of_a_real_compile(tmp_path):
    """The drop's kernels compiled from an empty cache in a fresh process: the CPU seconds it took are within a factor
    of two of the table's (compile_estimate.COMPILE_CPU, the reference machine's), on whatever CPU runs the tests."""
    cpu, table = _compile_cpu([DROP], tmp_path), spec_cpu(parse_spec(DROP))
    assert table / 2 < cpu < 2 * table, (cpu, table)


@pytest.mark.parametrize(("args", "said"), [(["--help"], "usage: python -m sim.commands.compile"), (["nope"], "not this command's parent's"),
                                            (["PARENT", "a,b"], "'a,b' is not a kernels spec")])  # fmt: skip
def test_the_compile_command_says_its_usage_and_its_mistakes_in_a_line(args, said):
    """`python -m sim.commands.compile`, which a run's note names: --help prints its usage; a wrong process id or spec is
    one line and exit 2, not a traceback."""
    argv = [str(os.getpid()) if a == "PARENT" else a for a in args]
    done = subprocess.run([sys.executable, "-m", "sim.commands.compile", *argv], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert said in done.stdout + done.stderr and "Traceback" not in done.stderr, done.stderr
    assert done.returncode == (0 if args == ["--help"] else 2)


def test_a_scenes_kernels_compile_side_by_side_one_child_per_core(tmp_path, monkeypatch):
    """rm3's kernels (its bodies' loads, the system step) compile in two children at once on two cores: each child,
    given its share of the specs, waits until the other has started (it would wait in vain were they one after the
    other), and the shares hold every spec once, the longest alone."""
    specs = sim.Simulation(sim.load_scene("rm3"), backend="numpy").specs
    assert len(specs) >= 2
    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    child = (f"import os, sys, time, pathlib; d = pathlib.Path({str(tmp_path)!r}); (d / str(os.getpid())).write_text(' '.join(sys.argv[1:]))\n"
             "deadline = time.monotonic() + 60\nwhile len(list(d.iterdir())) < 2 and time.monotonic() < deadline: time.sleep(0.05)\n"
             "sys.exit(0 if len(list(d.iterdir())) == 2 else 3)")  # fmt: skip
    monkeypatch.setenv(compiling.COMMAND_ENV, shlex.join([sys.executable, "-c", child]))
    compiler = compiling.Compiler(specs)
    assert compiler.wait(), compiler.failure()
    given = sorted(p.read_text().split() for p in tmp_path.iterdir())
    assert sorted(word for share in given for word in share) == sorted(compiling.spec_argument(s) for s in specs)
    longest = max(specs, key=spec_cpu)
    assert [compiling.spec_argument(longest)] in given  # the system step alone; the loads in the other child
    assert shares_of(specs) == [(longest,), tuple(s for s in specs if s != longest)]
    assert compiler.expected > 0

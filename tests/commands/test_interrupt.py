"""Every mistake and interruption ends cleanly: an output that cannot be written is refused before
the run, and Ctrl-C stops any command within a second with one line, exit 130, and whole rows kept."""

from __future__ import annotations

import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from sim.commands import main
from sim.system.frame import CSV_COLUMNS
from tests.scenes import heaving_farm


@pytest.mark.parametrize("out, why", [("/tmp", "is a folder"), ("/nonexistent/dir/x.csv", "does not exist"), ("/proc/x.csv", "cannot write"),
                                      ("/dev/full", "not a regular file")])  # fmt: skip
def test_an_output_that_cannot_be_written_is_refused_before_the_run(out, why, capsys):
    assert main(["run", "--t-end", "1", "--out", out]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1 and why in captured.err


def interrupt(args: list[str], ready, timeout: float = 120.0) -> tuple[subprocess.CompletedProcess, float]:
    """Start `python -m sim ARGS`, send Ctrl-C once `ready()` holds; the result and how long it took to stop."""
    proc = subprocess.Popen([sys.executable, "-m", "sim", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + timeout
    while not ready() and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.05)
    assert proc.poll() is None, "finished before it could be interrupted"
    proc.send_signal(signal.SIGINT)
    sent = time.monotonic()
    out, err = ended(proc)
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err), time.monotonic() - sent


def ended(proc: subprocess.Popen, timeout: float = 30.0) -> tuple[str, str]:
    """The output of a process told to stop; one that does not within `timeout` is killed (with its group's workers), so
    a failed test leaves no load behind for the next."""
    try:
        return proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()
        raise


def test_ctrl_c_during_a_run_keeps_whole_rows_and_says_where_it_stopped(tmp_path):
    csv = tmp_path / "x.csv"
    done, stopped_in = interrupt(["run", "--t-end", "1e6", "--max-steps", "1000000000", "--every", "1000", "--out", str(csv)],
                                 lambda: any(p.stat().st_size > 20_000 for p in tmp_path.glob("_x.csv.*.partial")))  # fmt: skip
    # (the rows go to a temporary beside x.csv until the run ends: under its name the file is whole, Ctrl-C too)
    assert done.returncode == 130 and stopped_in < 5.0  # at once (0.1-0.3 s here; 1.08 s on a loaded machine): a run that
    # only stopped at its end would take hours
    assert done.stderr.count("\n") == 1 and "interrupted (Ctrl-C) at t = " in done.stderr and "rows in" in done.stderr
    rows = np.loadtxt(csv, delimiter=",", skiprows=1)
    assert rows.ndim == 2 and rows.shape[1] == len(CSV_COLUMNS) and np.isfinite(rows).all()  # whole lines, no NaN
    assert f"kept {len(rows)} rows" in done.stderr and not list(tmp_path.glob("_*.partial"))


@pytest.mark.slow
@pytest.mark.parametrize("backend", ["serial", "local", "dask"])
def test_ctrl_c_during_a_sweep_keeps_its_chunks_and_resume_finishes(tmp_path, backend):
    """On each backend, Ctrl-C once a chunk is written: the running chunks are dropped, not waited for (Dask's cluster
    waited for each busy worker: 4-8 s), one line, exit 130; --resume runs the rest."""
    out = tmp_path / "s"
    args = ["sweep", "--param", "density=300:900:12", "--param", "orientation_seed=0:1:2", "--t-end", "200", "--chunk", "4",
            "--backend", backend, "--workers", "2", "--out", str(out)]  # fmt: skip
    done, stopped_in = interrupt(args, lambda: len(list(out.glob("chunk-*.parquet"))) >= 1)
    assert done.returncode == 130 and stopped_in < 3.0, done.stderr  # a chunk takes ~5 s here: not waited for (2 s once under load)
    assert "interrupted (Ctrl-C)" in done.stderr and "--resume" in done.stderr and "Traceback" not in done.stderr
    kept = len(list(out.glob("chunk-*.parquet")))
    assert 1 <= kept < 6 and not list(out.glob("*.partial"))
    finished = subprocess.run([sys.executable, "-m", "sim", *args, "--resume"], capture_output=True, text=True, timeout=300)
    assert finished.returncode == 0 and f"({kept} already done, {6 - kept} to run)" in finished.stdout


@pytest.mark.slow
def test_ctrl_c_in_a_study_command_is_one_line():
    proc = subprocess.Popen([sys.executable, "-m", "studies", "decay", "--scene", "damped", "--duration", "5000"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, cwd=Path(__file__).resolve().parents[2])  # fmt: skip
    time.sleep(6.0)
    proc.send_signal(signal.SIGINT)
    out, err = ended(proc)
    assert (
        proc.returncode == 130 and err.strip().endswith("decay interrupted (Ctrl-C) before writing its results") and "Traceback" not in err
    )


def test_an_output_is_never_half_written_and_another_file_is_not_replaced_unasked(tmp_path):
    """`run --out` onto a file a run did not write is refused (one line, exit 2) and the file kept; --overwrite replaces
    it. Rerunning over a run's own CSV replaces it and says so. Two runs writing one name at once both finish, each
    file whole: the name holds one run's rows (not a mix), the other run's summary says it replaced that one's."""
    import subprocess
    import sys

    notes = tmp_path / "notes.csv"
    notes.write_text("my,own\n1,2\n")
    flags = ["-m", "sim", "run", "--scene", "drop", "--t-end", "2", "--every", "1"]
    done = subprocess.run([sys.executable, *flags, "--out", str(notes)], capture_output=True, text=True, timeout=300)
    assert done.returncode == 2 and "did not write; give --overwrite" in done.stderr and notes.read_text() == "my,own\n1,2\n"
    done = subprocess.run([sys.executable, *flags, "--out", str(notes), "--overwrite"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0 and notes.read_text().startswith("t,") and "(replaced the earlier file)" in done.stdout
    done = subprocess.run([sys.executable, *flags, "--out", str(notes)], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0 and "(replaced the earlier file)" in done.stdout  # a run's own CSV: replaced without asking
    same = tmp_path / "same.csv"
    runs = [subprocess.Popen([sys.executable, *flags, "--t-end", t_end, "--out", str(same)], stdout=subprocess.PIPE, text=True)
            for t_end in ("20", "30")]  # fmt: skip
    said = [run.communicate(timeout=300)[0] for run in runs]
    assert [run.returncode for run in runs] == [0, 0]
    rows = same.read_text().splitlines()
    assert len(rows) - 1 in (20 * 200 + 1, 30 * 200 + 1)  # one run's rows, whole (drop: dt 5 ms)
    assert sum("another run wrote there while this one ran" in s for s in said) == 1, said
    assert not list(tmp_path.glob("_*.partial"))  # no temporary left behind


@pytest.mark.slow
@pytest.mark.parametrize("after", [0.1, 0.3, 0.5, 0.7, 0.9, 1.2, 2.0, 4.0])
def test_ctrl_c_at_any_moment_of_a_run_is_one_line_and_exit_130(after, tmp_path):
    """SIGINT at a spread of moments from the start (Python's imports, the command's set-up, the stepping): one line,
    exit 130, within 3 s, and whatever CSV there is holds whole rows. Before: a KeyboardInterrupt traceback (exit -2)
    while the modules loaded, and a Ctrl-C swallowed by a library's `except BaseException` (trimesh's optional imports),
    the run going on for minutes."""
    csv = tmp_path / "x.csv"
    started = time.monotonic()
    done, stopped_in = interrupt(["run", "--scene", "damped", "--t-end", "100000", "--every", "7", "--out", str(csv)],
                                 lambda: time.monotonic() - started >= after)  # fmt: skip
    assert done.returncode == 130 and stopped_in < 3.0, (done.stderr, stopped_in)
    assert done.stderr.count("\n") == 1 and "interrupted (Ctrl-C)" in done.stderr and "Traceback" not in done.stderr, done.stderr
    if csv.exists():
        rows = np.loadtxt(csv, delimiter=",", skiprows=1, ndmin=2)
        assert rows.shape[1] == len(CSV_COLUMNS) and np.isfinite(rows).all()


def _commands(tmp_path: Path) -> dict[str, list[str]]:
    """Each command on work that lasts well past 4 s: the error study, the benchmark tables, a sweep on all cores, the
    lines following 4000 s of slow surge, a farm of 400 devices (its set-up announced, then seconds long), and the
    take-off's latching search (40 s of time-domain runs in waves longer than its natural period)."""
    root = Path(__file__).resolve().parents[2]
    t = np.linspace(0.0, 4000.0, 801)
    motion = tmp_path / "surge.txt"
    np.savetxt(motion, np.column_stack([t, 4.0 * (1 - np.cos(np.pi * t / 4000.0)), *([0 * t] * 5)]), header="t x y z roll pitch yaw")
    return {
        "compare": ["compare", "--scene", "damped"],
        "bench": ["bench"],
        "sweep": ["sweep", "--scene", "damped", "--param", "density=300:900:50", "--t-end", "400", "--backend", "local", "--out", str(tmp_path / "sweep")],
        "lines": ["lines", "--lines", str(root / "assets" / "moorings" / "md_5MW_OC4Semi.dat"), "--motion", str(motion), "--dt", "0.05",
                  "--out", str(tmp_path / "lines.csv")],
        "farm": ["run", "--scene", heaving_farm(tmp_path, 20), "--t-end", "1"],
        "gains": ["gains", "--scene", "point-absorber", "--wave-period", "3.5"],
    }  # fmt: skip


@pytest.mark.slow
@pytest.mark.parametrize("command", ["compare", "bench", "sweep", "lines", "farm", "gains"])
@pytest.mark.parametrize("after", [0.3, 1.0, 1.5, 3.5])
def test_ctrl_c_at_any_moment_of_every_command_is_one_line_and_exit_130(command, after, tmp_path):
    """SIGINT at a spread of moments into each command (imports, set-up, work): exit 130 within 3 s, the last line of
    stderr says it was interrupted, and no traceback. A Ctrl-C that a library swallows while the command sets up
    (compare at 1-1.2 s here: trimesh's imports) is heard at the command's next check: it went on for minutes."""
    started = time.monotonic()
    done, stopped_in = interrupt(_commands(tmp_path)[command], lambda: time.monotonic() - started >= after)
    assert done.returncode == 130 and stopped_in < 3.0, (done.stderr, stopped_in)
    assert "Traceback" not in done.stderr and "interrupted (Ctrl-C)" in done.stderr.strip().splitlines()[-1], done.stderr


@pytest.mark.slow
@pytest.mark.parametrize("after", [4.0, 5.5])
def test_ctrl_c_while_dask_workers_compute_drops_their_chunks_at_once(after, tmp_path):
    """A sweep on a Dask LocalCluster, Ctrl-C while its workers compute: they are ended, not waited for (a graceful
    close waited for each busy worker's chunk: 2.4-7.8 s), so the command stops within 3 s with its one line."""
    args = ["sweep", "--scene", "damped", "--param", "density=300:900:100", "--backend", "dask", "--out", str(tmp_path / "s")]
    started = time.monotonic()
    done, stopped_in = interrupt(args, lambda: time.monotonic() - started >= after)
    assert done.returncode == 130 and stopped_in < 3.0, (done.stderr, stopped_in)  # (2.01 s once under load: 3 s, as the others)
    assert done.stderr.count("\n") == 1 and "interrupted (Ctrl-C)" in done.stderr and "Traceback" not in done.stderr, done.stderr


@pytest.mark.slow
@pytest.mark.parametrize("after", [0.3, 1.5, 3.5, 8.0])
def test_ctrl_c_at_any_moment_of_the_viewer_ends_it_in_one_line(after):
    """SIGINT into `python -m app` while it imports, compiles its scene's kernels or serves: it ends within 3 s, with
    exit 130 and one line before the server is up, exit 0 once serving (Ctrl-C is how a viewer is closed), never a
    traceback; the port is let go (a second server binds it at once)."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    proc = subprocess.Popen([sys.executable, "-m", "app", "--scene", "waves", "--port", str(port)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)  # fmt: skip
    time.sleep(after)
    assert proc.poll() is None, "the viewer ended before its Ctrl-C"
    proc.send_signal(signal.SIGINT)
    sent = time.monotonic()
    out, err = ended(proc)
    stopped_in = time.monotonic() - sent
    serving = "floatsim viewer: http://" in out
    assert stopped_in < 3.0 and proc.returncode == (0 if serving else 130), (proc.returncode, stopped_in, err)
    assert "Traceback" not in err and (serving or "interrupted" in err.strip().splitlines()[-1]), err
    with socket.socket() as again:
        again.bind(("127.0.0.1", port))

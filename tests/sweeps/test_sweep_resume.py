"""A sweep folder is trusted only as far as it checks out (issue 23, item 7), through the command line:
damaged or missing chunk files are run again on --resume, a damaged manifest is called damaged, chunks
that cannot be told from another sweep's are never mixed with a new one, and the local backend's workers
die with the command even when it is killed outright."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import psutil
import pytest

ROOT = Path(__file__).resolve().parents[2]
GRID = ["--param", "density=300:900:6", "--t-end", "1", "--scene", "damped", "--chunk", "1", "--history-every", "20"]


def sweep(out: Path, *extra: str, grid=GRID) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-m", "sim", "sweep", *grid, "--out", str(out), *extra], capture_output=True, text=True,
                          timeout=300, env=env)  # fmt: skip


def table(folder: Path) -> pd.DataFrame:
    """The folder read whole, in case order (histories: then in time)."""
    frame = pd.read_parquet(folder)
    return frame.sort_values(list(frame.columns[:2])).reset_index(drop=True)


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> Path:
    """An undamaged run of GRID: six chunks of one case, each with its history."""
    out = tmp_path_factory.mktemp("sweep") / "ref"
    done = sweep(out)
    assert done.returncode == 0, done.stderr
    return out


def test_damaged_and_missing_chunks_are_run_again_on_resume(reference, tmp_path):
    out = tmp_path / "s"
    shutil.copytree(reference, out)
    chunk = lambda cid: out / f"chunk-{cid:05d}.parquet"  # noqa: E731
    chunk(0).write_bytes(chunk(0).read_bytes()[:200])  # truncated
    chunk(1).write_bytes(b"not parquet at all\n" * 20)  # garbage
    chunk(2).write_bytes(b"")  # empty
    (out / "_history" / "chunk-00003.parquet").unlink()  # a history chunk deleted
    edited = pd.read_parquet(chunk(4))
    edited["z"] += 1.0  # valid Parquet with the right rows, but not what was written
    edited.to_parquet(chunk(4))
    with pytest.raises(Exception):  # what the issue saw: the folder no longer reads
        pd.read_parquet(out)
    done = sweep(out, "--resume")
    assert done.returncode == 0, done.stderr
    assert "(1 already done, 5 to run)" in done.stdout
    notes = [line for line in done.stderr.splitlines() if line.startswith("floatsim: note:")]
    assert len(notes) == 5 and all("running chunk" in n for n in notes), done.stderr
    assert "Traceback" not in done.stderr
    for cid, why in (
        (0, "not readable"),
        (1, "not readable"),
        (2, "not readable"),
        (3, "_history/chunk-00003.parquet: missing"),
        (4, "checksum"),
    ):
        assert any(f"running chunk {cid} again" in n and why in n for n in notes), (cid, notes)
    pd.testing.assert_frame_equal(table(out), table(reference), check_exact=True)
    pd.testing.assert_frame_equal(table(out / "_history"), table(reference / "_history"), check_exact=True)
    again = sweep(out, "--resume")  # now whole: nothing to run, nothing to say
    assert again.returncode == 0 and "(6 already done, 0 to run)" in again.stdout and "note" not in again.stderr


@pytest.mark.parametrize("damage", [b'{"key": "353d', b"\xff\xfe garbage", b"[1, 2, 3]", b""])
def test_a_damaged_manifest_is_called_damaged(reference, tmp_path, damage):
    out = tmp_path / "s"
    shutil.copytree(reference, out)
    (out / "_manifest.json").write_bytes(damage)
    done = sweep(out, "--resume")
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
    assert "_manifest.json is damaged" in done.stderr and "different sweep" not in done.stderr and "--out" in done.stderr


def test_chunks_without_a_manifest_are_never_mixed_with_another_sweep(reference, tmp_path):
    out = tmp_path / "s"
    shutil.copytree(reference, out)
    (out / "_manifest.json").unlink()
    before = {p.name: p.read_bytes() for p in out.glob("chunk-*.parquet")}
    other = ["--param", "density=400,800", "--t-end", "1", "--scene", "damped"]
    for extra in ((), ("--resume",)):
        done = sweep(out, *extra, grid=other)
        assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
        assert "no _manifest.json" in done.stderr and "choose another --out" in done.stderr
    assert {p.name: p.read_bytes() for p in out.glob("chunk-*.parquet")} == before  # nothing written, nothing mixed
    assert not (out / "_manifest.json").exists()


def test_a_different_sweep_into_a_finished_folder_is_refused(reference, tmp_path):
    out = tmp_path / "s"
    shutil.copytree(reference, out)
    done = sweep(out, "--resume", grid=["--param", "density=400,800", "--t-end", "1", "--scene", "damped"])
    assert done.returncode == 2 and "holds a different sweep" in done.stderr and done.stderr.count("\n") == 1


@pytest.mark.slow
def test_local_workers_die_with_the_killed_command(tmp_path):
    """SIGKILL leaves the command no time to stop its workers: they must notice on their own."""
    out = tmp_path / "k"
    args = [sys.executable, "-m", "sim", "sweep", "--param", "density=300:900:8", "--t-end", "600", "--scene", "damped", "--chunk", "2",
            "--backend", "local", "--workers", "2", "--out", str(out)]  # fmt: skip
    workers: list[psutil.Process] = []
    main = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env={**os.environ, "PYTHONPATH": str(ROOT)})
    try:
        parent = psutil.Process(main.pid)
        deadline = time.monotonic() + 120
        while len(workers) < 2 and time.monotonic() < deadline:
            time.sleep(0.1)
            workers = [p for p in parent.children() if "resource_tracker" not in " ".join(p.cmdline())]
        assert len(workers) == 2, "the workers never started"
        time.sleep(1.0)  # they are computing their first chunks
        assert all(w.is_running() for w in workers)
        os.kill(main.pid, signal.SIGKILL)
        main.wait(timeout=10)
        _, alive = psutil.wait_procs(workers, timeout=5)
        alive = [p for p in alive if p.is_running() and p.status() != psutil.STATUS_ZOMBIE]
        assert not alive, f"workers outlived the command: {[p.pid for p in alive]}"
    finally:  # whatever failed, leave nothing running
        main.kill()
        for w in workers:
            if w.is_running():
                w.kill()

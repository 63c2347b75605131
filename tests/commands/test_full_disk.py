"""A full disk ends every command that writes in one line and exit 2, never a traceback (issue 37), on a real
full filesystem (a small tmpfs): a run's CSV is cut back to its last whole row and the line says how many rows
it holds; a sweep keeps the chunks written before (whole, recorded) and --resume finishes once there is room;
a replay page or a video is whole under its name or absent. A sweep's temporaries start with '_', so a folder
with one left over (a killed write) still reads with pandas.read_parquet."""

from __future__ import annotations

import contextlib
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from sim.commands.output import TEMPORARY

ROOT = Path(__file__).resolve().parents[2]


@contextlib.contextmanager
def full_disk(folder: Path, size: str = "64k"):
    """A tmpfs of `size` mounted at `folder` (root only), unmounted after; the test is skipped where mount is refused."""
    folder.mkdir()
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(folder)], capture_output=True, text=True)
    if mounted.returncode != 0:
        pytest.skip(f"a full filesystem needs `mount -t tmpfs` (root): {mounted.stderr.strip() or 'refused'}")
    try:
        yield folder
    finally:
        subprocess.run(["umount", "-l", str(folder)], check=True)


def cli(*args: str, module: str = "sim") -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-m", module, *args], capture_output=True, text=True, timeout=300, env=env)


def one_line(done: subprocess.CompletedProcess) -> str:
    """The one line a full disk gets (a note the run printed before, e.g. that it runs on numpy while its kernels are not
    compiled on this machine, is not part of it)."""
    lines = [line for line in done.stderr.splitlines() if not line.startswith("floatsim: note:")]
    assert done.returncode == 2 and len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    assert "No space left on device" in lines[0]
    return lines[0] + "\n"


def assert_cut_at_a_whole_row(csv: Path, said: str) -> None:
    """The rows the line reports are the newline-ended lines after the header, and the file ends with one."""
    data = csv.read_bytes()
    assert data.endswith(b"\n")
    kept = int(re.search(r"kept the header and (\d+) whole rows", said).group(1))
    assert kept == data.count(b"\n") - 1 and kept > 10
    rows = np.loadtxt(csv, delimiter=",", skiprows=1)
    assert rows.shape[0] == kept and np.isfinite(rows).all()


@pytest.mark.parametrize("scene", ["drop", "rm3"])  # one body; several
def test_a_run_onto_a_full_disk_keeps_whole_rows_and_says_how_many(scene, tmp_path):
    with full_disk(tmp_path / "disk") as disk:
        csv = disk / "x.csv"
        done = cli("run", "--scene", scene, "--t-end", "60", "--every", "1", "--out", str(csv))
        said = one_line(done)
        assert said.startswith(f"floatsim: cannot write {csv}: No space left on device (kept the header and ")
        assert_cut_at_a_whole_row(csv, said)


SWEEP = ["sweep", "--param", "density=300:900:12", "--t-end", "0.1", "--chunk", "1"]
"""Twelve chunks of about 5 kB (8 kB on the tmpfs): the disk of 64 kB is full after about seven."""


def run_sweep_onto_a_full_disk(tmp_path: Path, backend: str, resume: bool) -> None:
    """A sweep fills the disk: the chunks it says it wrote are whole, recorded and read as one table; no temporary
    is left; with room again, --resume runs only the rest."""
    with full_disk(tmp_path / "disk") as disk:
        out = disk / "s"
        args = [*SWEEP, "--backend", backend, "--workers", "2", "--out", str(out)]
        said = one_line(cli(*args))
        written = int(re.search(r": (\d+) chunks of 12 written to ", said).group(1))
        assert (
            re.match(rf"floatsim: cannot write {out}/(chunk-\d{{5}}\.parquet|_manifest\.json): ", said)
            and "rerun with --resume to finish" in said
        )
        recorded = json.loads((out / "_manifest.json").read_text())["files"]
        assert 2 <= written < 12 and len(recorded) == written  # chunks finish in any order on workers
        assert sorted(p.name for p in out.iterdir()) == sorted(["_manifest.json", *recorded])  # every file recorded, no temporary
        assert len(pd.read_parquet(out)) == written
        if not resume:
            return
        subprocess.run(["mount", "-o", "remount,size=4m", str(disk)], check=True)
        done = cli(*args, "--resume")
        assert done.returncode == 0 and f"({written} already done, {12 - written} to run)" in done.stdout, done.stderr
        assert sorted(pd.read_parquet(out)["case"]) == list(range(12))


def test_a_sweep_onto_a_full_disk_keeps_its_chunks(tmp_path):
    run_sweep_onto_a_full_disk(tmp_path, "serial", resume=False)


@pytest.mark.slow
@pytest.mark.parametrize("backend", ["serial", "local", "dask"])
def test_a_sweep_onto_a_full_disk_keeps_its_chunks_and_resume_finishes(tmp_path, backend):
    run_sweep_onto_a_full_disk(tmp_path, backend, resume=True)


def test_a_replay_that_does_not_fit_is_absent_not_half_written(tmp_path):
    csv = tmp_path / "x.csv"
    with full_disk(tmp_path / "disk") as disk:  # the replay page is about 0.8 MB
        said = one_line(
            cli(
                "run", "--scene", "drop", "--t-end", "1", "--out", str(csv), "--record", str(disk / "x.html"), module="app.recording.record"
            )
        )
        assert said.startswith(f"floatsim: cannot write {disk / 'x.html'}: No space left on device (no replay written; the CSV is whole)")
        assert list(disk.iterdir()) == []
    assert np.loadtxt(csv, delimiter=",", skiprows=1).shape[0] == 21


@pytest.mark.slow
def test_a_video_that_does_not_fit_is_absent_not_half_written(tmp_path):
    pytest.importorskip("av")
    with full_disk(tmp_path / "disk", size="8k") as disk:  # 11 frames take 11-13 kB
        said = one_line(
            cli("run", "--scene", "drop", "--t-end", "1", "--fps", "10", "--video", str(disk / "x.mp4"), module="app.recording.record")
        )
        assert said.startswith(f"floatsim: cannot write {disk / 'x.mp4'}: No space left on device (no video written)")
        assert list(disk.iterdir()) == []


KILLED_WRITE = """
import os, sys, pyarrow.parquet as pq
from pathlib import Path
from sim.commands.sweep import write
real = pq.write_table
def killed(table, where, **kw):
    real(table, where, **kw)
    os.truncate(where, 100)
    os._exit(9)  # killed before the rename: half a file under the temporary's name
pq.write_table = killed
write(Path(sys.argv[1]), {"case": [99]})
"""


GRID = ["sweep", "--param", "density=300,900", "--t-end", "0.1", "--chunk", "1"]


def killed_while_writing(out: Path) -> pd.DataFrame:
    """A sweep into `out`, then a write of a chunk killed before its rename; what the sweep wrote."""
    assert cli(*GRID, "--out", str(out)).returncode == 0
    whole = pd.read_parquet(out)
    killed = subprocess.run(
        [sys.executable, "-c", KILLED_WRITE, str(out / "chunk-00003.parquet")], env={**os.environ, "PYTHONPATH": str(ROOT)}
    )
    assert killed.returncode == 9
    (left,) = [p for p in out.iterdir() if p.name.endswith(".partial")]
    assert TEMPORARY.fullmatch(left.name) and left.name.startswith("_chunk-00003.parquet.")
    return whole


def test_a_temporary_left_by_a_killed_write_does_not_spoil_the_folder(tmp_path):
    out = tmp_path / "s"
    whole = killed_while_writing(out)
    pd.testing.assert_frame_equal(pd.read_parquet(out), whole)  # the half file is skipped by the reader


@pytest.mark.slow
def test_resume_removes_the_temporaries_of_writes_that_did_not_finish(tmp_path):
    out = tmp_path / "s"
    whole = killed_while_writing(out)
    (out / "chunk-00001.partial").write_bytes(b"PAR1 half")  # an earlier floatsim's name: it spoils the folder
    with pytest.raises(Exception):
        pd.read_parquet(out)
    done = cli(*GRID, "--out", str(out), "--resume")
    assert done.returncode == 0 and "(2 already done, 0 to run)" in done.stdout, done.stderr
    assert done.stderr.startswith("floatsim: note: removed 2 temporary files of a write that did not finish")
    assert sorted(p.name for p in out.iterdir()) == ["_manifest.json", "chunk-00000.parquet", "chunk-00001.parquet"]
    pd.testing.assert_frame_equal(pd.read_parquet(out), whole)

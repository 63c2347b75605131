"""Sweeps: grids of cases in chunks, identical numbers on every backend and chunking, results that
survive an interruption or a dying worker, clear errors; and the floating cube's stable orientation
found two independent ways (dynamics to rest, and the least potential over orientations)."""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from sim.commands import main
from sim.sweeps.grid import Sweep, case_scene, chunks, parse_param

GRID = ["--param", "density=300:900:4", "--param", "orientation_seed=0:2:3", "--settle", "--t-end", "40", "--scene", "damped"]


def results(folder: Path) -> pd.DataFrame:
    return pd.read_parquet(folder).sort_values("case").reset_index(drop=True)


def test_grid_is_the_product_of_lists_and_ranges():
    sweep = Sweep("damped", (parse_param("density=100:900:5"), parse_param("tilt=0,10"), parse_param("integrator=rk4,implicit")))
    cases = sweep.cases()
    assert len(cases) == 20 and cases[0] == {"density": 100.0, "tilt": 0.0, "integrator": "rk4"} and cases[-1]["density"] == 900.0
    scenes = [case_scene(sweep.base(), c) for c in cases]
    assert scenes[2].initial.orientation == pytest.approx((math.cos(math.radians(5)), math.sin(math.radians(5)), 0, 0))
    plan = chunks(Sweep(**{**sweep.__dict__, "chunk": 3}), scenes)
    assert sorted(i for c in plan for i in c) == list(range(20)) and max(map(len, plan)) == 3
    for c in plan:  # rk4 and implicit cases never share an ensemble
        assert len({scenes[i].step.integrator for i in c}) == 1


@pytest.mark.slow
def test_every_backend_and_chunking_gives_the_same_numbers_bit_for_bit(tmp_path):
    assert main(["sweep", *GRID, "--out", str(tmp_path / "serial"), "--chunk", "5"]) == 0
    serial = results(tmp_path / "serial")
    assert len(serial) == 12 and set(serial.status) == {"rest"}
    # the cube comes to rest face up at r = 0.9 and corner up (54.7 degrees) at r = 0.3 to 0.7, from any start
    assert serial[serial.density == 900].tilt_deg.max() < 0.5
    assert np.allclose(serial[serial.density < 800].tilt_deg, math.degrees(math.acos(3**-0.5)), atol=0.5)
    assert main(["sweep", *GRID, "--out", str(tmp_path / "small"), "--chunk", "2"]) == 0
    assert main(["sweep", *GRID, "--out", str(tmp_path / "local"), "--chunk", "5", "--backend", "local", "--workers", "2"]) == 0
    assert main(["sweep", *GRID, "--out", str(tmp_path / "dask"), "--chunk", "5", "--backend", "dask", "--workers", "2"]) == 0
    for other in ("small", "local", "dask"):
        pd.testing.assert_frame_equal(results(tmp_path / other), serial, check_exact=True)


def test_resume_runs_only_the_missing_chunks(tmp_path, capsys):
    out = tmp_path / "s"
    assert main(["sweep", *GRID, "--out", str(out), "--chunk", "2"]) == 0
    full = results(out)
    for cid in (1, 4):  # an interruption lost these two
        (out / f"chunk-{cid:05d}.parquet").unlink()
    capsys.readouterr()
    assert main(["sweep", *GRID, "--out", str(out), "--chunk", "2", "--resume"]) == 0
    said = capsys.readouterr().out
    assert "(4 already done, 2 to run)" in said and "ran 2 chunks (4 cases" in said
    pd.testing.assert_frame_equal(results(out), full, check_exact=True)
    assert main(["sweep", *GRID, "--out", str(out), "--chunk", "2"]) == 2  # no --resume: refuses to mix


@pytest.mark.slow
def test_a_worker_killed_mid_run_keeps_the_finished_chunks(tmp_path):
    out = tmp_path / "k"
    args = [sys.executable, "-m", "sim", "sweep", "--param", "density=300:900:8", "--param", "orientation_seed=0:3:4", "--t-end", "300",
            "--scene", "damped", "--chunk", "2", "--backend", "local", "--workers", "2", "--out", str(out)]  # fmt: skip
    run = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while not list(out.glob("chunk-*.parquet")) and time.monotonic() < deadline:
        time.sleep(0.05)
    children = [int(p) for p in Path(f"/proc/{run.pid}/task/{run.pid}/children").read_text().split()]
    workers = [p for p in children if b"resource_tracker" not in Path(f"/proc/{p}/cmdline").read_bytes()]
    assert workers, "no worker processes"
    os.kill(workers[0], signal.SIGKILL)
    _, err = run.communicate(timeout=120)
    written = len(list(out.glob("chunk-*.parquet")))
    assert run.returncode == 4 and "rerun with --resume" in err and 1 <= written < 16
    done = subprocess.run([*args, "--resume"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0 and f"({written} already done, {16 - written} to run)" in done.stdout
    assert len(results(out)) == 32


@pytest.mark.slow
def test_a_small_sweep_on_every_core_is_cut_into_a_chunk_per_worker(tmp_path):
    """The README's `sweep --param density=300:1500:7 --backend local` on 2 workers: 2 chunks (4 + 3 cases), not one chunk of
    7 on one worker (issue 39); --resume on another backend keeps the sweep's own chunks and runs only the one lost."""
    out = tmp_path / "s"
    args = [sys.executable, "-m", "sim", "sweep", "--param", "density=300:1500:7", "--t-end", "0.5", "--out", str(out)]
    done = subprocess.run([*args, "--backend", "local", "--workers", "2"], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "7 cases of 'damped' in 2 chunks of up to 4, backend local" in done.stdout
    assert json.loads((out / "_manifest.json").read_text())["chunks"] == [[0, 1, 2, 3], [4, 5, 6]]
    (out / "chunk-00001.parquet").unlink()
    again = subprocess.run([*args, "--backend", "serial", "--resume"], capture_output=True, text=True, timeout=600)
    assert again.returncode == 0 and "in 2 chunks of up to 4 (1 already done, 1 to run)" in again.stdout, again.stdout + again.stderr
    assert len(results(out)) == 7


def test_a_cube_heavier_than_water_is_reported_sunk_without_a_draft(tmp_path):
    """`python -m sim sweep` over densities above water's (issue 39): those cubes end wholly under water, sinking; their
    status says `sank` and their draft is NaN (it said `end` with a "draft" of 64 m), while the floating one keeps its
    Archimedes draft."""
    out = tmp_path / "s"
    done = subprocess.run([sys.executable, "-m", "sim", "sweep", "--param", "density=900,1100,1500", "--t-end", "8", "--out", str(out)],
                          capture_output=True, text=True, timeout=600)  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    assert "(3 cases: 1 end, 2 sank)" in done.stdout
    rows = results(out).set_index("density")
    assert list(rows.status) == ["end", "sank", "sank"]
    assert rows.draft.loc[[1100.0, 1500.0]].isna().all() and rows.period.loc[[1100.0, 1500.0]].isna().all()
    assert (rows.z.loc[[1100.0, 1500.0]] < -2.0).all() and 0.5 < rows.draft.loc[900.0] < 3**0.5  # still bobbing: under its diagonal


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--param", "wobble=1:2:3"], "--param wobble: unknown parameter"),
        (["--param", "density=1:2:0"], "the range is empty"),
        (["--param", "density=abc"], "values must be numbers"),
        (["--param", "density=-5,300"], "density must be >= 0.001"),
        (["--scene", "damped"], "nothing to sweep"),
        (
            ["--param", "density=300", "--scheduler", "tcp://127.0.0.1:9", "--timeout", "1"],
            "cannot reach the Dask scheduler at tcp://127.0.0.1:9",
        ),
        (["--param", "density=300", "--scheduler", "foo", "--timeout", "1"], "cannot reach the Dask scheduler at foo"),
        (["--param", "orientation_seed=-1,2"], "seeds must be in 0..4294967295"),
        (["--param", "density=100:900:10000000000"], "over the limit of 200,000 cases"),
    ],
)
def test_bad_sweep_input_is_one_line(argv, message, capsys, tmp_path):
    assert main(["sweep", *argv, "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err


def test_sweep_file_and_output_mistakes_are_one_line(tmp_path, capsys):
    (tmp_path / "file").write_text("")
    assert main(["sweep", "--param", "density=300", "--out", str(tmp_path / "file")]) == 2
    assert "is a file, give a folder" in capsys.readouterr().err
    bad = tmp_path / "bad.toml"
    bad.write_text('chunk = "big"\n[params]\ndensity = "300"\n')
    assert main(["sweep", "--file", str(bad), "--out", str(tmp_path / "o")]) == 2
    assert "chunk must be a whole number" in capsys.readouterr().err
    nested = tmp_path / "nested.toml"  # [set] written as TOML tables, not quoted keys
    nested.write_text('scene = "rest"\n[params]\ndensity = "300,500"\n[set]\nfluid.damping = 300.0\n[set.step]\ndt = 0.01\n')
    assert main(["sweep", "--file", str(nested), "--t-end", "0.5", "--out", str(tmp_path / "n")]) == 0
    assert dict(json_manifest(tmp_path / "n")["set"]) == {"fluid__damping": 300.0, "step__dt": 0.01, "step__t_end": 0.5}


def json_manifest(folder: Path) -> dict:
    import json

    return json.loads((folder / "_manifest.json").read_text())


@pytest.mark.parametrize("dt", [0.004, 0.003, 0.007])
def test_settling_is_checked_every_second_whatever_the_step(dt, tmp_path):
    """The rest checks fall on whole seconds even when 1 s is not a whole number of 0.1 s samples of steps."""
    out = tmp_path / "s"
    assert main(["sweep", "--param", "density=500", "--scene", "rest", "--settle", "--t-end", "10", "--set", "fluid.damping=300", "--dt", str(dt),
                 "--out", str(out)]) == 0  # fmt: skip
    row = results(out).iloc[0]
    checks = row.time_to_rest / (round(1.0 / dt) * dt)  # a whole number of checks, one every round(1 / dt) steps
    assert row.status == "rest" and row.time_to_rest < 9.0 and abs(checks - round(checks)) < 1e-6


def test_histories_on_request(tmp_path):
    out = tmp_path / "h"
    assert main(["sweep", "--param", "density=500,900", "--t-end", "2", "--history-every", "20", "--scene", "drop", "--out", str(out)]) == 0
    history = pd.read_parquet(out / "_history")
    assert len(history) == 2 * 21 and set(history.case) == {0, 1}
    assert history[history.case == 1].z.iloc[0] == pytest.approx(0.0)
    assert len(results(out)) == 2  # the folder read whole skips _history and _manifest.json


@pytest.mark.slow
def test_least_potential_orientation_of_the_cube():
    """The static route alone: face up where it is the classic answer (r = 0.1, 0.9: GM > 0 and lowest),
    corner up (54.7 degrees) in the middle (Erdos, Schibler & Herndon, Am. J. Phys. 60, 335 (1992))."""
    from studies.stability import static_tilts

    static, energies = static_tilts(np.array([0.1, 0.4, 0.6, 0.9]))
    np.testing.assert_allclose(static, [0.0, 54.7356, 54.7356, 0.0], atol=0.05)
    # face up, U = M g (z_G - z_B) = M g (s/2 - d/2) with draft d = r s: the minimiser reaches it exactly
    assert energies[0] == pytest.approx(100.0 * 9.81 * (0.5 - 0.05), rel=1e-9)


@pytest.mark.slow
def test_simulation_and_energy_minimisation_agree_on_how_a_cube_floats(tmp_path):
    """Outside narrow bands around the transitions, the lowest rest state the dynamics reach from random
    starts is the static least-potential orientation."""
    from sim.commands.sweep import sweep
    from studies.stability import StabilityArgs, classify, lowest_found, static_tilts, sweep_args

    args = StabilityArgs(ratios=5, seeds=4, t_end=90.0, backend="serial", out=str(tmp_path / "st"))
    assert sweep(sweep_args(args, str(tmp_path / "st-sweep"))) == 0
    found = lowest_found(classify(pd.read_parquet(tmp_path / "st-sweep")))
    ratios = np.linspace(20.0, 980.0, 5) / 1000.0
    static, _ = static_tilts(ratios)
    for r, s in zip(ratios, static):
        assert abs(found[float(r)] - s) < 1.0, (r, found[float(r)], s)


def test_the_documented_sweep_file_is_the_stability_sweep():
    from sim.commands.sweep import SweepArgs, build
    from studies.stability import StabilityArgs, sweep_args

    from_file = build(SweepArgs(file=str(Path(__file__).resolve().parents[2] / "assets" / "sweeps" / "cube-stability.toml")))
    assert len(from_file) == 49 * 8 and from_file.settle
    assert from_file.key() == build(sweep_args(StabilityArgs(), "unused")).key()

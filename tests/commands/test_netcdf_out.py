"""Issue 60, netCDF out: `floatsim run --out run.nc` holds the CSV's rows as a dataset over time with CF units and the
scene in its attributes, read back with xarray; a Ctrl-C keeps the rows so far; without xarray, one line naming the
extra."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from tests.commands.test_interrupt import interrupt

xr = pytest.importorskip("xarray")  # the netcdf extra (in the test extra)
ROOT = Path(__file__).resolve().parents[2]


def run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "sim", "run", *args], cwd=ROOT, capture_output=True, text=True, timeout=300)


def test_a_run_as_netcdf_holds_the_csvs_rows_with_units_and_its_scene(tmp_path):
    """The drop for 1 s as CSV and as netCDF: the same rows (the CSV's 12 digits), `time` the CSV's t in s, each column
    a variable with its units (z in m, u in m s-1, E_total in J), the scene's density and water back from the
    attributes, and the command in `history`."""
    csv, nc = tmp_path / "drop.csv", tmp_path / "drop.nc"
    for out in (csv, nc):
        done = run("--scene", "drop", "--t-end", "1", "--out", str(out))
        assert done.returncode == 0 and str(out) in done.stdout, done.stderr
    rows = np.genfromtxt(csv, delimiter=",", names=True)
    with xr.open_dataset(nc) as ds:
        np.testing.assert_allclose(ds["time"].values, rows["t"], rtol=1e-11)
        for name in rows.dtype.names[1:]:
            np.testing.assert_allclose(ds[name].values, rows[name], rtol=1e-10, atol=1e-300, err_msg=name)
        assert (ds["z"].attrs["units"], ds["uz"].attrs["units"], ds["E_total"].attrs["units"], ds["time"].attrs["units"]) == (
            "m",
            "m s-1",
            "J",
            "s",
        )
        assert ds.attrs["Conventions"] == "CF-1.8" and "--scene drop" in ds.attrs["history"]
        scene = json.loads(ds.attrs["floatsim_scene"])
    assert scene["name"] == "drop" and scene["fluid"]["rho"] == 1000.0 and scene["step"]["t_end"] == 1.0


@pytest.mark.slow  # rm3's set-up (its radiation's fit)
def test_several_bodies_name_their_variables_and_units(tmp_path):
    """rm3's two bodies and its take-off: `float_z` is the float's height in m, `float_P_pto` its take-off's power in W."""
    nc = tmp_path / "rm3.nc"
    done = run("--scene", "rm3", "--t-end", "0.5", "--every", "1", "--out", str(nc))
    assert done.returncode == 0, done.stderr
    with xr.open_dataset(nc) as ds:
        assert ds["float_z"].attrs["units"] == "m" and ds["float_z"].attrs["long_name"].startswith("float: ")
        assert ds["float_P_pto"].attrs["units"] == "W" and ds["spar_wy"].attrs["units"] == "rad s-1"
        assert ds.sizes["time"] == 11 and abs(float(ds["float_z"][0]) - (-0.7)) < 1e-6


def test_ctrl_c_keeps_the_rows_so_far_in_the_netcdf_file(tmp_path):
    """A long run to run.nc stopped by Ctrl-C once it has stepped a while: exit 130, one line saying how many rows it
    kept, and the file holds them, time increasing, no NaN."""
    nc = tmp_path / "x.nc"
    started = time.monotonic()  # its set-up (xarray) takes 2-4 s under load: a Ctrl-C there keeps nothing, rightly
    done, stopped_in = interrupt(["run", "--t-end", "1e6", "--max-steps", "1000000000", "--every", "100", "--out", str(nc)],
                                 lambda: time.monotonic() - started > 6.0)  # fmt: skip
    assert done.returncode == 130 and stopped_in < 10.0, done.stderr
    assert done.stderr.count("\n") == 1 and "interrupted (Ctrl-C)" in done.stderr, done.stderr
    with xr.open_dataset(nc) as ds:
        t = ds["time"].values
        assert len(t) > 1 and f"kept {len(t)} rows" in done.stderr and np.all(np.diff(t) > 0) and np.isfinite(ds["z"].values).all()
    assert not list(tmp_path.glob("_*.partial*"))


def test_without_xarray_a_netcdf_out_is_one_line_naming_the_extra(tmp_path):
    """xarray made unimportable: `--out run.nc` is refused before the run in one line naming `.[netcdf]`; a CSV still runs."""
    code = ("import sys, runpy; sys.modules['xarray'] = None; sys.argv = ['floatsim', 'run', '--scene', 'drop', '--t-end', '0.1', "
            f"'--out', {str(tmp_path / 'x.nc')!r}]; runpy.run_module('sim', run_name='__main__')")  # fmt: skip
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and done.stderr.count("\n") == 1 and ".[netcdf]" in done.stderr, done.stderr
    assert not (tmp_path / "x.nc").exists()


def test_a_sweep_gathers_its_cases_over_its_parameters_into_one_netcdf(tmp_path):
    """3 densities x 2 dampings: one dataset whose dimensions are the two parameters (with their declared units),
    each result a variable over them holding the Parquet row of that case, and the sweep's key and command in its
    attributes; a --netcdf name not ending in .nc is one line before any case runs."""
    out, nc = tmp_path / "grid", tmp_path / "grid.nc"
    args = ["sweep", "--param", "density=300:900:3", "--param", "damping=0,100", "--t-end", "1", "--out", str(out)]
    done = subprocess.run([sys.executable, "-m", "sim", *args, "--netcdf", str(nc)], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0 and str(nc) in done.stdout, done.stderr
    import pandas as pd

    rows = pd.read_parquet(out)
    with xr.open_dataset(nc) as ds:
        assert dict(ds.sizes) == {"density": 3, "damping": 2}
        assert ds["density"].attrs["units"] == "kg/m^3" and ds["z"].attrs["units"] == "m" and ds["period"].attrs["units"] == "s"
        for _, row in rows.iterrows():
            case = ds.sel(density=row["density"], damping=row["damping"])
            assert float(case["z"]) == row["z"] and float(case["E_total"]) == row["E_total"] and str(case["status"].values) == row["status"]
        assert "density=300:900:3" in ds.attrs["history"] and json.loads(ds.attrs["floatsim_sweep"])["cases"] == 6
    wrong = subprocess.run([sys.executable, "-m", "sim", *args[:-1], str(tmp_path / "other"), "--netcdf", str(tmp_path / "x.csv")], cwd=ROOT,
                           capture_output=True, text=True, timeout=120)  # fmt: skip
    assert wrong.returncode == 2 and wrong.stderr.count("\n") == 1 and "--netcdf must name a .nc file" in wrong.stderr
    assert not (tmp_path / "other").exists()
    foreign = tmp_path / "coefficients.nc"  # a netCDF floatsim did not write (a user's Capytaine solve, say): never replaced
    foreign.write_bytes(b"CDF\x01" + bytes(100))
    refused = subprocess.run([sys.executable, "-m", "sim", *args[:-1], str(tmp_path / "other"), "--netcdf", str(foreign)], cwd=ROOT,
                             capture_output=True, text=True, timeout=120)  # fmt: skip
    assert refused.returncode == 2 and "an existing file floatsim did not write" in refused.stderr and foreign.stat().st_size == 104
    again = subprocess.run([sys.executable, "-m", "sim", *args, "--resume", "--netcdf", str(nc)], cwd=ROOT, capture_output=True, text=True,
                           timeout=300)  # fmt: skip
    assert again.returncode == 0, again.stderr  # its own earlier file is replaced

"""Issue 60, wave gauges: `[[gauges]] x, y` and `--gauge X Y` write the sea's elevation at fixed points, as Airy's
closed form has it; a gauge at a measured record's point writes the record beside the sea made from it; mistakes are
one line."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from sim.water.seas import wavenumber

ROOT = Path(__file__).resolve().parents[2]


def run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "sim", "run", *args], cwd=ROOT, capture_output=True, text=True, timeout=300)


def test_gauges_in_a_regular_swell_read_airys_wave_at_their_points(tmp_path):
    """The waves preset (H 0.5 m, T 6 s, along +x) with gauges at x = 0 and 10 m (--gauge): past the ramp, each column is
    (H/2) cos(k x - omega t + phi) with k from the dispersion relation, to 1e-6 of the amplitude (phi fitted on the
    first gauge), and in the columns eta_g1, eta_g2 after the others."""
    out = tmp_path / "g.csv"
    done = run("--scene", "waves", "--t-end", "40", "--every", "5", "--gauge", "0", "0", "--gauge", "10", "0", "--out", str(out))
    assert done.returncode == 0, done.stderr
    rows = np.genfromtxt(out, delimiter=",", names=True)
    assert rows.dtype.names[-2:] == ("eta_g1", "eta_g2")
    late = rows["t"] > 25.0  # the default ramp: 3.5 periods
    t, a, w = rows["t"][late], 0.25, 2 * math.pi / 6.0
    k = float(wavenumber(np.array([w]), 9.81, math.inf)[0])
    c, s = np.linalg.lstsq(np.column_stack([np.cos(w * t), np.sin(w * t)]), rows["eta_g1"][late], rcond=None)[0]
    assert math.hypot(c, s) == pytest.approx(a, rel=1e-6)
    phi = math.atan2(s, c)  # eta_g1 = a cos(w t - phi) = a cos(k 0 - w t + phi)
    np.testing.assert_allclose(rows["eta_g2"][late], a * np.cos(k * 10.0 - w * t + phi), atol=1e-6 * a)


def test_a_gauge_at_a_measured_record_reads_the_record_and_the_sea_made_from_it(tmp_path):
    """WEC-Sim's measured sea (assets/records) with `[[gauges]] at_record = true`: past its ramp, the sea's elevation
    there follows the record (its components to four times its peak frequency, linear between its samples) within 5 %
    RMS of the record's spread, correlated above 0.998."""
    scene = tmp_path / "rec.toml"
    scene.write_text(f"""[body]\nshape = "cube"\nsize = 1.0\npoints_per_edge = 6\ndensity = 900.0\n[fluid]\ndamping = 20.0\n
[waves]\nkind = "record"\nrecord = "{ROOT / "assets" / "records" / "rm3_wecsim_eta.csv"}"\n[initial]\nposition = [0.0, 0.0, -0.4]\n
[step]\ndt = 0.05\nt_end = 100.0\n[[gauges]]\nname = "buoy"\nat_record = true\n""")
    out = tmp_path / "rec.csv"
    done = run("--scene", str(scene), "--every", "2", "--out", str(out))
    assert done.returncode == 0, done.stderr
    rows = np.genfromtxt(out, delimiter=",", names=True)
    late = rows["t"] > 40.0
    sea, record = rows["eta_buoy"][late], rows["record_buoy"][late]
    assert np.sqrt(np.mean((sea - record) ** 2)) < 0.05 * np.std(record) and np.corrcoef(sea, record)[0, 1] > 0.998


@pytest.mark.parametrize(
    "gauges, message",
    [
        ("[[gauges]]\nx = 1.0\n", "give the gauge's x and y"),
        ('[[gauges]]\nx = 1.0\ny = "a"\n', "x and y must be finite numbers"),
        ("[[gauges]]\nx = 1.0\ny = 0.0\nz = 2.0\n", "unknown key 'z'"),
        ('[[gauges]]\nname = "a"\nx = 1.0\ny = 0.0\n[[gauges]]\nname = "a"\nx = 2.0\ny = 0.0\n', "two gauges named 'a'"),
        ('[[gauges]]\nname = "1st"\nx = 1.0\ny = 0.0\n', "use a letter"),
        ("[[gauges]]\nat_record = true\n", "is not a measured record"),
        ("[[gauges]]\nx = nan\ny = 0.0\n", "x and y must be finite numbers"),
    ],
)
def test_a_wrong_gauge_is_one_line(tmp_path, gauges, message):
    scene = tmp_path / "s.toml"
    scene.write_text((ROOT / "assets" / "scenes" / "drop.toml").read_text() + "\n" + gauges)
    done = run("--scene", str(scene), "--t-end", "0.1")
    assert done.returncode == 2 and done.stderr.count("\n") == 1 and message in done.stderr, done.stderr


def test_gauges_of_several_bodies_and_netcdf_name_their_units(tmp_path):
    """rm3 with a gauge 30 m up-wave: its column in the CSV of two bodies, and in netCDF with units m."""
    xr = pytest.importorskip("xarray")
    out = tmp_path / "rm3.nc"
    done = run("--scene", "rm3", "--t-end", "0.5", "--gauge", "-30", "0", "--out", str(out))
    assert done.returncode == 0, done.stderr
    with xr.open_dataset(out) as ds:
        assert ds["eta_g1"].attrs["units"] == "m" and "gauge g1" in ds["eta_g1"].attrs["long_name"]
        assert ds.sizes["time"] > 1

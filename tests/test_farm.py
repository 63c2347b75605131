"""Farms ([farm], sim/farm.py): the grid laid out as [[bodies]], each device's power (without radiation: the one
device's), the refusals and the BEM solve's memory limit."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from sim.config import load_scene, with_overrides
from sim.errors import ConfigError

ROOT = Path(__file__).resolve().parents[1]


def test_the_farm_preset_is_its_device_on_a_grid():
    """Six copies d1..d6, row by row, 10 m apart from where the scene places its one device, each on its own slide with
    its own take-off; the [farm] table goes back to one device once laid out (validating again changes nothing)."""
    farm = load_scene("farm")
    device = load_scene("point-absorber")
    assert [e.name for e in farm.bodies] == [f"d{i}" for i in range(1, 7)]
    for i, e in enumerate(farm.bodies):
        row, column = divmod(i, 3)
        np.testing.assert_allclose(e.initial.position, np.add(device.initial.position, (10.0 * column, 10.0 * row, 0.0)))
        assert (e.constraint.joint, e.constraint.pto_damping, e.parent) == ("prismatic", 2000.0, "world")
    assert (farm.farm.rows, farm.farm.columns) == (1, 1)
    assert with_overrides(farm, d3__pto_damping=500.0).bodies[2].constraint.pto_damping == 500.0  # one device's own take-off
    rm3 = with_overrides(load_scene("rm3"), farm__columns=2, farm__spacing=100.0)  # a device of several bodies
    assert [(e.name, e.parent) for e in rm3.bodies] == [("d1_spar", "world"), ("d1_float", "d1_spar"), ("d2_spar", "world"),
                                                        ("d2_float", "d2_spar")]  # fmt: skip
    assert rm3.bodies[3].initial.position[0] == pytest.approx(100.0)


@pytest.mark.slow
def test_each_device_of_a_farm_without_radiation_takes_the_one_devices_power(tmp_path):
    """Two devices 10 m apart without radiation do not feel one another: each one's mean take-off power over the last
    five wave periods is the one device's (the point absorber alone, run on its own) within 1e-4 (their starts differ by the
    wave's phase between them, a transient gone to 1e-5 by then)."""
    env = dict(os.environ, FLOATSIM_BACKEND="numpy")
    flags = ["--radiation", "none", "--t-end", "22", "--every", "1"]
    one, two = tmp_path / "one.csv", tmp_path / "two.csv"
    scene = tmp_path / "pair.toml"
    text = (ROOT / "assets" / "scenes" / "farm.toml").read_text().replace("rows = 2", "rows = 1").replace("columns = 3", "columns = 2")
    scene.write_text(text.replace("damping = 100.0", "damping = 0.0"))
    for args, out in ((["--scene", str(scene)], two), (["--scene", "point-absorber", "--damping", "0"], one)):
        done = subprocess.run([sys.executable, "-m", "sim", "run", *args, *flags, "--out", str(out)], cwd=ROOT, env=env,
                              capture_output=True, text=True, timeout=600)  # fmt: skip
        assert done.returncode == 0, done.stderr[-1500:]
    a = np.genfromtxt(one, delimiter=",", names=True)
    b = np.genfromtxt(two, delimiter=",", names=True)

    def mean_power(t, E):
        return (E[-1] - np.interp(t[-1] - 5 * 2.2, t, E)) / (5 * 2.2)

    alone = mean_power(a["t"], a["E_pto"])
    assert alone > 0.1
    for d in ("d1", "d2"):
        assert mean_power(b["t"], b[f"{d}_E_pto"]) == pytest.approx(alone, rel=1e-4), d


def test_a_farm_it_cannot_build_is_one_line(tmp_path):
    text = (ROOT / "assets" / "scenes" / "moored-buoy.toml").read_text() + "\n[farm]\nrows = 2\n"
    scene = tmp_path / "moored-farm.toml"
    scene.write_text(text)
    done = subprocess.run([sys.executable, "-m", "sim", "run", "--scene", str(scene), "--t-end", "0.1"], cwd=ROOT, capture_output=True,
                          text=True, timeout=300)  # fmt: skip
    assert done.returncode == 2 and "[farm] with [moorings]" in done.stderr and len(done.stderr.strip().splitlines()) == 1, done.stderr


def test_a_solve_past_the_memory_is_refused_with_its_numbers(monkeypatch):
    """The joint solve's dense matrices, 32 N^2 bytes: refused past half the memory available, before any is made."""
    from sim import farm, limits

    monkeypatch.setattr(limits, "available_bytes", lambda: 1.0e9)
    farm.check_panels(3000, 5)  # 288 MB: within 500 MB
    with pytest.raises(ConfigError, match="4000 wet panels: its matrices take about 0.512 GB, over the 0.5 GB"):
        farm.check_panels(4000, 6)

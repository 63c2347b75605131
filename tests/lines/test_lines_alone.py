"""Mooring lines alone under a prescribed motion (`python -m sim lines`, sim/lines/lines_alone.py): against OpenFAST's MoorDyn
on its own r-test case, the elastic catenary at rest and under a slow motion, and the one-line refusals."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
LINES = ROOT / "assets" / "moorings" / "md_5MW_OC4Semi.dat"
REFERENCE = ROOT / "assets" / "reference" / "md_5MW_OC4Semi_rows.csv"


def _lines(tmp_path, *args: str) -> tuple[subprocess.CompletedProcess, dict | None]:
    out = tmp_path / "tensions.csv"
    done = subprocess.run([sys.executable, "-m", "sim", "lines", *args, "--out", str(out)], cwd=ROOT, capture_output=True, text=True,
                          timeout=600)  # fmt: skip
    if done.returncode != 0:
        return done, None
    data = np.genfromtxt(out, delimiter=",", names=True)
    return done, {name: data[name] for name in data.dtype.names}


def _reference() -> np.ndarray:
    return np.genfromtxt(REFERENCE, delimiter=",", names=True, skip_header=1)


def test_the_oc4_semis_lines_under_openfasts_motion_pull_as_openfasts_moordyn(tmp_path):
    """OpenFAST's r-test md_5MW_OC4Semi: the three 835 m chains of the OC4-DeepCwind semi, their fairleads moved as
    OpenFAST's MoorDyn driver moved them (its printed positions, about 26 rows every 2.7 s over 60 s, through a cubic
    spline). Each fairlead's tension is OpenFAST's within 2 % at every printed row (measured 1.6 %, 0.9 % after the
    first 5 s), and each anchor's within 1.5 % (measured 1.2 %)."""
    ref = _reference()
    motion = tmp_path / "motion.csv"
    columns = [ref["t"]] + [ref[f"P{p}P{c}"] for p in (4, 5, 6) for c in "XYZ"]
    np.savetxt(motion, np.column_stack(columns), delimiter=",", header="t,x4,y4,z4,x5,y5,z5,x6,y6,z6", fmt="%.10g")
    done, run = _lines(tmp_path, "--lines", str(LINES), "--motion", str(motion), "--dt", "0.0125")
    assert run is not None, done.stderr
    assert "3 lines" in done.stdout
    for i in (1, 2, 3):
        fair = np.interp(ref["t"], run["t"], run[f"T_fair_{i}"])
        anchor = np.interp(ref["t"], run["t"], run[f"T_anch_{i}"])
        assert np.abs(fair / ref[f"FAIRTEN{i}"] - 1).max() < 0.02, i
        assert np.abs(anchor / ref[f"ANCHTEN{i}"] - 1).max() < 0.015, i
    # the points followed the motion given
    np.testing.assert_allclose(np.interp(ref["t"], run["t"], run["x_1"]), ref["P4PX"], atol=1e-6)


@pytest.mark.slow
def test_the_oc4_semis_lines_close_their_energy_with_what_they_dissipate(tmp_path):
    """The same case with --energy: the work OpenFAST's motion does on the chains (1.7 MJ at most, W_in) is what they
    store (E_lines: their motion, wet weight lifted, stretch and seabed spring) plus what their drag, internal damping
    and the seabed have dissipated (D_lines, 190 kJ in 60 s), within 1e-3 of the work at every step (measured 1e-4)."""
    ref = _reference()
    motion = tmp_path / "motion.csv"
    columns = [ref["t"]] + [ref[f"P{p}P{c}"] for p in (4, 5, 6) for c in "XYZ"]
    np.savetxt(motion, np.column_stack(columns), delimiter=",", header="t,x4,y4,z4,x5,y5,z5,x6,y6,z6", fmt="%.10g")
    done, run = _lines(tmp_path, "--lines", str(LINES), "--motion", str(motion), "--dt", "0.0125", "--energy")
    assert run is not None, done.stderr
    residual = run["W_in"] - (run["E_lines"] - run["E_lines"][0]) - run["D_lines"]
    assert run["D_lines"][-1] > 1e5 and np.all(np.diff(run["D_lines"]) >= 0)
    assert np.abs(residual).max() < 1e-3 * np.abs(run["W_in"]).max(), (np.abs(residual).max(), np.abs(run["W_in"]).max())
    assert "energy: the moved points did" in done.stdout


def _catenary_tension(anchor, fairlead) -> float:
    from sim.lines.catenary import fairlead_tension

    w = (113.35 - 1025.0 * np.pi * 0.0766**2 / 4) * 9.80665  # the file's chain in its water
    gap = np.asarray(fairlead) - np.asarray(anchor)
    return fairlead_tension(float(np.hypot(*gap[:2])), float(gap[2]), 835.35, w, 7.536e8)


def test_a_slow_surge_pulls_as_the_elastic_catenary(tmp_path):
    """The OC4 semi's spread moved as a rigid body 8 m in surge over 400 s (a quasi-static pull): the fairlead tensions
    MoorDyn gives (its net force on the fairlead node) are the elastic catenary's (sim.lines.catenary) within 1 % all the way
    (measured 0.8 %), up-wave and down-wave lines alike."""
    t = np.linspace(0.0, 400.0, 81)
    surge = 4.0 * (1 - np.cos(np.pi * t / 400.0))  # from rest to rest
    motion = tmp_path / "surge.txt"
    np.savetxt(motion, np.column_stack([t, surge, 0 * t, 0 * t, 0 * t, 0 * t, 0 * t]), header="t x y z roll pitch yaw")
    done, run = _lines(tmp_path, "--lines", str(LINES), "--motion", str(motion), "--dt", "0.05", "--every", "200")
    assert run is not None, done.stderr
    anchors = {1: (418.8, 725.383, -200.0), 2: (-837.6, 0.0, -200.0), 3: (418.8, -725.383, -200.0)}
    fairleads = {1: (20.434, 35.393, -14.0), 2: (-40.868, 0.0, -14.0), 3: (20.434, -35.393, -14.0)}
    for i in (1, 2, 3):
        x = np.interp(run["t"], t, surge)
        expected = [_catenary_tension(anchors[i], np.add(fairleads[i], (s, 0.0, 0.0))) for s in x]
        np.testing.assert_allclose(run[f"T_fair_{i}"], expected, rtol=0.01)
    assert run["T_fair_2"][-1] > 1.2 * run["T_fair_2"][0]  # the down-wave line took up the pull


@pytest.mark.parametrize(
    "flags, message",
    [
        (["--lines", "nowhere.dat", "--motion", "nowhere.txt"], "--lines: no such file"),
        (["--lines", str(LINES), "--motion", str(LINES)], "the motion needs at least 4 rows"),
        (["--lines", str(LINES), "--motion", "MOTION5"], "5 columns after the time; give 6"),
        (["--lines", str(LINES), "--motion", "MOTION6", "--t-end", "99"], "must lie within the motion's times"),
    ],
)
def test_a_motion_it_cannot_follow_is_one_line(tmp_path, flags, message):
    for name, columns in (("MOTION5", 6), ("MOTION6", 7)):
        path = tmp_path / f"{name}.txt"
        np.savetxt(path, np.column_stack([np.arange(5.0)] + [np.zeros(5)] * (columns - 1)))
        flags = [str(path) if f == name else f for f in flags]
    done, _ = _lines(tmp_path, *flags)
    assert done.returncode == 2 and message in done.stderr and len(done.stderr.strip().splitlines()) == 1, done.stderr

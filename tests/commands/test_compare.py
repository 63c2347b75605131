"""`python -m sim compare` as a user runs it: each integrator's observed order against its declared one where the forces
are smooth, and the note that says why the orders fall where samples cross the water line."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from sim import INTEGRATORS

ROOT = Path(__file__).resolve().parents[2]
SUBMERGED = ["--z0", "-3", "--density", "1500", "--shape", "box", "--extents", "1", "0.6", "0.3", "--points-per-edge", "3"]
"""The damped scene's body made an asymmetric box (three different moments of inertia: a nonlinear tumble) that sinks from
3 m down: no sample ever reaches the water line, so every force is smooth in time."""


def compare(*flags: str) -> tuple[list[dict], list[str]]:
    """The table's rows and the lines under it, from `python -m sim compare` in a child process (numpy: no compile)."""
    env = {**os.environ, "FLOATSIM_BACKEND": "numpy", "PYTHONPATH": str(ROOT)}
    done = subprocess.run([sys.executable, "-m", "sim", "compare", "--repeats", "1", *flags], capture_output=True, text=True,
                          timeout=300, env=env, cwd=ROOT)  # fmt: skip
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    table = [line for line in lines if line.startswith("|")]
    keys = [cell.strip() for cell in table[0].strip("|").split("|")]
    rows = [dict(zip(keys, (cell.strip() for cell in line.strip("|").split("|")))) for line in table[2:]]
    return rows, lines[lines.index(table[-1]) + 1 :]


def floor_of(notes: list[str]) -> float:
    return float(next(line for line in notes if line.startswith("reference floor")).split()[2])


def test_on_a_smooth_scene_each_integrator_shows_its_declared_order():
    """Every observed order (slope of log error against log dt, dt halving from 0.04 to 0.01 s over 1 s) within 0.3 of the
    integrator's declared order, with every error far above the reference's own (so no order is cut off by the floor)."""
    rows, notes = compare("--scene", "damped", *SUBMERGED, "--t-end", "1", "--dts", "0.04", "0.02", "0.01")
    assert any(line.startswith("smooth: no samples crossed the water line") for line in notes), notes
    floor = floor_of(notes)
    assert 0 < floor < 1e-12  # the reference is that close to one at 10x its tolerance
    assert {row["integrator"] for row in rows} == {"euler", "splitting", "implicit", "rk4"}
    for name in ("euler", "splitting", "implicit", "rk4"):
        mine = [row for row in rows if row["integrator"] == name]
        assert [float(row["dt (s)"]) for row in mine] == [0.04, 0.02, 0.01]
        assert all(int(row["declared order"]) == INTEGRATORS[name].order for row in mine)
        assert all(float(row["error (m)"]) > 100 * floor for row in mine)
        orders = [float(row["observed order"]) for row in mine[1:]]
        assert orders == pytest.approx([INTEGRATORS[name].order] * 2, abs=0.3), (name, mine)


@pytest.mark.slow  # two DOP853 references through the jumps: about 5 s of CPU
def test_where_samples_cross_the_water_line_it_says_so_and_rk4_loses_its_order():
    """The damped cube's samples cross the water line and the damping force jumps there: the note says so, and rk4's
    observed order falls well short of 4 somewhere on dt 0.04 to 0.005 s (the errors above the reference's floor)."""
    rows, notes = compare("--scene", "damped", "--points-per-edge", "4", "--t-end", "1", "--dts", "0.04", "0.02", "0.01", "0.005",
                          "--integrators", "rk4")  # fmt: skip
    note = next(line for line in notes if line.startswith("not smooth:"))
    assert int(note.split()[2]) > 0 and "the damping force jumps at each" in note, note
    assert all(float(row["error (m)"]) > 100 * floor_of(notes) for row in rows)
    assert min(float(row["observed order"]) for row in rows[1:]) < INTEGRATORS["rk4"].order - 1, rows


def test_a_step_that_does_not_divide_the_duration_is_refused(capsys):
    """Its last step would end short of t_end (12 steps of 0.08 s end at 0.96 s) and its 'error' would be the motion it
    missed: refused in one line before any run."""
    from sim.commands import main

    assert main(["compare", "--t-end", "1", "--dts", "0.04", "0.08"]) == 2
    assert "dt 0.08 does not divide t_end 1" in capsys.readouterr().err

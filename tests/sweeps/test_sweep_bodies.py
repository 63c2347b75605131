"""Sweeps of a scene of several bodies: a wave-energy converter's power matrix over wave period and take-off damping,
from the CLI, against linear theory; and the one-line errors of a sweep that cannot be run."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

from sim.scene.config import load_scene, with_overrides
from sim.sweeps.grid import case_scene
from sim.system.frequency import response
from sim.system.tree import build
from tests.system.test_rm3 import _shipped_only  # noqa: F401  (the fixture: the shipped coefficients, no solve)


def sweep(*flags: str, timeout: float = 600) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "sim", "sweep", *flags], capture_output=True, text=True, timeout=timeout)


@pytest.mark.slow  # over 4 s (the marker's rule)
def test_a_power_matrix_of_rm3_matches_linear_theory(tmp_path):
    """rm3 with linear hydro (stepped exactly) over two wave periods and two take-off dampers, 300 s each in 1 m waves:
    the mean power over each run's second half matches the frequency domain's 0.5 c omega^2 |a xi_rel|^2 within 2 %
    (the radiation memory's fit and what is left of the start's transient), and the float's amplitude |a xi_rel| too."""
    base = with_overrides(load_scene("rm3"), fluid__hydro="linear")
    system, _ = build(base)
    c = system.radiation.coefficients
    indices = [int(np.argmin(abs(c.omega - 2 * np.pi / T))) for T in (6.0, 8.0)]
    periods = [2 * np.pi / float(c.omega[i]) for i in indices]
    dampers = [0.6e6, 2.4e6]
    out = tmp_path / "matrix"
    done = sweep("--scene", "rm3", "--set", "fluid.hydro=linear", "--set", "waves.height=1.0", "--set", "step.dt=0.1", "--t-end", "300",
                 "--param", "period=" + ",".join(f"{T:.12g}" for T in periods), "--param", "float.pto_damping=" + ",".join(map(str, dampers)),
                 "--out", str(out))  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    table = pd.read_parquet(out).sort_values("case").reset_index(drop=True)
    assert len(table) == 4 and set(table.status) == {"end"}
    for _, row in table.iterrows():
        i = indices[periods.index(min(periods, key=lambda T: abs(T - row["period"])))]
        scene = case_scene(
            with_overrides(base, waves__height=1.0), {"period": row["period"], "float.pto_damping": row["float.pto_damping"]}
        )
        system, rest = build(scene)
        xi = response(system, rest, i, froude_krylov=np.concatenate([loads.X[0] for loads in system.loads]) / 0.5)
        slide = next(g for g in system.joints if g.name == "float")
        w, relative = float(c.omega[i]), 0.5 * abs(xi[slide.dofs.start])
        expected = 0.5 * row["float.pto_damping"] * w * w * relative**2
        assert row["float_power"] == pytest.approx(expected, rel=0.02), (row["period"], row["float.pto_damping"])
        assert row["float_amplitude"] == pytest.approx(relative, rel=0.02)
        assert row["spar_power"] == 0.0  # no take-off on the spar's slide
    by = table.set_index(["period", "float.pto_damping"])["float_power"]
    assert by.max() > 2e4 and by.min() > 5e3  # tens of kilowatts in 1 m waves: a real converter, not a body at rest


@pytest.mark.parametrize(
    "flags, message",
    [
        (["--scene", "rm3", "--param", "buoy.pto_damping=1e6"], "'buoy' is not a section or one of the bodies (spar, float)"),
        (["--scene", "rm3", "--param", "float.colour=1"], "KEY one of controller, damping, declutch_time, density"),
        (["--scene", "damped", "--param", "float.pto_damping=1e6"], "the one body of this scene is named 'body' (body.pto_damping)"),
        (["--scene", "rm3", "--param", "z0=0,1"], "the start parameters are for one-body scenes"),
        (["--scene", "rm3", "--param", "float.pto_damping=1e6", "--settle"], "--settle is for one-body scenes"),
        (["--scene", "rm3", "--param", "float.pto_damping=-1"], "PTO damping must be >= 0"),
    ],
)
def test_a_sweep_of_bodies_it_cannot_run_is_a_one_line_error(flags, message, tmp_path):
    done = sweep(*flags, "--out", str(tmp_path / "out"), timeout=120)
    assert done.returncode != 0 and message in done.stderr and "Traceback" not in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) <= 2


def test_a_one_body_sweep_varies_its_take_off_by_name_and_the_energy_closes(tmp_path):
    """body.pto_damping on a one-body scene (its body is named `body`): a cube let go 0.1 m high on a vertical slide in
    still water, the take-off its only damping: the energy it absorbed is what the body lost (E_pto + E_total = E_total(0)),
    to the scheme's second order at dt 5 ms, and a stiffer damper absorbs it sooner."""
    from sim.simulation import Simulation

    out = tmp_path / "pto"
    done = sweep("--scene", "damped", "--set", "fluid.forces=panels", "--set", "fluid.damping=0", "--set", "constraint.joint=prismatic",
                 "--param", "z0=-0.3", "--param", "body.pto_damping=300,3000", "--t-end", "2", "--out", str(out), timeout=300)  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    table = pd.read_parquet(out).sort_values("body.pto_damping").reset_index(drop=True)
    base = with_overrides(load_scene("damped"), fluid__forces="panels", fluid__damping=0.0, constraint__joint="prismatic")
    start = Simulation(case_scene(base, {"z0": -0.3, "body.pto_damping": 300.0}), backend="numpy").frame().E_total
    for _, row in table.iterrows():
        assert row["E_pto"] > 0.0
        assert row["E_pto"] + row["E_total"] == pytest.approx(start, abs=1e-3 * row["E_pto"])
    assert table["E_pto"].iloc[1] > table["E_pto"].iloc[0]

"""Sweeps of a scene of several bodies: a wave-energy converter's power matrix over wave period and take-off damping,
from the CLI, against linear theory; and the one-line errors of a sweep that cannot be run."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
from test_rm3 import _shipped_only  # noqa: F401  (the fixture: the shipped coefficients, no solve)

from sim.config import load_scene, with_overrides
from sim.sweeps.grid import case_scene
from sim.system import build
from sim.system_frequency import response


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
        (["--scene", "rm3", "--param", "buoy.pto_damping=1e6"], "the scene has no body 'buoy' (its bodies: spar, float)"),
        (["--scene", "rm3", "--param", "float.colour=1"], "KEY one of pto_damping"),
        (["--scene", "damped", "--param", "float.pto_damping=1e6"], "BODY.KEY is for scenes of several bodies"),
        (["--scene", "rm3", "--param", "z0=0,1"], "the start parameters are for one-body scenes"),
        (["--scene", "rm3", "--param", "float.pto_damping=1e6", "--settle"], "--settle is for one-body scenes"),
        (["--scene", "rm3", "--param", "float.pto_damping=-1"], "PTO damping must be >= 0"),
    ],
)
def test_a_sweep_of_bodies_it_cannot_run_is_a_one_line_error(flags, message, tmp_path):
    done = sweep(*flags, "--out", str(tmp_path / "out"), timeout=120)
    assert done.returncode != 0 and message in done.stderr and "Traceback" not in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) <= 2

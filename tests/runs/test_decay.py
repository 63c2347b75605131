"""Free-decay tests: the record's analysis against closed forms, and the command a user runs."""

import math

import numpy as np
import pytest

from sim import Simulation, load_scene, with_overrides
from sim.bodies.surface import wet_panels
from sim.decay import analyse, release, signal
from sim.water.seas import StillWater
from studies.__main__ import main as studies_main


def test_analysis_of_a_damped_cosine_is_exact():
    t = np.arange(0.0, 30.0, 0.005)
    sigma, omega = 0.21, 2 * math.pi / 1.7
    wd = math.sqrt(omega**2 - sigma**2)
    y = 0.05 * np.exp(-sigma * t) * (np.cos(wd * t) + sigma / wd * np.sin(wd * t))  # released from rest
    d = analyse("heave", t, y)
    assert d.period == pytest.approx(2 * math.pi / wd, rel=1e-4)
    assert d.rate == pytest.approx(sigma, rel=1e-3)
    assert d.damping_ratio == pytest.approx(sigma / omega, rel=2e-3)
    first = math.pi / wd  # the first trough of a release from rest
    assert d.first_trough_time == pytest.approx(first, abs=1e-3)
    assert d.first_trough == pytest.approx(-0.05 * math.exp(-sigma * first), rel=1e-4)


def test_sphere_without_radiation_rings_at_its_hydrostatic_period_and_with_it_decays():
    """No damping, no radiation: no decay, and the period 2 pi sqrt(M / (rho g A_wp)) (A_wp = dV/dz of the
    mesh at rest, small amplitude). With radiation (the preset): slower, and it decays by the waves alone."""
    periods = {}
    for radiation in ("none", "bem"):
        sim = Simulation(with_overrides(load_scene("sphere"), fluid__radiation=radiation))
        dof, z_rest = release(sim, 0.005, 0.0)
        t, y = [0.0], [signal(sim, dof, z_rest)]
        for _ in range(1600):
            sim.step(1)
            t.append(sim.state.t)
            y.append(signal(sim, dof, z_rest))
        periods[radiation] = analyse(dof, np.array(t), np.array(y))
    volume = lambda z: wet_panels(sim.body, StillWater(), np.array([0.0, 0.0, z]), np.eye(3), 0.0).submerged_volume  # noqa: E731
    waterplane = (volume(z_rest - 1e-4) - volume(z_rest + 1e-4)) / 2e-4
    assert periods["none"].period == pytest.approx(2 * math.pi * math.sqrt(sim.body.mass / (1000.0 * 9.81 * waterplane)), rel=2e-3)
    assert abs(periods["none"].rate) < 1e-3
    assert periods["bem"].period > 1.1 * periods["none"].period  # the added mass
    assert periods["bem"].rate > 0.1  # radiation damping alone


def test_decay_command_writes_its_numbers_and_figure(tmp_path, capsys):
    out = tmp_path / "decay.png"
    assert studies_main(["decay", "--scene", "rest", "--drop", "0.02", "--duration", "4", "--out", str(out), "--radiation", "none",
                         "--damping", "50"]) == 0  # fmt: skip
    text = capsys.readouterr().out
    assert "heave decay of 'rest'" in text and "damped period" in text and "first trough" in text
    assert out.stat().st_size > 10_000


@pytest.mark.parametrize("argv, message", [(["--tilt", "95"], "--tilt must be"), (["--duration", "0"], "--duration must be"),
                                           (["--scene", "nosuch"], "unknown scene"), (["--scene", "rm3"], "has several bodies")])  # fmt: skip
def test_decay_command_bad_input_is_one_line(argv, message, capsys):
    assert studies_main(["decay", *argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]

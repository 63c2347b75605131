"""A joint released from a displaced pose ([constraint] start): the decay tests of several bodies, through `floatsim run`."""

import numpy as np
import pytest

from sim.commands import main

SLIDE = """
[fluid]
damping = 0.0
[step]
dt = 0.01
t_end = 30.0
[[bodies]]
name = "cube"
shape = "cube"
density = 500.0
{joint}
"""


def _run(tmp_path, joint: str, *flags: str) -> tuple[int, dict]:
    scene, out = tmp_path / "scene.toml", tmp_path / "run.csv"
    scene.write_text(SLIDE.format(joint=joint))
    try:
        code = main(["run", "--scene", str(scene), "--out", str(out), *flags])
    except SystemExit as e:  # a parse error exits from the parser
        code = e.code
    if code:
        return code, {}
    d = np.genfromtxt(out, delimiter=",", names=True)
    return code, {k: d[k] for k in d.dtype.names}


def test_a_spring_slide_released_from_its_start_swings_about_the_given_pose(tmp_path):
    """The floating cube (500 kg, at rest where the scene puts it) on a surge slide with a 100 N/m spring, started
    0.2 m along it: in still water nothing else acts along x, so x = 0.2 cos(sqrt(k / m) t) about the given pose."""
    code, d = _run(tmp_path, 'joint = "prismatic"\naxis = [1.0, 0.0, 0.0]\npto_stiffness = 100.0\nstart = 0.2')
    assert code == 0
    exact = 0.2 * np.cos(np.sqrt(100.0 / 500.0) * d["t"])
    assert d["cube_x"][0] == pytest.approx(0.2) and d["cube_theta"][0] == pytest.approx(0.2)
    assert np.abs(d["cube_x"] - exact).max() < 1e-5  # second order at dt = 0.01 s: 2e-6
    assert np.abs(d["cube_z"]).max() < 1e-9  # the slide holds its height: the rest the scene gave


def test_a_hinge_started_turned_swings_as_the_pendulum_it_is(tmp_path):
    """No water (rho = 0): the cube (500 kg, its inertia given, 100 kg m^2) on a hinge 1 m above its centre of mass,
    started turned 0.1 rad, is a compound pendulum: T = 2 pi sqrt((I + m d^2) / (m g d)) (1 + theta_0^2 / 16 + ...)."""
    code, d = _run(tmp_path, 'inertia = [100.0, 100.0, 100.0]\njoint = "revolute"\naxis = [1.0, 0.0, 0.0]\npivot = [0.0, 0.0, 1.0]\n'
                   "start = 0.1", "--rho", "0")  # fmt: skip
    assert code == 0
    theta, t = d["cube_theta"], d["t"]
    assert theta[0] == pytest.approx(0.1)
    i = np.flatnonzero((theta[:-1] < 0) & (theta[1:] >= 0))
    up = t[i] - theta[i] * (t[i + 1] - t[i]) / (theta[i + 1] - theta[i])
    small = 2 * np.pi * np.sqrt((100.0 + 500.0) / (500.0 * 9.81))
    assert np.median(np.diff(up)) == pytest.approx(small * (1 + 0.1**2 / 16 + 11 * 0.1**4 / 3072), rel=1e-4)
    assert theta.min() == pytest.approx(-0.1, abs=1e-4)  # no water, no loss: it swings as far the other way


@pytest.mark.parametrize(("joint", "message"), [
    ('joint = "fixed"', "start is a joint's coordinate: it needs a prismatic, revolute or planar joint, not 'fixed'"),
    ('joint = "free"\nstart = 0.1', "start is a joint's coordinate"),
])  # fmt: skip
def test_a_start_without_a_coordinate_is_one_clear_line(joint, message, tmp_path, capsys):
    code, _ = _run(tmp_path, joint + ("\nstart = 0.1" if "start" not in joint else ""))
    assert code == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_one_body_refuses_a_start_in_one_line(capsys):
    code = main(["run", "--scene", "rest", "--joint", "prismatic", "--start", "0.1", "--t-end", "0.1"])
    assert code == 2
    assert "[constraint] start is for a [[bodies]] entry" in capsys.readouterr().err


def test_a_long_bem_max_period_keeps_the_solve_grid_above_zero():
    """[fluid] bem_max_period reaches the grid down at its own spacing, but never to zero or below (a 1 m body asked
    for 100 s waves: its spacing is 0.17 rad/s); shorter asks reach past 2 pi / T."""
    import math

    from sim.hydro.bem import default_frequencies
    from sim.hydro.radiation import longest_wave
    from sim.scene.config import FluidConfig

    for length, period in ((1.0, 100.0), (28.0, 500.0), (28.0, 60.0)):
        w = default_frequencies(length, lowest=longest_wave(FluidConfig(bem_max_period=period), None))
        step = np.diff(w)
        assert w[0] > 0 and np.allclose(step, step[0])
        assert w[0] <= 2 * math.pi / period or w[0] < step[0]  # reached, or as near zero as the spacing allows

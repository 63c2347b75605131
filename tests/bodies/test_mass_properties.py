"""A body's centre of mass and inertia as its designer gives them ([body] centre_of_mass, inertia), through `floatsim run`."""

import numpy as np
import pytest

from sim.commands import main

RHO, G = 1000.0, 9.81
MASS, DROP = 500.0, 0.3
"""A unit cube at half its water's density (draft 0.5 m), ballasted: its centre of mass 0.3 m below its centre."""


def _scene(tmp_path, inertia: str) -> str:
    path = tmp_path / "ballasted.toml"
    path.write_text(f"""
[body]
shape = "cube"
density = 500.0
centre_of_mass = [0.0, 0.0, {-DROP}]
{inertia}
[fluid]
forces = "panels"
damping = 0.0
[initial]
position = [0.0, 0.0, {-DROP}]
omega = [0.02, 0.0, 0.0]
[step]
dt = 0.005
t_end = 12.0
""")
    return str(path)


def _roll_period(csv: str) -> float:
    d = np.genfromtxt(csv, delimiter=",", names=True)
    roll, t = 2.0 * np.arctan2(d["qx"], d["qw"]), d["t"]
    i = np.flatnonzero((roll[:-1] < 0) & (roll[1:] >= 0))
    up = t[i] - roll[i] * (t[i + 1] - t[i]) / (roll[i + 1] - roll[i])
    return float(np.median(np.diff(up)))


def _roll_stiffness() -> float:
    """rho g V GM: GM = BM + KB - KG = (1/12)/0.5 + 0.25 - (0.5 - DROP) for the unit cube at draft 0.5 m."""
    volume = MASS / RHO
    return RHO * G * volume * ((1.0 / 12.0) / volume + 0.25 - (0.5 - DROP))


@pytest.mark.parametrize("given", [True, False], ids=["inertia given", "shell inertia about the given centre"])
def test_the_roll_period_is_the_ballasted_bodys_closed_form(given, tmp_path, capsys):
    """Small free roll of the ballasted cube: T = 2 pi sqrt(I_xx / (rho g V GM)). Given, I_xx is the user's; unset,
    the uniform shell's about its centre, 5/18 m a^2, moved to the given centre of mass (parallel axes)."""
    inertia = MASS * (5.0 / 18.0 + DROP**2)
    line = "inertia = [50.0, 50.0, 60.0]" if given else ""
    out = tmp_path / "roll.csv"
    main(["run", "--scene", _scene(tmp_path, line), "--out", str(out)])
    said = capsys.readouterr().out
    assert ("as given" if given else "exact (mesh shell) about the given centre of mass") in said
    assert "GM +0.217 m" in said  # 1/6 + 0.25 - 0.2: the given centre of mass sets the stability
    expected = 2.0 * np.pi * np.sqrt((50.0 if given else inertia) / _roll_stiffness())
    assert _roll_period(str(out)) == pytest.approx(expected, rel=2e-4)


@pytest.mark.parametrize(("flags", "message"), [
    (["--inertia", "1", "1", "5"], "are not a rigid body's"),
    (["--inertia", "0", "1", "1"], "moments of inertia must be > 0"),
    (["--centre-of-mass", "0", "0", "nan"], "centre of mass must be finite"),
])  # fmt: skip
def test_impossible_mass_properties_get_one_clear_line(flags, message, tmp_path, capsys):
    try:
        code = main(["run", "--scene", _scene(tmp_path, ""), "--t-end", "0.1", *flags])
    except SystemExit as e:  # a parse error exits from the parser
        code = e.code
    assert code == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_a_sweep_and_a_live_density_change_keep_the_given_inertia(tmp_path):
    """Given moments are the body's whatever its mass: an ensemble of two densities (a sweep's cases) and a live
    density change keep them, where a shell's inertia scales with the mass."""
    from sim import Simulation
    from sim.ensemble import Ensemble
    from sim.scene.config import load_scene, with_overrides

    scene = load_scene(_scene(tmp_path, "inertia = [50.0, 40.0, 60.0]"))
    ensemble = Ensemble([with_overrides(scene, body__density=d) for d in (400.0, 600.0)], backend="numpy")
    assert [s.body.mass for s in ensemble.sims] == [400.0, 600.0]
    assert all(np.array_equal(s.body.inertia, [50.0, 40.0, 60.0]) for s in ensemble.sims)
    sim = Simulation(scene, backend="numpy")
    sim.update(body__density=700.0)
    assert sim.body.mass == 700.0 and np.array_equal(sim.body.inertia, [50.0, 40.0, 60.0])

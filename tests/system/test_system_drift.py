"""Issue 42, the waves' drift force on several bodies (`[waves] drift = true` with [[bodies]]): the far field of the
bodies' joint solve, with them moving as the linear system does, gives the drift of them all together, applied to the
root of their one tree. Checked: a one-entry system drifts as the one body does, rm3 free to surge drifts at the rate
its drift force predicts, and what is not built is one line."""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from sim.scene.config import load_scene
from sim.system.tree import build

ROOT = Path(__file__).resolve().parents[2]


def _scene(tmp_path, name: str, text: str) -> Path:
    path = tmp_path / f"{name}.toml"
    path.write_text(text.replace("../meshes/", str(ROOT / "assets" / "meshes") + "/"))
    return path


def _free_rm3(tmp_path) -> Path:
    """rm3 with its spar free to surge, heave and pitch (a planar joint) and linear hydrostatics (no mean force of its own)."""
    text = (ROOT / "assets" / "scenes" / "rm3.toml").read_text()
    text = text.replace('position = [0.0, 0.0, -18.6743]\njoint = "prismatic"\naxis = [0.0, 0.0, 1.0]',
                        'position = [0.0, 0.0, -18.6743]\njoint = "planar"\naxis = [0.0, 1.0, 0.0]')  # fmt: skip
    assert 'joint = "planar"' in text
    return _scene(tmp_path, "free-rm3", text.replace("[fluid]\n", '[fluid]\nhydro = "linear"\n'))


def _run(tmp_path, scene: Path, tag: str, *flags: str, backend: str = "numba") -> np.ndarray:
    out = tmp_path / f"{tag}.csv"
    env = {**os.environ, "FLOATSIM_BACKEND": backend}
    done = subprocess.run([sys.executable, "-m", "sim", "run", "--scene", str(scene), "--out", str(out), *flags], cwd=ROOT,
                          capture_output=True, text=True, timeout=600, env=env)  # fmt: skip
    assert done.returncode == 0, done.stderr
    return np.genfromtxt(out, delimiter=",", names=True)


def _drift(path) -> tuple:
    scene = load_scene(str(path))
    scene = dataclasses.replace(scene, waves=dataclasses.replace(scene.waves, drift=True))
    system, _ = build(scene)
    return system, system.radiation.wave_drift


def test_rm3_free_to_surge_drifts_downwave_at_the_rate_its_drift_force_predicts(tmp_path):
    """rm3's spar on a planar joint (the float on it), linear hydrostatics, its regular waves (2.5 m, 8 s), run by
    `floatsim run` with and without --wave-drift: the difference of the spar's surges accelerates at F / (M + A_11(0))
    after the ramp, F = a² D the two bodies' mean drift force (22.7 kN), M their mass and A_11(0) their surge added mass
    with its coupling, within 3 % (measured 0.5-1.1 %); downwave, without a sideways force. The compiled run and the
    numpy one agree to 1e-9 m over 2 s."""
    scene = _free_rm3(tmp_path)
    system, drift = _drift(scene)
    F = drift.mean
    assert F[0] > 1e4 and abs(F[1]) < 1e-3 * F[0]
    on = _run(tmp_path, scene, "on", "--t-end", "80", "--every", "4", "--wave-drift", "True")
    off = _run(tmp_path, scene, "off", "--t-end", "80", "--every", "4")
    c = system.radiation.coefficients
    mass = sum(m.body.mass for m in system.members)
    A = c.added_mass[0]
    expected = F[0] / (mass + A[0, 0] + A[6, 6] + 2 * A[0, 6])
    t, dx = on["t"], on["spar_x"] - off["spar_x"]
    late = t >= 20.0
    fit = np.polynomial.polynomial.polyfit(t[late], dx[late], 2)
    assert 2 * fit[2] == pytest.approx(expected, rel=0.03)
    numpy_run = _run(tmp_path, scene, "numpy", "--t-end", "2", "--every", "4", "--wave-drift", "True", backend="numpy")
    np.testing.assert_allclose(numpy_run["spar_x"], on["spar_x"][: len(numpy_run["spar_x"])], atol=1e-9)


def test_one_body_as_a_system_of_one_feels_the_drift_the_body_does(tmp_path):
    """The sphere on a surge slide in regular waves, as the one-body scene and as one [[bodies]] entry: the same mean
    drift force (their motions from two codes: drift.body_rao and system_frequency.raos) within 1e-6."""
    from sim import Simulation
    from sim.scene.config import with_overrides

    sea = {"waves__kind": "regular", "waves__height": 0.05, "waves__period": 1.5, "waves__drift": True, "constraint__joint": "prismatic",
           "constraint__axis": (1.0, 0.0, 0.0), "initial__position": (0.0, 0.0, 0.0)}  # fmt: skip
    one = Simulation(with_overrides(load_scene("sphere"), **sea), backend="numpy").model.radiation.drift.mean
    sphere = (ROOT / "assets" / "scenes" / "sphere.toml").read_text()
    body = sphere[sphere.index("[body]") :].split("\n[", 1)[0].replace("[body]\n", "")
    fluid = sphere[sphere.index("[fluid]") :].split("\n[", 1)[0]
    text = (f'{fluid}\n\n[waves]\nkind = "regular"\nheight = 0.05\nperiod = 1.5\n\n[[bodies]]\nname = "sphere"\n{body}\n'
            'position = [0.0, 0.0, 0.0]\njoint = "prismatic"\naxis = [1.0, 0.0, 0.0]\n')  # fmt: skip
    _, drift = _drift(_scene(tmp_path, "sphere-system", text))
    np.testing.assert_allclose(drift.mean, one, rtol=1e-6, atol=1e-6 * abs(one[0]))


@pytest.mark.parametrize(
    "extra, message",
    [
        (
            '[[bodies]]\nname = "b"\nshape = "cube"\nsize = 1.0\ndensity = 500.0\nposition = [5.0, 0.0, 0.0]\n',
            "joined in one tree",
        ),  # fmt: skip
    ],
)
def test_drift_on_bodies_apart_is_one_line(tmp_path, extra, message):
    """Two bodies each on the world: the far field gives only their total, so the drift is refused in one line before
    any solve."""
    text = ('[fluid]\nradiation = "bem"\n\n[waves]\nkind = "regular"\ndrift = true\n\n'
            '[[bodies]]\nname = "a"\nshape = "cube"\nsize = 1.0\ndensity = 500.0\n\n' + extra)  # fmt: skip
    done = subprocess.run([sys.executable, "-m", "sim", "run", "--scene", str(_scene(tmp_path, "apart", text)), "--t-end", "1"],
                          cwd=ROOT, capture_output=True, text=True, timeout=600)  # fmt: skip
    assert done.returncode == 2 and message in done.stderr and len(done.stderr.strip().splitlines()) == 1, done.stderr


def test_drift_with_a_bem_file_is_one_line():
    """A WAMIT .out carries no mean drift (its .8 or .9 would): the drift is refused in one line, before any solve."""
    done = subprocess.run([sys.executable, "-m", "sim", "run", "--scene", "rm3-wecsim-moorings", "--wave-drift", "True", "--t-end", "1"],
                          cwd=ROOT, capture_output=True, text=True, timeout=600)  # fmt: skip
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert "holds no mean drift: WAMIT's .8 or .9" in done.stderr

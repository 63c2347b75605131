"""Issue 60, WAMIT's mean drift files (`.8` by momentum conservation, `.9` by pressure integration) beside a scene's
`bem_file`: WEC-Sim Applications' floating hemisphere (assets/coefficients/wamit/hemisphere.*, studies/wamit_examples.py)
drives a run whose drift force is the file's, a `.9` alone is read in its place, and floatsim's own far-field drift of
the same body (its Capytaine solve) is checked against WAMIT's `.8`."""

from __future__ import annotations

import math
import shutil
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import trimesh

from sim.errors import ConfigError
from sim.hydro import bem
from sim.hydro.drift import body_rao, mean_drift
from sim.io.bem_file import drift_table
from sim.io.wamit_drift import read_drift

ROOT = Path(__file__).resolve().parents[2]
WAMIT = ROOT / "assets" / "coefficients" / "wamit"
RHO, G = 1000.0, 9.80665
MASS = RHO * 2.07293
"""The hemisphere as WAMIT had it: its displaced volume (its .out), floating freely."""


def drift_at(path: Path, omega: float) -> float:
    """The surge drift per unit amplitude squared, N/m², of a `.8` or `.9` at omega (linear between its frequencies)."""
    periods, _, D = read_drift(path, RHO, G)
    return float(np.interp(omega, 2 * math.pi / periods[::-1], D[::-1, 0, 0, 0]))


def run_hemisphere(folder: Path, bem_file: Path, period: float = 2.0, height: float = 0.1) -> subprocess.CompletedProcess:
    trimesh.creation.icosphere(subdivisions=3, radius=1.0).export(folder / "hemisphere.stl")
    scene = folder / "hemisphere.toml"
    scene.write_text(f'[fluid]\ng = {G}\nforces = "panels"\nradiation = "bem"\nbem_file = "{bem_file}"\n\n'
                     f'[waves]\nkind = "regular"\nheight = {height}\nperiod = {period}\ndrift = true\n\n'
                     f'[[bodies]]\nname = "hemisphere"\nshape = "mesh"\nmesh = "hemisphere.stl"\nmass = {MASS}\n\n'
                     '[step]\ndt = 0.01\nt_end = 0.1\n')  # fmt: skip
    return subprocess.run([sys.executable, "-m", "sim", "run", "--scene", str(scene)], cwd=ROOT, capture_output=True, text=True,
                          timeout=600)  # fmt: skip


def mean_fx(done: subprocess.CompletedProcess) -> float:
    line = next(line for line in done.stdout.splitlines() if line.startswith("wave drift: mean Fx = "))
    return float(line.split("Fx = ")[1].split()[0])


@pytest.mark.parametrize("period, height", [(2.0, 0.1), (1.8, 0.2)])
def test_the_drift_of_a_run_is_the_files(tmp_path, period, height):
    """The run's mean drift force is a^2 D(omega) of the `.8` beside the `.1`, at the wave's frequency (linear between the
    file's, as the drift force interpolates), and the summary says where it came from."""
    done = run_hemisphere(tmp_path, WAMIT / "hemisphere.1", period, height)
    assert done.returncode == 0, done.stderr
    expected = (height / 2) ** 2 * drift_at(WAMIT / "hemisphere.8", 2 * math.pi / period)
    assert mean_fx(done) == pytest.approx(expected, rel=1e-5) and "from the bem_file's mean drift" in done.stdout


def test_a_pressure_integration_alone_is_read_and_none_is_one_line(tmp_path):
    """Without a `.8`, the `.9` gives the drift (WAMIT's pressure integration: 6009 N/m² against the momentum's 8213 at
    3.5 rad/s on this coarse hull); with neither, a drift is refused in one line naming the files that would give it."""
    for suffix in (".1", ".3", ".9", ".hst", ".out"):
        shutil.copy(WAMIT / f"hemisphere{suffix}", tmp_path / f"h{suffix}")
    done = run_hemisphere(tmp_path, tmp_path / "h.1")
    assert done.returncode == 0, done.stderr
    assert mean_fx(done) == pytest.approx(0.05**2 * drift_at(WAMIT / "hemisphere.9", math.pi), rel=1e-5)
    (tmp_path / "h.9").unlink()
    done = run_hemisphere(tmp_path, tmp_path / "h.1")
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert "holds no mean drift: WAMIT's .8 or .9 beside its .1 gives it" in done.stderr


def test_the_files_drift_tends_to_the_short_wave_limit():
    """The units: WAMIT prints F / (rho g A^2 L). In short waves the hull's waterline reflects the wave it meets (the
    sphere is vertical there), so the drift tends to a vertical cylinder's short-wave limit, (2/3) rho g R per unit
    amplitude squared (Faltinsen 1990, ch. 5: 6.54 kN/m² for R = 1 m): the file's at 6.5 rad/s (kR = 4.3) is 5.96,
    nearing it from below."""
    assert drift_at(WAMIT / "hemisphere.8", 6.5) == pytest.approx(2 / 3 * RHO * G * 1.0, rel=0.1)


@pytest.mark.slow  # a Capytaine solve of the hemisphere with its far field
def test_floatsims_own_far_field_drift_of_the_hemisphere_meets_wamits(tmp_path, monkeypatch):
    """floatsim's mean drift from its own solve's far field (drift.mean_drift, the body moving as WAMIT's did: its mass,
    radii of gyration 0.4 m, waterplane) against WAMIT's `.8`, at WAMIT's frequencies away from the irregular ones its
    run did not remove (IRR = 0: spikes at 5.0, 6.2 and 7.1 rad/s) and off the resonance's steep flank (below 3.5 rad/s
    the drift rises 30-fold in 0.5 rad/s: a 0.3 % shift of the heave resonance moves it 5 %)."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    omega = np.array([3.55, 3.75, 4.05, 4.55, 5.55, 5.95])  # on the shipped grid (0.1 rad/s apart)
    hull = trimesh.creation.icosphere(subdivisions=3, radius=1.0)
    c = bem.radiation_coefficients(hull.vertices, hull.faces, RHO, G, math.inf, omega, panel=0.3, progress=False, far_field=True)
    M = np.diag([MASS] * 3 + [0.16 * MASS] * 3)
    C = np.zeros((6, 6))
    C[2, 2] = RHO * G * 3.128583  # WAMIT's waterplane (its .hst)
    ours = mean_drift(c, body_rao(c, M, C), G)[:, 0, 0]
    theirs = np.array([drift_at(WAMIT / "hemisphere.8", w) for w in omega])
    np.testing.assert_allclose(ours, theirs, rtol=0.03)


def test_a_drift_files_units_headings_and_moment_point(tmp_path):
    """A `.8` written here (ULEN 2, two headings listed out of order, a yaw row, the body's origin off the world's):
    forces come out as rho g L Fbar, the yaw moment as rho g L^2 Mbar moved to the world's origin (M_z + x0 F_y - y0 F_x),
    each heading's in its place, and the file's periods onto the run's frequencies."""
    rows = [(10.0, 90.0, 90.0, 1, 0.1, 0.0, 0.1, 0.0), (10.0, 90.0, 90.0, 2, 0.3, 0.0, 0.3, 0.0), (10.0, 90.0, 90.0, 6, 0.2, 0.0, 0.2, 0.0),
            (10.0, 0.0, 0.0, 1, 0.5, 0.0, 0.5, 0.0), (10.0, 0.0, 0.0, 2, 0.0, 0.0, 0.0, 0.0), (10.0, 0.0, 0.0, 6, 0.05, 0.0, 0.05, 0.0),
            (10.0, 0.0, 90.0, 1, 9.0, 0.0, 9.0, 0.0),  # a bichromatic pair of headings: left out
            (5.0, 0.0, 0.0, 1, 1.0, 0.0, 1.0, 0.0), (5.0, 90.0, 90.0, 1, 2.0, 0.0, 2.0, 0.0)]  # fmt: skip
    path = tmp_path / "run.8"
    path.write_text(" WAMIT Numeric Output -- Filename  run.8\n" + "".join(" ".join(f"{v:.6E}" for v in r) + "\n" for r in rows))
    L, x0, y0 = 2.0, 3.0, -1.0
    run = SimpleNamespace(omega=np.array([2 * math.pi / 10.0, 2 * math.pi / 5.0]), headings=np.radians([0.0, 90.0]), g=G, length=L,
                          centers=np.array([[x0, y0, 0.0]]), added_mass=np.zeros((2, 6, 6)))  # fmt: skip
    table = drift_table(tmp_path / "run.1", run, SimpleNamespace(rho=RHO))
    force, moment = RHO * G * L, RHO * G * L**2
    np.testing.assert_allclose(table[0, 0], [0.5 * force, 0.0, 0.05 * moment + x0 * 0.0 - y0 * 0.5 * force], rtol=1e-6)
    np.testing.assert_allclose(table[0, 1], [0.1 * force, 0.3 * force, 0.2 * moment + x0 * 0.3 * force - y0 * 0.1 * force], rtol=1e-6)
    np.testing.assert_allclose(table[1, :, 0], [1.0 * force, 2.0 * force], rtol=1e-6)


def test_several_bodies_drift_is_their_total_from_the_9(tmp_path):
    """Two bodies' `.9` (modes 1, 2, 6 and 7, 8, 12, each body's yaw about its own origin): the run's drift is their total,
    the yaw about the world's origin (each body's M_z + x_b F_y,b - y_b F_x,b); the `.8` alone is refused in one line (its
    momentum flux is the bodies' together)."""
    rows = [(10.0, 0.0, 0.0, 1, 0.5, 0.0, 0.5, 0.0), (10.0, 0.0, 0.0, 2, 0.1, 0.0, 0.1, 0.0), (10.0, 0.0, 0.0, 6, 0.05, 0.0, 0.05, 0.0),
            (10.0, 0.0, 0.0, 3, 7.0, 0.0, 7.0, 0.0),  # heave: not a drift floatsim applies
            (10.0, 0.0, 0.0, 7, 0.2, 0.0, 0.2, 0.0), (10.0, 0.0, 0.0, 8, -0.3, 0.0, -0.3, 0.0), (10.0, 0.0, 0.0, 12, 0.02, 0.0, 0.02, 0.0)]  # fmt: skip
    text = " WAMIT Numeric Output -- Filename  run.9\n" + "".join(" ".join(f"{v:.6E}" for v in r) + "\n" for r in rows)
    (tmp_path / "run.9").write_text(text)
    origins = np.array([[0.0, 0.0, 0.0], [30.0, 5.0, 0.0]])
    run = SimpleNamespace(omega=np.array([2 * math.pi / 10.0]), headings=np.radians([0.0]), g=G, length=1.0, centers=origins,
                          added_mass=np.zeros((1, 12, 12)))  # fmt: skip
    table = drift_table(tmp_path / "run.1", run, SimpleNamespace(rho=RHO))
    f = RHO * G
    x1, y1 = origins[1, :2]
    expected = [(0.5 + 0.2) * f, (0.1 - 0.3) * f, (0.05 + 0.02) * f + x1 * (-0.3 * f) - y1 * (0.2 * f)]
    np.testing.assert_allclose(table[0, 0], expected, rtol=1e-6)
    (tmp_path / "run.9").rename(tmp_path / "run.8")
    with pytest.raises(ConfigError, match="several bodies' drift is read from WAMIT's .9"):
        drift_table(tmp_path / "run.1", run, SimpleNamespace(rho=RHO))

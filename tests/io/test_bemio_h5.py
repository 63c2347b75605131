"""Issue 60, BEMIO's `.h5` files (WEC-Sim's and SEA-Stack's input) as a scene's coefficients: SEA-Stack's IEA sphere
read to its units (Hulme's high-frequency added mass, rho g times its waterplane) and run as SEA-Stack ran its decay;
radiation from the impulse response alone; the other time factor told by physics; the mistakes in one line."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from sim.io.bem_file import kind_of
from sim.io.bemio_h5 import read_bemio

h5py = pytest.importorskip("h5py")  # the bemio extra
trimesh = pytest.importorskip("trimesh")
ROOT = Path(__file__).resolve().parents[2]
SPHERE = ROOT / "assets" / "coefficients" / "bemio" / "iea_sphere.h5"
REFERENCE = ROOT / "assets" / "reference" / "iea_sphere_decay.csv"
R, MASS = 5.0, 261800.0
"""The IEA sphere's radius (m) and mass (kg): half submerged at rest, its centre of gravity 2 m below its centre."""


def sphere_scene(tmp_path: Path, bem_file: Path, start: float = -1.0, waves: str = "", t_end: float = 40.0) -> Path:
    """SEA-Stack's IEA sphere decay: the sphere on a vertical slide, its centre of gravity (2 m below its centre) at
    `start` (rest: -2 m)."""
    trimesh.creation.icosphere(subdivisions=4, radius=R).export(tmp_path / "sphere.stl")
    scene = tmp_path / "iea_sphere.toml"
    scene.write_text(f'[fluid]\nforces = "panels"\nradiation = "bem"\nbem_file = "{bem_file}"\n\n{waves}'
                     f'[[bodies]]\nname = "sphere"\nshape = "mesh"\nmesh = "sphere.stl"\nmass = {MASS}\n'
                     f'centre_of_mass = [0.0, 0.0, -2.0]\nposition = [0.0, 0.0, {start}]\njoint = "prismatic"\naxis = [0.0, 0.0, 1.0]\n\n'
                     f"[step]\ndt = 0.01\nt_end = {t_end}\n")  # fmt: skip
    return scene


def run_cli(scene: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "sim", "run", "--scene", str(scene), *args], cwd=ROOT, capture_output=True, text=True,
                          timeout=600)  # fmt: skip


def test_the_iea_sphere_file_reads_to_its_units():
    """Told apart from a netCDF4 file by content; its added mass at infinite frequency is Hulme's (1982) half the
    displaced mass in heave; its heave stiffness and its longest waves' heave force are rho g pi R^2 (0.2 %);
    its coefficients are about the centre of gravity, 2 m below the centre, where a sphere's surge and pitch couple
    (A15 = 2 A11: a sphere's pressure passes through its centre)."""
    assert kind_of(SPHERE) == "bemio"
    c, gravity, g, C = read_bemio(SPHERE)
    displaced = 1000.0 * 2 / 3 * math.pi * R**3
    assert c.added_mass_inf[2, 2] == pytest.approx(0.5 * displaced, rel=0.002)
    stiffness = 1000.0 * g * math.pi * R**2
    assert C[2, 2] == pytest.approx(stiffness, rel=0.002)
    assert abs(c.diffraction[0, 0, 2]) == pytest.approx(stiffness, rel=0.002)  # (omega = 0.05 rad/s)
    assert np.allclose(c.center, [0.0, 0.0, -2.0])
    assert abs(c.added_mass_inf[0, 4]) == pytest.approx(2.0 * c.added_mass_inf[0, 0], rel=0.01)
    assert c.omega[0] < c.omega[-1] and np.all(np.diff(c.omega) > 0)


def test_a_decay_from_the_iea_sphere_file_heaves_as_sea_stacks(tmp_path):
    """The sphere released 1 m above rest, 40 s, its radiation from the file: its heave is SEA-Stack's (Chrono with the
    same file and nonlinear hydrostatics) within 1 % of the release at every instant (0.65 % measured), and 2.7 cm from
    SEA-Stack's run with linear hydrostatics, which floatsim's exact wet surface is not."""
    out = tmp_path / "decay.csv"
    done = run_cli(sphere_scene(tmp_path, SPHERE), "--out", str(out))
    assert done.returncode == 0, done.stderr
    run = np.genfromtxt(out, delimiter=",", names=True)
    reference = np.genfromtxt(REFERENCE, delimiter=",", names=True, skip_header=1)
    z = np.interp(reference["t"], run["t"], run["sphere_z"])
    assert np.abs(z - reference["z_nonlinear"]).max() < 0.01
    assert np.abs(z - reference["z_linear"]).max() > 0.02
    assert reference["z_nonlinear"].min() < -2.8  # (the decay swings: an undamped body would not pass this)


def _copy(source: Path, target: Path, change) -> Path:
    """`source` copied to `target` with `change(file)` applied to the copy."""
    target.write_bytes(source.read_bytes())
    with h5py.File(target, "r+") as f:
        change(f)
    return target


def _impulse_response_only(f) -> None:
    """WEC-Sim's K(t) = (2/pi) int B(w)/rho cos(w t) dw in place of added_mass/all and radiation_damping/all, as SEA-Stack's
    own scripts write their files."""
    hc = f["body1/hydro_coeffs"]
    w = f["simulation_parameters/w"][()].ravel()
    B = hc["radiation_damping/all"][()] * w
    t = np.arange(0.0, 30.0, 0.02)
    K = (2 / math.pi) * np.trapezoid(B[..., None] * np.cos(np.outer(w, t)), w, axis=-2)
    del hc["added_mass/all"], hc["radiation_damping/all"]
    hc["radiation_damping/impulse_response_fun/K"] = K
    hc["radiation_damping/impulse_response_fun/t"] = t[:, None]


def test_radiation_from_the_impulse_response_alone(tmp_path):
    """A file with only the radiation's impulse response: its A and B are the ones the response was made from,
    within 1 % of their largest over the sphere's waves (0.3 to 8 rad/s)."""
    c0, *_ = read_bemio(SPHERE)
    c, *_ = read_bemio(_copy(SPHERE, tmp_path / "irf.h5", _impulse_response_only))
    band = (c.omega > 0.3) & (c.omega < 8.0)
    for M, M0 in ((c.added_mass, c0.added_mass), (c.damping, c0.damping)):
        for i, j in ((2, 2), (0, 0), (0, 4), (4, 4)):
            assert np.abs(M[band, i, j] - M0[band, i, j]).max() < 0.01 * np.abs(M0[:, i, j]).max()


def _other_time_factor(f) -> None:
    """The excitation's phases for e^(-i omega t), as SEA-Stack's trimaran script writes Capytaine's into its file."""
    hc = f["body1/hydro_coeffs/excitation"]
    for name in ("im", "phase"):
        hc[name][...] = -hc[name][()]


@pytest.mark.slow  # two runs in waves (9 s)
def test_the_other_time_factor_is_told_by_physics_and_taken_with_a_note(tmp_path):
    """The same file with its excitation's phases conjugated: a note says which time factor its long-wave surge force
    shows, and the sphere in waves heaves exactly as from the file in BEMIO's own."""
    waves = '[waves]\nkind = "regular"\nheight = 1.0\nperiod = 7.0\ndepth = 200.0\n\n'
    heaves = []
    for name, path in (("bemio", SPHERE), ("other", _copy(SPHERE, tmp_path / "other.h5", _other_time_factor))):
        out = tmp_path / f"{name}.csv"
        done = run_cli(sphere_scene(tmp_path, path, start=-2.0, waves=waves, t_end=10.0), "--out", str(out))
        assert done.returncode == 0, done.stderr
        assert ("e^(-i omega t) (Capytaine's)" in done.stderr) == (name == "other"), done.stderr
        heaves.append(np.genfromtxt(out, delimiter=",", names=True)["sphere_z"])
    assert np.ptp(heaves[0]) > 0.1  # (the waves move it: 0.22 m in these 10 s)
    assert np.abs(heaves[0] - heaves[1]).max() < 1e-9


def _drop(name: str):
    return lambda f: f.__delitem__(name)


@pytest.mark.parametrize(
    "change, setting, message",
    [
        (_drop("body1/hydro_coeffs/added_mass/inf_freq"), "", "body1 has no added_mass/inf_freq"),
        (lambda f: f["simulation_parameters/g"].__setitem__(Ellipsis, 9.80), "", "was solved with g = 9.8 m/s^2, the scene has 9.81"),
        (lambda f: f["simulation_parameters/rho"].__setitem__(Ellipsis, 1025.0), "", "density 1025"),
        (lambda f: f["body1/hydro_coeffs/linear_restoring_stiffness"].__setitem__(Ellipsis, 0.5 * f["body1/hydro_coeffs/linear_restoring_stiffness"][()]),
         "", "heave stiffness is"),
        (lambda f: f.move("body1", "body2"), "", "no body1, body2, ... groups in order"),
        (_drop("body1/hydro_coeffs/excitation/re"), "wave", None),  # (mag and phase serve)
    ],
)  # fmt: skip
def test_mistakes_are_one_line(tmp_path, change, setting, message):
    """A cut file, another g or density, another body's stiffness, bodies misnumbered: each one line, exit 2."""
    path = _copy(SPHERE, tmp_path / "case.h5", change)
    waves = '[waves]\nkind = "regular"\nheight = 1.0\nperiod = 7.0\ndepth = 200.0\n\n' if setting == "wave" else ""
    done = run_cli(sphere_scene(tmp_path, path, waves=waves), "--t-end", "0.5")
    if message is None:
        assert done.returncode == 0, done.stderr
        return
    assert done.returncode == 2 and message in done.stderr, done.stderr
    assert "Traceback" not in done.stderr and len([line for line in done.stderr.splitlines() if "error" in line]) == 1, done.stderr


def test_without_h5py_one_line_names_the_extra(tmp_path):
    code = ("import sys; sys.modules['h5py'] = None; from sim.commands import floatsim; "
            f"sys.exit(floatsim(['run', '--scene', {str(sphere_scene(tmp_path, SPHERE))!r}, '--t-end', '0.1']))")  # fmt: skip
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 2 and 'pip install -e ".[bemio]"' in done.stderr, done.stderr
    assert "Traceback" not in done.stderr


def _bemio_file(path: Path, omega, A, B, A_inf, X, headings_deg, cg, rho=1025.0, g=9.81, depth=None) -> Path:
    """Known dimensional coefficients (floatsim's time factor) as WEC-Sim's writeBEMIOH5 lays them out, as h5py sees
    it: per body its six rows against every column, nondimensional (A/rho, B/(rho w), X/(rho g)), WAMIT's e^(i w t)."""
    bodies = A.shape[1] // 6
    with h5py.File(path, "w") as f:
        f["simulation_parameters/rho"] = [[rho]]
        f["simulation_parameters/g"] = [[g]]
        f["simulation_parameters/w"] = omega[:, None]
        f["simulation_parameters/wave_dir"] = np.asarray(headings_deg, float)[:, None]
        f["simulation_parameters/water_depth"] = "infinite" if depth is None else [[depth]]
        for b in range(bodies):
            rows = slice(6 * b, 6 * b + 6)
            hc = f.create_group(f"body{b + 1}/hydro_coeffs")
            hc["added_mass/inf_freq"] = A_inf[rows] / rho
            hc["added_mass/all"] = np.moveaxis(A[:, rows], 0, -1) / rho
            hc["radiation_damping/all"] = np.moveaxis(B[:, rows], 0, -1) / (rho * omega)
            Xb = np.conj(X[:, :, rows]).transpose(2, 1, 0) / (rho * g)
            hc["excitation/re"], hc["excitation/im"] = Xb.real, Xb.imag
            f[f"body{b + 1}/properties/cg"] = np.asarray(cg[b], float)[:, None]
    return path


def test_several_bodies_come_back_as_the_coefficients_they_were_written_from(tmp_path):
    """Two bodies 30 m apart, two headings, frequencies written in descending order: every coupling block, the
    excitation of each body at each heading, each body's centre of gravity and the depth come back."""
    rng = np.random.default_rng(60)
    n, d = 5, 12
    omega = np.linspace(2.0, 0.4, n)
    A, B = rng.uniform(1e3, 1e5, (n, d, d)), rng.uniform(1e2, 1e4, (n, d, d))
    A_inf = rng.uniform(1e3, 1e5, (d, d))
    X = (rng.normal(size=(n, 2, d)) + 1j * rng.normal(size=(n, 2, d))) * 1e4
    cg = [(0.0, 0.0, -1.0), (30.0, 0.0, -0.5)]
    c, gravity, g, C = read_bemio(_bemio_file(tmp_path / "two.h5", omega, A, B, A_inf, X, [90.0, 0.0], cg, depth=50.0))
    order = np.argsort(omega)
    assert np.allclose(c.omega, omega[order]) and c.depth == 50.0 and g == 9.81 and C is None
    assert np.allclose(c.added_mass, A[order]) and np.allclose(c.damping, B[order]) and np.allclose(c.added_mass_inf, A_inf)
    assert np.allclose(c.headings, np.radians([0.0, 90.0]))
    assert np.allclose(c.diffraction, X[order][:, ::-1])  # (headings sorted: 0 then 90 degrees)
    assert np.allclose(c.center, cg) and np.allclose(gravity, cg)


def _two_headings(f) -> None:
    """The file's excitation at 0 and 90 degrees (the sphere's is the same at both, as an axisymmetric body's is)."""
    del f["simulation_parameters/wave_dir"]
    f["simulation_parameters/wave_dir"] = [[0.0], [90.0]]
    hc = f["body1/hydro_coeffs/excitation"]
    for name in ("re", "im", "mag", "phase"):
        values = hc[name][()]
        del hc[name]
        hc[name] = np.concatenate([values, values], axis=1)


@pytest.mark.parametrize("direction, refused", [(45.0, False), (90.0, False), (180.0, True), (300.0, True)])
def test_a_sea_outside_the_files_headings_is_one_line(tmp_path, direction, refused):
    """A file solved at 0 and 90 degrees excites waves between them (interpolated) and at them; waves from the gap
    beyond (more than 90 degrees without a heading) are refused in one line."""
    path = _copy(SPHERE, tmp_path / "two.h5", _two_headings)
    waves = f'[waves]\nkind = "regular"\nheight = 1.0\nperiod = 7.0\ndepth = 200.0\ndirection = {direction}\n\n'
    done = run_cli(sphere_scene(tmp_path, path, start=-2.0, waves=waves), "--t-end", "0.2")
    if not refused:
        assert done.returncode == 0, done.stderr
        return
    assert done.returncode == 2 and "has no headings between 90 and 0 degrees" in done.stderr, done.stderr
    assert "Traceback" not in done.stderr


def test_a_file_without_excitation_runs_in_still_water_and_is_refused_in_waves(tmp_path):
    """Radiation only (a decay's needs): the run goes; the same file under waves is one line."""

    def no_excitation(f) -> None:
        for name in ("re", "im", "mag", "phase"):
            del f[f"body1/hydro_coeffs/excitation/{name}"]

    path = _copy(SPHERE, tmp_path / "radiation.h5", no_excitation)
    done = run_cli(sphere_scene(tmp_path, path), "--t-end", "0.5")
    assert done.returncode == 0, done.stderr
    waves = '[waves]\nkind = "regular"\nheight = 1.0\nperiod = 7.0\ndepth = 200.0\n\n'
    done = run_cli(sphere_scene(tmp_path, path, waves=waves), "--t-end", "0.5")
    assert done.returncode == 2 and "has no wave excitation" in done.stderr, done.stderr

"""Issue 60, WAMIT's numeric files as a scene's coefficients (`[fluid] bem_file = "run.1"`): the `.1`, `.3` and `.hst`
of WEC-Sim's two BEMIO examples (assets/coefficients/wamit, studies/wamit_examples.py) against the `.out` of the same
WAMIT run and the closed forms their units must meet, a file written here from known coefficients read back, the same
run from either file, and the user's mistakes in one line."""

from __future__ import annotations

import math
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh

from sim.errors import ConfigError
from sim.io.bem_file import kind_of
from sim.io.wamit import read_out
from sim.io.wamit_numeric import Assumed, read_numeric, stiffness

ROOT = Path(__file__).resolve().parents[2]
WAMIT = ROOT / "assets" / "coefficients" / "wamit"
RHO, G = 1000.0, 9.81
DEEP = Assumed(G, math.inf, np.zeros((1, 3)))
ROUNDING = 2 * math.sin(math.radians(0.25)) + 1e-6
"""The `.out` prints the excitation's phase in whole degrees: up to half a degree off, |dX| <= 2 sin(0.25 deg) |X|."""


@pytest.mark.parametrize("name", ["cyl", "ellipsoid"])
def test_the_numeric_files_and_the_out_of_one_run_agree(name):
    """Added mass and damping (and A at infinite frequency) equal to the files' printed digits; the excitation within
    the `.out`'s whole-degree phases (the `.3` prints Re and Im to 7 digits); the same periods, depth, g, heading."""
    out = read_out(WAMIT / f"{name}.out", RHO)
    run, beside = read_numeric(WAMIT / f"{name}.1", RHO, DEEP)
    assert beside and run.depth == out.depth and run.g == out.g
    np.testing.assert_allclose(run.omega, out.omega, rtol=1e-6)
    np.testing.assert_array_equal(run.headings, out.headings)
    for field in ("added_mass", "damping", "added_mass_inf"):
        a, b = getattr(run, field), getattr(out, field)
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-6 * np.abs(b).max(), err_msg=field)
    assert np.all(np.abs(run.excitation - out.excitation) <= ROUNDING * np.abs(run.excitation) + 1e-9 * np.abs(run.excitation).max())


def test_the_cylinders_long_wave_heave_force_is_its_hydrostatic_stiffness():
    """In waves long against its 3 m of water (T = 157 s), the cylinder's heave force per metre of wave from the `.3` is
    rho g times its waterplane, the heave stiffness of its `.hst` (4 decimal places of a 0.35 m radius), within 0.1 %:
    the excitation's and the stiffness's units (rho g L^2) meet."""
    run, _ = read_numeric(WAMIT / "cyl.1", RHO, DEEP)
    C = stiffness(WAMIT / "cyl.1", run, RHO)
    assert abs(run.excitation[0, 0, 2]) == pytest.approx(C[2, 2], rel=1e-3)
    assert C[2, 2] == pytest.approx(RHO * G * math.pi * 0.35**2, rel=0.01)


def test_the_ellipsoids_heave_damping_meets_haskinds_relation():
    """The half ellipsoid in deep water (axisymmetric): B33 = omega k |X3|^2 / (2 rho g^2) from the `.1`'s damping and
    the `.3`'s excitation, within 2 % over 0.3-3 rad/s (the units rho omega L^3 and rho g L^2, the conjugation aside)."""
    run, _ = read_numeric(WAMIT / "ellipsoid.1", RHO, DEEP)
    band = (run.omega > 0.3) & (run.omega < 3.0)
    w = run.omega[band]
    haskind = w * (w * w / G) * np.abs(run.excitation[band, 0, 2]) ** 2 / (2 * RHO * G * G)
    np.testing.assert_allclose(run.damping[band, 2, 2], haskind, rtol=0.02)


def _numeric_text(omega, A, B, A_inf, headings, X, L: float = 1.0) -> tuple[str, str]:
    """(.1, .3) as WAMIT (or Capytaine's export) writes them, periods and headings shuffled, tab-separated."""
    d = A.shape[1]
    rot = (np.arange(d) % 6) >= 3
    k = 3 + rot[:, None].astype(int) + rot[None, :].astype(int)
    one = [f"{0.0:12.6e}\t{i + 1:5d}\t{j + 1:5d}\t{A_inf[i, j] / (RHO * L ** k[i, j]):12.6e}" for i in range(d) for j in range(d)]
    three = []
    for n in np.random.default_rng(2).permutation(len(omega)):
        T = 2 * math.pi / omega[n]
        one += [f"{T:12.6e}\t{i + 1:5d}\t{j + 1:5d}\t{A[n, i, j] / (RHO * L ** k[i, j]):12.6e}\t{B[n, i, j] / (RHO * omega[n] * L ** k[i, j]):12.6e}"
                for i in range(d) for j in range(d)]  # fmt: skip
        for m in np.random.default_rng(3).permutation(len(headings)):
            for i in range(d):
                x = np.conj(X[n, m, i]) / (RHO * G * L ** (2 if i % 6 < 3 else 3))
                three.append(f"{T:12.6e}\t{math.degrees(headings[m]):12.6f}\t{i + 1:5d}\t{abs(x):12.6e}\t{math.degrees(np.angle(x)):12.3f}"
                             f"\t{x.real:12.6e}\t{x.imag:12.6e}")  # fmt: skip
    return "\n".join(one) + "\n", "\n".join(three) + "\n"


def test_a_numeric_run_comes_back_as_the_coefficients_it_was_written_from(tmp_path):
    """Known coefficients of one body (random, at 4 periods and 3 headings, shuffled) written as Capytaine 3's export
    writes them: read back to the 7 printed digits, frequencies increasing, headings in [0, 2 pi), e^(-i omega t); with
    no `.out` beside them, about the world's origin and the body's own centre of mass."""
    rng = np.random.default_rng(0)
    omega, headings = np.array([0.5, 1.0, 1.5, 2.0]), np.radians([0.0, 90.0, 270.0])
    A, B = rng.uniform(1e3, 1e5, (4, 6, 6)), rng.uniform(1e2, 1e4, (4, 6, 6))
    A_inf = rng.uniform(1e3, 1e5, (6, 6))
    X = rng.normal(size=(4, 3, 6)) * 1e4 + 1j * rng.normal(size=(4, 3, 6)) * 1e4
    one, three = _numeric_text(omega, A, B, A_inf, headings, X)
    (tmp_path / "run.1").write_text(one)
    (tmp_path / "run.3").write_text(three)
    cg = np.array([[0.0, 0.0, -0.3]])
    run, beside = read_numeric(tmp_path / "run.3", RHO, Assumed(G, 50.0, cg))  # the .3 named: its .1 is read too
    assert not beside and run.depth == 50.0 and run.g == G
    np.testing.assert_allclose(run.omega, omega, rtol=1e-6)
    np.testing.assert_allclose(run.headings, headings, atol=1e-7)
    for got, want in ((run.added_mass, A), (run.damping, B), (run.added_mass_inf, A_inf), (run.excitation, X)):
        np.testing.assert_allclose(got, want, rtol=2e-6 * 4)
    np.testing.assert_array_equal(run.centers, np.zeros((1, 3)))
    np.testing.assert_array_equal(run.gravity_centers, cg)
    assert kind_of(tmp_path / "run.1") == "numeric" and kind_of(WAMIT / "cyl.out") == "out"


def test_a_run_whose_name_has_dots_reads_its_own_files(tmp_path):
    """cyl_0.35m.1 reads cyl_0.35m.3 and cyl_0.35m.out, not cyl_0.3 and cyl_0.out (another run's, were they there)."""
    for suffix in (".1", ".3", ".out"):
        shutil.copy(WAMIT / f"cyl{suffix}", tmp_path / f"cyl_0.35m{suffix}")
    shutil.copy(WAMIT / "ellipsoid.out", tmp_path / "cyl_0.out")  # a decoy: a deep-water run
    run, has_out = read_numeric(tmp_path / "cyl_0.35m.1", RHO, DEEP)
    assert has_out and run.depth == 3.0


@pytest.mark.parametrize(
    "cut, message",
    [
        (lambda one, three: ("".join(one.splitlines(keepends=True)[:-10]), three), "entries, the other periods"),
        (lambda one, three: (one[: one.rindex("\n", 0, len(one) - 1) + 16], three), "numbers, a .1 row has 4 or 5"),
        (lambda one, three: (one, "".join(three.splitlines(keepends=True)[: len(three.splitlines()) // 3])), "lacks the excitation"),
        (lambda one, three: (one, None), "is not beside it"),
    ],
)
def test_a_cut_or_missing_numeric_file_is_one_error(tmp_path, cut, message):
    """The cylinder's `.1` without its last 10 rows, or cut inside its last row; its `.3` cut to a third; no `.3`."""
    one = (WAMIT / "cyl.1").read_text()
    three = (WAMIT / "cyl.3").read_text()
    one, three = cut(one, three)
    (tmp_path / "cyl.1").write_text(one)
    if three is not None:
        (tmp_path / "cyl.3").write_text(three)
    with pytest.raises(ConfigError, match=message) as e:
        read_numeric(tmp_path / "cyl.1", RHO, DEEP)
    assert "\n" not in str(e.value)


def ellipsoid_scene(tmp_path: Path, bem_file: str, **waves) -> Path:
    """WEC-Sim's WAMIT ellipsoid as a scene: the half ellipsoid below its axes 4.5, 4.5, 1.8 m (a whole one, the upper
    half dry), floating at its centre (76.2 t, the file's centre of gravity), heaving on a vertical slide in regular
    waves 1 m high and 6 s long (a free body drifts: its heave then follows where the drift took it)."""
    mesh = trimesh.creation.icosphere(subdivisions=4)
    mesh.apply_scale([4.5, 4.5, 1.8])
    mesh.export(tmp_path / "ellipsoid.stl")
    sea = {"kind": '"regular"', "height": 1.0, "period": 6.0, **waves}
    text = (f'[fluid]\nforces = "panels"\nradiation = "bem"\nbem_file = "{bem_file}"\n\n[waves]\n'
            + "".join(f"{k} = {v}\n" for k, v in sea.items())
            + '\n[[bodies]]\nname = "ellipsoid"\nshape = "mesh"\nmesh = "ellipsoid.stl"\nmass = 76213.9\njoint = "prismatic"\n'
            'axis = [0.0, 0.0, 1.0]\n\n[step]\ndt = 0.05\nt_end = 40.0\n')  # fmt: skip
    path = tmp_path / f"scene_{Path(bem_file).suffix[1:]}.toml"
    path.write_text(text)
    return path


def run_cli(tmp_path, scene: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "sim", "run", "--scene", str(scene), *args], cwd=ROOT, capture_output=True, text=True,
                          timeout=600)  # fmt: skip


@pytest.mark.slow  # two 40 s runs in waves
def test_the_ellipsoid_heaves_the_same_from_its_numeric_files_as_from_its_out(tmp_path):
    """The same WAMIT run read from its `.1`/`.3` and from its `.out` drives the same heave within 1 % of its
    amplitude (the `.out`'s whole-degree phases are the difference), and the heave is the size linear theory gives
    (between 0.3 and 1.5 of the wave's amplitude at 6 s, above the body's heave resonance)."""
    heaves = []
    for name in ("ellipsoid.1", "ellipsoid.out"):
        out = tmp_path / f"{name}.csv"
        done = run_cli(tmp_path, ellipsoid_scene(tmp_path, str(WAMIT / name)), "--out", str(out))
        assert done.returncode == 0, done.stderr
        heaves.append(np.genfromtxt(out, delimiter=",", names=True)["ellipsoid_z"])
    numeric, out = heaves
    amplitude = np.ptp(out[len(out) // 2 :]) / 2
    assert 0.15 < amplitude < 0.75
    assert np.abs(numeric - out).max() < 0.01 * amplitude


def _copied(tmp_path: Path, name: str, hst: str | None = None) -> Path:
    for suffix in (".1", ".3"):
        shutil.copy(WAMIT / f"{name}{suffix}", tmp_path / f"{name}{suffix}")
    if hst:
        shutil.copy(WAMIT / hst, tmp_path / f"{name}.hst")
    return tmp_path / f"{name}.1"


def _conjugated(tmp_path: Path) -> Path:
    """The ellipsoid's `.1` and a `.3` of the other time factor: each row's phase and imaginary part negated."""
    one = _copied(tmp_path, "ellipsoid")
    three = one.with_suffix(".3")
    title, *rows = [line.split() for line in three.read_text().splitlines()]
    flipped = [" ".join(w[:4] + [str(-float(w[4])), w[5], str(-float(w[6]))]) for w in rows]
    three.write_text("\n".join([" ".join(title), *flipped]) + "\n")
    return one


@pytest.mark.parametrize(
    "files, waves, message",
    [
        (_conjugated, {}, "has the other time factor"),
        (lambda t: _copied(t, "ellipsoid", hst="cyl.hst"), {}, "heave stiffness is"),
        (lambda t: WAMIT / "ellipsoid.1", {"depth": 50.0}, "was solved for water inf m deep, the scene's waves are 50 m deep"),
        (lambda t: _copied(t, "cyl"), {}, "heave force in the bem_file's longest waves"),
    ],
)
def test_another_bodys_numeric_files_are_one_line(tmp_path, files, waves, message):
    """A `.3` of the other time factor (e^(-i omega t)); the cylinder's `.hst` beside the ellipsoid's `.1`; the ellipsoid's run (deep water, its `.out` beside it) for a
    sea 50 m deep; the cylinder's numeric files alone (no `.out`, no `.hst`) for the ellipsoid."""
    done = run_cli(tmp_path, ellipsoid_scene(tmp_path, str(files(tmp_path)), **waves), "--t-end", "1")
    assert done.returncode == 2 and message in done.stderr, done.stderr
    assert "Traceback" not in done.stderr and len([line for line in done.stderr.splitlines() if "error" in line]) == 1, done.stderr


def test_numeric_files_without_their_out_run_with_a_note(tmp_path):
    """The ellipsoid's `.1` and `.3` alone: a note says what was taken (ULEN 1, the world's origin, the scene's g and
    depth), and the run goes."""
    done = run_cli(tmp_path, ellipsoid_scene(tmp_path, str(_copied(tmp_path, "ellipsoid"))), "--t-end", "0.5")
    assert done.returncode == 0, done.stderr
    assert "read without its .out" in done.stderr

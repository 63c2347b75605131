"""Issue 60, a NEMOH run as a scene's coefficients (`[fluid] bem_file = "Nemoh.cal"`): WEC-Sim's NEMOH run of the half
ellipsoid meets WAMIT's run of the same body (another code, another mesh) in its coefficients and in a run, and the
mistakes are one line."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh

from sim.io.bem_file import kind_of
from sim.io.nemoh import read_nemoh
from sim.io.wamit_numeric import Assumed, read_numeric

ROOT = Path(__file__).resolve().parents[2]
NEMOH = ROOT / "assets" / "coefficients" / "nemoh" / "ellipsoid"
WAMIT = ROOT / "assets" / "coefficients" / "wamit"
IRREGULAR = 2.4
"""rad/s: below NEMOH's first irregular frequency for this body (its run did not remove them: B33 jumps 8 % at 2.67)."""


def _wamit():
    run, _ = read_numeric(WAMIT / "ellipsoid.1", 1000.0, Assumed(9.81, np.inf, np.zeros((1, 3))))
    return run


def test_a_nemoh_run_is_told_by_content_from_its_cal_or_its_results():
    assert kind_of(NEMOH / "Nemoh.cal") == "nemoh"
    assert kind_of(NEMOH / "Results" / "RadiationCoefficients.tec") == "nemoh"
    assert kind_of(WAMIT / "ellipsoid.1") == "numeric"


def test_nemohs_ellipsoid_meets_wamits_run_of_the_same_body():
    """Added mass, damping and excitation (surge, heave, pitch) within 2 % of each entry's peak below NEMOH's first
    irregular frequency; the added mass at infinite frequency NEMOH does not give, made from its damping (Ogilvie),
    WAMIT's within 0.5 % in heave and 1.5 % in pitch; its stiffness rho g times the waterplane NEMOH measured."""
    c, gravity, g, C = read_nemoh(NEMOH / "Nemoh.cal")
    run = _wamit()
    low = run.omega < IRREGULAR
    for i, j in ((0, 0), (2, 2), (4, 4), (0, 4)):
        for ours, theirs in ((c.added_mass, run.added_mass), (c.damping, run.damping)):
            at = np.interp(run.omega[low], c.omega, ours[:, i, j])
            assert np.abs(at - theirs[low, i, j]).max() < 0.02 * np.abs(theirs[:, i, j]).max(), (i, j)
    for j in (0, 2, 4):
        X = c.diffraction[:, 0, j]
        at = np.interp(run.omega[low], c.omega, X.real) + 1j * np.interp(run.omega[low], c.omega, X.imag)
        assert np.abs(at - run.excitation[low, 0, j]).max() < 0.02 * np.abs(run.excitation[:, 0, j]).max(), j
    assert c.added_mass_inf[2, 2] == pytest.approx(run.added_mass_inf[2, 2], rel=0.005)
    assert c.added_mass_inf[4, 4] == pytest.approx(run.added_mass_inf[4, 4], rel=0.015)
    assert C[2, 2] == pytest.approx(1000.0 * g * 63.57517, rel=1e-4)  # (Hydrostatics.dat's waterplane area)
    assert np.allclose(gravity, 0.0) and g == 9.81 and c.depth == np.inf


def _scene(tmp_path: Path, bem_file: Path) -> Path:
    mesh = trimesh.creation.icosphere(subdivisions=4)
    mesh.apply_scale([4.5, 4.5, 1.8])
    mesh.export(tmp_path / "ellipsoid.stl")
    scene = tmp_path / f"{bem_file.stem}.toml"
    scene.write_text(f'[fluid]\nforces = "panels"\nradiation = "bem"\nbem_file = "{bem_file}"\n\n'
                     '[waves]\nkind = "regular"\nheight = 1.0\nperiod = 6.0\n\n'
                     '[[bodies]]\nname = "ellipsoid"\nshape = "mesh"\nmesh = "ellipsoid.stl"\nmass = 76213.9\njoint = "prismatic"\n'
                     'axis = [0.0, 0.0, 1.0]\n\n[step]\ndt = 0.05\nt_end = 40.0\n')  # fmt: skip
    return scene


def run_cli(scene: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "sim", "run", "--scene", str(scene), *args], cwd=ROOT, capture_output=True, text=True,
                          timeout=600)  # fmt: skip


def test_the_ellipsoid_heaves_the_same_from_nemoh_as_from_wamit(tmp_path):
    """On a slide in 1 m waves of 6 s for 40 s: the heave from NEMOH's run within 2 % of its amplitude of the heave from
    WAMIT's (1.5 % measured), NEMOH's phases taken as floatsim's time factor without a note."""
    heaves = []
    for name, path in (("nemoh", NEMOH / "Nemoh.cal"), ("wamit", WAMIT / "ellipsoid.1")):
        out = tmp_path / f"{name}.csv"
        done = run_cli(_scene(tmp_path, path), "--out", str(out))
        assert done.returncode == 0 and "time factor" not in done.stderr, done.stderr
        heaves.append(np.genfromtxt(out, delimiter=",", names=True)["ellipsoid_z"])
    nemoh, wamit = heaves
    amplitude = np.ptp(wamit[len(wamit) // 2 :]) / 2
    assert 0.4 < amplitude < 0.6
    assert np.abs(nemoh - wamit).max() < 0.02 * amplitude


def _copy(tmp_path: Path) -> Path:
    shutil.copytree(NEMOH, tmp_path / "run")
    return tmp_path / "run"


def _five_dofs(run: Path) -> None:
    cal = run / "Nemoh.cal"
    cal.write_text(cal.read_text().replace("6\t\t\t\t! Number of degrees of freedom", "5\t\t\t\t! Number of degrees of freedom", 1))


def _extra_number(run: Path) -> None:
    """A row of ExcitationForce.tec one number longer (another run's force count)."""
    tec = run / "Results" / "ExcitationForce.tec"
    lines = tec.read_text().splitlines()
    lines[8] += " 0.1E+01"
    tec.write_text("\n".join(lines) + "\n")


def _cut(run: Path) -> None:
    tec = run / "Results" / "RadiationCoefficients.tec"
    tec.write_text("\n".join(tec.read_text().splitlines()[:-30]) + "\n")


@pytest.mark.parametrize(
    "change, message",
    [
        (_five_dofs, "degrees of freedom are not surge, sway, heave, roll, pitch and yaw"),
        (_cut, "(a cut file, or another run's bodies?)"),
        (_extra_number, "has 1002 numbers, 77 rows of 13 are 1001"),
        (lambda run: (run / "Mesh" / "KH.dat").write_text("1 2 3\n"), "is not a 6 x 6 stiffness matrix"),
        (lambda run: (run / "Results" / "ExcitationForce.tec").unlink(), "ExcitationForce.tec' is missing"),
        (lambda run: (run / "Mesh" / "KH.dat").write_text((NEMOH / "Mesh" / "KH.dat").read_text().replace("0.6236735E+06", "0.3118E+06")),
         "heave stiffness is"),
    ],
)  # fmt: skip
def test_mistakes_are_one_line(tmp_path, change, message):
    """A run of five dofs, a cut results file, a row too long, a stiffness that is not 6 x 6, a missing results file,
    another body's stiffness: each one line, exit 2."""
    run = _copy(tmp_path)
    change(run)
    done = run_cli(_scene(tmp_path, run / "Nemoh.cal"), "--t-end", "0.5")
    assert done.returncode == 2 and message in done.stderr, done.stderr
    assert "Traceback" not in done.stderr and len([line for line in done.stderr.splitlines() if "error" in line]) == 1, done.stderr


def _nemoh_run(folder: Path, omega, A, B, X, headings_deg, points, rho=1025.0, g=9.81) -> Path:
    """Known dimensional coefficients (floatsim's time factor) as a NEMOH run lays them out: Nemoh.cal with each body's
    six dofs about its point, a radiation zone per mode moved (rows: omega, then A and B of every force), an
    excitation zone per heading (rows: omega, then |X| and arg X of every force)."""
    d = A.shape[1]
    cal = [
        "--- Environment ---",
        f"{rho}\t! RHO",
        f"{g}\t! G",
        "0.\t! DEPTH",
        "0. 0.\t! XEFF YEFF",
        "--- Bodies ---",
        f"{d // 6}\t! bodies",
    ]
    for x, y, z in points:
        cal += ["--- Body ---", "mesh\\body.dat", "100 50", "6\t! Number of degrees of freedom"]
        cal += [f"1 {a} {b} {c} 0. 0. 0." for a, b, c in np.eye(3)] + [f"2 {a} {b} {c} {x} {y} {z}" for a, b, c in np.eye(3)]
        cal += (
            ["6\t! forces"] + [f"1 {a} {b} {c} 0. 0. 0." for a, b, c in np.eye(3)] + [f"2 {a} {b} {c} {x} {y} {z}" for a, b, c in np.eye(3)]
        )
        cal += ["0\t! additional lines"]
    cal += ["--- Load cases ---", f"{len(omega)} {omega.min()} {omega.max()}", f"{len(headings_deg)} 0. 90."]
    (folder / "Results").mkdir(parents=True)
    (folder / "Nemoh.cal").write_text("\n".join(cal) + "\n")
    head = ['VARIABLES="w (rad/s)"'] + [f'"A {i + 1} {j + 1}" "B {i + 1} {j + 1}"' for i in range(1) for j in range(d)]
    zones = []
    for moved in range(d):
        zones.append(f'Zone t="Motion of body {moved // 6 + 1} in DoF {moved % 6 + 1}",I= {len(omega)},F=POINT')
        zones += [
            " ".join(f"{v:.9E}" for v in [w, *np.ravel(np.column_stack([A[k, :, moved], B[k, :, moved]]))]) for k, w in enumerate(omega)
        ]
    (folder / "Results" / "RadiationCoefficients.tec").write_text("\n".join(head + zones) + "\n")
    zones = []
    for h, beta in enumerate(headings_deg):
        zones.append(f'Zone t="Diffraction force - beta = {beta:.3f} deg",I= {len(omega)},F=POINT')
        zones += [
            " ".join(f"{v:.9E}" for v in [w, *np.ravel(np.column_stack([np.abs(X[k, h]), np.angle(X[k, h])]))]) for k, w in enumerate(omega)
        ]
    (folder / "Results" / "ExcitationForce.tec").write_text("\n".join(head + zones) + "\n")
    return folder / "Nemoh.cal"


def test_several_bodies_come_back_as_the_coefficients_they_were_written_from(tmp_path):
    """Two bodies 100 m apart (as WEC-Sim's NEMOH cubes), two headings: every coupling block, each body's excitation at
    each heading and each body's reference point come back; without Mesh/ files, the centres of gravity are the
    reference points and there is no stiffness to check."""
    rng = np.random.default_rng(61)
    n, d = 6, 12
    omega = np.array([0.9, 0.3, 1.8, 1.2, 0.6, 1.5])  # (out of order, as the headings: the reader sorts both)
    A, B = rng.uniform(1e3, 1e5, (n, d, d)), rng.uniform(1e2, 1e4, (n, d, d))
    X = (rng.normal(size=(n, 2, d)) + 1j * rng.normal(size=(n, 2, d))) * 1e4
    points = [(0.0, 0.0, -2.5), (100.0, 0.0, -2.5)]
    c, gravity, g, C = read_nemoh(_nemoh_run(tmp_path / "cubes", omega, A, B, X, [30.0, 0.0], points))
    order = np.argsort(omega)
    assert np.allclose(c.omega, omega[order]) and np.allclose(c.added_mass, A[order]) and np.allclose(c.damping, B[order])
    assert np.allclose(c.diffraction, X[order][:, ::-1]) and np.allclose(c.headings, np.radians([0.0, 30.0]))
    assert np.allclose(c.center, points) and np.allclose(gravity, points) and C is None and c.rho == 1025.0 and c.depth == np.inf


def test_nemohs_own_lower_case_folders_and_untitled_headings_read_the_same(tmp_path):
    """NEMOH writes results/ and mesh/ (WEC-Sim's examples have Results/ and Mesh/), and prints a heading in 7
    characters (-100 degrees and below as *******): the run reads the same, its headings from Nemoh.cal's load cases."""
    run = _copy(tmp_path)
    (run / "Results").rename(run / "results")
    (run / "Mesh").rename(run / "mesh")
    tec = run / "results" / "ExcitationForce.tec"
    tec.write_text(tec.read_text().replace("beta =   0.000 deg", "beta = ******* deg"))
    ours, gravity, _, C = read_nemoh(run / "Nemoh.cal")
    theirs, _, _, C0 = read_nemoh(NEMOH / "Nemoh.cal")
    assert np.allclose(ours.added_mass, theirs.added_mass) and np.allclose(ours.diffraction, theirs.diffraction)
    assert np.allclose(ours.headings, [0.0]) and C is not None and np.allclose(C, C0)

"""Issue 42, a scene's coefficients from a file (`[fluid] bem_file`): WAMIT's output read with its units and time
convention (a file written here from known coefficients comes back as they were; WEC-Sim's RM3 run, as shipped, meets
the thin disc's added mass, Haskind's relation and the long-wave heave force), the bodies matched and moved to their
centres of mass, the same run whether its rm3 solve comes from Capytaine or as a WAMIT file, and the user's mistakes."""

from __future__ import annotations

import dataclasses
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from sim.errors import ConfigError
from sim.hydro.bem import Coefficients
from sim.io.bem_file import matched, moved
from sim.io.wamit import read_out

ROOT = Path(__file__).resolve().parents[2]
RHO, G = 1000.0, 9.81


def wamit_text(c: Coefficients, g: float = G, whole_degrees: bool = False, cg=None) -> str:
    """`c` as WAMIT prints it (.out, L = 1): nondimensional, time factor e^(i omega t), periods in a shuffled order."""
    k = len(np.atleast_2d(c.center).reshape(-1, 3))
    centers = np.atleast_2d(c.center).reshape(-1, 3)
    d = 6 * k
    lines = [" WAMIT  Version 7.2", f" Gravity:     {g:.5f}                Length scale:        1.00000", " Water depth:        infinite"]
    for b, x in enumerate(centers):
        cgb = np.zeros(3) if cg is None else cg[b]
        lines += [f" Body number: N= {b + 1}       Total panels:  100",
                  f" XBODY = {x[0]:10.4f} YBODY = {x[1]:10.4f} ZBODY = {x[2]:10.4f} PHIBODY =   0.0",
                  f" Center of Gravity  (Xg,Yg,Zg): {cgb[0]:12.6f} {cgb[1]:12.6f} {cgb[2]:12.6f}"]  # fmt: skip
    star = "\n " + "*" * 72 + "\n"
    blocks = ["\n".join(lines)]
    inf = "\n".join(f"   {i + 1:3d}   {j + 1:3d}   {c.added_mass_inf[i, j] / RHO:.9E}" for i in range(d) for j in range(d))
    blocks.append(
        f" Wave period = zero        Wavenumber = infinite\n\n    ADDED-MASS COEFFICIENTS\n     I     J         A(I,J)\n\n{inf}\n"
    )
    X = c.diffraction + c.froude_krylov
    for n in np.random.default_rng(1).permutation(len(c.omega)):
        w = c.omega[n]
        rows = "\n".join(f"   {i + 1:3d}   {j + 1:3d}   {c.added_mass[n, i, j] / RHO:.9E}   {c.damping[n, i, j] / (RHO * w):.9E}"
                         for i in range(d) for j in range(d))  # fmt: skip
        text = (f" Wave period (sec) =  {2 * math.pi / w:.9E}        Wavenumber (kL) =  {w * w / g:.6E}\n\n"
                f"    ADDED-MASS AND DAMPING COEFFICIENTS\n     I     J         A(I,J)         B(I,J)\n\n{rows}\n\n\n"
                "    DIFFRACTION EXCITING FORCES AND MOMENTS\n")  # fmt: skip
        for m, beta in enumerate(c.headings):
            text += f"\n  Wave Heading (deg) :   {math.degrees(beta):.6f}\n\n     I     Mod[Xh(I)]     Pha[Xh(I)]\n\n"
            for i in range(d):
                x = np.conj(X[n, m, i]) / (RHO * g)  # e^(-i w t) -> e^(i w t); L = 1
                phase = math.degrees(np.angle(x))
                text += f"   {i + 1:3d}   {abs(x):.9E}   {round(phase) if whole_degrees else phase:.6f}\n"
        blocks.append(text)
    return star.join(blocks) + star


def _coefficients(bodies: int = 2, headings=(0.0, math.pi / 2)) -> Coefficients:
    """Coefficients with every entry its own number (symmetric, damping positive definite), for a round trip."""
    rng = np.random.default_rng(7)
    d, n = 6 * bodies, 5
    omega = np.linspace(0.3, 2.0, n)
    M = rng.normal(size=(n, d, d))
    A = np.einsum("nij,nkj->nik", M, M) * 1e5 + np.eye(d) * 1e6
    B = np.einsum("nij,nkj->nik", M[::-1], M[::-1]) * 1e4 + np.eye(d) * 1e3
    A_inf = A[-1] * 0.9
    beta = np.array(headings)
    X = (rng.normal(size=(n, len(beta), d)) + 1j * rng.normal(size=(n, len(beta), d))) * 1e5
    centers = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, -20.0]])[:bodies]
    return Coefficients(omega, A, B, A_inf, RHO, math.inf, 100 * bodies, centers if bodies > 1 else centers[0], beta, X, np.zeros_like(X))


def test_a_wamit_file_comes_back_as_the_coefficients_it_was_written_from(tmp_path):
    """Dimensions (rho L^k, rho omega L^k, rho g L^m), the conjugate time factor, periods in any order, the
    infinite-frequency block, two bodies and two headings: every entry back to the digits printed."""
    c = _coefficients()
    path = tmp_path / "two.out"
    path.write_text(wamit_text(c))
    run = read_out(path, RHO)
    np.testing.assert_allclose(run.omega, c.omega, rtol=1e-9)
    np.testing.assert_allclose(run.added_mass, c.added_mass, rtol=1e-8, atol=1e-8 * np.abs(c.added_mass).max())
    np.testing.assert_allclose(run.damping, c.damping, rtol=1e-8, atol=1e-8 * np.abs(c.damping).max())
    np.testing.assert_allclose(run.added_mass_inf, c.added_mass_inf, rtol=1e-8)
    np.testing.assert_allclose(run.excitation, c.diffraction, rtol=1e-7, atol=1e-7 * np.abs(c.diffraction).max())
    np.testing.assert_allclose(run.headings, c.headings)
    np.testing.assert_allclose(run.centers, c.center)
    assert run.depth == math.inf and run.g == G and run.panels == 200


def test_whole_degree_phases_cost_under_one_percent(tmp_path):
    """WAMIT prints phases in whole degrees: each force then within 2 sin(0.25 deg) = 0.87 % of its size."""
    c = _coefficients(bodies=1, headings=(0.0,))
    path = tmp_path / "one.out"
    path.write_text(wamit_text(c, whole_degrees=True))
    X = read_out(path, RHO).excitation
    error = np.abs(X - c.diffraction) / np.abs(c.diffraction)
    assert error.max() < 2 * math.sin(math.radians(0.25)) + 1e-6 and error.max() > 1e-4


def test_moving_the_reference_point_is_the_rigid_shift():
    """About a point d below: heave and surge unchanged, pitch added mass A55 + d^2 A11 (surge-pitch coupling zero
    at the start), the surge-pitch coupling d A11; and back again to the start."""
    c = _coefficients(bodies=1)
    A = np.zeros_like(c.added_mass)
    A[:, 0, 0], A[:, 2, 2], A[:, 4, 4] = 2e5, 3e5, 5e6
    c = dataclasses.replace(c, added_mass=A)
    d = 4.0
    there = moved(c, np.array([[0.0, 0.0, -1.0 - d]]))
    np.testing.assert_allclose(there.added_mass[:, 4, 4], 5e6 + d * d * 2e5)
    np.testing.assert_allclose(there.added_mass[:, 0, 4], d * 2e5)  # surge at the old point is u + d theta_dot
    np.testing.assert_allclose(there.added_mass[:, 2, 2], 3e5)
    back = moved(there, np.array([[0.0, 0.0, -1.0]]))
    np.testing.assert_allclose(back.added_mass, c.added_mass, atol=1e-6)
    np.testing.assert_allclose(back.diffraction, c.diffraction, atol=1e-6)


def test_the_bodies_are_taken_by_where_they_start():
    """A scene listing the file's second body first gets its blocks first; two scene bodies nearest one file body: one line."""
    c = _coefficients()
    swapped = matched(c, np.array([[0.0, 0.0, -20.2], [0.0, 0.0, -1.0]]), Path("x.out"))
    np.testing.assert_array_equal(swapped.added_mass[:, :6, :6], c.added_mass[:, 6:, 6:])
    np.testing.assert_array_equal(swapped.added_mass[:, :6, 6:], c.added_mass[:, 6:, :6])
    np.testing.assert_array_equal(swapped.diffraction[..., :6], c.diffraction[..., 6:])
    with pytest.raises(ConfigError, match="nearest the same body"):
        matched(c, np.array([[0.0, 0.0, -2.0], [0.0, 0.0, -3.0]]), Path("x.out"))


def test_wec_sims_rm3_run_meets_the_closed_forms():
    """The shipped RM3 coefficients (WEC-Sim's WAMIT run, studies/rm3_wecsim.py): the plate's heave added mass in long
    waves is the thin disc's 8/3 rho a^3 (a = 15 m) within 1 %; the float's heave force in long waves is rho g times
    its waterplane (7 m and 10 m radii, 72 sections) within 0.5 %; its heave damping meets Haskind's relation for an
    axisymmetric body in deep water, B33 = omega k |X3|^2 / (2 rho g^2), within 3 % over the waves' band."""
    c = Coefficients.load(ROOT / "assets" / "coefficients" / "imported" / "rm3_wecsim.npz")
    spar, fl = 2, 8  # heave of the scene's first body (the spar) and second (the float)
    assert c.added_mass[0, spar, spar] == pytest.approx(8 / 3 * RHO * 15.0**3, rel=0.01)
    waterplane = 0.5 * 72 * math.sin(2 * math.pi / 72) * (10.0**2 - 3.0**2)
    X = c.diffraction + c.froude_krylov
    assert abs(X[0, 0, fl]) == pytest.approx(RHO * G * waterplane, rel=0.005)
    band = (c.omega > 0.4) & (c.omega < 2.5)
    w = c.omega[band]
    haskind = w * (w * w / G) * np.abs(X[band, 0, fl]) ** 2 / (2 * RHO * G * G)
    np.testing.assert_allclose(c.damping[band, fl, fl], haskind, rtol=0.03)


def run_cli(tmp_path, scene: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "sim", "run", "--scene", str(scene), *args], cwd=ROOT, capture_output=True, text=True,
                          timeout=600)  # fmt: skip


def _scene_with(tmp_path, bem_file: str) -> Path:
    text = (ROOT / "assets" / "scenes" / "rm3.toml").read_text().replace("../meshes/", str(ROOT / "assets" / "meshes") + "/")
    text = text.replace("bem_min_period = 5.0", f'bem_min_period = 5.0\nbem_file = "{bem_file}"')
    path = tmp_path / "scene.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    "content, message",
    [
        ("not a WAMIT file\n", "is not a WAMIT output file floatsim can read"),
        (None, "no such file"),
    ],
)
def test_a_bad_bem_file_is_one_line(tmp_path, content, message):
    target = tmp_path / "coefficients.out"
    if content is not None:
        target.write_text(content)
    done = run_cli(tmp_path, _scene_with(tmp_path, str(target)), "--t-end", "1")
    assert done.returncode == 2 and message in done.stderr and len(done.stderr.strip().splitlines()) == 1, done.stderr


def test_a_file_of_other_bodies_is_one_line(tmp_path):
    """A one-body file for the two bodies of rm3; a file whose body is not where the scene's is (its long waves'
    heave force is another waterplane's)."""
    c = _coefficients(bodies=1, headings=(0.0,))
    target = tmp_path / "one.out"
    target.write_text(wamit_text(c))
    done = run_cli(tmp_path, _scene_with(tmp_path, str(target)), "--t-end", "1")
    assert done.returncode == 2 and "holds 1 bodies, the scene 2" in done.stderr and len(done.stderr.strip().splitlines()) == 1, done.stderr


@pytest.mark.slow
def test_rm3_runs_the_same_from_its_solve_written_as_a_wamit_file(tmp_path):
    """rm3's shipped Capytaine solve written as WAMIT prints it (whole-degree phases, its Froude-Krylov force and
    diffraction summed as WAMIT gives them): read back, split over floatsim's own wet surfaces and fitted anew, the
    float's and spar's heave over 60 s of regular waves within 2 % of the float's amplitude of the run from the solve."""
    from sim.scene.config import load_scene
    from sim.system.tree import build

    system, _ = build(load_scene("rm3"))
    c = system.radiation.coefficients
    target = tmp_path / "rm3.out"
    target.write_text(wamit_text(c, whole_degrees=True))
    rows = []
    for scene in (ROOT / "assets" / "scenes" / "rm3.toml", _scene_with(tmp_path, str(target))):
        out = tmp_path / f"{len(rows)}.csv"
        done = run_cli(tmp_path, scene, "--t-end", "60", "--out", str(out))
        assert done.returncode == 0, done.stderr
        rows.append(np.genfromtxt(out, delimiter=",", names=True))
    solved, read = rows
    amplitude = np.ptp(solved["float_z"]) / 2
    for column in ("float_z", "spar_z"):
        assert np.abs(read[column] - solved[column]).max() < 0.02 * amplitude, column

"""Issue 60, a Capytaine dataset saved as netCDF as a scene's coefficients (`[fluid] bem_file = "run.nc"`): the layout
Capytaine writes read back to the coefficients it was written from (one body and two, dofs in any order), a user's own
Capytaine solve of the sphere running the decay test as floatsim's own solve does, and the mistakes in one line."""

from __future__ import annotations

import math
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from sim.errors import ConfigError
from sim.io.bem_file import kind_of
from sim.io.capytaine_nc import MODES, read_capytaine

xr = pytest.importorskip("xarray")  # the netcdf extra
ROOT = Path(__file__).resolve().parents[2]
RHO, G = 1000.0, 9.81


def capytaine_file(path: Path, omega, A, B, X, headings, centers, names: list[str], order=None, with_inf=True) -> Path:
    """Coefficients in the layout of Capytaine's `assemble_dataset` saved by `export_dataset`: (omega, influenced_dof,
    radiating_dof) matrices with omega = inf last, the excitation over (complex, omega, wave_direction, influenced_dof),
    the dofs in `order` (a permutation), rotation centres over (body, space_coordinate)."""
    dofs = [f"{n}__{m}" if len(names) > 1 else m for n in names for m in MODES]
    order = np.arange(len(dofs)) if order is None else np.asarray(order)
    w = np.append(omega, np.inf) if with_inf else np.asarray(omega)
    A_all = A[: len(w)][:, order][:, :, order]
    B_all = B[: len(w)][:, order][:, :, order]
    Xo = X[:, :, order]
    ds = xr.Dataset(
        {"added_mass": (("omega", "influenced_dof", "radiating_dof"), A_all),
         "radiation_damping": (("omega", "influenced_dof", "radiating_dof"), B_all),
         "excitation_force": (("complex", "omega", "wave_direction", "influenced_dof"),
                              np.stack([np.pad(Xo.real, ((0, len(w) - len(omega)), (0, 0), (0, 0))),
                                        np.pad(Xo.imag, ((0, len(w) - len(omega)), (0, 0), (0, 0)))]))},
        coords={"omega": w, "influenced_dof": [dofs[k] for k in order], "radiating_dof": [dofs[k] for k in order],
                "wave_direction": headings, "complex": ["re", "im"], "space_coordinate": ["x", "y", "z"],
                "rotation_center": ((("body",) if len(names) > 1 else ()) + ("space_coordinate",), centers if len(names) > 1 else centers[0]),
                "rho": RHO, "g": G, "water_depth": np.inf, "forward_speed": 0.0},
    )  # fmt: skip
    ds.to_netcdf(path, engine="scipy")
    return path


def known(bodies: int, n: int = 4, m: int = 2):
    rng = np.random.default_rng(bodies)
    d = 6 * bodies
    A = rng.uniform(1e3, 1e5, (n + 1, d, d))
    B = rng.uniform(1e2, 1e4, (n + 1, d, d))
    B[-1] = 0.0
    X = rng.normal(size=(n, m, d)) * 1e4 + 1j * rng.normal(size=(n, m, d)) * 1e4
    return np.linspace(0.5, 2.0, n), A, B, X, np.radians([0.0, 90.0])[:m]


@pytest.mark.parametrize("bodies", [1, 2])
def test_a_capytaine_dataset_comes_back_as_the_coefficients_it_was_written_from(tmp_path, bodies):
    """Known coefficients, their dofs shuffled (BODY__Heave before BODY__Surge, the second body first): read back in
    floatsim's order, body after body, exactly; A at infinite frequency from omega = inf; the excitation whole (e^(-i
    omega t), as Capytaine's), the rotation centres as given."""
    omega, A, B, X, headings = known(bodies)
    centers = np.array([[0.0, 0.0, -1.0], [10.0, 0.0, -2.0]])[:bodies]
    order = np.random.default_rng(7).permutation(6 * bodies)
    path = capytaine_file(tmp_path / "run.nc", omega, A, B, X, headings, centers, ["float", "spar"][:bodies], order)
    assert kind_of(path) == "netcdf"
    c, gravity, g, C = read_capytaine(path)
    np.testing.assert_array_equal(c.omega, omega)
    np.testing.assert_array_equal(c.added_mass, A[:-1])
    np.testing.assert_array_equal(c.damping, B[:-1])
    np.testing.assert_array_equal(c.added_mass_inf, A[-1])
    np.testing.assert_array_equal(c.diffraction, X)
    np.testing.assert_array_equal(np.atleast_2d(c.center), centers)
    assert g == G and C is None and c.rho == RHO and math.isinf(c.depth)
    np.testing.assert_array_equal(gravity, centers)  # no center_of_mass: the rotation centres


def test_a_solve_keyed_by_period_reads_as_one_keyed_by_omega(tmp_path):
    """Capytaine lets a solve be keyed by period (or freq, wavelength, wavenumber), omega then a coordinate: the same
    coefficients come back."""
    omega, A, B, X, headings = known(1)
    path = capytaine_file(tmp_path / "omega.nc", omega, A, B, X, headings, np.zeros((1, 3)), ["a"])
    with xr.open_dataset(path) as ds:
        by_period = ds.load().assign_coords(period=("omega", 2 * np.pi / ds["omega"].values)).swap_dims({"omega": "period"})
    by_period.to_netcdf(tmp_path / "period.nc", engine="scipy")
    a, b = read_capytaine(path)[0], read_capytaine(tmp_path / "period.nc")[0]
    np.testing.assert_array_equal(b.omega, a.omega)
    np.testing.assert_array_equal(b.added_mass, a.added_mass)
    np.testing.assert_array_equal(b.diffraction, a.diffraction)


@pytest.mark.parametrize(
    "change, message",
    [
        ({"with_inf": False}, "has no omega = inf"),
        ({"names": ["a"], "bad_dof": True}, "is not a rigid-body mode"),
    ],
)
def test_a_dataset_floatsim_cannot_take_is_one_line(tmp_path, change, message):
    omega, A, B, X, headings = known(1)
    path = tmp_path / "run.nc"
    capytaine_file(path, omega, A, B, X, headings, np.zeros((1, 3)), ["a"], with_inf=change.get("with_inf", True))
    if change.get("bad_dof"):
        with xr.open_dataset(path) as ds:
            ds = ds.load().assign_coords(radiating_dof=["Surge", "Sway", "Heave", "Roll", "Pitch", "Flex"])
        path.unlink()
        ds.to_netcdf(path, engine="scipy")
    with pytest.raises(ConfigError, match=message) as e:
        read_capytaine(path)
    assert "\n" not in str(e.value)


def test_an_hdf5_file_without_its_reader_is_one_line(tmp_path):
    """A netCDF4 file (HDF5, as Capytaine writes where netCDF4 is installed) on a machine without h5netcdf: one line
    naming it (here: HDF5's signature on a file xarray cannot open)."""
    path = tmp_path / "run.nc"
    path.write_bytes(b"\x89HDF\r\n\x1a\n" + bytes(200))
    assert kind_of(path) == "netcdf"
    with pytest.raises(ConfigError, match="cannot read it") as e:
        read_capytaine(path)
    assert "\n" not in str(e.value)


SOLVE = """
    import capytaine as cpt, numpy as np, xarray as xr, logging
    logging.getLogger("capytaine").setLevel(logging.ERROR)
    mesh = cpt.mesh_sphere(radius=0.5, center=(0, 0, 0), resolution=(12, 24)).immersed_part()
    body = cpt.FloatingBody(mesh=mesh, dofs=cpt.rigid_body_dofs(rotation_center=(0, 0, 0)), center_of_mass=(0, 0, 0), name="sphere")
    omegas = np.concatenate([np.linspace(0.5, 20.0, 40), [np.inf]])
    problems = xr.Dataset(coords={"omega": omegas, "wave_direction": [0.0], "radiating_dof": list(body.dofs), "rho": 1000.0, "water_depth": np.inf})
    cpt.export_dataset("sphere.nc", cpt.BEMSolver().fill_dataset(problems, body))
"""
"""A user's script, as Capytaine's documentation writes one: its own sphere of 0.5 m (144 panels), radiation and
diffraction at 40 frequencies and at infinity, saved with export_dataset."""


SCENE = """
[fluid]
forces = "panels"
damping = 0.0
radiation = "bem"
bem_file = "sphere.nc"

[[bodies]]
name = "sphere"
shape = "mesh"
mesh = "{mesh}"
samples = 2000
density = 500.0
position = [0.0, 0.0, 0.1]

[step]
dt = 0.005
t_end = 20.0
"""


@pytest.mark.slow  # a Capytaine solve
def test_a_users_capytaine_solve_of_the_sphere_runs_its_decay_as_floatsims_own(tmp_path):
    """floatsim's sphere decay test (released 10 cm high) with its coefficients from the user's own solve (another
    mesh of the sphere) heaves as the preset with floatsim's solve does, within 2 % of the release over 10 s, and
    the dataset's heave stiffness is the sphere's rho g pi r^2 (checked on the way in)."""
    done = subprocess.run([sys.executable, "-c", textwrap.dedent(SOLVE)], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    scene = SCENE.format(mesh=ROOT / "assets" / "meshes" / "sphere.stl")  # the sphere preset's, as one of [[bodies]]
    (tmp_path / "scene.toml").write_text(scene)
    heaves = []
    for args in (["--scene", str(tmp_path / "scene.toml")], ["--scene", "sphere"]):
        out = tmp_path / f"{len(heaves)}.csv"
        run = subprocess.run([sys.executable, "-m", "sim", "run", *args, "--t-end", "10", "--out", str(out)], cwd=ROOT,
                             capture_output=True, text=True, timeout=600)  # fmt: skip
        assert run.returncode == 0, run.stderr
        rows = np.genfromtxt(out, delimiter=",", names=True)
        heaves.append(rows["sphere_z"] if "sphere_z" in rows.dtype.names else rows["z"])
    theirs, ours = heaves
    assert theirs[0] == pytest.approx(0.1) and np.abs(theirs - ours).max() < 0.02 * 0.1

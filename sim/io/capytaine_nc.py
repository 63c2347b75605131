"""Radiation and excitation coefficients from a Capytaine dataset saved as netCDF, the Python side's exchange format
(`cpt.BEMSolver().fill_dataset(...)` then `cpt.export_dataset("run.nc", dataset)`, Capytaine's documented way; WecOptTool
reads the same files).

What is read (Capytaine's `assemble_dataset` layout): `added_mass` and `radiation_damping` over (omega, influenced_dof,
radiating_dof), the added mass at omega = inf (the solve must include it), `excitation_force` over (omega,
wave_direction, influenced_dof), complex values stored as a `complex` dimension (re, im); `rho`, `g`, `water_depth`;
each body's `rotation_center` (the point its rotations are about) and `center_of_mass`, over (body, space_coordinate)
for several bodies, whose dofs are named BODY__Surge ... BODY__Yaw; `hydrostatic_stiffness` when it was computed, to
check the bodies. Capytaine's time factor is floatsim's, e^(-i omega t). Read through xarray (the netcdf extra); a
netCDF4 (HDF5) file needs h5netcdf too.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from sim.errors import ConfigError
from sim.hydro.bem import Coefficients
from sim.io.netcdf import EXTRA

MODES = ("Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw")


def _complex(da):
    """A DataArray with Capytaine's `complex` dimension (re, im) as complex numbers."""
    if "complex" not in da.dims:
        return da.values
    return da.sel(complex="re").values + 1j * da.sel(complex="im").values


def _dof_order(names: list[str]) -> tuple[list[int], int]:
    """The positions of `names` (Capytaine's dofs: Surge ... or BODY__Surge ...) in floatsim's order, body after body
    as they first appear, six rigid modes each; and the body count. One line for any other dof."""
    bodies: list[str] = []
    slots = []
    for name in names:
        body, _, mode = name.rpartition("__")
        if mode not in MODES:
            raise ConfigError(f"dof {name!r} is not a rigid-body mode ({', '.join(MODES)}): floatsim takes rigid bodies only")
        if body not in bodies:
            bodies.append(body)
        slots.append(6 * bodies.index(body) + MODES.index(mode))
    if sorted(slots) != list(range(6 * len(bodies))):
        raise ConfigError(f"the dofs {', '.join(names)} are not six rigid modes for each body")
    return [slots.index(k) for k in range(6 * len(bodies))], len(bodies)


def _points(ds, name: str, bodies: int) -> np.ndarray | None:
    """(bodies, 3) a per-body point coordinate (rotation_center, center_of_mass), or None when absent or NaN."""
    if name not in ds.coords and name not in ds.data_vars:
        return None
    values = np.asarray(ds[name].values, float).reshape(-1, 3)
    return None if values.shape[0] != bodies or np.isnan(values).any() else values


def read_capytaine(path: Path) -> tuple[Coefficients, np.ndarray, float, np.ndarray | None]:
    """(the coefficients about each body's rotation centre with the whole excitation in `diffraction`, each body's
    centre of mass ((k, 3), the rotation centres where not given), g, the hydrostatic stiffness or None): one-line
    ConfigError on a file that is not a Capytaine dataset floatsim can take."""
    try:
        import xarray as xr  # the netcdf extra
    except ImportError:
        raise ConfigError(f"[fluid] bem_file {str(path)!r} is netCDF, read through xarray, which is not installed: {EXTRA}") from None
    where = f"[fluid] bem_file {str(path)!r}"
    try:
        ds = xr.open_dataset(path).load()
    except (ValueError, OSError) as e:
        hdf5 = open(path, "rb").read(4) == b"\x89HDF"
        why = "a netCDF4 (HDF5) file needs h5netcdf: pip install h5netcdf" if hdf5 else str(e).splitlines()[0]
        raise ConfigError(f"{where}: cannot read it ({why})") from None
    keyed = [d for d in ("period", "freq", "wavelength", "wavenumber") if d in ds.dims and "omega" not in ds.dims]
    if keyed and "omega" in ds.coords:  # a solve keyed by another frequency coordinate (Capytaine allows four)
        ds = ds.swap_dims({keyed[0]: "omega"})
    missing = [v for v in ("added_mass", "radiation_damping", "omega", "radiating_dof", "influenced_dof", "rho", "g", "water_depth")
               if v not in ds.variables]  # fmt: skip
    if missing:
        raise ConfigError(f"{where} is not a Capytaine dataset floatsim can read (no {', '.join(missing)})")
    if float(ds.get("forward_speed", 0.0)) != 0.0:
        raise ConfigError(f"{where} was solved with forward speed {float(ds['forward_speed']):g} m/s; floatsim's bodies have none")
    try:
        radiating, n = _dof_order([str(v) for v in ds["radiating_dof"].values])
        influenced, _ = _dof_order([str(v) for v in ds["influenced_dof"].values])
    except ConfigError as e:
        raise ConfigError(f"{where}: {e}") from None
    omega = np.asarray(ds["omega"].values, float)
    if not np.isinf(omega).any():
        raise ConfigError(f"{where} has no omega = inf (the added mass at infinite frequency): add np.inf to the solve's omegas")
    finite = np.isfinite(omega) & (omega > 0)
    order = np.argsort(omega[finite])

    def matrix(name: str) -> np.ndarray:
        M = ds[name].transpose("omega", "influenced_dof", "radiating_dof").values
        return M[:, influenced][:, :, radiating]

    A, B = matrix("added_mass"), matrix("radiation_damping")
    A_inf = A[np.isinf(omega)][0]
    headings, X = None, None
    if "excitation_force" in ds.data_vars or "diffraction_force" in ds.data_vars:
        total = ds["excitation_force"] if "excitation_force" in ds.data_vars else ds["diffraction_force"] + ds["Froude_Krylov_force"]
        X = _complex(total.transpose(*(("complex",) if "complex" in total.dims else ()), "omega", "wave_direction", "influenced_dof"))
        X = X[finite][order][:, :, influenced]
        turn = np.mod(np.asarray(ds["wave_direction"].values, float), 2 * math.pi)
        by_heading = np.argsort(turn)
        headings, X = turn[by_heading], X[:, by_heading]
    depth = float(ds["water_depth"])
    centers = _points(ds, "rotation_center", n)
    if centers is None:
        raise ConfigError(f"{where} has no rotation_center for its {n} bodies (give each body rigid_body_dofs(rotation_center=...))")
    gravity = _points(ds, "center_of_mass", n)
    C = ds["hydrostatic_stiffness"].transpose("influenced_dof", "radiating_dof").values[influenced][:, radiating] if (
        "hydrostatic_stiffness" in ds.data_vars and ds["hydrostatic_stiffness"].ndim == 2) else None  # fmt: skip
    c = Coefficients(omega[finite][order], A[finite][order], B[finite][order], A_inf, float(ds["rho"]), depth if depth > 0 else math.inf,
                     0, centers[0] if n == 1 else centers, headings, X, None if X is None else np.zeros_like(X))  # fmt: skip
    return c, (centers if gravity is None else gravity), float(ds["g"]), C

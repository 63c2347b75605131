"""A run's rows as a netCDF dataset (`floatsim run --out run.nc`), the format Capytaine, WecOptTool and SEA-Stack write:
one dimension, time; each column of the CSV a variable with CF-style `units` and `long_name`; the scene whole in the
attributes (`floatsim_scene`, JSON), readable back with `xarray.open_dataset`.

Written through xarray (the `netcdf` extra: `pip install -e ".[netcdf]"`) with its scipy engine, netCDF3 (64-bit
offsets): no HDF5 library needed, and every netCDF reader reads it.
"""

from __future__ import annotations

import datetime
import json

import numpy as np

from sim.errors import ConfigError

EXTRA = 'pip install -e ".[netcdf]"'
UNITS = {
    **{c: ("m", f"centre of mass {c}") for c in ("x", "y", "z")},
    **{c: ("1", f"orientation quaternion {c[1]} (body to world, scalar first)") for c in ("qw", "qx", "qy", "qz")},
    **{c: ("m s-1", f"velocity {c[1]}") for c in ("ux", "uy", "uz")},
    **{c: ("rad s-1", f"angular velocity {c[1]}") for c in ("wx", "wy", "wz")},
    **{c: ("kg m2 s-1", f"angular momentum {c[1]}") for c in ("Lx", "Ly", "Lz")},
    **{c: ("N", f"total force {c[1]}") for c in ("Fx", "Fy", "Fz")},
    **{c: ("N m", f"total moment {c[1]} about the centre of mass") for c in ("Tx", "Ty", "Tz")},
    "E_kin": ("J", "kinetic energy"),
    "E_grav": ("J", "gravitational potential energy"),
    "E_hyd": ("J", "hydrostatic energy (exact)"),
    "E_hyd_model": ("J", "hydrostatic energy of the force model"),
    "E_spring": ("J", "energy of the take-offs' springs"),
    "E_total": ("J", "total energy"),
    "E_rad": ("J", "energy radiated in waves so far"),
    "E_pto": ("J", "energy absorbed by the take-off so far"),
    "E_lines": ("J", "energy stored in the mooring lines"),
    "D_lines": ("J", "energy dissipated by the mooring lines so far"),
    "A_sub": ("m2", "wetted surface area"),
    "V_sub": ("m3", "submerged volume"),
    "eta": ("m", "free-surface elevation at the centre of mass"),
    "P_diff": ("W", "power of the diffraction force"),
    "P_pto": ("W", "power absorbed by the take-off"),
    "F_pto": ("N", "take-off force on its joint (N m on a hinge)"),
    "theta": ("m", "joint coordinate (rad on a hinge)"),
    "rate": ("m s-1", "joint rate (rad s-1 on a hinge)"),
    **{c: ("N", f"mooring lines' pull {c[1]}") for c in ("Fx_moor", "Fy_moor", "Fz_moor")},
    "T_fair_max": ("N", "largest fairlead tension"),
}
"""Each column's units (UDUNITS, as CF asks) and long name, by its name less any body's or joint's prefix."""

SWEEP_UNITS = {
    "status": ("", "how the case ended (end, rest, sank, diverged)"),
    "t": ("s", "time the case ended"),
    "time_to_rest": ("s", "time the body came to rest"),
    "speed": ("m s-1", "speed at the end"),
    "spin": ("rad s-1", "angular speed at the end"),
    "tilt_deg": ("degree", "tilt of the face nearest the top from level"),
    "draft": ("m", "depth of the lowest point below the water"),
    "period": ("s", "period of heave"),
    "E_pto": ("J", "energy absorbed by every take-off"),
    "power": ("W", "take-off's mean power over the run's second half"),
    "amplitude": ("m", "joint coordinate's amplitude over the run's second half (rad on a hinge)"),
}
"""A sweep's own result columns (sim/sweeps/chunk.py), beside the run's."""


def describe(column: str, table: dict = UNITS) -> tuple[str, str]:
    """(units, long_name) of a column: `float_z` is a body's `z`, `pto_P_pto` a joint's `P_pto`, `T_fair_3` a fairlead's
    ("" units: not known)."""
    if column in table:
        return table[column]
    if column.startswith("T_fair_"):
        return "N", f"tension at fairlead {column[7:]}"
    if column.startswith("eta_"):
        return "m", f"water surface elevation at gauge {column[4:]}"
    if column.startswith("record_"):
        return "m", f"measured record at gauge {column[7:]} (its mean removed)"
    for known in sorted(table, key=len, reverse=True):
        if column.endswith("_" + known):
            units, name = table[known]
            return units, f"{column[: -len(known) - 1]}: {name}"
    return "", column


def dataset(columns: list[str], rows: list, scene: dict, history: str):
    """The xarray Dataset of a run's `rows` (each in `columns` order, `t` first), with `scene` (a dict of plain
    values) and the command that made it (`history`) in its attributes."""
    import xarray as xr  # the netcdf extra: never imported by a run that writes CSV

    table = np.asarray(rows, float).reshape(-1, len(columns))
    variables = {}
    for k, name in enumerate(columns[1:], 1):
        units, long_name = describe(name)
        variables[name] = ("time", table[:, k], {"long_name": long_name, **({"units": units} if units else {})})
    now = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    return xr.Dataset(
        variables,
        coords={"time": ("time", table[:, 0], {"units": "s", "long_name": "simulated time", "standard_name": "time"})},
        attrs={
            "Conventions": "CF-1.8",
            "title": f"floatsim run of scene {scene.get('name', '')!r}",
            "source": "floatsim",
            "history": f"{now} {history}",
            "floatsim_scene": json.dumps(scene, default=_plain),
        },  # fmt: skip
    )


def grid_dataset(frame, params: list[tuple[str, str, str]], attrs: dict):
    """A sweep's results (a pandas DataFrame, one row per case) as a dataset over its swept parameters: `params`, in
    order, (name, units, long_name) of each, a dimension; each result column a variable over them (a power matrix
    is `d1_power` over `hs` and `tp`)."""
    import xarray as xr  # the netcdf extra

    names = [name for name, _, _ in params]
    ds = xr.Dataset.from_dataframe(frame.drop(columns=["case"], errors="ignore").set_index(names).sort_index())
    for name, units, long_name in params:
        ds[name].attrs.update({"long_name": long_name, **({"units": units} if units else {})})
    for name in ds.data_vars:
        units, long_name = describe(name, {**UNITS, **SWEEP_UNITS})
        ds[name].attrs.update({"long_name": long_name, **({"units": units} if units else {})})
    ds.attrs.update({"Conventions": "CF-1.8", "source": "floatsim", **attrs})
    return ds


def _plain(value):
    """What json cannot write itself: numpy's numbers and arrays, paths."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return str(value)


def write(ds, path: str) -> None:
    """`ds` into the netCDF3 file `path` (xarray's scipy engine)."""
    ds.to_netcdf(path, engine="scipy", format="NETCDF3_64BIT")


def check_extra() -> None:
    """One-line ConfigError unless xarray (the netcdf extra) is installed."""
    try:
        import xarray  # noqa: F401
    except ImportError:
        raise ConfigError(f"--out *.nc writes netCDF through xarray, which is not installed: {EXTRA}") from None

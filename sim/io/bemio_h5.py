"""Radiation and excitation coefficients from a BEMIO `.h5` file, WEC-Sim's and SEA-Stack's input (written by WEC-Sim's
`writeBEMIOH5` from WAMIT, NEMOH, AQWA or Capytaine runs, or by scripts that follow its layout).

What is read (WEC-Sim's `writeBEMIOH5`, as h5py sees it; the file's numbers are nondimensional as WAMIT's, without
the length scale):

- `simulation_parameters/`: `rho`, `g`, `water_depth` (a number, or the text "infinite"), `w` (rad/s), `wave_dir`
  (degrees);
- `bodyK/properties/cg`: each body's centre of gravity, the point its coefficients are about (WEC-Sim's equations of
  motion are about it and take the file as it is);
- `bodyK/hydro_coeffs/`: `added_mass/inf_freq` (6, 6N) and `added_mass/all` (6, 6N, n), A / rho; `radiation_damping/
  all` (6, 6N, n), B / (rho omega); `excitation/re` and `/im` (6, headings, n), X / (rho g) per metre of wave
  (or `mag` and `phase`); `linear_restoring_stiffness` (6, 6), C / (rho g), to check the bodies. Rows are the body's
  six modes, columns all the file's.

A file without `added_mass/all` and `radiation_damping/all` (SEA-Stack's own scripts write only the radiation's
impulse response) has them from `radiation_damping/impulse_response_fun/K` (K / rho against `t`), inverting WEC-Sim's
K(t) = (2/pi) int B(w) cos(w t) dw: B(w) = int K(t) cos(w t) dt, A(w) = A(inf) - (1/w) int K(t) sin(w t) dt (Ogilvie),
0.1 % of the largest entry over the IEA sphere's waves (0.3-8 rad/s; 1 % at the grid's ends) in SEA-Stack's file,
which has both.

BEMIO's time factor is WAMIT's, e^(i omega t) (its Capytaine and NEMOH readers conjugate to it): the excitation is
conjugated to floatsim's e^(-i omega t). Read through h5py (the bemio extra).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from sim.errors import ConfigError
from sim.hydro.bem import Coefficients
from sim.hydro.impulse_response import frequency_response

EXTRA = 'pip install -e ".[bemio]"'
MARK = b"simulation_parameters"
"""The group name every BEMIO file has, near its start (how an HDF5 file is told from a netCDF4 one without h5py)."""


def is_bemio(head: bytes) -> bool:
    """Whether an HDF5 file's first bytes are a BEMIO file's."""
    return head[:4] == b"\x89HDF" and MARK in head


def _body_numbers(f, where: str) -> list[int]:
    numbers = sorted(int(k[4:]) for k in f.keys() if k.startswith("body") and k[4:].isdigit())
    if not numbers or numbers != list(range(1, len(numbers) + 1)):
        raise ConfigError(f"{where} has no body1, body2, ... groups in order (found {', '.join(sorted(f.keys()))})")
    return numbers


def _get(f, name: str, where: str) -> np.ndarray:
    if name not in f:
        raise ConfigError(f"{where} has no {name} (a BEMIO file holds it)")
    return np.asarray(f[name][()])


def _scalar(f, name: str, where: str) -> float:
    value = _get(f, name, where)
    if value.dtype.kind in "SOU":
        text = value.item().decode() if isinstance(value.item(), bytes) else str(value.item())
        if text.strip().lower().startswith("inf"):
            return math.inf
        raise ConfigError(f"{where}: {name} is {text!r}, not a number")
    return float(value.ravel()[0])


def _radiation(hc, rho: float, omega: np.ndarray, where: str, body: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(6, 6N) A(inf) and (n, 6, 6N) A and B of one body's rows, dimensional."""
    A_inf = rho * _get(hc, "added_mass/inf_freq", f"{where} body{body}")
    if "added_mass/all" in hc and "radiation_damping/all" in hc:
        A = rho * np.moveaxis(_get(hc, "added_mass/all", where), -1, 0)
        B = rho * omega[:, None, None] * np.moveaxis(_get(hc, "radiation_damping/all", where), -1, 0)
    elif "radiation_damping/impulse_response_fun/K" in hc:
        K = rho * _get(hc, "radiation_damping/impulse_response_fun/K", where)
        t = _get(hc, "radiation_damping/impulse_response_fun/t", where).ravel()
        if K.ndim != 3 or K.shape[:2] != A_inf.shape or K.shape[2] != len(t) or len(t) < 2:
            raise ConfigError(f"{where} body{body}: the radiation's impulse response {K.shape} does not fit its {len(t)} times and the "
                              f"infinite-frequency added mass {A_inf.shape} (a cut file?)")  # fmt: skip
        A, B = frequency_response(K, t, omega, A_inf)
    else:
        raise ConfigError(f"{where} body{body} has neither radiation_damping/all nor its impulse response")
    if A.shape != (len(omega),) + A_inf.shape or B.shape != A.shape or A_inf.shape[0] != 6:
        raise ConfigError(f"{where} body{body}: added mass {A.shape} and damping {B.shape} do not fit {len(omega)} frequencies and "
                          f"the infinite-frequency added mass {A_inf.shape} (a cut file?)")  # fmt: skip
    return A_inf, A, B


def _excitation(hc, rho_g: float, shape: tuple[int, int], where: str) -> np.ndarray | None:
    """(n, m, 6) one body's excitation per metre of wave, floatsim's time factor; None when the file has none."""
    if "excitation/re" in hc and "excitation/im" in hc:
        X = _get(hc, "excitation/re", where) + 1j * _get(hc, "excitation/im", where)
    elif "excitation/mag" in hc and "excitation/phase" in hc:
        X = _get(hc, "excitation/mag", where) * np.exp(1j * _get(hc, "excitation/phase", where))
    else:
        return None
    if X.shape != (6,) + shape[::-1]:
        raise ConfigError(f"{where}: excitation {X.shape}, expected (6, {shape[1]} headings, {shape[0]} frequencies) (a cut file?)")
    return np.conj(rho_g * X.transpose(2, 1, 0))


def read_bemio(path: Path) -> tuple[Coefficients, np.ndarray, float, np.ndarray | None]:
    """(the coefficients about each body's centre of gravity with the whole excitation in `diffraction`, those centres
    ((k, 3), as capytaine_nc.read_capytaine and nemoh.read_nemoh give theirs), g, the hydrostatic stiffness (6N, 6N,
    block diagonal) or None): one-line ConfigError on a file floatsim cannot take."""
    try:
        import h5py  # the bemio extra
    except ImportError:
        raise ConfigError(
            f"[fluid] bem_file {str(path)!r} is a BEMIO .h5 file, read through h5py, which is not installed: {EXTRA}"
        ) from None
    where = f"[fluid] bem_file {str(path)!r}"
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        raise ConfigError(f"{where}: cannot read it ({str(e).splitlines()[0]})") from None
    with f:
        rho, g = _scalar(f, "simulation_parameters/rho", where), _scalar(f, "simulation_parameters/g", where)
        depth = _scalar(f, "simulation_parameters/water_depth", where) if "simulation_parameters/water_depth" in f else math.inf
        omega = _get(f, "simulation_parameters/w", where).ravel().astype(float)
        headings = np.radians(_get(f, "simulation_parameters/wave_dir", where).ravel().astype(float))
        bodies = _body_numbers(f, where)
        n6 = 6 * len(bodies)
        rows, forces, cg, C = [], [], [], np.zeros((n6, n6))
        for b in bodies:
            hc = f[f"body{b}/hydro_coeffs"] if f"body{b}/hydro_coeffs" in f else None
            if hc is None:
                raise ConfigError(f"{where} has no body{b}/hydro_coeffs")
            A_inf, A, B = _radiation(hc, rho, omega, where, b)
            if A_inf.shape[1] != n6:
                raise ConfigError(f"{where} body{b}: its added mass couples {A_inf.shape[1] // 6} bodies, the file has {len(bodies)}")
            rows.append((A_inf, A, B))
            forces.append(_excitation(hc, rho * g, (len(omega), len(headings)), where))
            cg.append(_get(f, f"body{b}/properties/cg", where).ravel().astype(float))
            if "linear_restoring_stiffness" in hc:
                C[6 * (b - 1) : 6 * b, 6 * (b - 1) : 6 * b] = rho * g * np.asarray(hc["linear_restoring_stiffness"][()])[:, :6]
    A_inf = np.concatenate([r[0] for r in rows], axis=0)
    A, B = (np.concatenate([r[k] for r in rows], axis=1) for k in (1, 2))
    order = np.argsort(omega)
    X = None if any(x is None for x in forces) else np.concatenate(forces, axis=2)[order]
    turn = np.mod(headings, 2 * math.pi)
    by_heading = np.argsort(turn)
    if X is not None:
        X = X[:, by_heading]
    centers = np.array(cg)
    if not np.isfinite(A).all() or not np.isfinite(B).all():
        raise ConfigError(f"{where}: its added mass or damping holds NaN or infinity")
    c = Coefficients(omega[order], A[order], B[order], A_inf, rho, depth if depth > 0 else math.inf, 0, centers[0] if len(bodies) == 1 else centers,
                     None if X is None else turn[by_heading], X, None if X is None else np.zeros_like(X))  # fmt: skip
    return c, centers, g, (C if C.any() else None)

"""Measured seas: a record of the surface elevation at one point, taken apart into Airy components.

A tank or buoy gives eta(t) at a reference point, not a spectrum. Taken as one period of a periodic sea
(the discrete Fourier transform over its length T = N dt), the record is a sum of components at
omega_j = 2 pi j / T, each travelling in the scene's wave direction with its own wavenumber; the body then
meets that sea through the same nonlinear Froude-Krylov, diffraction, radiation and drift as a JONSWAP sea.

The record's ends: the sea is the record's periodic extension. At every sample it equals the record less
its mean (a set-down or gauge offset, not a wave) and less the Nyquist component (which has no phase to
travel with); between samples it is the band-limited (trigonometric) interpolation; after T it repeats.
Where the record's two ends differ, the wrap from its last sample back to its first is a jump the
interpolation rings on; the wave ramp (by default 3.5 peak periods) keeps it off the body at the start.
"""

from __future__ import annotations

import functools
import math
import os
from pathlib import Path

import numpy as np

from sim.errors import ConfigError

PEAK_MULTIPLE = 4.0
"""Unless `cutoff_period` says otherwise, components up to this many times the record's peak frequency are kept (a
JONSWAP spectrum holds about 1e-3 of its variance above 4 omega_p): a gauge's noise and the leakage of waves between
the record's frequencies would otherwise give thousands of components, each costing the run."""
FLOOR = 1e-6
"""Components below this fraction of the largest are left out: each carries under 1e-12 of its variance (a
record written from a sea on the record's frequency grid comes back with exactly that sea's components)."""
MAX_COMPONENTS = 4096
"""As many as a JONSWAP sea may have ([waves] components)."""
MIN_SAMPLES = 8
SPACING_SLACK = 1e-3
"""Sample times may differ from a uniform grid by this fraction of the step (times written with few digits)."""


def record_path(name: str, base_dir: str = ".") -> Path:
    """The record file a scene names: relative to the scene file, else to the working directory."""
    path = Path(name)
    if not path.is_absolute() and not path.is_file():
        path = Path(base_dir) / path
    return path


MAX_ELEVATION = 1e4
"""m: no measured sea is higher (a damaged value, 1e308, overflowed every sum of the record before it was refused)."""


def read_record(path: Path) -> tuple[float, np.ndarray]:
    """(dt, eta) of a CSV of time (s) and elevation (m), two columns; lines before the first row of numbers
    (a header) and lines starting with # are skipped. One-line ConfigError on anything else."""
    try:
        stat = os.stat(path)
    except OSError as e:
        raise ConfigError(f"[waves] record {str(path)!r}: {e.strerror or e}") from None
    return _read(str(path), stat.st_mtime_ns, stat.st_size)


@functools.lru_cache(maxsize=8)
def _read(path: str, mtime_ns: int, size: int) -> tuple[float, np.ndarray]:
    del mtime_ns, size  # the cache key: an edited file is read again
    rows = []
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            for number, line in enumerate(f, 1):
                text = line.strip()
                if not text or text.startswith("#"):
                    continue
                cells = text.replace(";", ",").replace("\t", ",").split(",")
                cells = cells if len(cells) > 1 else text.split()  # comma, semicolon, tab or space separated
                try:
                    values = [float(c) for c in cells]
                except ValueError:
                    if rows:
                        raise ConfigError(f"[waves] record {path!r} line {number}: {text[:60]!r} is not two numbers (time, eta)") from None
                    continue  # a header
                if len(values) != 2:
                    raise ConfigError(f"[waves] record {path!r} line {number}: {len(values)} columns, expected 2 (time in s, eta in m)")
                rows.append(values)
    except OSError as e:
        raise ConfigError(f"[waves] record {path!r}: {e.strerror or e}") from None
    if len(rows) < MIN_SAMPLES:
        raise ConfigError(f"[waves] record {path!r} has {len(rows)} samples: at least {MIN_SAMPLES} rows of time (s), eta (m)")
    data = np.array(rows)
    if not np.all(np.isfinite(data)):
        raise ConfigError(f"[waves] record {path!r} has a value that is not a finite number")
    t, eta = data[:, 0], data[:, 1]
    if np.max(np.abs(eta)) > MAX_ELEVATION or np.max(np.abs(t)) > MAX_ELEVATION * 1e4:  # (before any sum of them overflows)
        raise ConfigError(f"[waves] record {path!r} has an elevation of {np.max(np.abs(eta)):.3g} m or a time of {np.max(np.abs(t)):.3g} s: "
                          f"no sea rises {MAX_ELEVATION:g} m, nor a record lasts 1e8 s (a unit or a damaged value?)")  # fmt: skip
    dt = (t[-1] - t[0]) / (len(t) - 1)
    if not dt > 0 or np.max(np.abs(np.diff(t) - dt)) > SPACING_SLACK * dt:
        raise ConfigError(f"[waves] record {path!r}: the times must rise in equal steps (resample it onto a uniform grid first)")
    eta.flags.writeable = False
    return float(dt), eta


def components(dt: float, eta: np.ndarray, cutoff_period: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(omega, amplitude, alpha) with eta(t_n) - mean = sum_j amplitude_j cos(omega_j t_n + alpha_j) at every
    sample t_n = n dt (less the Nyquist component and the components left out), keeping omega_j <= 2 pi /
    cutoff_period (unset: PEAK_MULTIPLE times the peak frequency) and the components above FLOOR of the largest."""
    n = len(eta)
    c = np.fft.rfft(eta - eta.mean())[1 : (n + 1) // 2]  # the mean and (n even) the Nyquist bin left out
    omega = 2 * math.pi * np.arange(1, len(c) + 1) / (n * dt)
    amplitude = 2 * np.abs(c) / n
    if not amplitude.size or amplitude.max() == 0:
        raise ConfigError("the record is flat: its elevation never changes (no waves to take apart)")
    keep = amplitude >= FLOOR * amplitude.max()
    highest = PEAK_MULTIPLE * omega[np.argmax(amplitude)] if cutoff_period is None else 2 * math.pi / cutoff_period
    keep &= omega <= highest * (1 + 1e-12)
    if keep.sum() > MAX_COMPONENTS:
        raise ConfigError(f"the record has {int(keep.sum())} components (over {MAX_COMPONENTS}): keep the longer waves with [waves] "
                          f"cutoff_period (--wave-cutoff-period), e.g. {math.ceil(100 * n * dt / MAX_COMPONENTS) / 100:g} s")  # fmt: skip
    return omega[keep], amplitude[keep], np.angle(c[keep])


def peak_period(dt: float, eta: np.ndarray, cutoff_period: float | None = None) -> float:
    """The period of the record's largest component, s (the default ramp counts in it)."""
    omega, amplitude, _ = components(dt, eta, cutoff_period)
    if not amplitude.size:
        raise ConfigError(f"the record has no component longer than cutoff_period = {cutoff_period:g} s")
    return float(2 * math.pi / omega[np.argmax(amplitude)])


def measured(waves, base_dir: str = ".") -> tuple[float, np.ndarray]:
    """(dt, eta) of the record a scene's [waves] table names."""
    if not waves.record:
        raise ConfigError('[waves] kind = "record" needs [waves] record = "file.csv" (time in s, eta in m)')
    path = record_path(waves.record, base_dir)
    if not path.is_file():
        where = "" if Path(waves.record).is_absolute() else f" (looked in the working directory and {base_dir})"
        raise ConfigError(f"[waves] record {waves.record!r}: no such file{where}")
    return read_record(path)


def repeat_period(omega: np.ndarray) -> float:
    """The time after which a sum of components of frequencies `omega` repeats, s: 2 pi over their greatest common
    divisor (a record's are whole multiples of 2 pi over its length, so at most its length; its longest kept wave's
    period only where that divides every other's)."""
    tol = 1e-9 * float(np.max(omega))
    common = 0.0
    for w in map(float, omega):  # Euclid's algorithm, a remainder within round-off of 0 or of the divisor taken as 0
        a, b = w, common
        while b > tol:
            r = math.fmod(a, b)
            a, b = b, (0.0 if min(r, b - r) <= tol else r)
        common = a
    return 2 * math.pi / common


def describe(sea, waves) -> str:
    """The note a run with a record gives: how many components it kept, over which periods, and when it repeats."""
    shortest, longest = 2 * math.pi / sea.omega.max(), 2 * math.pi / sea.omega.min()
    why = (
        f"cutoff_period {waves.cutoff_period:g} s"
        if waves.cutoff_period is not None
        else "a quarter of its peak period: set cutoff_period to keep more"
    )
    return (f"the measured sea: {len(sea.omega)} components of periods {shortest:.3g}-{longest:.4g} s ({why}); "
            f"the sea repeats after {repeat_period(sea.omega):.4g} s")  # fmt: skip

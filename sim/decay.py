"""Free-decay tests, the naval architect's standard check: release a floating body displaced from its
equilibrium (raised, or heeled) and measure how it rings down: damped period, decay rate, first trough."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sim.bodies.rotation import quat_multiply
from sim.bodies.state import initial_state
from sim.hydro.equilibrium import rest_height
from sim.simulation import Simulation


@dataclass(frozen=True)
class Decay:
    """What a free decay record shows. Units of the signal: m (heave) or degrees (roll)."""

    dof: str
    periods: np.ndarray
    """Damped periods between successive maxima and between successive minima, s."""
    rate: float
    """Decay rate sigma of the exponential fitted to the extrema's magnitudes, 1/s."""
    first_trough: float
    """The first minimum's value (its undershoot of the equilibrium), and when it came."""
    first_trough_time: float
    extrema: tuple[np.ndarray, np.ndarray]
    """(times, values) of the interpolated extrema."""

    @property
    def period(self) -> float:
        return float(np.median(self.periods)) if len(self.periods) else math.nan

    @property
    def damping_ratio(self) -> float:
        """zeta from the logarithmic decrement delta = sigma T: delta / sqrt(4 pi^2 + delta^2)."""
        delta = self.rate * self.period
        return delta / math.sqrt(4 * math.pi**2 + delta**2)


def extrema(t: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Local maxima and minima, each refined by the parabola through it and its neighbours."""
    inner = y[1:-1]
    k = np.flatnonzero(((inner > y[:-2]) & (inner >= y[2:])) | ((inner < y[:-2]) & (inner <= y[2:]))) + 1
    a, b, c = y[k - 1], y[k], y[k + 1]
    curvature = a - 2 * b + c
    d = np.where(curvature != 0, 0.5 * (a - c) / np.where(curvature != 0, curvature, 1.0), 0.0)
    return t[k] + d * (t[1] - t[0]), b - 0.25 * (a - c) * d


def analyse(dof: str, t: np.ndarray, y: np.ndarray) -> Decay:
    """Periods, decay rate and first trough of a record y(t) about zero (the equilibrium)."""
    te, ye = extrema(t, y)
    maxima, minima = ye > 0, ye < 0
    periods = np.concatenate([np.diff(te[maxima]), np.diff(te[minima])])
    big = np.abs(ye) > 1e-3 * np.abs(y).max()  # past the noise floor
    rate = -np.polyfit(te[big], np.log(np.abs(ye[big])), 1)[0] if big.sum() >= 3 else math.nan
    trough = np.flatnonzero(minima)
    first = (float(ye[trough[0]]), float(te[trough[0]])) if len(trough) else (math.nan, math.nan)
    return Decay(dof, periods, float(rate), *first, (te, ye))


def release(sim: Simulation, drop: float, tilt_deg: float) -> tuple[str, float]:
    """Put the body at its equilibrium height (for its scene orientation), raised by `drop` and heeled by
    `tilt_deg` about the world x axis, at rest. Returns the degree of freedom measured and z at rest."""
    start = initial_state(sim.body, sim.scene)
    z_rest = rest_height(sim.body, sim.scene.fluid, start.R_world_body)
    half = math.radians(tilt_deg) / 2
    q = quat_multiply(np.array([math.cos(half), math.sin(half), 0.0, 0.0]), start.q_world_body)
    sim.reset(type(start)(0.0, np.array([0.0, 0.0, z_rest + drop]), q, np.zeros(3), np.zeros(3)))
    return ("roll" if tilt_deg else "heave"), z_rest


def signal(sim: Simulation, dof: str, z_rest: float) -> float:
    """Heave: z above the rest height, m. Roll: the heel about world x, degrees."""
    if dof == "heave":
        return float(sim.state.x_world[2] - z_rest)
    R = sim.state.R_world_body
    return math.degrees(math.atan2(R[2, 1], R[2, 2]))

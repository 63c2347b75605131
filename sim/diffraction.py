"""The wave force a body adds by being there: linear diffraction from a boundary-element solve (Capytaine).

floatsim's waves push on the wet surface with their own, undisturbed pressure: the Froude-Krylov force,
nonlinear here (the exact wet surface of each instant). A body that is not small against the wavelength
also scatters the waves, and the scattered wave's pressure on it is the diffraction force. In linear
potential flow, for one wave component a cos(k (x cos beta + y sin beta) - omega t + phi),

    F_d(t) = Re{ X_d(omega, beta) a e^(i (k (x0 cos beta + y0 sin beta) + phi)) e^(-i omega t) },

X_d the diffraction force per unit wave amplitude on the body held at its rest pose (6 dofs, world axes,
moments about the centre of mass at rest: `bem.Coefficients.diffraction`), (x0, y0) the rest position the
solve is referenced to. The components add up. X_d is interpolated linearly in heading (periodic, the
solve's grid is 15 degrees) and in frequency, falling linearly to 0 at omega = 0 (long waves pass a body
unscattered); components above the solve's grid (waves shorter than half the body) get none.

Valid where linear theory is: wave steepness small, and body motions small against the wave (the
scattered wave is the one of the body at rest; the Froude-Krylov part keeps its exact wet surface).
Left out: second-order forces (mean and slow drift), slamming, green water, and any current.
The same as the "nonlinear Froude-Krylov + linear diffraction" of WEC-Sim's nonlinear hydro mode.
"""

from __future__ import annotations

import math

import numpy as np

from .bem import Coefficients


def transfer_at(c: Coefficients, X: np.ndarray, omega: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """(n, 6) complex X (the solve's (frequencies, headings, 6)) at each (omega_i, beta_i), interpolated
    linearly in heading (periodic) and frequency; 0 at omega = 0 and above the grid."""
    omega, beta = np.atleast_1d(np.asarray(omega, float)), np.atleast_1d(np.asarray(beta, float))
    headings = np.append(c.headings, c.headings[0] + 2 * math.pi)
    table = np.concatenate([X, X[:, :1]], axis=1)  # the first heading again, a turn later
    b = np.mod(beta, 2 * math.pi)
    j = np.clip(np.searchsorted(headings, b, side="right") - 1, 0, len(headings) - 2)
    wb = ((b - headings[j]) / (headings[j + 1] - headings[j]))[:, None]
    grid = np.concatenate([[0.0], c.omega])
    zero = np.zeros((1, *table.shape[1:]), complex)
    table = np.concatenate([zero, table], axis=0)
    inside = omega <= grid[-1]
    k = np.clip(np.searchsorted(grid, omega, side="right") - 1, 0, len(grid) - 2)
    wo = np.clip((omega - grid[k]) / (grid[k + 1] - grid[k]), 0.0, 1.0)[:, None]
    at = lambda kk, jj: table[kk, jj]  # noqa: E731  ((n, 6) for index arrays kk, jj)
    low = (1 - wb) * at(k, j) + wb * at(k, j + 1)
    high = (1 - wb) * at(k + 1, j) + wb * at(k + 1, j + 1)
    return np.where(inside[:, None], (1 - wo) * low + wo * high, 0.0)


class Diffraction:
    """The diffraction force of one body in one sea: a complex amplitude (6,) per wave component,
    fixed when the sea and the body's rest position are; the force at time t is their sum."""

    def __init__(self, c: Coefficients, water, rest_xy):
        x0, y0 = (float(v) for v in rest_xy)
        phase = water.k * (x0 * np.cos(water.direction) + y0 * np.sin(water.direction)) + water.phase
        X = transfer_at(c, c.diffraction, water.omega, water.direction)
        self.amplitude = X * (water.amplitude * np.exp(1j * phase))[:, None]
        """(n, 6) complex: component i adds Re{amplitude_i e^(-i omega_i t)}."""
        self.omega = np.asarray(water.omega, float)
        self.above_grid = int(np.count_nonzero(self.omega > c.omega[-1]))
        """How many components are above the solve's frequencies (they get no diffraction force)."""

    def force(self, t: float) -> np.ndarray:
        """(6,) force and moment about the centre of mass, world frame, N and N m."""
        return (self.amplitude * np.exp(-1j * self.omega * t)[:, None]).real.sum(axis=0)

"""The wave force a body adds by being there: linear diffraction from a boundary-element solve (Capytaine).

floatsim's waves push on the wet surface with their own, undisturbed pressure: the Froude-Krylov force,
nonlinear here (the exact wet surface of each instant). A body that is not small against the wavelength
also scatters the waves, and the scattered wave's pressure on it is the diffraction force. In linear
potential flow, for one wave component a cos(k (x cos beta + y sin beta) - omega t + phi),

    F_d(t) = r(t) Re{ X_d(omega, beta) a e^(i (k (x cos beta + y sin beta) + phi)) e^(-i omega t) },

X_d the diffraction force per unit wave amplitude on the body held at its rest pose (6 dofs, world axes,
moments about the centre of mass at rest: `bem.Coefficients.diffraction`), (x, y) the horizontal position of
its centre of mass now (where the Froude-Krylov force acts too: a body that drifts meets the wave's phase
where it is), r(t) the sea's ramp (water.ramp_factor). The components add up. X_d is interpolated linearly
in heading (periodic, the solve's grid is 15 degrees) and in frequency, falling linearly to 0 at omega = 0
(long waves pass a body unscattered); components above the solve's grid (waves shorter than half the body)
get none. Several bodies solved together: each body's block, phased at its own centre.

Valid where linear theory is: wave steepness small, and body motions small against the wave (the
scattered wave is the one of the body at rest, turned by neither its pitch nor its yaw; the Froude-Krylov
part keeps its exact wet surface). Left out: second-order forces (mean and slow drift), slamming, green water,
and any current. The same as the "nonlinear Froude-Krylov + linear diffraction" of WEC-Sim's nonlinear hydro mode.
"""

from __future__ import annotations

import math

import numpy as np

from sim.hydro.bem import Coefficients
from sim.water.seas import ramp_factor


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
    """The diffraction force of one body (or several solved together) in one sea: per wave component a complex
    amplitude (6 per body) referred to the world's origin, shifted at each evaluation to where each body is."""

    def __init__(self, c: Coefficients, water, solved_xy=(0.0, 0.0)):
        """`solved_xy`: (bodies, 2) where the solve placed each body's centre of mass (one body: (2,), its own centre
        at the origin; several: their starting positions)."""
        solved = np.atleast_2d(np.asarray(solved_xy, float))
        self.k = np.column_stack([water.k * np.cos(water.direction), water.k * np.sin(water.direction)])
        """(n, 2) each component's wave vector, rad/m."""
        X = transfer_at(c, c.diffraction, water.omega, water.direction).reshape(len(water.omega), len(solved), 6)
        phase = water.phase[:, None] - self.k @ solved.T  # (n, bodies): the solve's wave phase, taken back to the origin
        self.amplitude = (X * (water.amplitude[:, None] * np.exp(1j * phase))[:, :, None]).reshape(len(water.omega), -1)
        """(n, 6 bodies) complex: component i adds r(t) Re{amplitude_i e^(i (k_i . x_b - omega_i t))} to body b's block."""
        self.omega = np.asarray(water.omega, float)
        self.ramp = float(water.ramp)
        self.bodies = len(solved)
        self.above_grid = int(np.count_nonzero(self.omega > c.omega[-1]))
        """How many components are above the solve's frequencies (they get no diffraction force)."""

    def amplitudes(self, at) -> np.ndarray:
        """(n, 6 bodies) complex: each component's force with the bodies' centres at `at` ((bodies, 2 or 3), or one
        body's (2,) or (3,)), unramped: component i adds Re{amplitude_i e^(-i omega_i t)}."""
        xy = np.atleast_2d(np.asarray(at, float))[:, :2]
        shift = np.exp(1j * (self.k @ xy.T))  # (n, bodies)
        return (self.amplitude.reshape(len(self.omega), self.bodies, 6) * shift[:, :, None]).reshape(len(self.omega), -1)

    def force(self, t: float, at) -> np.ndarray:
        """(6 bodies,) force and moment about each centre of mass, world frame, N and N m, at time t with the bodies'
        centres of mass at `at` (as `amplitudes`)."""
        xy = np.atleast_2d(np.asarray(at, float))[:, :2]
        turn = np.exp(1j * (self.k @ xy.T - self.omega[:, None] * t))  # (n, bodies)
        each = (self.amplitude.reshape(len(self.omega), self.bodies, 6) * turn[:, :, None]).real.sum(axis=0)
        return ramp_factor(t, self.ramp) * each.ravel()

    def kernel_arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
        """(re, im, waves, ramp) for the compiled kernels (kernels/radiation.py), one body: the amplitudes' real and
        imaginary parts (n, 6), each component's (omega, k_x, k_y) (n, 3), and the ramp's duration, s."""
        waves = np.column_stack([self.omega, self.k])
        return (*(np.ascontiguousarray(a, dtype=float) for a in (self.amplitude.real, self.amplitude.imag, waves)), self.ramp)


NO_DIFFRACTION = (np.zeros((0, 6)), np.zeros((0, 6)), np.zeros((0, 3)), 0.0)
"""Diffraction.kernel_arrays of a body without diffraction."""

"""The water a body floats in: where its surface is, how it moves, and its pressure.

Every wet test and every force term asks a `Water`, never the plane z = 0 itself. Still water is
the first kind; waves plug in as further kinds with the same three questions. World frame, SI units.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class StillWater:
    """Calm water, surface z = 0, at rest: hydrostatic pressure p = -rho g z below the surface.

    Still water is time-independent and its pressure is linear in z, which lets the compiled
    kernels keep running sums over the wet set and integrate panels in closed form."""

    rho: float = 1000.0
    """Water density, kg/m^3."""
    g: float = 9.81
    """Gravitational acceleration, m/s^2."""

    kind = "still"
    is_still = True

    def elevation(self, xy: np.ndarray, t: float) -> np.ndarray:
        """Surface height eta(x, y, t) at (..., 2) horizontal positions, m."""
        return np.zeros(np.shape(xy)[:-1])

    def velocity(self, points: np.ndarray, t: float) -> np.ndarray:
        """Fluid velocity at (..., 3) points under the surface, m/s."""
        return np.zeros(np.shape(points))

    def pressure(self, points: np.ndarray, t: float) -> np.ndarray:
        """Gauge pressure at (..., 3) points under the surface, Pa (zero on the surface)."""
        return -self.rho * self.g * points[..., 2]

    def height_above_surface(self, points: np.ndarray, t: float) -> np.ndarray:
        """z - eta at (..., 3) points: negative where they are wet."""
        return points[..., 2] - self.elevation(points[..., :2], t)

"""Where a body floats at rest in still water."""

from __future__ import annotations

import numpy as np

from .errors import ConfigError


def rest_height(body, fluid, R: np.ndarray) -> float:
    """The centre of mass's height at which the body, held at orientation R, displaces its own mass
    (the exact clipped volume of its mesh), m. ConfigError when it cannot float."""
    from scipy.optimize import brentq

    from .surface import wet_panels
    from .water import StillWater

    water = StillWater(fluid.rho, fluid.g)

    def excess(z: float) -> float:
        return fluid.rho * wet_panels(body, water, np.array([0.0, 0.0, z]), R, 0.0).submerged_volume - body.mass

    reach = float(np.linalg.norm(body.mesh_vertices, axis=1).max()) * 1.01
    if excess(-reach) <= 0.0:
        raise ConfigError(f"this body ({body.mass:.4g} kg) is heavier than the water it can displace: it has no floating equilibrium")
    return float(brentq(excess, -reach, reach, xtol=1e-10))

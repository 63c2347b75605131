"""Where a body floats at rest in still water."""

from __future__ import annotations

import numpy as np

from .errors import ConfigError


def rest_height(body, fluid, R: np.ndarray, pull: float = 0.0) -> float:
    """The centre of mass's height at which the body, held at orientation R, displaces its own mass (the exact
    clipped volume of its mesh), and with `pull` (N, a vertical force on it: negative down, as mooring lines pull)
    what holds that up too, m. ConfigError when it cannot float."""
    from scipy.optimize import brentq

    from .surface import wet_panels
    from .water import StillWater

    water = StillWater(fluid.rho, fluid.g)

    def excess(z: float) -> float:
        return fluid.rho * wet_panels(body, water, np.array([0.0, 0.0, z]), R, 0.0).submerged_volume - (body.mass - pull / fluid.g)

    reach = float(np.linalg.norm(body.mesh_vertices, axis=1).max()) * 1.01
    if excess(-reach) <= 0.0:
        if pull < 0.0:
            raise ConfigError(f"this body ({body.mass:.4g} kg) cannot hold up its mooring lines' pull ({-pull:.4g} N down at rest) as well as "
                              "its weight: shorter or lighter lines, or a larger body")  # fmt: skip
        raise ConfigError(f"this body ({body.mass:.4g} kg) is heavier than the water it can displace: it has no floating equilibrium")
    return float(brentq(excess, -reach, reach, xtol=1e-10))


def scene_rest_height(body, scene, R: np.ndarray) -> float:
    """The centre of mass's rest height in the scene, m, body orientation R (body to world): `rest_height` with the
    mooring lines' vertical pull at rest (at the scene's starting horizontal position), found by fixed-point
    iteration (the pull changes little with the draft: two or three rounds); without lines, the free rest."""
    from .config import moored

    z = rest_height(body, scene.fluid, R)
    if not moored(scene):
        return z
    from .moorings import rest_pull
    from .rotation import quat_to_matrix

    R_input = R @ quat_to_matrix(body.q_input_body).T  # the frame the lines' fairleads are given in, to world
    x, y = (float(v) for v in scene.initial.position[:2])
    for _ in range(30):
        step = rest_height(body, scene.fluid, R, pull=float(rest_pull(scene, np.array([x, y, z]), R_input)[2])) - z
        z += step
        if abs(step) < 1e-10 * body.radius:
            break
    return z

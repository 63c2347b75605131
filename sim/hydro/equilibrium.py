"""Where a body floats at rest in still water."""

from __future__ import annotations

import numpy as np

from sim.bodies.rotation import quat_to_matrix
from sim.bodies.surface import wet_panels
from sim.errors import ConfigError
from sim.lines.moorings import check_lines, moored, rest_pull
from sim.water.seas import StillWater


def rest_height(body, fluid, R: np.ndarray, pull: float = 0.0) -> float:
    """The centre of mass's height at which the body, held at orientation R, displaces its own mass (the exact
    clipped volume of its mesh), and with `pull` (N, a vertical force on it: negative down, as mooring lines pull)
    what holds that up too, m. ConfigError when it cannot float."""
    from scipy.optimize import brentq

    if fluid.g <= 0.0:  # no weight, no buoyancy: every height is a rest (g = 0: a torque-free body, say)
        raise ConfigError("without gravity (g = 0) a body has no floating rest: it stays where it is put")
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


def scene_rest(body, scene, R: np.ndarray) -> np.ndarray:
    """(3,) the centre of mass at rest in the scene, m, body orientation R (body to world): without lines, the free
    rest (`rest_height`) under the starting position; with a spread or anchors of lines, where their pull balances
    (horizontally by Newton steps on their stiffness, vertically by `rest_height` with their vertical pull: each a few
    rounds, the lines' elastic catenaries being cheap); with a MoorDyn file, the lines' vertical pull under the
    starting position (the file's fairleads are where the body starts)."""

    x, y = (float(v) for v in scene.initial.position[:2])
    z = rest_height(body, scene.fluid, R)
    if not moored(scene):
        return np.array([x, y, z])

    R_input = R @ quat_to_matrix(body.q_input_body).T  # the frame the lines' fairleads are given in, to world
    level = not scene.moorings.line_file
    start = np.array([x, y, z])
    check_lines(scene, np.asarray(scene.initial.position, float), R_input)  # a mistake is said now, not after a solve
    try:
        for _ in range(30):
            at = np.array([x, y, z])
            pull = rest_pull(scene, at, R_input)
            if level:
                K = pull_stiffness(scene, at, R_input)
                level = bool(np.linalg.eigvalsh(0.5 * (K + K.T)).min() > 1e-9 * np.abs(K).max())  # one line: no such rest
                if level:
                    x, y = np.array([x, y]) + np.linalg.solve(K, pull[:2])
            step = rest_height(body, scene.fluid, R, pull=float(pull[2])) - z
            z += step
            if abs(step) + abs(x - at[0]) + abs(y - at[1]) < 1e-10 * body.radius:
                break
    except ValueError:  # a catenary with no solution: the lines' own checks at the start say why, later
        return start
    return np.array([x, y, z])


def pull_stiffness(scene, at: np.ndarray, R_input: np.ndarray, step: float = 1e-4) -> np.ndarray:
    """(2, 2) -d(pull_xy)/d(x, y) of the scene's lines on a body held at `at`, N/m (central differences)."""

    K = np.zeros((2, 2))
    for axis in (0, 1):
        dx = np.zeros(3)
        dx[axis] = step
        K[:, axis] = -(rest_pull(scene, at + dx, R_input)[:2] - rest_pull(scene, at - dx, R_input)[:2]) / (2 * step)
    return K

"""Why a body floats the way it does: the centre of buoyancy, the waterplane, the metacentre and GM of
one pose in calm water, exactly from the mesh clipped at the plane z = 0.

With the submerged part of the surface S (outward normals nu) and the waterplane W closing it at z = 0,
the divergence theorem turns every volume and waterplane integral into one over S, and on W the fields
used here vanish or are the integrand itself:
    V = int_S z nu_z dA,   V B = int_S (x z, y z, z^2 / 2) nu_z dA,   int_W f(x, y) dA = -int_S f nu_z dA.
Every integrand is quadratic in position, so the edge-midpoint rule on the clipped triangles is exact.

Inclined by a small angle about a horizontal axis through the waterplane's centroid F, at constant
volume, the centre of buoyancy moves on a curve of radius BM = I / V, I the waterplane's second moment
about that axis (Bouguer's metacentre). The body rights itself when GM = z_B + BM - z_G > 0 about
every axis; the least of the two principal values decides. Valid for small inclinations about the
given pose: a large heel is the panel model's job (the simulation), not this formula's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sim.bodies.rotation import quat_to_matrix
from sim.bodies.surface import clip_triangles
from sim.errors import ConfigError
from sim.hydro.equilibrium import rest_height


@dataclass(frozen=True)
class Hydrostatics:
    """Calm-water hydrostatics of one pose, world frame, SI units."""

    volume: float
    """Displaced volume V, m^3."""
    buoyancy_centre: np.ndarray
    """(3,) B, the centroid of the displaced volume, m."""
    waterplane_area: float
    """Area of the section at z = 0, m^2."""
    waterplane_centre: np.ndarray
    """(3,) F, its centroid (z = 0), m."""
    waterplane_inertia: np.ndarray
    """(2, 2) second moments of the waterplane about F in (x, y), m^4."""
    axes: np.ndarray
    """(2, 2) columns: the horizontal principal directions of the waterplane, least inertia first."""
    bm: np.ndarray
    """(2,) metacentric radii I / V about the two principal axes, least first, m."""
    metacentre: np.ndarray
    """(3,) M = B + BM_min z_hat: the lower (governing) metacentre, m."""
    gm: np.ndarray
    """(2,) metacentric heights z_M - z_G about the two principal axes, least first, m."""
    waterline: np.ndarray
    """(s, 2, 3) segments where the surface meets the body, m."""

    @property
    def stable(self) -> bool:
        return bool(self.gm[0] > 0.0)


def hydrostatics(body, x: np.ndarray, R: np.ndarray) -> Hydrostatics | None:
    """The hydrostatics of `body` with its centre of mass at x and orientation R; None when dry or
    wholly submerged (no waterplane, no metacentre)."""
    P = (body.mesh_vertices @ R.T + x)[body.mesh_faces]  # (f, 3, 3) world
    T, owner = clip_triangles(P, P[:, :, 2])
    if not len(T):
        return None
    cross = np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])  # 2 A nu
    mid = 0.5 * (T + T[:, [1, 2, 0]])  # edge midpoints: exact for quadratics, weight A / 3 each
    wz = (cross[:, 2] / 6.0)[:, None]  # (A / 3) nu_z per node
    X, Y, Z = mid[..., 0], mid[..., 1], mid[..., 2]
    volume = float((wz * Z).sum())
    area = -3.0 * float(wz.sum())  # three nodes per triangle
    segments = waterline(P)
    if volume <= 0.0 or area <= 1e-12 * max(volume, 1e-300) ** (2 / 3):
        return None
    B = np.array([(wz * X * Z).sum(), (wz * Y * Z).sum(), (wz * Z * Z).sum() / 2]) / volume
    F = -np.array([(wz * X).sum(), (wz * Y).sum()]) / area
    Sxx, Sxy, Syy = -(wz * X * X).sum(), -(wz * X * Y).sum(), -(wz * Y * Y).sum()
    # an inclination about a horizontal axis moves B perpendicular to it: the second moment of distance
    # from the axis is n^T J n with n that perpendicular, J the (x, y) covariance about F
    J = np.array([[Sxx, Sxy], [Sxy, Syy]]) - area * np.outer(F, F)
    moments, axes = np.linalg.eigh(J)  # ascending: n = axes[:, 0] is the direction of least resistance
    bm = moments / volume
    gm = B[2] + bm - x[2]
    M = B + np.array([0.0, 0.0, bm[0]])
    return Hydrostatics(volume, B, area, np.array([*F, 0.0]), J, axes, bm, M, gm, segments)


def waterline(P: np.ndarray, h: np.ndarray | None = None) -> np.ndarray:
    """(s, 2, 3) segments where the linear function h (vertex values (k, 3), default the height z)
    changes sign across the triangles P (k, 3, 3)."""
    h = P[:, :, 2] if h is None else h
    below = h < 0.0
    count = below.sum(axis=1)
    sel = np.flatnonzero((count == 1) | (count == 2))
    if not len(sel):
        return np.zeros((0, 2, 3))
    odd = np.where(count[sel] == 1, np.argmax(below[sel], axis=1), np.argmax(~below[sel], axis=1))
    order = (odd[:, None] + np.arange(3)) % 3
    p = np.take_along_axis(P[sel], order[:, :, None], axis=1)
    v = np.take_along_axis(h[sel], order, axis=1)
    a = p[:, 0] + (p[:, 1] - p[:, 0]) * (v[:, 0] / (v[:, 0] - v[:, 1]))[:, None]
    b = p[:, 2] + (p[:, 0] - p[:, 2]) * (v[:, 2] / (v[:, 2] - v[:, 0]))[:, None]
    return np.stack([a, b], axis=1)


def at_rest(body, fluid, R: np.ndarray | None = None) -> tuple[float, float, Hydrostatics | None]:
    """Where the body floats held at orientation R (default: as its mesh file has it) in calm water: the centre of
    mass's height, the draft (depth of its lowest point) and the hydrostatics there. ConfigError
    when it cannot float."""

    R = quat_to_matrix(body.q_input_body) if R is None else R
    z = rest_height(body, fluid, R)
    lowest = float((body.mesh_vertices @ R.T)[:, 2].min())
    return z, -(z + lowest), hydrostatics(body, np.array([0.0, 0.0, z]), R)


def describe_rest(body, fluid, R: np.ndarray | None = None) -> str:
    """One line on how a body floats: volume, mass, draft at rest and GM (with what its sign means)."""

    head = f"volume {body.volume:.4g} m^3, mass {body.mass:.4g} kg"
    if fluid.g <= 0.0:
        return f"{head}: without gravity (g = 0) it neither floats nor sinks"
    try:
        z, draft, h = at_rest(body, fluid, R)
    except ConfigError:
        return f"{head}: heavier than the water it displaces, it sinks"
    if h is None:
        return f"{head}, floats at draft {draft:.4g} m"
    if abs(h.gm[0]) < 1e-3 * body.radius:
        verdict = "neutral: a heel neither grows nor rights itself"
    else:
        verdict = "stable as given" if h.stable else "unstable as given: it rolls over to another pose"
    return f"{head}, floats at draft {draft:.4g} m with GM {h.gm[0]:+.3g} m ({verdict})"


LEAK_BAND = 0.8
"""The points model is known to keep rocking or drifting when |GM| / BM < LEAK_BAND * sqrt(h / L) (h the
sample spacing, L the waterplane's size): an empirical bound read off the accuracy report's map of the
cube over density and N (part 6), which also counts the runs it misses and the false alarms."""


def leak_margin(body, fluid, R: np.ndarray | None = None) -> float | None:
    """|GM| / BM / sqrt(h / L) of the body floating as given, h = sqrt(mean sample area), L = sqrt(waterplane
    area): below LEAK_BAND the points model's rest is unreliable. None when it does not float with a waterplane."""

    try:
        h = at_rest(body, fluid, R)[2]
    except ConfigError:
        return None
    if h is None or h.bm[0] <= 0.0:
        return None
    spacing = float(np.sqrt(np.mean(body.area)))
    return float(abs(h.gm[0]) / h.bm[0] / np.sqrt(spacing / np.sqrt(h.waterplane_area)))


def sampled_model_warning(body, fluid, R: np.ndarray | None = None) -> str | None:
    """A one-line warning when the points model runs a body in the band where it misbehaves, else None."""
    if fluid.forces != "points" or fluid.rho * fluid.g == 0.0:
        return None
    margin = leak_margin(body, fluid, R)
    if margin is None or margin >= LEAK_BAND:
        return None
    return (
        "the points model may keep this body rocking or drifting for ever: its GM is close to zero for its sample spacing "
        f"(|GM|/BM = {margin:.2f} sqrt(h/L), band < {LEAK_BAND:g}); use the cells or panels force model (the accuracy report's part 6)"
    )


def floating_potential(body, fluid, R: np.ndarray) -> float:
    """The potential energy of the body held at orientation R and floating freely in height, J, up to a
    constant: with the displaced mass equal to the body's, U = M g (z_G - z_B) (gravity's M g z_G plus
    the water's -rho g V z_B). Its minima over orientations are the stable floating orientations."""

    z = rest_height(body, fluid, R)
    h = hydrostatics(body, np.array([0.0, 0.0, z]), R)
    return body.mass * fluid.g * (z - h.buoyancy_centre[2])


def lowest_orientation(body, fluid, starts: list[np.ndarray], xatol: float = 1e-6) -> tuple[np.ndarray, float]:
    """The orientation of least `floating_potential` found by Nelder-Mead from each start (rotation
    matrices), and its potential: the static answer to "how does it float", independent of any dynamics."""
    from scipy.optimize import minimize
    from scipy.spatial.transform import Rotation

    best = (None, np.inf)
    for R0 in starts:

        def u(v, R0=R0):
            return floating_potential(body, fluid, Rotation.from_rotvec(v).as_matrix() @ R0)

        res = minimize(u, np.zeros(3), method="Nelder-Mead", options={"xatol": xatol, "fatol": 1e-12 * body.mass * fluid.g, "initial_simplex":
                                                                     0.3 * np.vstack([np.zeros(3), np.eye(3)]), "maxiter": 2000})  # fmt: skip
        if res.fun < best[1]:
            best = (Rotation.from_rotvec(res.x).as_matrix() @ R0, float(res.fun))
    return best

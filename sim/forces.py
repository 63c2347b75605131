"""Hydrostatic pressure, viscous damping and gravity on a sampled body, as pure functions of the pose.

All vectors are world frame, SI units. Torques are about the centre of mass. The wet samples of a
pose are found once (`wetted`) and every term and diagnostic reads the same arrays.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .body import Body
from .rotation import skew

FORCE_MODELS = ("points", "panels")


@dataclass(frozen=True)
class Params:
    """Fluid and field parameters; replaced whole between steps when the user changes them."""

    rho: float = 1000.0
    """Water density, kg/m^3."""
    g: float = 9.81
    """Gravitational acceleration, m/s^2."""
    damping: float = 0.0
    """Viscous damping coefficient d, N s/m^3."""
    forces: str = "points"
    """How water forces are integrated over the surface: 'points' (the samples, the report's
    model) or 'panels' (the mesh's triangles clipped at the water line, integrated exactly)."""


@dataclass(frozen=True, eq=False)
class Wetted:
    """The wet surface at one pose as elements (samples, or clipped triangles), world frame, with
    the integrals every force term and diagnostic needs. For a sample they are its value times its
    area (the midpoint rule); for a clipped triangle they are exact, since depth and velocity are
    linear over it."""

    area: np.ndarray
    """(m,) wet area of each element, m^2."""
    normal: np.ndarray
    """(m, 3) outward unit normals."""
    lever: np.ndarray
    """(m, 3) element centroid relative to the centre of mass, m."""
    z_area: np.ndarray
    """(m,) integral of z dA, m^3 (all z < 0: depth h = -z)."""
    z_lever: np.ndarray
    """(m, 3) integral of z r dA, m^4 (r relative to the centre of mass)."""
    z2_area: np.ndarray
    """(m,) integral of z^2 dA, m^4."""
    rr: np.ndarray | None
    """(3, 3) sum of the integrals of r r^T dA, m^4; only computed when damping is on."""
    index: np.ndarray
    """(m,) which of the body's samples (or mesh triangles) each element comes from."""

    @property
    def submerged_area(self) -> float:
        return float(self.area.sum())

    @property
    def submerged_volume(self) -> float:
        """Divergence theorem with the field (0, 0, z): V = integral of z nu_z dA over the wet
        surface (the water-plane cut has z = 0 and adds nothing)."""
        return float(self.z_area @ self.normal[:, 2])


EMPTY = Wetted(np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), np.zeros((0, 3)), np.zeros(0), np.zeros((3, 3)), np.zeros(0, int))


def wetted(body: Body, x: np.ndarray, R: np.ndarray, need_rr: bool = True) -> Wetted:
    """The submerged samples (z < 0) of `body` at centre of mass `x` and orientation `R`."""
    z_all = x[2] + body.r_body @ R[2]
    index = np.flatnonzero(z_all < 0.0)
    lever = body.r_body[index] @ R.T
    area, z = body.area[index], z_all[index]
    za = z * area
    return Wetted(
        area=area,
        normal=body.n_body[index] @ R.T,
        lever=lever,
        z_area=za,
        z_lever=za[:, None] * lever,
        z2_area=za * z,
        rr=(lever * area[:, None]).T @ lever if need_rr else None,
        index=index,
    )


def _edge_point(a: np.ndarray, b: np.ndarray, za: np.ndarray, zb: np.ndarray) -> np.ndarray:
    """Where the edge a->b crosses z = 0 (rows; za and zb of opposite signs)."""
    return a + (b - a) * (za / (za - zb))[:, None]


def wetted_panels(body: Body, x: np.ndarray, R: np.ndarray, need_rr: bool = True) -> Wetted:
    """The mesh's triangles clipped at z = 0, with their exact wet integrals.

    A triangle with one vertex under water keeps a triangle, one with two keeps a quadrilateral
    (split in two); rolling the vertices to put the odd one first keeps the winding, hence the
    outward normal. Over a triangle, for linear f and g: integral f g dA = A/12 (sum f_i g_i + sum f_i sum g_i).
    """
    lever_v = body.mesh_vertices @ R.T
    z_v = x[2] + lever_v[:, 2]
    faces = body.mesh_faces
    zf = z_v[faces]
    below = zf < 0.0
    count = below.sum(axis=1)
    tris, owners = [], []
    whole = np.flatnonzero(count == 3)
    tris.append(lever_v[faces[whole]])
    owners.append(whole)
    for n_below in (1, 2):
        sel = np.flatnonzero(count == n_below)
        if not len(sel):
            continue
        # put the odd vertex (the one under water for n=1, above it for n=2) first
        first = np.argmax(below[sel] if n_below == 1 else ~below[sel], axis=1)
        order = (first[:, None] + np.arange(3)) % 3
        v = np.take_along_axis(faces[sel], order, axis=1)
        p0, p1, p2 = lever_v[v[:, 0]], lever_v[v[:, 1]], lever_v[v[:, 2]]
        z0, z1, z2 = z_v[v[:, 0]], z_v[v[:, 1]], z_v[v[:, 2]]
        e01, e20 = _edge_point(p0, p1, z0, z1), _edge_point(p2, p0, z2, z0)
        if n_below == 1:
            tris.append(np.stack([p0, e01, e20], axis=1))
            owners.append(sel)
        else:  # quadrilateral e01 -> p1 -> p2 -> e20
            tris += [np.stack([e01, p1, p2], axis=1), np.stack([e01, p2, e20], axis=1)]
            owners += [sel, sel]
    P = np.concatenate(tris)
    index = np.concatenate(owners)
    if not len(P):
        return EMPTY
    Z = x[2] + P[:, :, 2]
    np.minimum(Z, 0.0, out=Z)  # edge points are exactly on the water line
    normal = body.face_normals[index] @ R.T
    area = 0.5 * np.einsum("ki,ki->k", np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), normal)
    sz, sr = Z.sum(axis=1), P.sum(axis=1)
    w = area / 12.0
    rr = None
    if need_rr:
        rr = np.einsum("k,kvi,kvj->ij", w, P, P) + np.einsum("k,ki,kj->ij", w, sr, sr)
    return Wetted(
        area=area,
        normal=normal,
        lever=sr / 3.0,
        z_area=area * sz / 3.0,
        z_lever=w[:, None] * (np.einsum("kv,kvi->ki", Z, P) + sz[:, None] * sr),
        z2_area=w * (np.einsum("kv,kv->k", Z, Z) + sz * sz),
        rr=rr,
        index=index,
    )


def pressure(params: Params, wet: Wetted) -> tuple[np.ndarray, np.ndarray]:
    """Hydrostatic force: the integral of -rho g h nu dA = rho g z nu dA, and its torque."""
    rg = params.rho * params.g
    force = rg * (wet.z_area @ wet.normal)
    torque = rg * np.cross(wet.z_lever, wet.normal).sum(axis=0)
    return force, torque


def damping_matrix(params: Params, wet: Wetted) -> np.ndarray:
    """6x6 symmetric positive semi-definite D with (F, T) = -D (u, omega) for the damping term.

    The force is -d times the integral of v = u + omega x r over the wet surface, so
    F = -d (A u + omega x S) and T = -d (S x u + J omega), with S = integral of r dA and
    J = integral of (|r|^2 Id - r r^T) dA. Linear in (u, omega) at a fixed pose: the implicit
    scheme's handle.
    """
    S = wet.area @ wet.lever
    D = np.empty((6, 6))
    D[:3, :3] = wet.area.sum() * np.eye(3)
    D[:3, 3:] = -skew(S)
    D[3:, :3] = skew(S)
    D[3:, 3:] = np.trace(wet.rr) * np.eye(3) - wet.rr
    return params.damping * D


def damping(params: Params, wet: Wetted, u: np.ndarray, omega: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Viscous force: the integral of -d v dA over the wet surface, and its torque."""
    loads = -damping_matrix(params, wet) @ np.concatenate([u, omega])
    return loads[:3], loads[3:]


def gravity(body: Body, params: Params) -> np.ndarray:
    """-M g z_hat at the centre of mass (no torque)."""
    return np.array([0.0, 0.0, -body.mass * params.g])


def hydrostatic_energy(params: Params, wet: Wetted) -> float:
    """U_b = rho g * integral over the submerged volume of (-z) dV = -(rho g / 2) * integral of z^2 nu_z dA."""
    return float(-0.5 * params.rho * params.g * (wet.z2_area @ wet.normal[:, 2]))


class Model:
    """A body with its parameters: the scene's force terms, and only those (no damping when d = 0).

    Caches the wet samples of the last pose asked for, so an integrator step that ends where the
    next begins, and the frame read in between, find the samples once.
    """

    def __init__(self, body: Body, params: Params):
        self.body = body
        self.params = params
        self.has_gravity = params.g != 0.0
        self.has_pressure = params.rho * params.g != 0.0
        self.has_damping = params.damping != 0.0 and params.rho != 0.0
        self.needs_wet = self.has_pressure or self.has_damping
        self._weight = gravity(body, params)
        self._cache_key: bytes | None = None
        self._cache: Wetted | None = None
        self._wetted = wetted_panels if params.forces == "panels" else wetted

    @property
    def terms(self) -> tuple[str, ...]:
        names = ("gravity", self.has_gravity), ("pressure", self.has_pressure), ("damping", self.has_damping)
        return tuple(n for n, on in names if on)

    def wetted(self, x: np.ndarray, R: np.ndarray) -> Wetted:
        if not self.needs_wet:
            return EMPTY
        key = x.tobytes() + R.tobytes()
        if key != self._cache_key:
            self._cache, self._cache_key = self._wetted(self.body, x, R, self.has_damping), key
        return self._cache

    def conservative(self, wet: Wetted) -> tuple[np.ndarray, np.ndarray]:
        """Gravity plus pressure: the forces that depend on the pose only."""
        force, torque = self._weight.copy(), np.zeros(3)
        if self.has_pressure and len(wet.area):
            fp, tp = pressure(self.params, wet)
            force += fp
            torque += tp
        return force, torque

    def damping_matrix(self, wet: Wetted) -> np.ndarray | None:
        if not self.has_damping or not len(wet.area):
            return None
        return damping_matrix(self.params, wet)

    def loads(self, wet: Wetted, u: np.ndarray, omega: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Total force and torque on the body for a pose's wet samples and a twist (u, omega)."""
        force, torque = self.conservative(wet)
        if self.has_damping and len(wet.area):
            fd, td = damping(self.params, wet, u, omega)
            force += fd
            torque += td
        return force, torque

"""Hydrostatic pressure, viscous damping and gravity on a sampled body, as pure functions of the pose.

All vectors are world frame, SI units. Torques are about the centre of mass. The wet samples of a
pose are found once (`wetted`) and every term and diagnostic reads the same arrays.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .body import Body
from .rotation import skew


@dataclass(frozen=True)
class Params:
    """Fluid and field parameters; replaced whole between steps when the user changes them."""

    rho: float = 1000.0
    """Water density, kg/m^3."""
    g: float = 9.81
    """Gravitational acceleration, m/s^2."""
    damping: float = 0.0
    """Viscous damping coefficient d, N s/m^3."""


@dataclass(frozen=True, eq=False)
class Wetted:
    """World-frame geometry of the submerged samples (z < 0) at one pose."""

    lever: np.ndarray
    """(m, 3) R r_k: sample position relative to the centre of mass, world frame, m."""
    normal: np.ndarray
    """(m, 3) outward unit normals, world frame."""
    z: np.ndarray
    """(m,) sample heights, m (all negative: depth h_k = -z_k)."""
    area: np.ndarray
    """(m,) sample areas, m^2."""
    index: np.ndarray
    """(m,) indices of these samples in the body's arrays."""

    @property
    def submerged_area(self) -> float:
        return float(self.area.sum())

    @property
    def submerged_volume(self) -> float:
        """Divergence theorem with the field (0, 0, z): V = sum z nu_z a over the wet surface
        (the water-plane cut has z = 0 and adds nothing)."""
        return float(self.area @ (self.z * self.normal[:, 2]))


def wetted(body: Body, x: np.ndarray, R: np.ndarray) -> Wetted:
    """The submerged samples of `body` at centre of mass `x` and orientation `R`."""
    z_all = x[2] + body.r_body @ R[2]
    index = np.flatnonzero(z_all < 0.0)
    return Wetted(
        lever=body.r_body[index] @ R.T,
        normal=body.n_body[index] @ R.T,
        z=z_all[index],
        area=body.area[index],
        index=index,
    )


def pressure(params: Params, wet: Wetted) -> tuple[np.ndarray, np.ndarray]:
    """Hydrostatic force -rho g h_k a_k nu_k summed over wet samples, and its torque."""
    c = (params.rho * params.g) * (wet.z * wet.area)  # = -rho g h a
    force = c @ wet.normal
    torque = c @ np.cross(wet.lever, wet.normal)
    return force, torque


def damping_matrix(params: Params, wet: Wetted) -> np.ndarray:
    """6x6 symmetric positive semi-definite D with (F, T) = -D (u, omega) for the damping term.

    Sum over wet k of d a_k G_k^T G_k with G_k = [Id, -[R r_k]x], so -d a_k (u + w x R r_k) summed
    gives the force and the torque. Linear in (u, w) for a fixed pose: the implicit scheme's handle.
    """
    a, rho_w = wet.area, wet.lever
    S = a @ rho_w
    J = (a @ np.einsum("ki,ki->k", rho_w, rho_w)) * np.eye(3) - (rho_w * a[:, None]).T @ rho_w
    D = np.empty((6, 6))
    D[:3, :3] = a.sum() * np.eye(3)
    D[:3, 3:] = -skew(S)
    D[3:, :3] = skew(S)
    D[3:, 3:] = J
    return params.damping * D


def damping(params: Params, wet: Wetted, u: np.ndarray, omega: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Viscous force -d a_k v_k on wet samples, with v_k = u + omega x (R r_k), and its torque."""
    f = -params.damping * wet.area[:, None] * (u + np.cross(omega, wet.lever))
    return f.sum(axis=0), np.cross(wet.lever, f).sum(axis=0)


def gravity(body: Body, params: Params) -> np.ndarray:
    """-M g z_hat at the centre of mass (no torque)."""
    return np.array([0.0, 0.0, -body.mass * params.g])


def hydrostatic_energy(params: Params, wet: Wetted) -> float:
    """U_b = rho g * integral over the submerged volume of (-z) dV = -(rho g / 2) sum z^2 nu_z a."""
    return float(-0.5 * params.rho * params.g * (wet.area @ (wet.z**2 * wet.normal[:, 2])))


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
        self._empty = Wetted(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), np.zeros(0), np.zeros(0, dtype=int))

    @property
    def terms(self) -> tuple[str, ...]:
        names = ("gravity", self.has_gravity), ("pressure", self.has_pressure), ("damping", self.has_damping)
        return tuple(n for n, on in names if on)

    def wetted(self, x: np.ndarray, R: np.ndarray) -> Wetted:
        if not self.needs_wet:
            return self._empty
        key = x.tobytes() + R.tobytes()
        if key != self._cache_key:
            self._cache, self._cache_key = wetted(self.body, x, R), key
        return self._cache

    def conservative(self, wet: Wetted) -> tuple[np.ndarray, np.ndarray]:
        """Gravity plus pressure: the forces that depend on the pose only."""
        force, torque = self._weight.copy(), np.zeros(3)
        if self.has_pressure and len(wet.z):
            fp, tp = pressure(self.params, wet)
            force += fp
            torque += tp
        return force, torque

    def damping_matrix(self, wet: Wetted) -> np.ndarray | None:
        if not self.has_damping or not len(wet.z):
            return None
        return damping_matrix(self.params, wet)

    def loads(self, wet: Wetted, u: np.ndarray, omega: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Total force and torque on the body for a pose's wet samples and a twist (u, omega)."""
        force, torque = self.conservative(wet)
        if self.has_damping and len(wet.z):
            fd, td = damping(self.params, wet, u, omega)
            force += fd
            torque += td
        return force, torque

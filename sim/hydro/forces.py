"""Force terms and their registry: one function per physical term, each declaring its parameters.

A term is `(body, water, fluid, wet, twist, t) -> Load`: the force and the torque about the centre
of mass in the world frame, for the wet surface of one pose (`surface.WetSurface`), a twist
(u, omega) stacked as (6,) and a time. A term that depends on the twist also gives its Jacobian:
D = -d(load)/d(twist), 6x6, and affine = load + D twist, so load(v) ~ affine - D v near the twist.
The implicit scheme solves that linear model exactly over each half step (stable for any
coefficient); the other schemes just evaluate the term.

Adding a term: its function here, its line in TERMS (with its Param declarations), and its compiled
twin in kernels/forces.py. Config, CLI flags, viewer controls and clamps read the declarations.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from sim.bodies.rotation import skew
from sim.bodies.surface import DUNAVANT4, DUNAVANT4_WEIGHTS, WET_SURFACE, WetSurface, clip_triangles, empty_surface, triangle_areas
from sim.parameters import Param


class Load(NamedTuple):
    force: np.ndarray
    """(3,) N, world frame."""
    torque: np.ndarray
    """(3,) N m about the centre of mass, world frame."""
    D: np.ndarray | None = None
    """(6, 6) -d(force, torque)/d(u, omega) for terms that depend on the twist, else None."""
    affine: np.ndarray | None = None
    """(6,) (force, torque) + D (u, omega): the load of the linearised term at zero twist."""


def _relative_velocity(wet: WetSurface, twist: np.ndarray) -> np.ndarray:
    """(m, 3) velocity of each node relative to the water, m/s."""
    return twist[:3] + np.cross(twist[3:], wet.lever) - wet.flow


def _wrench(wet: WetSurface, f: np.ndarray) -> np.ndarray:
    """(6,) total force and torque about the centre of mass of node forces f (m, 3)."""
    m = wet.lever.T @ f  # m[i, j] = sum of r_i f_j: the torque is its antisymmetric part
    return np.array([*f.sum(axis=0), m[1, 2] - m[2, 1], m[2, 0] - m[0, 2], m[0, 1] - m[1, 0]])


def gravity(body, water, fluid, wet, twist, t) -> Load:
    """-M g z_hat at the centre of mass (no torque)."""
    return Load(np.array([0.0, 0.0, -body.mass * water.g]), np.zeros(3))


def pressure(body, water, fluid, wet, twist, t) -> Load:
    """The water's pressure on the wet surface: the integral of -p nu dA, and its torque."""
    f = -(wet.weight * wet.pressure)[:, None] * wet.normal
    w = _wrench(wet, f)
    return Load(w[:3], w[3:])


DAMPING = Param("fluid", "damping", 0.0, "Viscous damping coefficient d: a wet element feels -d a v_rel", "N s/m^3",
                lo=0.0, hi=1.0e7, label="Damping", gui=(0.0, 5000.0, 1.0))  # fmt: skip


def damping_matrix(fluid, wet: WetSurface) -> np.ndarray:
    """6x6 symmetric positive semi-definite D with (F, T) = -D (u, omega) in still water.

    The force is -d times the integral of v = u + omega x r over the wet surface, so
    F = -d (A u + omega x S) and T = -d (S x u + J omega), with S = integral of r dA and
    J = integral of (|r|^2 Id - r r^T) dA."""
    S, rr = wet.first_moment, wet.second_moment
    D = np.empty((6, 6))
    D[:3, :3] = wet.submerged_area * np.eye(3)
    D[:3, 3:] = -skew(S)
    D[3:, :3] = skew(S)
    D[3:, 3:] = np.trace(rr) * np.eye(3) - rr
    return fluid.damping * D


def damping(body, water, fluid, wet, twist, t) -> Load:
    """Linear viscous damping: the integral of -d v_rel dA, linear in the twist."""
    D = damping_matrix(fluid, wet)
    affine = np.zeros(6) if water.at_rest else _wrench(wet, fluid.damping * wet.weight[:, None] * wet.flow)
    load = affine - D @ twist
    return Load(load[:3], load[3:], D, affine)


DRAG_COEFFICIENT = Param("fluid", "drag_coefficient", 0.0, "Quadratic (pressure) drag coefficient C_d: a wet element moving into the "
                         "water feels -(1/2) rho C_d a (v_rel . n)^2 n", lo=0.0, hi=100.0, label="Drag C_d", gui=(0.0, 5.0, 0.05))  # fmt: skip


def _advancing_nodes(water, wet: WetSurface, twist: np.ndarray, t: float) -> WetSurface:
    """Nodes of the part of the wet surface that moves into the water (v_rel . n > 0).

    Points: the wet samples doing so. Panels: each wet triangle clipped again where v_rel . n
    changes sign, with a degree-4 rule; v_rel is taken linear across the triangle (exact for a rigid
    body in still water; in waves the water's velocity is interpolated from the triangle's vertices,
    like the wave surface above it)."""
    if wet.triangles is None:
        return wet
    if not len(wet.triangles):
        return empty_surface(wet.x)
    n = wet.triangle_normal
    flow = water.velocity(wet.x + wet.triangles, t)
    vn = np.einsum("kvi,ki->kv", twist[:3] + np.cross(twist[3:], wet.triangles) - flow, n)
    T, owner = clip_triangles(np.concatenate([wet.triangles, flow], axis=2), -vn)
    area = triangle_areas(T[..., :3], n[owner])
    nodes = np.einsum("qv,kvi->kqi", DUNAVANT4, T).reshape(-1, 6)
    weight = (area[:, None] * DUNAVANT4_WEIGHTS).ravel()
    lever = nodes[:, :3]
    return WetSurface(wet.x, wet.x + lever, lever, weight, np.repeat(n[owner], 6, axis=0), np.repeat(owner, 6), water=water, t=t,
                      given_flow=nodes[:, 3:])  # fmt: skip


def drag(body, water, fluid, wet, twist, t) -> Load:
    """Quadratic drag: -(1/2) rho C_d (v_rel . n)^2 n per unit area where v_rel . n > 0, zero elsewhere."""
    nodes = _advancing_nodes(water, wet, twist, t)
    vn = np.einsum("ki,ki->k", _relative_velocity(nodes, twist), nodes.normal)
    c = water.rho * fluid.drag_coefficient * nodes.weight * np.maximum(vn, 0.0)  # d|f|/d(v.n) per node
    f = (-0.5 * c * vn)[:, None] * nodes.normal
    load = _wrench(nodes, f)
    g = np.hstack([nodes.normal, np.cross(nodes.lever, nodes.normal)])  # d(v.n)/d(u, omega)
    D = (g * c[:, None]).T @ g
    return Load(load[:3], load[3:], D, load + D @ twist)


@dataclass(frozen=True)
class Term:
    name: str
    function: Callable[..., Load]
    params: tuple[Param, ...] = ()
    """Its parameters (in the [fluid] table): the scene schema, flags and controls come from these."""
    twist: bool = False
    """Whether it depends on the twist (then it gives D and affine)."""
    linear: bool = True
    """Whether its load is affine in the twist (its linearisation is exact, the implicit scheme need not iterate)."""
    used: Callable[[Any], bool] | None = None
    """Whether a scene's fluid section uses it; default: water present and every parameter nonzero."""

    def is_used(self, fluid) -> bool:
        if self.used is not None:
            return self.used(fluid)
        return fluid.rho != 0.0 and all(getattr(fluid, p.key) != 0 for p in self.params)


HEAVE_DAMPING = Param("fluid", "heave_damping", 0.0, "Linear heave damping B_33: the body feels -B_33 w (w its vertical velocity) while "
                      "wet, as the heave entry of a linear damping matrix (WEC-Sim's linearDamping)", "N s/m", lo=0.0, hi=1.0e9,
                      label="Heave damping", gui=(0.0, 1.0e5, 100.0))  # fmt: skip


def heave_damping(body, water, fluid, wet, twist, t) -> Load:
    """-B_33 w on the centre of mass (no torque): the heave entry of a linear damping matrix, on the body's own vertical
    velocity (as WEC-Sim's body linearDamping, not relative to the water); D = B_33 at (2, 2), the affine part zero."""
    D = np.zeros((6, 6))
    D[2, 2] = fluid.heave_damping
    return Load(np.array([0.0, 0.0, -fluid.heave_damping * twist[2]]), np.zeros(3), D, np.zeros(6))


TERMS: tuple[Term, ...] = (
    Term("gravity", gravity, used=lambda f: f.g != 0.0),
    Term("pressure", pressure, used=lambda f: f.rho * f.g != 0.0),
    Term("damping", damping, (DAMPING,), twist=True),
    Term("drag", drag, (DRAG_COEFFICIENT,), twist=True, linear=False),
    Term("heave_damping", heave_damping, (HEAVE_DAMPING,), twist=True, used=lambda f: f.heave_damping != 0.0),
)
"""Every force term, in the order the compiled kernels number them (bit i of their `terms` mask)."""


class Model:
    """A body in water with the scene's force terms, and only those a scene uses.

    Caches the wet surface of the last pose asked for, so an integrator step that ends where the
    next begins, and the frame read in between, find it once."""

    def __init__(self, body, water, fluid, radiation=None, held: bool = False):
        self.body, self.water, self.fluid = body, water, fluid
        self.radiation = radiation
        """radiation.Radiation (added mass and memory about the rest pose), or None."""
        self.held = np.zeros(6) if held else None
        """(6,) a load another model gives the body (the mooring lines, lines/moorings.py), held over each step:
        force and moment about the centre of mass, world frame, N and N m. Its owner writes it between steps. None: none."""
        self.terms = tuple(term for term in TERMS if term.is_used(fluid))
        self.pose_terms = tuple(term for term in self.terms if not term.twist)
        self.twist_terms = tuple(term for term in self.terms if term.twist)
        self.needs_wet = any(term.name != "gravity" for term in self.terms)
        self.linear_in_twist = all(term.linear for term in self.twist_terms)
        self._wet_surface = WET_SURFACE[fluid.forces]
        self._cache_key: tuple | None = None
        self._cache: WetSurface | None = None

    @property
    def term_names(self) -> tuple[str, ...]:
        """The names of the terms in use, in the registry's order."""
        return tuple(term.name for term in self.terms)

    def has(self, name: str) -> bool:
        """Whether the term `name` is in use."""
        return any(term.name == name for term in self.terms)

    def wetted(self, x: np.ndarray, R: np.ndarray, t: float = 0.0) -> WetSurface:
        """The wet part of the surface at a pose (x: centre of mass, R: body to world) and time, which the terms integrate over
        (the last one is kept: several terms ask for the same)."""
        if not self.needs_wet:
            return empty_surface(x)
        key = (x.tobytes(), R.tobytes(), t if not self.water.flat else 0.0)
        if key != self._cache_key:
            self._cache, self._cache_key = self._wet_surface(self.body, self.water, x, R, t), key
        return self._cache

    def _sum(self, terms, wet, twist, t) -> tuple[np.ndarray, np.ndarray]:
        force, torque = np.zeros(3), np.zeros(3)
        for term in terms:
            load = term.function(self.body, self.water, self.fluid, wet, twist, t)
            force += load.force
            torque += load.torque
        return force, torque

    def pose_loads(self, wet: WetSurface, t: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Force and torque of the terms that depend on the pose only (gravity, pressure), and the held load."""
        force, torque = self._sum(self.pose_terms, wet, None, t)
        if self.held is not None:
            force, torque = force + self.held[:3], torque + self.held[3:]
        return force, torque

    def twist_loads(self, wet: WetSurface, twist: np.ndarray, t: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Force and torque of the terms that depend on the twist (damping, drag)."""
        if not len(wet.weight):
            return np.zeros(3), np.zeros(3)
        return self._sum(self.twist_terms, wet, twist, t)

    def loads(self, wet: WetSurface, u: np.ndarray, omega: np.ndarray, t: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Total force and torque for a pose's wet surface and a twist (u, omega)."""
        force, torque = self.pose_loads(wet, t)
        fv, tv = self.twist_loads(wet, np.concatenate([u, omega]), t)
        return force + fv, torque + tv

    def linearised(
        self, wet: WetSurface, twist: np.ndarray, t: float = 0.0, pose: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """(f, D): the loads near `twist` as f - D (u, omega), f (6,), D (6, 6) or None (no twist terms
        wet). `pose`: the pose loads (6,) when already known (they do not depend on the twist)."""
        f = np.concatenate(self.pose_loads(wet, t)) if pose is None else pose
        if not self.twist_terms or not len(wet.weight):
            return f, None
        D = np.zeros((6, 6))
        for term in self.twist_terms:
            load = term.function(self.body, self.water, self.fluid, wet, twist, t)
            D += load.D
            f = f + load.affine
        return f, D

    def damping_matrix(self, wet: WetSurface) -> np.ndarray | None:
        """The linear damping term's D (None when the scene has no damping or nothing is wet)."""
        if not self.has("damping") or not len(wet.weight):
            return None
        return damping_matrix(self.fluid, wet)

    def hydrostatic_energy(self, wet: WetSurface) -> float:
        """The potential of the pressure over this wet surface, J (0 without the pressure term)."""
        return hydrostatic_energy(self.water, wet) if self.has("pressure") else 0.0


def hydrostatic_energy(water, wet: WetSurface) -> float:
    """U_b = rho g * integral over the submerged volume of (-z) dV = -(rho g / 2) * integral of z^2 nu_z dA (still water)."""
    z = wet.point[:, 2]
    return float(-0.5 * water.rho * water.g * (wet.weight * z * z) @ wet.normal[:, 2])


def compiled_model(model: Model) -> bool:
    """Whether the compiled twin (sim.kernels) has the model's force model for its water (cells: still water only)."""
    return model.fluid.forces != "cells" or model.water.flat

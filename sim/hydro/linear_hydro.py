"""Linear hydrostatics and Froude-Krylov force about the rest pose: WEC-Sim's default hydrodynamics, for bodies on joints.

`[fluid] hydro = "linear"`. About each body's starting pose (x0, R0), with xi = (x - x0, phi), phi the rotation
vector of R R0^T (world axes), a body's loads near the twist nu are

    f(x, R, t) = f0 - C xi + r(t) Re sum_i X_i e^(i (k_i . (x - x0) - omega_i t)),   D = D0,

- f0: its pose loads (gravity and the water's pressure over the wet surface, the force model's own) at rest in
  still water; C = -df/dxi there, by central differences of the same loads (the stiffness the frequency-domain
  check uses, system/frequency.py);
- X_i: the Froude-Krylov force of wave component i (a_i, omega_i, k_i, heading beta_i, phase phi_i): the
  undisturbed wave's linear pressure rho g a_i E_i(z) e^(i (k_i (x cos beta_i + y sin beta_i) + phi_i)) integrated
  over the wet surface at rest (E_i = cosh(k_i (z + h)) / cosh(k_i h), deep water e^(k_i z)), omega_i met
  with the current; phased where the body's centre of mass is now (k_i . (x - x0) over its horizontal offset from
  rest, as the diffraction force is), and r(t) the sea's ramp (water.ramp_factor);
- D0: the linear damping term at rest in still water (on the body's own velocity, as WEC-Sim's linear damping).
Radiation and diffraction come from the bodies' BEM solve as in the nonlinear mode. Per step this costs a 6 x 6
product and a sum over the components, not a clip of the mesh at the surface: a 64-component sea on RM3 runs
about 40 times faster than with the exact wet surface.

Valid where linear theory is: motions and waves small against the body's draft and the wavelength (the wet
surface stays the one at rest; no change of waterplane, no slamming, no parametric roll). Quadratic drag needs the
instantaneous wet surface: a linear scene refuses it. Energies: E_hyd is the linear model's potential about rest.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from sim.bodies.rotation import matrix_to_quat, quat_to_matrix, rotation_quat
from sim.bodies.surface import wet_panels
from sim.hydro.forces import Model, hydrostatic_energy
from sim.water.seas import StillWater, ramp_factor

STEP = 1e-4
"""Central differences' step: this times the body's radius (m), and in rad: the clipped loads are smooth there."""


def rotation_vector(R: np.ndarray) -> np.ndarray:
    """phi with R = exp(skew(phi)), |phi| <= pi: from R's trace and antisymmetric part (a few microseconds); near a
    half turn, where those lose the axis, through the quaternion."""
    c = 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0)
    if c < -0.9:
        q = matrix_to_quat(R)
        w, v = (q[0], q[1:]) if q[0] >= 0 else (-q[0], -q[1:])
        s = float(np.linalg.norm(v))
        return v * (2.0 * math.atan2(s, w) / s)
    v = 0.5 * np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])  # sin(angle) x the axis
    s = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    return v * (math.atan2(s, c) / s if s > 1e-12 else 1.0)


def moved(x0: np.ndarray, R0: np.ndarray, xi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The pose xi away from (x0, R0): translated by xi[:3], turned by the world rotation vector xi[3:]."""
    return x0 + xi[:3], quat_to_matrix(rotation_quat(xi[3:])) @ R0


class LinearLoads:
    """One body's linear loads, with the interface of body_loads.BodyLoads: (f, D) near a twist."""

    linear = True
    has_twin = True
    """Nothing to compile: a product and a sum per step (the system's `has_twin` stays its other bodies')."""
    spec = None
    compiled = False

    def __init__(self, model: Model, x0: np.ndarray, R0: np.ndarray):
        water = model.water
        self.model = model
        self.x0, self.R0 = np.array(x0, float), np.array(R0, float)
        still = Model(model.body, StillWater(water.rho, water.g), model.fluid)
        wet = still.wetted(self.x0, self.R0, 0.0)
        f0, D0 = still.linearised(wet, np.zeros(6))
        self.f0 = np.asarray(f0, float)
        """(6,) the pose loads at rest in still water (with gravity), world frame, about the centre of mass."""
        self.D0 = None if D0 is None else np.asarray(D0, float)
        self.C = self._stiffness(still)
        """(6, 6) -df/dxi at rest."""
        self.X, self.omega = self._froude_krylov(model)
        self.k = np.zeros((0, 2)) if water.flat else np.column_stack([water.k * np.cos(water.direction), water.k * np.sin(water.direction)])
        """(n, 2) each component's wave vector, rad/m."""
        self._excited: tuple = (None, None)
        self.E_hyd0 = hydrostatic_energy(still.water, wet_panels(model.body, still.water, self.x0, self.R0, 0.0))

    def _stiffness(self, still: Model) -> np.ndarray:
        radius = self.model.body.radius
        columns = []
        for j in range(6):
            h = STEP * (radius if j < 3 else 1.0)
            e = np.zeros(6)
            e[j] = h
            ahead, behind = (np.concatenate(still.pose_loads(still.wetted(*moved(self.x0, self.R0, s * e), 0.0))) for s in (1, -1))
            columns.append(-(ahead - behind) / (2 * h))
        return np.column_stack(columns)

    def _froude_krylov(self, model: Model) -> tuple[np.ndarray, np.ndarray]:
        """(n, 6) complex X_i per component and (n,) omega_i as met: none in still water."""
        water = model.water
        if water.flat:
            return np.zeros((0, 6), complex), np.zeros(0)
        calm = replace(water, amplitude=np.zeros_like(water.amplitude))  # the surface at z = 0, the force model's wave nodes
        wet = Model(model.body, calm, model.fluid).wetted(self.x0, self.R0, 0.0)
        pressure = water.pressure_amplitudes(wet.point)  # (m, n): each component at each node
        area = wet.weight[:, None] * wet.normal
        X = -np.concatenate([area.T @ pressure, (wet.weight[:, None] * np.cross(wet.lever, wet.normal)).T @ pressure]).T
        return X, water.omega_met

    def xi(self, x: np.ndarray, R: np.ndarray) -> np.ndarray:
        return np.concatenate([x - self.x0, rotation_vector(R @ self.R0.T)])

    def excitation(self, t: float, x: np.ndarray) -> np.ndarray:
        """(6,) the Froude-Krylov force and moment at time t with the centre of mass at x, world frame (the last kept: a
        step's last kick and the next one's first ask at the same time and place)."""
        key = (t, x[0], x[1])
        if self._excited[0] != key:
            if len(self.omega):
                psi = self.k @ (x[:2] - self.x0[:2]) - self.omega * t
                self._excited = (key, ramp_factor(t, self.model.water.ramp) * (np.exp(1j * psi) @ self.X).real)
            else:
                self._excited = (key, np.zeros(6))
        return self._excited[1]

    def __call__(self, x: np.ndarray, R: np.ndarray, t: float, nu: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        return self.f0 - self.C @ self.xi(x, R) + self.excitation(t, x), self.D0

    def use_kernels(self, on: bool, expand: bool = True) -> None:
        """Nothing to compile."""

    def energy(self, x: np.ndarray, R: np.ndarray) -> float:
        """The water's part of the linear model's potential at (x, R): E_hyd at rest, minus the work of f0's buoyancy part
        (f0 less the weight, whose work is E_grav's), plus (1/2) xi^T C xi (C's symmetric part)."""
        xi = self.xi(x, R)
        buoyancy = self.f0.copy()
        buoyancy[2] += self.model.body.mass * self.model.water.g
        return float(self.E_hyd0 - buoyancy @ xi + 0.5 * xi @ (0.5 * (self.C + self.C.T)) @ xi)

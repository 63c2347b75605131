"""Several bodies in the frequency domain: the linear response the time-domain runs are checked against.

About the rest state s0 (each body at its starting pose, at rest), in regular waves of unit amplitude,
frequency omega (one of the BEM solve's) and heading beta, the generalised motion q = Re{xi e^(-i omega t)}:

    [-omega^2 (M_q + J^T A(omega) J) - i omega (J^T (B(omega) + D) J + C) + K] xi = J^T (X_FK + X_d),

J (6k x d) the bodies' twists per unit generalised velocity, A and B the 6k x 6k added mass and radiation
damping of the joint solve, X_FK and X_d its Froude-Krylov and diffraction forces, D the terms' linear damping
at rest, C the take-offs' dampers, K the stiffness of the time-domain model itself: minus the derivative of
its generalised pose loads (gravity, the exact clipped pressure, the take-offs' springs) in still water, by
central differences. The same coefficients and excitation the run uses, so the comparison tests the time
stepping, the memory fit and the coupling, not the BEM.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from sim.hydro.forces import Model
from sim.water.seas import StillWater

if TYPE_CHECKING:  # the tree steps in time and asks this module for its linear response: types only here
    from sim.system.tree import System, SystemState


def pose_load(system: System, s: SystemState, still: list[Model]) -> np.ndarray:
    """(d,) the generalised pose loads at rest in still water (models `still`), with the take-offs' springs."""
    pose = system.pose(s)
    Q = np.zeros(system.n_dofs)
    for m, x, R, J in zip(still, pose.x, pose.R, pose.J):
        Q += J.T @ np.concatenate(m.pose_loads(m.wetted(x, R, 0.0)))
    for g in system.joints:
        Q[g.dofs.start] -= g.stiffness * s.theta[g.coordinate]
    return Q


def stiffness(system: System, s0: SystemState, step: float = 1e-4) -> np.ndarray:
    """(d, d) K = -dQ/dq at s0 (central differences along each generalised coordinate)."""
    water = StillWater(system.water.rho, system.water.g)
    still = [Model(m.body, water, m.model.fluid) for m in system.members]
    columns = []
    for e in np.eye(system.n_dofs):
        ahead, behind = system.drifted(s0, step, e), system.drifted(s0, -step, e)
        columns.append(-(pose_load(system, ahead, still) - pose_load(system, behind, still)) / (2 * step))
    return np.column_stack(columns)


def damping_at_rest(system: System, pose) -> np.ndarray:
    """(d, d) the terms' linear damping at rest in still water and the take-offs' dampers, generalised."""
    D = np.zeros((system.n_dofs, system.n_dofs))
    for m, x, R, Jb in zip(system.members, pose.x, pose.R, pose.J):
        Dm = Model(m.body, StillWater(system.water.rho, system.water.g), m.model.fluid)
        _, lin = Dm.linearised(Dm.wetted(x, R, 0.0), np.zeros(6))
        if lin is not None:
            D += Jb.T @ lin @ Jb
    for g in system.joints:
        D[g.dofs.start, g.dofs.start] += g.damping
    return D


def response(system: System, s0: SystemState, i: int, heading: int = 0, diffraction: bool = True, froude_krylov=None) -> np.ndarray:
    """(d,) complex xi per unit wave amplitude at the solve's frequency i and heading index `heading`; `froude_krylov`:
    (6k,) complex, the bodies' Froude-Krylov force per unit amplitude to use instead of the solve's (a linear run's own)."""
    c = system.radiation.coefficients
    w = float(c.omega[i])
    pose = system.pose(s0)
    J = np.vstack(pose.J)
    M = system.mass_matrix(pose) + J.T @ c.added_mass[i] @ J
    D = J.T @ c.damping[i] @ J + damping_at_rest(system, pose)
    X_FK = c.froude_krylov[i, heading] if froude_krylov is None else froude_krylov
    X = J.T @ (X_FK + (c.diffraction[i, heading] if diffraction else 0.0))
    return np.linalg.solve(-(w**2) * M - 1j * w * D + stiffness(system, s0), X)


def raos(system: System, s0: SystemState) -> np.ndarray:
    """(n, m, 6k) complex: each body's motion (its twist's integral, about its centre of mass, world axes) per unit wave
    amplitude at every frequency and heading of the solve: `response` at all of them, the stiffness taken once."""
    c = system.radiation.coefficients
    pose = system.pose(s0)
    J = np.vstack(pose.J)
    M, D, K = system.mass_matrix(pose), damping_at_rest(system, pose), stiffness(system, s0)
    out = np.zeros((len(c.omega), len(c.headings), J.shape[0]), complex)
    for i, w in enumerate(np.asarray(c.omega, float)):
        Z = -(w**2) * (M + J.T @ c.added_mass[i] @ J) - 1j * w * (J.T @ c.damping[i] @ J + D) + K
        X = (c.froude_krylov[i] + c.diffraction[i]) @ J  # (m, d)
        out[i] = np.linalg.solve(Z, X.T).T @ J.T
    return out


def steady_start(system: System, s0: SystemState, xi: np.ndarray, omega: float, amplitude: float) -> SystemState:
    """s0 moved onto the linear steady state a xi e^(-i omega t) at t = 0: coordinates, velocities and the radiation memory
    (x' = F x + G nu solved for nu = -i omega a J xi)."""
    q, v = (amplitude * xi).real, (-1j * omega * amplitude * xi).real
    start = replace(system.drifted(s0, 1.0, q), v=v)
    rad = system.radiation
    if rad is not None:
        nu = np.vstack(system.pose(s0).J) @ (-1j * omega * amplitude * xi)
        start = replace(start, memory=np.linalg.solve(-1j * omega * np.eye(rad.states) - rad.F, rad.G @ nu).real)
    return start

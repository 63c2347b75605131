"""The evolving state of a rigid body: time, pose and momenta."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from sim.bodies.body import Body
from sim.bodies.rotation import normalized, quat_multiply, quat_to_matrix

if TYPE_CHECKING:
    from sim.scene.config import SceneConfig


@dataclass(frozen=True, eq=False)
class State:
    t: float
    """Simulated time, s."""
    x_world: np.ndarray
    """(3,) centre-of-mass position, world frame, m."""
    q_world_body: np.ndarray
    """(4,) unit quaternion (w, x, y, z) rotating body-frame vectors into the world frame."""
    u_world: np.ndarray
    """(3,) centre-of-mass velocity, world frame, m/s."""
    L_world: np.ndarray
    """(3,) angular momentum about the centre of mass, world frame, kg m^2/s."""
    memory: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """Radiation memory states (radiation.Radiation; empty without radiation)."""
    E_rad: float = 0.0
    """Energy the body has given to the waves it radiates so far, J."""

    @property
    def R_world_body(self) -> np.ndarray:
        """The orientation as a rotation matrix, body to world."""
        return quat_to_matrix(self.q_world_body)

    def is_finite(self) -> bool:
        """Whether every number of the state is finite."""
        return bool(np.isfinite(self.as_vector()).all())

    def as_vector(self) -> np.ndarray:
        """(13,) x, q, u, L stacked (for solve_ivp); with radiation, then the memory and E_rad."""
        if not len(self.memory):
            return np.concatenate([self.x_world, self.q_world_body, self.u_world, self.L_world])
        return np.concatenate([self.x_world, self.q_world_body, self.u_world, self.L_world, self.memory, [self.E_rad]])

    @staticmethod
    def from_vector(t: float, y: np.ndarray) -> "State":
        extra = (y[13:-1].copy(), float(y[-1])) if len(y) > 13 else ()
        return State(t, y[0:3].copy(), y[3:7] / np.linalg.norm(y[3:7]), y[7:10].copy(), y[10:13].copy(), *extra)


def angular_velocity(body: Body, R: np.ndarray, L: np.ndarray) -> np.ndarray:
    """omega = R I^-1 R^T L, world frame, rad/s."""
    return R @ ((R.T @ L) / body.inertia)


def angular_momentum(body: Body, R: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """L = R I R^T omega, world frame."""
    return R @ (body.inertia * (R.T @ omega))


def initial_state(body: Body, scene: SceneConfig) -> State:
    """The state a scene starts its body in: [initial] position, orientation (after the input frame's turn), velocity, omega."""
    init = scene.initial
    q = normalized(quat_multiply(np.asarray(init.orientation, float), body.q_input_body))
    R = State(0.0, np.zeros(3), q, np.zeros(3), np.zeros(3)).R_world_body
    L = angular_momentum(body, R, np.asarray(init.omega, float))
    return State(0.0, np.asarray(init.position, float), q, np.asarray(init.velocity, float), L)

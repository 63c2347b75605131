"""A joint between the body and the world (the seabed), with a linear power take-off on its free coordinate.

Joints (`[constraint] joint`):
- `fixed`: the body does not move (its loads are still computed: a body held in the waves);
- `prismatic`: it slides along the world axis `axis` through its starting centre of mass, without turning;
  its coordinate s = axis . (x - x_0), m;
- `revolute`: it turns about the world axis `axis` through the world point `pivot` (its centre of mass
  swings on a circle about it); its coordinate theta, rad, from the starting pose, counted on through whole
  turns (the take-off's spring winds up: a hinge that turns past half a turn is not pulled the other way).

The body's twist is J(theta) theta_dot, J the joint's twist per unit rate (6,). Its motion is the joint
coordinate's: M_q theta_ddot = J . (F, T) + Q_pto, with M_q = J^T M J (M the rigid body's 6x6 mass in
world axes), and no gyroscopic term (a body turning about a fixed axis keeps its axial inertia). The
power take-off: Q_pto = -k (theta - theta_0) - c theta_dot; its absorbed power c theta_dot^2 (the CSV's
P_pto; E_pto its integral).

Stepping (`step`): Stormer-Verlet on (theta, theta_dot) with the twist-dependent loads (damping, drag,
the take-off's damper) linearised and their linear flow solved exactly over each half kick, as the free
body's `implicit` scheme does: second order, and stable for any damping. The pose is a function of theta, so the joint
never drifts: the constraint holds to round-off whatever the step.

With radiation the joint's mass takes the added mass at infinite frequency, J^T (M + A_inf) J, and its load
the radiation memory's force (the memory driven by the joint's twist) and the diffraction force.

Not yet: joints between two bodies (they come with several bodies).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sim.bodies.rotation import matrix_to_quat
from sim.bodies.state import State, angular_momentum, angular_velocity
from sim.control.laws import Law
from sim.hydro.forces import Model
from sim.water.seas import StillWater

JOINTS = ("free", "fixed", "prismatic", "revolute", "planar")


def _rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues: the rotation by `angle` about the unit vector `axis`."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * (k @ k)


@dataclass(frozen=True)
class WorldJoint:
    kind: str
    axis: np.ndarray
    """(3,) unit vector, world frame."""
    pivot: np.ndarray
    """(3,) a point on a revolute joint's axis, world frame, m."""
    x0: np.ndarray
    R0: np.ndarray
    """The starting pose: the coordinate is 0 there."""
    stiffness: float
    damping: float

    @classmethod
    def of_scene(cls, scene, x0: np.ndarray, R0: np.ndarray) -> WorldJoint | None:
        c = scene.constraint
        if c.joint == "free":
            return None
        axis = np.asarray(c.axis, float)
        x0 = np.asarray(x0, float).copy()
        return cls(c.joint, axis / np.linalg.norm(axis), x0 + np.asarray(c.pivot, float), x0, np.asarray(R0, float).copy(), float(c.pto_stiffness),
                   float(c.pto_damping))  # fmt: skip

    @property
    def dofs(self) -> int:
        return 0 if self.kind == "fixed" else 1

    def pose(self, theta: float) -> tuple[np.ndarray, np.ndarray]:
        """(x, R) at the coordinate theta."""
        if self.kind == "prismatic":
            return self.x0 + theta * self.axis, self.R0
        if self.kind == "revolute":
            turn = _rotation(self.axis, theta)
            return self.pivot + turn @ (self.x0 - self.pivot), turn @ self.R0
        return self.x0, self.R0

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """(6,) the twist (u, omega) per unit coordinate rate at the centre of mass x."""
        if self.kind == "prismatic":
            return np.concatenate([self.axis, np.zeros(3)])
        if self.kind == "revolute":
            return np.concatenate([np.cross(self.axis, x - self.pivot), self.axis])
        return np.zeros(6)

    def coordinate(self, s: State, near: float = 0.0) -> float:
        """theta of a state on the joint; a hinge's the turn of the pose nearest to `near` (the pose gives it
        up to whole turns: the caller that steps on counts them by passing the last theta)."""
        if self.kind == "prismatic":
            return float(self.axis @ (s.x_world - self.x0))
        if self.kind == "revolute":
            turn = s.R_world_body @ self.R0.T
            sin = 0.5 * float(self.axis @ np.array([turn[2, 1] - turn[1, 2], turn[0, 2] - turn[2, 0], turn[1, 0] - turn[0, 1]]))
            theta = math.atan2(sin, 0.5 * (np.trace(turn) - 1.0))
            return theta + 2.0 * math.pi * round((near - theta) / (2.0 * math.pi))
        return 0.0

    def mass(self, body, R: np.ndarray, J: np.ndarray) -> float:
        """M_q = J^T M J: the body's mass along the joint."""
        inertia = R @ np.diag(body.inertia) @ R.T
        return float(body.mass * J[:3] @ J[:3] + J[3:] @ inertia @ J[3:])

    def rate(self, body, s: State) -> float:
        """theta_dot of a state: its twist projected on the joint in the kinetic-energy metric."""
        if not self.dofs:
            return 0.0
        J = self.jacobian(s.x_world)
        omega = angular_velocity(body, s.R_world_body, s.L_world)
        R = s.R_world_body
        inertia = R @ np.diag(body.inertia) @ R.T
        return float((body.mass * J[:3] @ s.u_world + J[3:] @ inertia @ omega) / self.mass(body, R, J))

    def state(self, body, t: float, theta: float, rate: float, like: State) -> State:
        """The body's state at (theta, theta_dot) (radiation's fields copied from `like`)."""
        x, R = self.pose(theta)
        J = self.jacobian(x)
        return State(t, x, matrix_to_quat(R), J[:3] * rate, angular_momentum(body, R, J[3:] * rate), like.memory, like.E_rad)

    def take_off(self, theta: float, rate: float) -> float:
        """The take-off's generalised force -k theta - c theta_dot (N or N m)."""
        return -self.stiffness * theta - self.damping * rate


def step(model, joint: WorldJoint, s: State, dt: float, theta: float, law=None) -> tuple[State, float, float]:
    """One Stormer-Verlet step on the joint's coordinate (`theta`: its last value, which counts a hinge's
    whole turns), twist terms and the take-off's spring and damper implicit in each half kick; returns the new state,
    the energy the take-off absorbed over the step, J, and the new coordinate. `law`: the take-off's control.Law over
    the step (default: the joint's spring and damper); its force's work is -f times the coordinate's change."""

    body = model.body
    law = Law(0.0, joint.stiffness, joint.damping) if law is None else law
    theta, rate = joint.coordinate(s, near=theta), joint.rate(body, s)
    start = theta
    memory, radiated = s.memory, s.E_rad
    if not joint.dofs:
        return State(s.t + dt, joint.x0, matrix_to_quat(joint.R0), np.zeros(3), np.zeros(3), memory, radiated), 0.0, 0.0
    if law.held:  # locked: the rate's kinetic energy to the lock, the memory on with the body still
        x, R = joint.pose(theta)
        J = joint.jacobian(x)
        rad = model.radiation
        mass = joint.mass(body, R, J) if rad is None else float(J @ rad.mass_matrix(body, R) @ J)
        memory, radiated = _drift_memory(model, joint, theta, theta, 0.0, memory, radiated, dt)
        new = joint.state(body, s.t + dt, theta, 0.0, State(s.t, s.x_world, s.q_world_body, s.u_world, s.L_world, memory, radiated))
        return new, 0.5 * mass * rate * rate, theta
    absorbed = 0.0
    for half in (0, 1):
        if half == 1:
            memory, radiated = _drift_memory(model, joint, theta, theta + dt * rate, rate, memory, radiated, dt)
            theta = theta + dt * rate
        rate, work = _kick(*_affine(model, joint, theta, rate, s.t + half * dt, memory, law), rate, 0.5 * dt, law.damping)
        absorbed += work
    new = joint.state(body, s.t + dt, theta, rate, State(s.t, s.x_world, s.q_world_body, s.u_world, s.L_world, memory, radiated))
    return new, absorbed - law.force * (theta - start), theta


def _drift_memory(model, joint: WorldJoint, theta0: float, theta1: float, rate: float, memory, radiated: float, dt: float):
    """(memory, E_rad) after the drift from theta0 to theta1 at `rate`: the radiation memory advanced exactly
    with the twist in the fit's axes averaged over both ends (as integrators.drift_memory), and the energy
    the radiated waves took, dt nu . mu averaged likewise."""
    rad = model.radiation
    if rad is None:
        return memory, radiated
    (x0, R0), (x1, R1) = joint.pose(theta0), joint.pose(theta1)
    nu0, nu1 = joint.jacobian(x0) * rate, joint.jacobian(x1) * rate
    new = rad.advance(memory, 0.5 * (rad.fit_velocity(R0, nu0) + rad.fit_velocity(R1, nu1)), dt)
    power = -0.5 * (nu0 @ rad.force(R0, memory) + nu1 @ rad.force(R1, new))
    return new, radiated + dt * power


def _kick(Q: float, Dq: float, Mq: float, v: float, h: float, c: float) -> tuple[float, float]:
    """(v(h), the take-off's work): M v' = Q - Dq v solved exactly over h (any Dq >= 0: stable, and the
    symmetric composition stays second order), and the integral of c v^2 over it."""
    lam = Dq / Mq
    if lam * h < 1e-12:  # no damping: a plain kick
        new = v + h * Q / Mq
        return new, c * h * (v * v + v * new + new * new) / 3.0
    a, b = Q / Dq, v - Q / Dq  # v(t) = a + b e^(-lam t)
    e1, e2 = -math.expm1(-lam * h), -math.expm1(-2.0 * lam * h)
    return a + b * (1.0 - e1), c * (a * a * h + 2.0 * a * b * e1 / lam + b * b * e2 / (2.0 * lam))


def _affine(model, joint: WorldJoint, theta: float, rate: float, t: float, memory, law) -> tuple[float, float, float]:
    """(Q0, D_q, M_q) with the generalised load ~ Q0 - D_q theta_dot near `rate`: the take-off's force and spring in Q0,
    its damper in D_q with the loads' own damping along the joint; with radiation, the memory's and the
    diffraction force in Q0 and the added mass at infinite frequency in M_q."""
    x, R = joint.pose(theta)
    J = joint.jacobian(x)
    wet = model.wetted(x, R, t)
    f, D = model.linearised(wet, J * rate, t)  # loads ~ f - D nu near nu = J rate
    Dq = law.damping + (0.0 if D is None else float(J @ D @ J))
    take_off = law.force - law.stiffness * theta
    rad = model.radiation
    if rad is None:
        return float(J @ f) + take_off, Dq, joint.mass(model.body, R, J)
    return float(J @ (f + rad.load(R, memory, t, x))) + take_off, Dq, float(J @ rad.mass_matrix(model.body, R) @ J)


def stiffness_along(model, joint: WorldJoint, step: float = 1e-4) -> float:
    """K = -dQ/dtheta at the joint's start in still water: the water's and gravity's stiffness along the joint (central
    differences of the generalised pose load), what a take-off's negative spring must stay below (control/laws.py)."""

    still = Model(model.body, StillWater(model.water.rho, model.water.g), model.fluid)

    def load(theta: float) -> float:
        x, R = joint.pose(theta)
        return float(joint.jacobian(x) @ np.concatenate(still.pose_loads(still.wetted(x, R, 0.0))))

    return -(load(step) - load(-step)) / (2.0 * step)

"""A system of one: a body alone, free or on one joint to the world, stepped by its own schemes.

This is the system step's specialisation for one body. A free body steps by the scene's integrator
(dynamics/integrators.py: seven schemes, explicit to adaptive) or its compiled twin (kernels/schemes.py, many steps a
call); a body on a joint steps on the joint's coordinate (dynamics/joints.py), its take-off's law asked of its controller
each step. Mooring lines (MoorDyn, lines/moorings.py) are advanced over each step and their mean pull is held on the body
over it; a free body on the compiled twin hands them its fairleads' kinematics from inside the compiled step
(schemes.step_held), so a step is one compiled call and one MoorDyn call.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from sim.bodies.rotation import matrix_to_quat, normalized, quat_multiply, quat_to_matrix
from sim.bodies.state import State, angular_momentum, angular_velocity
from sim.control.laws import Law
from sim.dynamics.joints import WorldJoint
from sim.dynamics.joints import step as joint_step
from sim.hydro.forces import Model, compiled_model
from sim.system.tree import Group, Member, System, SystemState

WIDTHS = {"free": 6, "fixed": 0, "prismatic": 1, "revolute": 1}
"""A system of one's velocities: six free, none fixed, the joint's rate on a slide or a hinge."""


class StepFailed(Exception):
    """A step left the finite numbers: `motion` is the last good one, `t` the time it failed at, `why` what went wrong."""

    def __init__(self, motion: Motion, t: float, why: str):
        super().__init__(why)
        self.motion, self.t, self.why = motion, t, why


@dataclass
class Motion:
    """Where a body of one is: its state, its joint's coordinate (a hinge's whole turns counted) and the energy its take-off
    has absorbed, J (0 and 0 when free)."""

    state: State
    theta: float = 0.0
    absorbed: float = 0.0


def system_of_one(model: Model, joint: WorldJoint | None, start: State) -> System:
    """The body as a system of one (system/tree.py): its group free about the starting pose `start`, or on its joint to the
    world (the joint's own starting pose), the take-off's spring and damper as the joint's."""
    kind = "free" if joint is None else joint.kind
    x0, R0 = (start.x_world, start.R_world_body) if joint is None else (joint.x0, joint.R0)
    width = WIDTHS[kind]
    member = Member("body", model, np.zeros(3), np.asarray(R0, float).copy())
    axis, pivot = (np.array([0.0, 0.0, 1.0]), x0) if joint is None else (joint.axis, joint.pivot)
    stiffness, damping = (0.0, 0.0) if joint is None else (joint.stiffness, joint.damping)
    group = Group("body", (member,), kind, -1, np.asarray(axis, float), np.asarray(pivot, float).copy(), np.asarray(x0, float).copy(),
                  stiffness, damping, slice(0, width), 0 if width else -1, np.asarray(x0, float).copy())  # fmt: skip
    return System([group], [(0, 0)], model.water, model.fluid)


def to_system(system: System, joint: WorldJoint | None, m: Motion) -> SystemState:
    """The body's motion as the system of one's state: a free group's centre of mass, its turn from the start and its twist
    (u, omega); a joint's coordinate, rate and absorbed energy."""
    s, g = m.state, system.groups[0]
    body = g.members[0].body
    if g.kind == "free":
        with np.errstate(all="ignore"):  # a state far off (a run that blew up stops there) reads as non-finite, not as an error
            turn = quat_multiply(s.q_world_body, matrix_to_quat(g.members[0].rotation) * [1.0, -1.0, -1.0, -1.0])
            v = np.concatenate([s.u_world, angular_velocity(body, s.R_world_body, s.L_world)])
        return SystemState(s.t, s.x_world[None, :].copy(), turn[None, :], np.zeros(0), v, np.zeros(0), s.memory, s.E_rad).with_body(s)
    width = WIDTHS[g.kind]
    with np.errstate(all="ignore"):
        rate = joint.rate(body, s)
    theta, v = np.array([m.theta])[:width], np.array([rate])[:width]
    return SystemState(s.t, np.zeros((0, 3)), np.zeros((0, 4)), theta, v, np.array([m.absorbed])[:width], s.memory, s.E_rad).with_body(s)


def from_system(system: System, joint: WorldJoint | None, s: SystemState) -> Motion:
    """The system of one's state as the body's motion: its body's own state where it has one (exactly), else from its
    coordinates and velocities (to_system's inverse, to round-off)."""
    g = system.groups[0]
    one = len(s.theta) == 1  # on a slide or a hinge
    if "_body" in s.__dict__:
        return Motion(s.body, float(s.theta[0]) if one else 0.0, float(s.absorbed[0]) if one else 0.0)
    if joint is not None:
        theta, rate = (float(s.theta[0]), float(s.v[0])) if one else (0.0, 0.0)
        like = State(s.t, np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(3), np.zeros(3), s.memory, s.E_rad)
        return Motion(joint.state(g.members[0].body, s.t, theta, rate, like), theta, float(s.absorbed[0]) if one else 0.0)
    pose = system.pose(s)
    x, J = pose.x[0], pose.J[0]
    nu = J @ s.v
    q0 = matrix_to_quat(g.members[0].rotation)
    q = normalized(quat_multiply(s.q_free[0], q0))
    state = State(s.t, np.asarray(x, float).copy(), q, nu[:3].copy(), angular_momentum(g.members[0].body, quat_to_matrix(q), nu[3:]),
                  s.memory, s.E_rad)  # fmt: skip
    return Motion(state)


class Single:
    """The step of a system of one. `model`, `integrator` and `joint` are the runner's (it replaces them whole on a change);
    `compiled` says whether the compiled twin steps (the runner sets it where `has_twin`)."""

    def __init__(self, model: Model, integrator, joint: WorldJoint | None):
        self.model, self.integrator, self.joint = model, integrator, joint
        self.compiled = False
        self.expand_waves = True
        """Whether the kernels may sum a many-component sea as a local expansion (kernels/water.py)."""
        self.step_seconds: float | None = None
        """Wall-time budget of one step of an adaptive method (None: only its evaluation cap)."""
        self._sea: tuple = (None, None)  # (model, its water packed for the kernels)
        self._rad: tuple = (None, None)  # ((model, dt), its radiation packed for the kernels)
        self._packed: tuple = (None, None, None, None)  # (model, scheme, its kernels, the model packed for them)

    # the compiled twin

    @property
    def has_twin(self) -> bool:
        """A fixed-step integrator with a twin, a force model it covers in this water, every term compiled, no joint."""
        from sim.kernels import SCHEMES, missing_terms  # numba's import (0.6 s): only where compiled kernels run

        return self.integrator.name in SCHEMES and compiled_model(self.model) and not missing_terms(self.model) and self.joint is None

    @property
    def spec(self):
        """What the compiled kernels specialise on for this body (kernels.Spec)."""
        from sim.kernels import spec_of  # numba's import (0.6 s): only where compiled kernels run

        return spec_of(self.model, self.integrator.name)

    def kernels(self):
        """The compiled kernels for this body (kernels.specialised: loaded from the disk cache, or compiled now)."""
        from sim.kernels import specialised  # numba's import (0.6 s): only where compiled kernels run

        return specialised(self.spec)

    def backend_notes(self, backend: str) -> list[str]:
        """What the user should know about how this body steps on `backend` (a scheme not used, a fallback to numpy)."""
        from sim.kernels import SCHEMES, missing_terms  # numba's import (0.6 s): only where compiled kernels run

        integ, notes = self.integrator, []
        if self.joint is not None and integ.name != "implicit":
            notes.append(
                f"a jointed body steps by its own scheme (Stormer-Verlet, its damping implicit): integrator '{integ.name}' is not used"
            )
        if backend == "numba" and self.joint is not None:
            notes.append("the joint has no compiled twin yet: the scene runs on the numpy reference (slower)")
        elif backend == "numba" and missing_terms(self.model):
            notes.append(
                f"the {', '.join(missing_terms(self.model))} term has no compiled twin: the scene runs on the numpy reference (slower)"
            )
        elif backend == "numba" and not integ.adaptive and integ.name not in SCHEMES:
            notes.append(f"integrator '{integ.name}' has no compiled twin: it runs on the numpy reference (slower)")
        elif backend == "numba" and not compiled_model(self.model):
            notes.append("the cells force model has no compiled twin in waves: it runs on the numpy reference (slower)")
        return notes

    # stepping

    def advance(self, m: Motion, n: int, dt: float, law: Callable[[State, float], Law] | None = None, lines=None) -> Motion:
        """`m` after n steps of dt; `law(s, theta)`: the take-off's law for the step from s at the coordinate theta (None: the joint's spring and damper);
        `lines`: the mooring lines (lines/moorings.Moorings) whose pull the model holds. Raises StepFailed."""
        if lines is None and self.joint is None:
            return Motion(self._compiled(m.state, n, dt) if self.compiled else self._numpy(m.state, n, dt))
        if self.joint is None and self.compiled:
            return Motion(self._moored(m.state, n, dt, lines))
        return self._coupled(m, n, dt, law, lines)

    def _numpy(self, state: State, n: int, dt: float) -> State:
        model, integrator = self.model, self.integrator
        if integrator.adaptive:
            integrator.max_seconds = self.step_seconds
        for _ in range(n):
            try:
                new = integrator.step(model, state, dt)
            except FloatingPointError as e:  # where np.seterr makes overflow raise, as in the tests
                new, why = None, f"floating-point error ({e})"
            else:
                why = "the state became non-finite"
            if new is None or not new.is_finite():
                raise StepFailed(Motion(state), state.t + dt, why)
            state = new
        return state

    def _coupled(self, m: Motion, n: int, dt: float, law, lines) -> Motion:
        """Step by step: the mooring lines advanced over each and their mean pull held over it; a jointed body stepped on its
        joint's coordinate."""
        body, held, joint = self.model.body, self.model.held, self.joint
        state, theta, absorbed = m.state, m.theta, m.absorbed
        try:
            for _ in range(n):
                if lines is not None:
                    R = state.R_world_body
                    held[:] = lines.advance(state.x_world, R, state.u_world, angular_velocity(body, R, state.L_world), dt)
                if joint is None:
                    try:
                        state = self._compiled(state, 1, dt) if self.compiled else self._numpy(state, 1, dt)
                    except StepFailed as e:
                        raise StepFailed(Motion(e.motion.state, theta, absorbed), e.t, e.why) from None
                    continue
                new, work, new_theta = joint_step(self.model, joint, state, dt, theta, None if law is None else law(state, theta))
                if not new.is_finite():
                    raise StepFailed(Motion(state, theta, absorbed), state.t + dt, "the state became non-finite")
                state, absorbed, theta = new, absorbed + work, new_theta
        finally:
            if lines is not None:
                held[:] = lines.load  # the pull now, as the frame shows it
        return Motion(state, theta, absorbed)

    def _packs(self, dt: float) -> tuple:
        """(kernels, the model packed for them, the sea, the radiation), each rebuilt only when what it packs changed."""
        from sim import kernels  # numba's import (0.6 s): only where compiled kernels run
        from sim.kernels.layout import HELD  # numba's import (0.6 s): only where compiled kernels run

        model = self.model
        body = model.body
        if self._packed[0] is not model or self._packed[1] != self.integrator.name:  # a step at a time costs 40 us less
            _, coef = kernels.pack(model)
            self._packed = (model, self.integrator.name, self.kernels(), kernels.Model(body.packed, body.mass, body.inertia, coef))
        elif model.held is not None:
            self._packed[3].coef[HELD:] = model.held  # the moorings' pull, new at every step
        if self._sea[0] != (model, self.expand_waves):
            self._sea = ((model, self.expand_waves), kernels.sea_pack(model.water, body, self.expand_waves))
        if self._rad[0] != (model, dt):
            self._rad = ((model, dt), kernels.radiation_pack(model.radiation, body, dt))
        return self._packed[2], self._packed[3], self._sea[1], self._rad[1]

    def _compiled(self, state: State, n: int, dt: float) -> State:
        compiled, packed, sea, rad = self._packs(dt)
        y, done = compiled.schemes.advance(state.as_vector(), state.t, n, dt, packed, sea, rad)
        new = _state_of(y, state.t + done * dt)
        if done < n:
            raise StepFailed(Motion(new), new.t + dt, "the state became non-finite")
        return new

    def _moored(self, state: State, n: int, dt: float, lines) -> State:
        """The compiled body and MoorDyn in turn, a step each: the kernels keep their carry and scratch from step to step
        (schemes.step_held, which also takes the lines' pull into the held load and gives the fairleads' next kinematics),
        so a step is one compiled call and one MoorDyn call. The same steps as the one-step-a-call loop, to round-off."""
        from sim.kernels import entry_point  # numba's import (0.6 s): only where compiled kernels run

        compiled, packed, sea, rad = self._packs(dt)
        t = state.t
        levers = lines.r_body
        pos, vel = np.empty(levers.size), np.empty(levers.size)
        y = state.as_vector()
        s, keep = compiled.schemes.held_start(y, t, dt, packed, sea, rad, levers, pos, vel)
        step = entry_point(
            compiled.schemes.step_held, (y, t, dt, packed, sea, rad, s, keep, lines._forces, lines._forces, levers, pos, vel, False)
        )
        pull = lines.pull
        failed = None
        try:
            for _ in range(n):
                now = lines._forces
                y, ok = step(y, t, dt, packed, sea, rad, s, keep, now, pull(pos, vel, dt), levers, pos, vel, False)
                if not ok:
                    failed = t + dt
                    break
                t += dt
        finally:  # the state reached, and the pull now as the frame shows it
            reached = _state_of(y, t)
            lines.settle(keep[0])
            self.model.held[:] = lines.load
        if failed is not None:
            raise StepFailed(Motion(reached), failed, "the state became non-finite")
        return reached


def _state_of(y: np.ndarray, t: float) -> State:
    extra = (y[13:-1].copy(), float(y[-1])) if len(y) > 13 else ()  # radiation: the memory and E_rad
    return State(t, y[0:3], y[3:7], y[7:10], y[10:13], *extra)

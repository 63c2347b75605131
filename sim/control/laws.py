"""Take-off control: the force a joint's power take-off puts on its coordinate, chosen at each step.

A controller reads, at the start of each step, the time, its joint's coordinate theta and rate theta_dot and the sea at
its body (`WaveState`), and gives the affine law the step holds:

    F = f - k theta - c theta_dot      (N on a slide, N m on a hinge)

k and c act inside the step's implicit kick (dynamics/joints.py, system/tree.py), so a stiff spring, a large damper or a
latch stays stable at any time step; f is held over the step. The take-off absorbs P = (c theta_dot - f) theta_dot (the
CSV's P_pto; its spring's power is stored, not absorbed), and E_pto adds that exactly over each step.

Shipped (`[constraint] controller`, the gains beside it):
- `passive`: the spring and damper (pto_stiffness >= 0, pto_damping), as before controllers existed;
- `reactive`: the same law with a negative spring allowed: complex-conjugate control at one frequency is
  k = omega^2 (m + A(omega)) - C, c = B(omega) (Falnes 2002, Ocean Waves and Oscillating Systems, ch. 6). The total
  stiffness along the joint, C + k, must stay positive (checked at the start: otherwise the body leaves its rest);
- `latching`: the damper, and a lock at each stop: when theta_dot changes sign the coordinate is held for `latch_time`
  (Babarit & Clement 2006, Applied Ocean Research 28: 77-91; for regular waves about (T - T_n) / 2). The lock is exact
  (the joint's rate set to zero and kept there: the other coordinates move on without it); it engages at the first
  step start after the stop and releases at the step start nearest its end;
- `declutching`: no take-off force for `declutch_time` after each stop, the damper the rest of the time
  (Babarit, Guglielmi & Clement 2009, Ocean Engineering 36: 1015-1024);
- `pi`: a proportional-integral loop on the rate's error from a reference (zero, or a callable of t in the API):
  F = -Kp e - Ki integral(e), Kp = pto_damping, Ki = pto_stiffness; the integral stops while the force is limited.
Any of them takes `pto_max_force`: where the law's force at a step's start passes it, the limit is held over that step
(explicit there; within a step that starts inside the limit the law runs on, by at most one step's change).

From Python a controller is any callable (t, JointState, WaveState) -> force, or a Controller (its own law):
`Simulation.control(fn)` (one body) or `Simulation.control(fn, "float")`. A callable's force is held over each step
(explicit: keep its gains well inside the step's stability). A law that never changes (passive, reactive) is packed once;
any other calls back into Python once a step, compiled runs too (docs/control.md gives the cost).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

from sim.errors import ConfigError

CONTROLLERS = ("passive", "reactive", "latching", "declutching", "pi")


@dataclass(frozen=True)
class Law:
    """F = force - stiffness theta - damping theta_dot, held over one step; or `held`: the joint locked over the step
    (a latch: its rate set to zero, the kinetic energy that takes counted as absorbed, and kept there)."""

    force: float = 0.0
    stiffness: float = 0.0
    damping: float = 0.0
    held: bool = False

    def at(self, theta: float, rate: float) -> float:
        """The force at (theta, theta_dot) (a lock's reaction is not known here: 0)."""
        return 0.0 if self.held else self.force - self.stiffness * theta - self.damping * rate


@dataclass(frozen=True)
class JointState:
    t: float
    theta: float
    """The joint's coordinate from its start, m or rad."""
    rate: float
    """theta_dot, m/s or rad/s."""
    dt: float = 0.0
    """The step the law is held over, s."""


class WaveState:
    """The sea at the joint's body: its surface over the body's starting (x, y), computed when asked."""

    def __init__(self, water, xy, t: float):
        self.water, self.xy, self.t = water, xy, float(t)

    @property
    def eta(self) -> float:
        """Elevation, m."""
        return float(self.water.elevation(self.xy, self.t))

    @property
    def eta_rate(self) -> float:
        """Its rate, m/s (a central difference over 1 ms)."""
        h = 5e-4
        return float(self.water.elevation(self.xy, self.t + h) - self.water.elevation(self.xy, self.t - h)) / (2 * h)


class Controller:
    """A take-off's law, stateful (timers, integrals): `law` once per step, in time order; `reset` to start again."""

    name = "controller"

    def law(self, joint: JointState, wave: WaveState) -> Law:
        raise NotImplementedError

    def reset(self) -> None:
        pass

    @property
    def linear(self) -> Law | None:
        """The law when it never changes (passive, reactive): the run may keep it packed; None otherwise."""
        return None


class Passive(Controller):
    name = "passive"

    def __init__(self, stiffness: float, damping: float):
        self._law = Law(0.0, float(stiffness), float(damping))

    def law(self, joint, wave) -> Law:
        return self._law

    @property
    def linear(self) -> Law:
        return self._law


class Reactive(Passive):
    name = "reactive"


class _Stops(Controller):
    """Something done for `hold` seconds from each stop of the joint (a change of the rate's sign, timed by linear
    interpolation between the two steps it falls between), ending at the step start nearest its end."""

    def __init__(self, damping: float, hold: float, special: Law):
        self.free, self.hold, self.special = Law(0.0, 0.0, float(damping)), float(hold), special
        self.reset()

    def reset(self) -> None:
        self.until, self.last = -math.inf, None

    def law(self, joint, wave) -> Law:
        if joint.t + 0.5 * joint.dt < self.until:  # the step starts nearer before the hold's end than after it
            return self.special
        last, self.last = self.last, joint
        if last is not None and last.rate * joint.rate < 0.0 and self.hold > 0.0:
            stop = last.t + (joint.t - last.t) * last.rate / (last.rate - joint.rate)
            self.until, self.last = stop + self.hold, None
            if joint.t + 0.5 * joint.dt < self.until:
                return self.special
        return self.free


class Latching(_Stops):
    name = "latching"

    def __init__(self, damping: float, latch_time: float):
        super().__init__(damping, latch_time, Law(held=True))


class Declutching(_Stops):
    name = "declutching"

    def __init__(self, damping: float, declutch_time: float):
        super().__init__(damping, declutch_time, Law())


class PI(Controller):
    """F = -Kp (theta_dot - r) - Ki (theta - theta_start - integral of r): the integral is the coordinate's, so the
    Ki term acts inside the kick as a spring; `reference` r(t) (m/s or rad/s) defaults to 0."""

    name = "pi"

    def __init__(self, kp: float, ki: float, reference: Callable[[float], float] | None = None):
        self.kp, self.ki, self.reference = float(kp), float(ki), reference
        self.reset()

    def reset(self) -> None:
        self.origin, self.last = None, None  # theta at which the integral is zero; the last (t, theta, r)

    def law(self, joint, wave) -> Law:
        r = 0.0 if self.reference is None else float(self.reference(joint.t))
        if self.origin is None:
            self.origin = joint.theta
        elif self.reference is not None:
            self.origin += 0.5 * (self.last[2] + r) * (joint.t - self.last[0])  # the reference's integral, trapezoidal
        self.last = (joint.t, joint.theta, r)
        return Law(self.kp * r + self.ki * self.origin, self.ki, self.kp)

    def saturated(self, joint: JointState) -> None:
        """The force was limited over the last step: the integral keeps its value (no wind-up)."""
        if self.last is not None and self.origin is not None:
            self.origin += joint.theta - self.last[1]


class Callback(Controller):
    """A Python callable (t, JointState, WaveState) -> force, held over each step."""

    def __init__(self, fn: Callable):
        self.fn, self.name = fn, getattr(fn, "__name__", "callable")

    def law(self, joint, wave) -> Law:
        return Law(float(self.fn(joint.t, joint, wave)))


class Limited(Controller):
    """Another controller's force kept within +-limit: past it, the limit held over the step."""

    def __init__(self, inner: Controller, limit: float):
        self.inner, self.limit, self.name = inner, float(limit), inner.name
        self._over = False

    def reset(self) -> None:
        self.inner.reset()
        self._over = False

    def law(self, joint, wave) -> Law:
        if self._over and isinstance(self.inner, PI):
            self.inner.saturated(joint)
        law = self.inner.law(joint, wave)
        F = law.at(joint.theta, joint.rate)
        self._over = abs(F) > self.limit
        return Law(math.copysign(self.limit, F)) if self._over else law


def of_constraint(c) -> Controller:
    """The controller a [constraint] table names."""
    kind = c.controller
    if kind in ("passive", "reactive"):
        made = (Passive if kind == "passive" else Reactive)(c.pto_stiffness, c.pto_damping)
    elif kind == "latching":
        made = Latching(c.pto_damping, c.latch_time)
    elif kind == "declutching":
        made = Declutching(c.pto_damping, c.declutch_time)
    else:
        made = PI(c.pto_damping, c.pto_stiffness)
    return made if c.pto_max_force is None else Limited(made, c.pto_max_force)


def wrap(controller) -> Controller:
    """A Controller as given, or a callable wrapped as one."""
    if isinstance(controller, Controller):
        return controller
    if callable(controller):
        return Callback(controller)
    raise TypeError(
        f"a controller is a callable (t, joint, wave) -> force or a sim.control.laws.Controller, not {type(controller).__name__}"
    )


def stiffness_check(kind: str, k: float, K0, e, where: str = "") -> None:
    """A negative take-off spring k on the coordinate e ((d,)) must leave the stiffness of the whole system positive
    (semi-)definite: K0 (d, d), the water's, gravity's and the other springs' at rest, plus k e e^T. Otherwise some motion
    (not always the joint's own: a float's spring against its spar's heave) leaves the rest: ConfigError, with the
    bound -1 / (e^T K0^+ e) (for one body -K)."""
    import numpy as np

    if k >= 0.0:
        return
    K0, e = np.atleast_2d(np.asarray(K0, float)), np.atleast_1d(np.asarray(e, float))
    K0 = 0.5 * (K0 + K0.T)
    scale = float(np.abs(np.linalg.eigvalsh(K0)).max(initial=0.0))
    lowest = float(np.linalg.eigvalsh(K0 + k * np.outer(e, e)).min())
    if lowest >= -1e-9 * scale:
        return
    reach = float(e @ np.linalg.pinv(K0) @ e)
    bound = f"keep pto_stiffness > {-1.0 / reach:.4g}" if reach > 0 else "this joint's stiffness along it is not positive"
    raise ConfigError(
        f"{where}{kind} control: pto_stiffness {k:g} leaves the stiffness at rest with a negative direction (eigenvalue "
        f"{lowest:.4g}): the bodies would leave their rest; {bound}"
    )

"""Time integrators with a declared order, chosen by name from `INTEGRATORS`.

Each is a small object with `name`, `order` and `step(model, state, dt) -> State`; forces reach it
only through the `Model`. Rotations are exact (quaternion exponentials), never linearised.
"""

from __future__ import annotations

import math
import time

import numpy as np

from sim.bodies.rotation import normalized, quat_multiply, quat_to_matrix, rotate_body, rotate_world
from sim.bodies.state import State, angular_momentum, angular_velocity
from sim.errors import SimulationDiverged
from sim.hydro.forces import Model


def kick(model: Model, R: np.ndarray, u, L, F, T, h: float):
    """(u, L) after the impulse h (F, T). With radiation the water's added mass takes its share:
    the twist changes by h (M_RB + A_inf)^-1 (F, T), and L = R I R^T omega stays the rigid body's."""
    rad = model.radiation
    if rad is None:
        return u + h * F / model.body.mass, L + h * T
    dnu = np.linalg.solve(rad.mass_matrix(model.body, R), h * np.concatenate([F, T]))
    return u + dnu[:3], L + angular_momentum(model.body, R, dnu[3:])


def with_memory(model: Model, R: np.ndarray, F, T, memory, t: float, x: np.ndarray):
    """The loads plus the radiation memory's force and, in waves, the diffraction force at time t with the centre of mass at x
    (when the scene has radiation)."""
    if model.radiation is None:
        return F, T
    f = model.radiation.load(R, memory, t, x)
    return F + f[:3], T + f[3:]


def drift_memory(model: Model, s: State, R0: np.ndarray, R1: np.ndarray, u, L, dt: float):
    """(memory, E_rad) after a drift of dt at the twist (u, L): the memory advanced exactly with the
    twist in the fit's axes (riding with the body) averaged over the drift's two orientations, and the energy it took from the body,
    dt nu . mu averaged likewise (mu = -the memory's force)."""
    rad = model.radiation
    if rad is None:
        return s.memory, s.E_rad
    body = model.body
    nu0 = np.concatenate([u, angular_velocity(body, R0, L)])
    nu1 = np.concatenate([u, angular_velocity(body, R1, L)])
    memory = rad.advance(s.memory, 0.5 * (rad.fit_velocity(R0, nu0) + rad.fit_velocity(R1, nu1)), dt)
    power = -0.5 * (nu0 @ rad.force(R0, s.memory) + nu1 @ rad.force(R1, memory))
    return memory, s.E_rad + dt * power


def free_rotation(model: Model, q: np.ndarray, L: np.ndarray, h: float) -> np.ndarray:
    """Torque-free rotation over h by the symmetric split of the kinetic energy into the three
    principal axes (Dullweber, Leimkuhler & McLachlan 1997): each sub-rotation is exact, |L| is
    kept to round-off, the composition is symplectic, time-reversible and second order; it is
    exact for an isotropic body such as the cube."""
    inertia = model.body.inertia
    for axis, frac in ((0, 0.5), (1, 0.5), (2, 1.0), (1, 0.5), (0, 0.5)):
        L_body = quat_to_matrix(q).T @ L
        v = np.zeros(3)
        v[axis] = frac * h * L_body[axis] / inertia[axis]
        q = rotate_body(q, v)
    return normalized(q)


def twist_flow(model: Model, wet, R: np.ndarray, u, L, h: float, t: float):
    """Advance (u, L) by h under the twist-dependent loads alone (damping, drag), pose frozen, by one
    explicit midpoint step: second order; for linear damping stable while h lambda_max <= 2."""
    if not model.twist_terms or not len(wet.weight):
        return u, L
    F, T = model.twist_loads(wet, np.concatenate([u, angular_velocity(model.body, R, L)]), t)
    u_mid, L_mid = kick(model, R, u, L, F, T, 0.5 * h)
    F, T = model.twist_loads(wet, np.concatenate([u_mid, angular_velocity(model.body, R, L_mid)]), t)
    return kick(model, R, u, L, F, T, h)


class Euler:
    """The source report's scheme: drift x, rotate by the exact exp(dt [w]x), evaluate the forces
    at the new pose, then kick u and L with them. First order."""

    name, order, adaptive = "euler", 1, False
    heave_limit, damping_limit = 2.0, 2.0  # stable while dt omega_heave and dt lambda_max stay below these

    def step(self, model: Model, s: State, dt: float) -> State:
        x = s.x_world + dt * s.u_world
        omega = angular_velocity(model.body, s.R_world_body, s.L_world)
        q = normalized(rotate_world(s.q_world_body, dt * omega))
        R = quat_to_matrix(q)
        memory, E_rad = drift_memory(model, s, s.R_world_body, R, s.u_world, s.L_world, dt)
        wet = model.wetted(x, R, s.t + dt)
        loads = model.loads(wet, s.u_world, angular_velocity(model.body, R, s.L_world), s.t + dt)
        F, T = with_memory(model, R, *loads, memory, s.t + dt, x)
        return State(s.t + dt, x, q, *kick(model, R, s.u_world, s.L_world, F, T, dt), memory, E_rad)


class Splitting:
    """Symmetric (Strang) splitting: half twist flow (damping, drag), half kick, drift with exact
    rotation, half kick, half twist flow. Symplectic and second order without damping; each half
    twist flow is an explicit midpoint step (second order, stable while dt lambda_max <= 4)."""

    name, order, adaptive = "splitting", 2, False
    heave_limit, damping_limit = 2.0, 4.0

    def step(self, model: Model, s: State, dt: float) -> State:
        h = 0.5 * dt
        x, q, u, L = s.x_world, s.q_world_body, s.u_world, s.L_world
        R = quat_to_matrix(q)
        wet = model.wetted(x, R, s.t)
        u, L = twist_flow(model, wet, R, u, L, h, s.t)
        u, L = kick(model, R, u, L, *with_memory(model, R, *model.pose_loads(wet, s.t), s.memory, s.t, x), h)
        x = x + dt * u
        q = free_rotation(model, q, L, dt)
        R0, R = R, quat_to_matrix(q)
        memory, E_rad = drift_memory(model, s, R0, R, u, L, dt)
        t = s.t + dt
        wet = model.wetted(x, R, t)
        u, L = kick(model, R, u, L, *with_memory(model, R, *model.pose_loads(wet, t), memory, t, x), h)
        u, L = twist_flow(model, wet, R, u, L, h, t)
        return State(t, x, q, u, L, memory, E_rad)


RELINEARISE = 60
"""At most this many relinearisations of a nonlinear twist term (drag) per half step."""
RELINEARISE_TOL = 1e-13
"""They stop once the end velocity changes by less than this, relative to the body's velocity scale."""


def linear_flow(model: Model, wet, R: np.ndarray, u, L, h: float, t: float, memory=None):
    """Advance (u, L) by h under every load linearised about a twist, pose frozen:
    d(M u, L)/dt = f - D (u, omega) (`Model.linearised`), a linear system with a constant forcing,
    solved exactly (`exact_linear_flow`): stable for any damping, no overshoot, and an overdamped
    body creeps at the physical speed.

    Linear terms (damping) are linearised exactly once. A nonlinear one (drag, quadratic) is
    linearised about the twist at the *end* of the half step, found by fixed-point iteration from the
    start twist: about the start alone, a body at rest would feel no drag for a whole step however
    stiff it is. At the end twist the iteration is Newton's method for the drag balance, so the
    terminal speed is the exact fixed point and a stiff start converges instead of overshooting.
    With radiation the memory's force (`memory`, frozen over the half step) and the diffraction force at t (the body where
    the wet surface's pose puts it) join the forcing."""
    body = model.body
    twist = np.concatenate([u, angular_velocity(body, R, L)])
    extra = np.zeros(6) if model.radiation is None else model.radiation.load(R, memory, t, wet.x)
    f, D = model.linearised(wet, twist, t)
    un, Ln = exact_linear_flow(model, R, u, L, f + extra, D, h)
    if model.linear_in_twist:
        return un, Ln
    scale = velocity_scale(body)
    pose = np.concatenate(model.pose_loads(wet, t)) + extra
    for _ in range(RELINEARISE):
        end = np.concatenate([un, angular_velocity(body, R, Ln)])
        u2, L2 = exact_linear_flow(model, R, u, L, *model.linearised(wet, end, t, pose), h)
        change = max(np.abs(u2 - un).max(), scale * np.abs(angular_velocity(body, R, L2 - Ln)).max())
        un, Ln = u2, L2
        if change <= RELINEARISE_TOL * (np.abs(un).max() + scale * np.abs(angular_velocity(body, R, Ln)).max()):
            break
    return un, Ln


def velocity_scale(body) -> float:
    """The radius of gyration, m: omega times it is a velocity comparable with u."""
    return float(np.sqrt(body.inertia.max() / body.mass))


def exact_linear_flow(model: Model, R: np.ndarray, u, L, f: np.ndarray, D: np.ndarray | None, h: float):
    """(u, L) after h of d(M u, L)/dt = f - D (u, omega), pose frozen, exactly. In y = Mg^(1/2) v
    with K = W D W: y(h) = exp(-hK) y0 + h phi(hK) W f, phi(x) = (1 - e^-x) / x. Each mode decays
    by exp(-h lambda) <= 1 and relaxes to its exact terminal velocity. With no D it is the plain kick."""
    body = model.body
    F, T = f[:3], f[3:]
    if D is None:
        return kick(model, R, u, L, F, T, h)
    if model.radiation is not None:  # the same with the generalised mass M_RB + A_inf: W = its inverse square root
        lam_m, V_m = np.linalg.eigh(model.radiation.mass_matrix(body, R))
        W = (V_m / np.sqrt(lam_m)) @ V_m.T
        y = np.linalg.solve(W, np.concatenate([u, angular_velocity(body, R, L)]))
        lam, V = np.linalg.eigh(W @ D @ W)
        x = h * np.maximum(lam, 0.0)
        phi = np.where(x > 1e-12, -np.expm1(-x) / np.where(x > 1e-12, x, 1.0), 1.0 - 0.5 * x)
        nu = W @ (V @ (np.exp(-x) * (V.T @ y) + h * phi * (V.T @ (W @ f))))
        return nu[:3], angular_momentum(body, R, nu[3:])
    sqrt_m, w_half = np.sqrt(body.mass), np.sqrt(body.inertia)
    y = np.concatenate([sqrt_m * u, R @ ((R.T @ L) / w_half)])
    g = np.concatenate([F / sqrt_m, R @ ((R.T @ T) / w_half)])
    W = np.zeros((6, 6))
    W[:3, :3] = np.eye(3) / sqrt_m
    W[3:, 3:] = (R / w_half) @ R.T
    lam, V = np.linalg.eigh(W @ D @ W)
    x = h * np.maximum(lam, 0.0)
    phi = np.where(x > 1e-12, -np.expm1(-x) / np.where(x > 1e-12, x, 1.0), 1.0 - 0.5 * x)
    y = V @ (np.exp(-x) * (V.T @ y) + h * phi * (V.T @ g))
    return y[:3] / sqrt_m, R @ (w_half * (R.T @ y[3:]))


class ImplicitSplitting(Splitting):
    """Strang splitting of the pose (drift with exact rotation) and the momenta (every load, the
    twist-dependent ones linearised about the current twist, solved exactly at a frozen pose):
    second order, stable for any damping coefficient, and an overdamped body creeps at its
    physical speed. Quadratic drag enters through its Jacobian at the end of each half step, so its
    terminal speed is exact and stiff drag is stable."""

    name = "implicit"
    damping_limit = float("inf")

    def step(self, model: Model, s: State, dt: float) -> State:
        h = 0.5 * dt
        x, q, u, L = s.x_world, s.q_world_body, s.u_world, s.L_world
        R = quat_to_matrix(q)
        u, L = linear_flow(model, model.wetted(x, R, s.t), R, u, L, h, s.t, s.memory)
        x = x + dt * u
        q = free_rotation(model, q, L, dt)
        R0, R = R, quat_to_matrix(q)
        memory, E_rad = drift_memory(model, s, R0, R, u, L, dt)
        t = s.t + dt
        u, L = linear_flow(model, model.wetted(x, R, t), R, u, L, h, t, memory)
        return State(t, x, q, u, L, memory, E_rad)


def derivative(model: Model, t: float, y: np.ndarray) -> np.ndarray:
    """d/dt of (x, q, u, L) stacked, for RK4 and solve_ivp; q need not be normalised. With radiation
    y also carries the memory and E_rad: (M_RB + A_inf) nu' = f - mu - (0, omega x L), L' = I nu'_w + omega x L."""
    x, q, u, L = y[0:3], y[3:7], y[7:10], y[10:13]
    R = quat_to_matrix(q)
    omega = angular_velocity(model.body, R, L)
    F, T = model.loads(model.wetted(x, R, t), u, omega, t)
    dq = 0.5 * quat_multiply(np.array([0.0, *omega]), q / np.sqrt(q @ q))
    rad = model.radiation
    if rad is None:
        return np.concatenate([u, dq, F / model.body.mass, T])
    memory = y[13:-1]
    nu = np.concatenate([u, omega])
    f = np.concatenate([F, T]) + rad.load(R, memory, t, x)
    spin = np.cross(omega, L)
    f[3:] -= spin
    dnu = np.linalg.solve(rad.mass_matrix(model.body, R), f)
    return np.concatenate(
        [u, dq, dnu[:3], angular_momentum(model.body, R, dnu[3:]) + spin, rad.rate(R, memory, nu), [-nu @ rad.force(R, memory)]]
    )


class RK4:
    """Classical fourth-order Runge-Kutta on (x, q, u, L); q is renormalised after each step."""

    name, order, adaptive = "rk4", 4, False
    heave_limit, damping_limit = 2.0 * 2**0.5, 2.785  # where RK4's stability region meets the axes

    def step(self, model: Model, s: State, dt: float) -> State:
        y, t = s.as_vector(), s.t
        k1 = derivative(model, t, y)
        k2 = derivative(model, t + 0.5 * dt, y + 0.5 * dt * k1)
        k3 = derivative(model, t + 0.5 * dt, y + 0.5 * dt * k2)
        k4 = derivative(model, t + dt, y + dt * k3)
        return State.from_vector(s.t + dt, y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4))


class Adaptive:
    """scipy's solve_ivp with error control; dt is only the output interval. Reference runs."""

    adaptive = True
    method, order = "RK45", 5
    heave_limit = damping_limit = float("inf")  # error control picks stable steps

    max_evaluations = 1_000_000
    """Force evaluations allowed for one output step (about a minute): a stiff setting stops with a message, never hangs."""

    def __init__(self, rtol: float = 1e-8, atol: float = 1e-10):
        self.name = self.method.lower()
        self.rtol, self.atol = rtol, atol
        self._h: float | None = None  # last step size: the next interval starts from it
        self.max_seconds: float | None = None
        """Wall-time budget of one output step (the viewer sets it, so its thread always gets back to its commands)."""

    def step(self, model: Model, s: State, dt: float) -> State:
        from scipy.integrate import solve_ivp  # 0.6 s to import: only for the adaptive methods

        t_end = s.t + dt
        options = {"first_step": min(self._h, t_end - s.t)} if self._h else {}  # (t + dt) - t may be < dt
        deadline = time.monotonic() + self.max_seconds if self.max_seconds else math.inf
        count = [0]

        def fun(t, y):
            count[0] += 1
            if count[0] > self.max_evaluations:
                raise SimulationDiverged(f"'{self.name}' needed more than {count[0]:,} force evaluations for one {dt:g} s step at "
                                         f"t = {s.t:g} s (a stiff setting): use --integrator implicit" + ("" if self.name == "radau" else ", or radau"))  # fmt: skip
            if time.monotonic() > deadline:  # checked every evaluation: one can take 0.1 s (60 000 samples in a sea)
                raise SimulationDiverged(f"'{self.name}' took over {self.max_seconds:g} s of wall time (its budget) for one {dt:g} s step at "
                                         f"t = {s.t:g} s (a stiff setting, or many samples): use --integrator implicit, a shorter --dt or fewer samples")  # fmt: skip
            return derivative(model, t, y)

        sol = solve_ivp(fun, (s.t, t_end), s.as_vector(), method=self.method, rtol=self.rtol, atol=self.atol, **options)
        if not sol.success:
            return State(s.t + dt, *(np.full(n, np.nan) for n in (3, 4, 3, 3)))
        if sol.t.size > 1:
            self._h = float(sol.t[-1] - sol.t[-2])
        return State.from_vector(s.t + dt, sol.y[:, -1])


class RK45(Adaptive):
    """Dormand-Prince 5(4), adaptive."""

    method, order = "RK45", 5


class DOP853(Adaptive):
    """Dormand-Prince 8(5,3), adaptive: the tight-tolerance reference."""

    method, order = "DOP853", 8


class Radau(Adaptive):
    """Radau IIA, implicit, order 5, adaptive: for stiff damping."""

    method, order = "Radau", 5


INTEGRATORS = {
    cls.name if not cls.adaptive else cls.method.lower(): cls for cls in (Euler, Splitting, ImplicitSplitting, RK4, RK45, DOP853, Radau)
}


def make_integrator(name: str, rtol: float = 1e-8, atol: float = 1e-10):
    """A fresh integrator by name (adaptive ones keep a step-size hint, so never share them)."""
    cls = INTEGRATORS[name]
    return cls(rtol=rtol, atol=atol) if cls.adaptive else cls()

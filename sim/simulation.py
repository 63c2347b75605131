"""A running simulation: set up from a scene, advanced in steps, observed as Frames; stops loudly on divergence."""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass

import numpy as np

from .body import Body, make_body
from .config import SceneConfig
from .forces import Model, Params, damping_matrix, hydrostatic_energy, wetted
from .integrators import make_integrator
from .rotation import normalized, quat_multiply
from .state import State, angular_momentum, angular_velocity

CSV_COLUMNS = (
    "t,x,y,z,qw,qx,qy,qz,ux,uy,uz,wx,wy,wz,Lx,Ly,Lz,Fx,Fy,Fz,Tx,Ty,Tz,E_kin,E_grav,E_hyd,E_total,A_sub,V_sub".split(",")
)


class SimulationDiverged(RuntimeError):
    """The state went non-finite or the energy blew up; the message names the time and a likely cause."""


@dataclass(frozen=True, eq=False)
class Frame:
    """A snapshot for viewers, CSV and tests. World frame, SI units."""

    t: float
    x_world: np.ndarray
    """(3,) centre of mass, m."""
    q_world_body: np.ndarray
    """(4,) orientation (w, x, y, z)."""
    u_world: np.ndarray
    """(3,) velocity, m/s."""
    omega_world: np.ndarray
    """(3,) angular velocity, rad/s."""
    L_world: np.ndarray
    """(3,) angular momentum, kg m^2/s."""
    force_world: np.ndarray
    """(3,) total force including gravity, N."""
    torque_world: np.ndarray
    """(3,) total torque about the centre of mass, N m."""
    E_kin: float
    E_grav: float
    E_hyd: float
    submerged_area: float
    """m^2."""
    submerged_volume: float
    """m^3 (from the samples, by the divergence theorem)."""
    wet_index: np.ndarray
    """Indices of the submerged samples."""

    @property
    def E_total(self) -> float:
        return self.E_kin + self.E_grav + self.E_hyd

    def row(self) -> list[float]:
        """Values in CSV_COLUMNS order."""
        return [self.t, *self.x_world, *self.q_world_body, *self.u_world, *self.omega_world, *self.L_world, *self.force_world, *self.torque_world,
                self.E_kin, self.E_grav, self.E_hyd, self.E_total, self.submerged_area, self.submerged_volume]  # fmt: skip


def observe(model: Model, state: State, compiled: bool = False) -> Frame:
    """All diagnostics of a state, from one set of wet samples (for the sampled model with
    compiled=True, from one pass of the compiled kernel: the same numbers to round-off)."""
    body, params = model.body, model.params
    R = state.R_world_body
    omega = angular_velocity(body, R, state.L_world)
    if compiled and params.forces == "points":
        from .fast import observe_points

        wet = np.empty(body.n_samples, dtype=bool)
        d = params.damping if model.has_damping else 0.0
        rho = params.rho if model.needs_wet else 0.0
        F, T, e_hyd, a_sub, v_sub = observe_points(state.x_world, R, state.u_world, omega, body.r_body, body.n_body, body.area,
                                                   body.mass, rho, params.g, d, wet)  # fmt: skip
        return Frame(state.t, state.x_world, state.q_world_body, state.u_world, omega, state.L_world, F, T,
                     E_kin=0.5 * body.mass * float(state.u_world @ state.u_world) + 0.5 * float(omega @ state.L_world),
                     E_grav=body.mass * params.g * float(state.x_world[2]), E_hyd=e_hyd if model.has_pressure else 0.0,
                     submerged_area=a_sub, submerged_volume=v_sub, wet_index=np.flatnonzero(wet))  # fmt: skip
    wet = model.wetted(state.x_world, R)
    F, T = model.loads(wet, state.u_world, omega)
    return Frame(
        t=state.t,
        x_world=state.x_world,
        q_world_body=state.q_world_body,
        u_world=state.u_world,
        omega_world=omega,
        L_world=state.L_world,
        force_world=F,
        torque_world=T,
        E_kin=0.5 * body.mass * float(state.u_world @ state.u_world) + 0.5 * float(omega @ state.L_world),
        E_grav=body.mass * params.g * float(state.x_world[2]),
        E_hyd=hydrostatic_energy(params, wet) if model.has_pressure else 0.0,
        submerged_area=wet.submerged_area,
        submerged_volume=wet.submerged_volume,
        wet_index=wet.index,
    )


def initial_state(body: Body, scene: SceneConfig) -> State:
    init = scene.initial
    q = normalized(quat_multiply(np.asarray(init.orientation, float), body.q_input_body))
    R = State(0.0, np.zeros(3), q, np.zeros(3), np.zeros(3)).R_world_body
    L = angular_momentum(body, R, np.asarray(init.omega, float))
    return State(0.0, np.asarray(init.position, float), q, np.asarray(init.velocity, float), L)


def with_mass(body: Body, mass: float) -> Body:
    """The same geometry with another total mass (inertia scales with it)."""
    return dataclasses.replace(body, mass=float(mass), inertia=body.inertia * (mass / body.mass))


def default_backend() -> str:
    """'numba' (compiled, the default) unless FLOATSIM_BACKEND=numpy or numba is missing."""
    choice = os.environ.get("FLOATSIM_BACKEND", "numba")
    if choice == "numba":
        try:
            import numba  # noqa: F401
        except ImportError:
            return "numpy"
    return choice


class Simulation:
    """Owns body, params, integrator and state. Not thread-safe: one thread drives it.

    backend 'numba' advances fixed-step integrators many steps per call in compiled code (GIL
    released); 'numpy' is the plain reference the tests compare it with. Adaptive integrators
    and all observations (frames) always use the numpy code.
    """

    def __init__(self, scene: SceneConfig, body: Body | None = None, backend: str | None = None):
        self.scene = scene
        self.backend = backend or default_backend()
        self._frame_key: tuple | None = None
        self._frame: Frame | None = None
        body = body or make_body(scene.body, scene.base_dir)
        fluid = scene.fluid
        self.model = Model(body, Params(fluid.rho, fluid.g, fluid.damping, fluid.forces))
        self.integrator = make_integrator(scene.step.integrator, scene.step.rtol, scene.step.atol)
        self.dt = float(scene.step.dt)
        self.state = initial_state(body, scene)
        self._rebase_energy()

    @property
    def body(self) -> Body:
        return self.model.body

    @property
    def params(self) -> Params:
        return self.model.params

    def frame(self) -> Frame:
        """Diagnostics of the current state (computed once per state and model)."""
        key = (self.state, self.model)
        if self._frame_key != key:
            self._frame, self._frame_key = observe(self.model, self.state, self.backend == "numba"), key
        return self._frame

    @property
    def compiled(self) -> bool:
        """Whether steps run in the compiled kernels (fixed-step integrators on the numba backend)."""
        return self.backend == "numba" and not self.integrator.adaptive

    def step(self, n: int = 1) -> State:
        """Advance n steps; on blow-up raise SimulationDiverged, leaving the last state known good."""
        checked = self.state
        self.state = self._advance_compiled(n) if self.compiled else self._advance_numpy(n)
        energy = self.frame().E_total
        if energy - self._E_ref > 10.0 * self._E_scale:
            t, self.state = self.state.t, checked  # back to the last state that passed this check
            raise SimulationDiverged(self._diagnose(t, f"the energy blew up ({energy:.3g} J from {self._E_ref:.3g} J)"))
        return self.state

    def _advance_numpy(self, n: int) -> State:
        model, integrator, dt = self.model, self.integrator, self.dt
        state = self.state
        for _ in range(n):
            try:
                new = integrator.step(model, state, dt)
            except FloatingPointError as e:  # where np.seterr makes overflow raise, as in the tests
                new, why = None, f"floating-point error ({e})"
            else:
                why = "the state became non-finite"
            if new is None or not new.is_finite():
                self.state = state
                raise SimulationDiverged(self._diagnose(state.t + dt, why))
            state = new
        return state

    def _advance_compiled(self, n: int) -> State:
        from . import fast

        p, body = self.params, self.body
        y, done = fast.advance(self.state.as_vector(), n, self.dt, fast.SCHEMES[self.integrator.name], fast.MODELS[p.forces],
                               body.packed, body.mass, body.inertia, p.rho, p.g, p.damping)  # fmt: skip
        state = State(self.state.t + done * self.dt, y[0:3], y[3:7], y[7:10], y[10:13])
        if done < n:
            self.state = state
            raise SimulationDiverged(self._diagnose(state.t + self.dt, "the state became non-finite"))
        return state

    def _rebase_energy(self) -> None:
        """Energy reference for blow-up detection: a rise of 10x the body's energy scale
        (its weight and displaced water lifted by its own size, plus its kinetic energy) is no drift."""
        frame = self.frame()
        body, p = self.body, self.params
        self._E_ref = frame.E_total
        self._E_scale = (body.mass + p.rho * body.volume) * max(p.g, 1e-3) * 2 * body.radius + frame.E_kin

    def stability_numbers(self) -> dict[str, float]:
        """The explicit stability numbers of PHYSICS.md for the current body and dt: dt * omega_heave
        (water-plane area ~ V^(2/3)) and dt * lambda_max, the fastest damping rate: the largest
        eigenvalue of diag(M, I)^(-1/2) D diag(M, I)^(-1/2) with the whole surface wet (sway and roll
        couple, so it exceeds d A / M)."""
        body, p = self.body, self.params
        omega = math.sqrt(p.rho * p.g * body.volume ** (2 / 3) / body.mass)
        rate = 0.0
        if p.damping > 0 and p.rho > 0:
            all_wet = wetted(body, np.array([0.0, 0.0, -1e9]), np.eye(3))
            w = np.concatenate([np.full(3, body.mass), body.inertia]) ** -0.5
            rate = float(np.linalg.eigvalsh(w[:, None] * damping_matrix(p, all_wet) * w[None, :]).max())
        return {"heave": self.dt * omega, "damping": self.dt * rate}

    def warnings(self) -> list[str]:
        """Settings past the integrator's stability limits (a run may blow up, or wander without blowing up)."""
        n, integ = self.stability_numbers(), self.integrator
        out = []
        if n["damping"] > integ.damping_limit:
            out.append(f"dt*lambda_max = {n['damping']:.3g} is past the damping limit {integ.damping_limit:.3g} of '{integ.name}': "
                       f"use --integrator implicit or --dt below {self.dt * integ.damping_limit / n['damping']:.3g}")  # fmt: skip
        if n["heave"] > integ.heave_limit:
            out.append(f"dt*omega_heave = {n['heave']:.3g} is past the heave limit {integ.heave_limit:.3g} of '{integ.name}': "
                       f"use --dt below {self.dt * integ.heave_limit / n['heave']:.3g}")  # fmt: skip
        return out

    def _diagnose(self, t: float, what: str) -> str:
        numbers, integ = self.stability_numbers(), self.integrator
        if numbers["damping"] > 0.5 * integ.damping_limit:
            cause = (f"dt = {self.dt:g} s is too large for this damping with '{integ.name}' (dt*lambda_max = {numbers['damping']:.3g}, "
                     f"its limit {integ.damping_limit:.3g}): use --integrator implicit or a smaller --dt")  # fmt: skip
        elif numbers["heave"] > 0.5 * integ.heave_limit:
            cause = (f"dt = {self.dt:g} s is too large for this body's heave oscillation (dt*omega = {numbers['heave']:.3g}, "
                     f"limit {integ.heave_limit:.3g}): use a smaller --dt")  # fmt: skip
        else:
            cause = "try a smaller --dt or another --integrator"
        return f"simulation diverged at t = {t:.6g} s: {what}; likely cause: {cause}"

    # Changes between steps (the viewer's commands). Each replaces the model, never patches arrays.

    def set_params(self, **changes) -> None:
        """Replace rho, g or damping; velocities are kept."""
        self.model = Model(self.body, dataclasses.replace(self.params, **changes))
        self._rebase_energy()

    def set_density(self, density: float) -> None:
        """New mass = density x volume, same geometry; keeps u and omega (so L scales with I)."""
        R = self.state.R_world_body
        omega = angular_velocity(self.body, R, self.state.L_world)
        body = with_mass(self.body, density * self.body.volume)
        self.model = Model(body, self.params)
        self.state = dataclasses.replace(self.state, L_world=angular_momentum(body, R, omega))
        self._rebase_energy()

    def set_dt(self, dt: float) -> None:
        self.dt = float(dt)

    def set_integrator(self, name: str) -> None:
        s = self.scene.step
        self.integrator = make_integrator(name, s.rtol, s.atol)

    def reset(self, state: State | None = None) -> None:
        """Back to the scene's initial pose and velocities, keeping the current parameters."""
        self.state = state or initial_state(self.body, self.scene)
        self._rebase_energy()

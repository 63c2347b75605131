"""Several bodies on joints (a scene's [[bodies]]): a tree of rigid groups in generalised coordinates.

Each body names a parent (a body listed before it, or the world: the seabed) and a joint to it:
- `free` (world only): six coordinates of its own, its centre of mass and orientation;
- `fixed`: welded to its parent: bodies welded together are one rigid *group* and move as one body;
- `prismatic`: slides along `axis` through its starting centre of mass, turning with its parent;
- `revolute`: turns about `axis` through `pivot` (given from its starting centre of mass).
Axes are given in world axes at the start; they move with the parent. A joint's coordinate theta
(m or rad) is 0 at the start, and its take-off acts on it: Q = -k theta - c theta_dot, absorbing
c theta_dot^2 (the energy it has taken is `SystemState.absorbed`).

The coordinates: each free group's centre of mass and orientation, each one-dof joint's theta; the
velocities v stack each free group's (u, omega) (world frame, at the group's centre of mass) and each
joint's theta_dot. Every body's pose is a function of the coordinates (forward kinematics), so the
joints hold to round-off whatever the step: no drift, nothing to project. Each body's twist is
nu_b = J_b v, and with M_b its 6x6 mass in world axes, the motion is

    M_q v_dot = sum_b J_b^T (w_b - gyro_b - M_b J_b_dot v) - K theta - C theta_dot,  M_q = sum_b J_b^T M_b J_b,

w_b the body's loads (its own force model's terms, as a one-body scene), gyro_b = (0, omega x I omega).

Stepping (`step`): Stormer-Verlet on a Lie group (a drift moves each free group at its velocity, its
orientation turned by exp(h omega)), with each half kick solving the linearised kick exactly: the
loads near v as Q0 - D v (D: the terms' damping, the take-offs' dampers and the velocity-product
terms' Jacobian), M v_dot = Q0 - D v over the half step by a matrix exponential, which also gives
each take-off's absorbed energy exactly (Van Loan's integral). Second order, and stable for any
damping, as the one-body implicit scheme and the joint to the world are.

The velocity-product term J_dot v is a central difference of J v along the motion (its error ~1e-10
relative); it is left out where every Jacobian is constant (slides on slides to the world).
Each body's loads come from the numpy reference or its compiled twin (system/body_loads.py), or with `[fluid] hydro =
"linear"` from the linear hydrostatics and Froude-Krylov force about the rest pose (hydro/linear_hydro.py); the kinematics and the
kicks here are the numpy reference, whose compiled twin (system/compiled.py, kernels/system.py) a run of several bodies steps on the numba backend. Mooring lines (MoorDyn, lines/moorings.py) hold one of the bodies ([moorings] body): the runner
advances them over each step and holds their mean pull on that body over it, as for one body.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from sim.bodies.body import Body, make_body
from sim.bodies.rotation import quat_to_matrix, rotate_world, skew
from sim.bodies.state import State, initial_state
from sim.bodies.surface import wet_panels
from sim.control.laws import Law
from sim.dynamics.joints import _rotation
from sim.errors import ConfigError
from sim.hydro.bem import bodies_coefficients, default_frequencies
from sim.hydro.diffraction import Diffraction
from sim.hydro.drift import Drift
from sim.hydro.forces import Model, hydrostatic_energy
from sim.hydro.linear_hydro import LinearLoads
from sim.hydro.radiation import held_step, longest_wave, lowest_frequency, passive_memory
from sim.io.bem_file import bem_file_path, from_file
from sim.lines.moorings import moored
from sim.scene.config import SceneConfig, diffracting
from sim.system.body_loads import BodyLoads
from sim.system.frequency import raos
from sim.water.seas import make_water


@dataclass(frozen=True, eq=False)
class Member:
    """A body in its group."""

    name: str
    model: Model
    offset: np.ndarray
    """(3,) its centre of mass from the group's, group frame, m."""
    rotation: np.ndarray
    """(3, 3) its principal frame in the group's frame."""

    @property
    def body(self) -> Body:
        return self.model.body


@dataclass(frozen=True, eq=False)
class Group:
    """Bodies welded together, and their joint to the parent group (or the world). The group's frame
    is the world's axes at the start, its origin the members' centre of mass."""

    name: str
    members: tuple[Member, ...]
    kind: str
    """free, fixed, prismatic or revolute."""
    parent: int
    """Index of the parent group, -1: the world."""
    axis: np.ndarray
    """(3,) unit joint axis, parent frame."""
    pivot: np.ndarray
    """(3,) a point on a revolute axis, parent frame, from the parent's origin (world: a world point), m."""
    offset: np.ndarray
    """(3,) the group's origin at theta = 0, parent frame, from the parent's origin, m."""
    stiffness: float = 0.0
    damping: float = 0.0
    dofs: slice = field(default_factory=lambda: slice(0, 0))
    """Its columns in v."""
    coordinate: int = -1
    """Index of theta (one-dof joints) or of its free pose (free groups) in the state."""
    origin: np.ndarray = field(default_factory=lambda: np.zeros(3))
    """(3,) its origin at the start, world frame, m."""
    plane: tuple = ()
    """A planar joint's two directions of sliding, parent frame (_in_plane)."""

    @property
    def mass(self) -> float:
        return sum(m.body.mass for m in self.members)


@dataclass(frozen=True, eq=False)
class SystemState:
    t: float
    x_free: np.ndarray
    """(f, 3) each free group's centre of mass, world, m."""
    q_free: np.ndarray
    """(f, 4) each free group's orientation (w, x, y, z) from its starting one."""
    theta: np.ndarray
    """(j,) each one-dof joint's coordinate, m or rad."""
    v: np.ndarray
    """(d,) the generalised velocities."""
    absorbed: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """(j,) the energy each take-off has absorbed so far, J."""
    memory: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """The radiation memory's states (empty without radiation)."""
    E_rad: float = 0.0
    """Energy the radiated waves have carried away so far, J."""

    def is_finite(self) -> bool:
        if "_body" in self.__dict__:  # a system of one's: its body's own state
            return self.body.is_finite() and bool(np.isfinite(self.theta).all())
        return bool(all(np.isfinite(a).all() for a in (self.x_free, self.q_free, self.theta, self.v)))

    # A body alone is a system of one (system/single.py): its state is also the body's, exact (bodies/state.State), as
    # its step reached it. A state made by hand or by dataclasses.replace has none: its body is frame.body_frames'.

    @property
    def body(self) -> State:
        """A system of one's body state (x_world, q_world_body, u_world, L_world); AttributeError for several bodies."""
        own = self.__dict__.get("_body")
        if own is None:
            raise AttributeError("a system's state: each body's pose and twist is system/frame.body_frames(system, state)")
        return own

    def with_body(self, body: State) -> SystemState:
        """This state, its body's own state `body` kept beside it (a system of one's)."""
        object.__setattr__(self, "_body", body)
        return self

    @property
    def x_world(self) -> np.ndarray:
        return self.body.x_world

    @property
    def q_world_body(self) -> np.ndarray:
        return self.body.q_world_body

    @property
    def u_world(self) -> np.ndarray:
        return self.body.u_world

    @property
    def L_world(self) -> np.ndarray:
        return self.body.L_world

    @property
    def R_world_body(self) -> np.ndarray:
        return self.body.R_world_body

    def as_vector(self) -> np.ndarray:
        """The body's (13,) x, q, u, L (then the radiation memory and E_rad): a system of one's."""
        return self.body.as_vector()


@dataclass(frozen=True, eq=False)
class Pose:
    """Every body's pose and the Jacobian of its twist, for one configuration."""

    x: list
    R: list
    J: list
    """(6, d) each body's twist (u at its centre of mass, omega), world frame, per unit v."""
    cache: dict = field(default_factory=dict)
    """What depends on this configuration only (the mass matrix, the radiation's frames), once computed."""

    @property
    def stacked(self) -> np.ndarray:
        """(6k, d) every body's Jacobian, one under the other."""
        if "stacked" not in self.cache:
            self.cache["stacked"] = np.vstack(self.J)
        return self.cache["stacked"]


class SystemRadiation:
    """The radiation of several bodies solved together (Capytaine, 6 dofs per body about its starting centre of
    mass): the added mass at infinite frequency and the memory (Cummins), coupling the bodies, and the
    diffraction force on each. Linear about the starting poses (start the bodies at rest); as for one body,
    the coefficients turn with each body (its block's axes ride with it)."""

    def __init__(self, added_mass_inf: np.ndarray, memory, R0: list, diffraction=None, coefficients=None):
        self.coefficients = coefficients
        """bem.Coefficients of the solve (6k x 6k): for the frequency domain (system/frequency.py)."""
        added = added_mass_inf + memory.residual_mass if memory.residual_mass.size else added_mass_inf  # (hydro/memory_fit.py)
        self.added_mass_inf = 0.5 * (added + added.T)
        self.F, self.G, self.H = memory.compact() if memory.blocks else (memory.F, memory.G, memory.H)  # the fewest states
        self.memory = memory
        self.R0 = R0
        self.diffraction = diffraction
        self.wave_drift = None
        """drift.Drift of the bodies together (their far field gives the total), applied to `drift_root`; or None."""
        self.drift_root = 0
        """The body the drift force acts on: the root of the bodies' one tree (scene order)."""
        self.drift_lever = np.zeros(2)
        """(2,) where that body starts (horizontal, world): the drift's yaw moment is about the solve's origin."""
        self._steps: dict = {}

    @classmethod
    def of(cls, models: list, starts: list, fluid, water=None, lowest: float | None = None, base_dir: str = ".",
           far_field: bool = False) -> SystemRadiation:  # fmt: skip
        """Solved (or read) about the starting poses, the grid reaching down to `lowest` (rad/s) where that is lower
        (moored bodies: `moored_lowest`); or from the scene's `bem_file` (io/bem_file.py)."""

        if fluid.bem_file:
            c = from_file(bem_file_path(fluid.bem_file, base_dir), models, starts, fluid, water, drift=far_field)
        else:
            parts = [(m.body.mesh_vertices @ s.R_world_body.T + s.x_world, m.body.mesh_faces, s.x_world) for m, s in zip(models, starts)]
            size = max(float(np.ptp(v, axis=0).max()) for v, _, _ in parts)
            omega = default_frequencies(size, fluid.g, min_period=fluid.bem_min_period, lowest=longest_wave(fluid, lowest))
            c = bodies_coefficients(parts, fluid.rho, fluid.g, omega=omega, excitation=water is not None or far_field, far_field=far_field)
        memory = passive_memory(c, length=max(m.body.radius for m in models))
        # the solve has each body where it starts
        diffraction = None if water is None else Diffraction(c, water, [s.x_world[:2] for s in starts])
        return cls(c.added_mass_inf, memory, [s.R_world_body for s in starts], diffraction, c)

    @property
    def states(self) -> int:
        return self.F.shape[0]

    def frames(self, pose: Pose) -> np.ndarray:
        """(6k, 6k) block diagonal: each body's turn from its starting pose, on its force and its moment."""
        if "T" in pose.cache:
            return pose.cache["T"]
        T = pose.cache["T"] = np.zeros((6 * len(pose.R), 6 * len(pose.R)))
        for b, (R, R0) in enumerate(zip(pose.R, self.R0)):
            T[6 * b : 6 * b + 3, 6 * b : 6 * b + 3] = T[6 * b + 3 : 6 * b + 6, 6 * b + 3 : 6 * b + 6] = R @ R0.T
        return T

    def load(self, T: np.ndarray, x: np.ndarray, t: float, positions: list) -> np.ndarray:
        """(6k,) the memory's loads (-mu, turned with the bodies) and the diffraction force on each body where its centre of
        mass is (`positions`), world frame; the drift force of them all on the root body (`attach_drift`)."""
        f = -T @ (self.H @ x)
        if self.diffraction is not None:
            f = f + self.diffraction.force(t, positions)
        if self.wave_drift is not None:
            r = self.drift_root
            F = self.wave_drift.force(t, positions[r])
            F[5] -= self.drift_lever[0] * F[1] - self.drift_lever[1] * F[0]  # about the root's centre of mass
            f = f.copy()
            f[6 * r : 6 * r + 6] += F
        return f

    def advance(self, x: np.ndarray, nu_fit: np.ndarray, dt: float) -> np.ndarray:
        """The memory after dt with a constant twist (in the fit's axes), exactly."""
        if dt not in self._steps:
            self._steps = {dt: held_step(self.F, self.G, dt)}
        Phi, Gamma = self._steps[dt]
        return Phi @ x + Gamma @ nu_fit

    def drift(self, system: System, before: SystemState, after: SystemState, h: float) -> SystemState:
        """The memory over a drift at the velocities v: driven by the twists in the fit's axes, averaged over both
        ends; the radiated energy h nu . mu likewise (as dynamics/joints.py does for one body)."""
        p0, p1 = system.pose(before), system.pose(after)
        T0, T1 = self.frames(p0), self.frames(p1)
        nu0, nu1 = p0.stacked @ before.v, p1.stacked @ before.v
        memory = self.advance(before.memory, 0.5 * (T0.T @ nu0 + T1.T @ nu1), h)
        power = 0.5 * (nu0 @ T0 @ (self.H @ before.memory) + nu1 @ T1 @ (self.H @ memory))
        return replace(after, memory=memory, E_rad=before.E_rad + h * power)


class System:
    """The static description: groups in tree order, each body's model. `bodies[i]` follows the scene's order."""

    def __init__(self, groups: list[Group], order: list[tuple[int, int]], water, fluid, radiation: SystemRadiation | None = None):
        self.groups, self.water, self.fluid = groups, water, fluid
        self.radiation = radiation
        """The bodies' radiation together (added mass, memory and diffraction, 6 dofs per body), or None."""
        self.order = order
        """(group, member) of each body in the scene's order."""
        self._pose: tuple = (None, None)
        self.held: list = [None] * len(order)
        """Each body's load another model gives it, held over the next step ((6,) world frame, or None): the mooring lines'."""
        self.loads = [BodyLoads(m.model) for m in self.members]
        """Each body's loads near a twist (the numpy reference, or its compiled twin: use_kernels)."""
        self.n_dofs = sum(g.dofs.stop - g.dofs.start for g in groups)
        self.joints = [g for g in groups if g.kind in ("prismatic", "revolute")]
        self.laws = self.passive_laws()
        """Each joint's take-off law over the next step (control.Law): its spring and damper, or its controller's (assembly.py)."""
        self.n_free = sum(g.kind == "free" for g in groups)
        constant = []
        for g in groups:  # a slide on slides to the world has a constant Jacobian; a lone hinge to the world no velocity-product load
            constant.append(g.kind in ("fixed", "prismatic") and (g.parent < 0 or constant[g.parent]))
        lone_hinge = [g.kind == "revolute" and g.parent < 0 and not any(h.parent == i for h in groups) for i, g in enumerate(groups)]
        self.needs_bias = not all(c or h for c, h in zip(constant, lone_hinge))
        # the velocities that change some Jacobian: not a slide of a group whose parent never turns (it moves the group and
        # what hangs on it rigidly, in the parent's unturning axes: no lever arm against a turning frame changes)
        unturning = []
        for g in groups:
            unturning.append(g.kind in ("fixed", "prismatic") and (g.parent < 0 or unturning[g.parent]))
        slides = {"free": 3, "prismatic": 1, "planar": 2}
        self._turning_dofs = [i for g in groups for k, i in enumerate(range(g.dofs.start, g.dofs.stop))
                              if not (k < slides.get(g.kind, 0) and (g.parent < 0 or unturning[g.parent]))]  # fmt: skip

    def passive_laws(self) -> list:
        """Each joint's take-off as its scene gives it: its spring and damper."""

        return [Law(0.0, g.stiffness, g.damping) for g in self.joints]

    @property
    def members(self) -> list[Member]:
        return [self.groups[g].members[m] for g, m in self.order]

    @property
    def has_twin(self) -> bool:
        """Whether every body's loads have a compiled twin (the kinematics and kicks are numpy either way)."""
        return all(loads.has_twin for loads in self.loads)

    @property
    def specs(self) -> list:
        """The kernels.Spec of the bodies' loads, each once."""
        return list(dict.fromkeys(loads.spec for loads in self.loads if loads.spec is not None))

    def use_kernels(self, on: bool, expand: bool = True) -> None:
        """The bodies' loads from their compiled twins (loaded from the disk cache, or compiled now) or, off, numpy."""
        for loads in self.loads:
            loads.use_kernels(on, expand)

    # kinematics

    def group_poses(self, s: SystemState) -> tuple[list, list, list]:
        """(x, R, J) of each group's origin: forward kinematics down the tree."""
        xs, Rs, Js = [], [], []
        for g in self.groups:
            if g.parent < 0:
                xp, Rp, Jp = np.zeros(3), np.eye(3), np.zeros((6, self.n_dofs))
            else:
                xp, Rp, Jp = xs[g.parent], Rs[g.parent], Js[g.parent]
            if g.kind == "free":
                x, R = s.x_free[g.coordinate].copy(), quat_to_matrix(s.q_free[g.coordinate])
                J = np.zeros((6, self.n_dofs))
                J[:, g.dofs] = np.eye(6)
            elif g.kind == "planar":  # in the plane normal to the axis, turning about it through the group's origin
                e1, e2 = g.plane
                a, b, phi = s.theta[g.coordinate : g.coordinate + 3]
                x, R = xp + Rp @ (g.offset + a * e1 + b * e2), Rp @ _rotation(g.axis, phi)
                J = _carried(Jp, x - xp)
                J[:3, g.dofs.start] += Rp @ e1
                J[:3, g.dofs.start + 1] += Rp @ e2
                J[3:, g.dofs.start + 2] += Rp @ g.axis
            else:
                theta = s.theta[g.coordinate] if g.coordinate >= 0 else 0.0
                a = Rp @ g.axis
                if g.kind == "revolute":
                    turn = _rotation(g.axis, theta)
                    x, R = xp + Rp @ (g.pivot + turn @ (g.offset - g.pivot)), Rp @ turn
                else:
                    x, R = xp + Rp @ (g.offset + theta * g.axis if g.kind == "prismatic" else g.offset), Rp
                J = _carried(Jp, x - xp)
                if g.kind == "prismatic":
                    J[:3, g.dofs.start] += a
                elif g.kind == "revolute":
                    J[:3, g.dofs.start] += skew(a) @ (x - (xp + Rp @ g.pivot))
                    J[3:, g.dofs.start] += a
            xs.append(x)
            Rs.append(R)
            Js.append(J)
        return xs, Rs, Js

    def pose(self, s: SystemState) -> Pose:
        """Each body's pose and twist Jacobian (the scene's order). A step asks for each configuration several times:
        the last one is kept."""
        key = (s.x_free.tobytes(), s.q_free.tobytes(), s.theta.tobytes())
        if self._pose[0] != key:
            self._pose = (key, self._pose_of(s))
        return self._pose[1]

    def _pose_of(self, s: SystemState) -> Pose:
        xg, Rg, Jg = self.group_poses(s)
        x, R, J = [], [], []
        for gi, mi in self.order:
            m = self.groups[gi].members[mi]
            xm = xg[gi] + Rg[gi] @ m.offset
            x.append(xm)
            R.append(Rg[gi] @ m.rotation)
            J.append(_carried(Jg[gi], xm - xg[gi]))
        return Pose(x, R, J)

    def joint_axes(self, s: SystemState) -> list[tuple[np.ndarray, np.ndarray]]:
        """Each one-dof joint's axis now, (a point on it, its unit direction), world frame: a slide's through its group's
        origin, a hinge's through its pivot."""
        xs, Rs, _ = self.group_poses(s)
        out = []
        for g in self.joints:
            xp, Rp = (np.zeros(3), np.eye(3)) if g.parent < 0 else (xs[g.parent], Rs[g.parent])
            i = self.groups.index(g)
            out.append((xs[i] if g.kind == "prismatic" else xp + Rp @ g.pivot, Rp @ g.axis))
        return out

    def drifted(self, s: SystemState, h: float, v: np.ndarray | None = None) -> SystemState:
        """The coordinates moved at velocity v (default s.v) for time h: free groups translated and turned by exp(h omega)."""
        v = s.v if v is None else v
        x, q, theta = s.x_free.copy(), s.q_free.copy(), s.theta.copy()
        for g in self.groups:
            if g.kind == "free":
                u, w = v[g.dofs][:3], v[g.dofs][3:]
                x[g.coordinate] += h * u
                q[g.coordinate] = rotate_world(q[g.coordinate], h * w)
            elif g.coordinate >= 0:  # a one-dof joint's coordinate, or a planar joint's three
                width = g.dofs.stop - g.dofs.start
                theta[g.coordinate : g.coordinate + width] += h * v[g.dofs]
        return replace(s, x_free=x, q_free=q, theta=theta)

    # dynamics

    def mass_matrix(self, pose: Pose) -> np.ndarray:
        """M_q = sum_b J_b^T M_b J_b."""
        if "M" not in pose.cache:
            M = pose.cache["M"] = np.zeros((self.n_dofs, self.n_dofs))
            for m, R, J in zip(self.members, pose.R, pose.J):
                M += J.T @ _body_mass(m.body, R) @ J
        return pose.cache["M"]

    def inertia(self, pose: Pose) -> np.ndarray:
        """M_q with the radiation's added mass at infinite frequency, J^T T A_inf T^T J (the water moving with the bodies)."""
        if "inertia" not in pose.cache:
            M = self.mass_matrix(pose)
            if self.radiation is not None:
                J, T = pose.stacked, self.radiation.frames(pose)
                M = M + J.T @ T @ self.radiation.added_mass_inf @ T.T @ J
            pose.cache["inertia"] = M
        return pose.cache["inertia"]

    def bias(self, s: SystemState, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(b(v), db/dv): the velocity-product load b(v) = sum_b J_b^T (M_b J_b_dot v + (0, omega x I omega)) and
        its Jacobian. J_b_dot is linear in the velocity: sum_i v_i dJ_b/dt along the i-th unit velocity, each a central
        difference of J_b there, once per configuration (the two kicks at a step's end and the next one's start share
        it); b is quadratic in v."""
        n = self.n_dofs
        if not self.needs_bias:
            return np.zeros(n), np.zeros((n, n))
        pose = self.pose(s)
        if "rates" not in pose.cache:
            eps, rates = 1e-5, [[np.zeros_like(J) for J in pose.J] for _ in range(n)]
            for i in self._turning_dofs:
                e = np.zeros(n)
                e[i] = 1.0
                ahead, behind = self._pose_of(self.drifted(s, eps, e)), self._pose_of(self.drifted(s, -eps, e))
                rates[i] = [(a - c) / (2 * eps) for a, c in zip(ahead.J, behind.J)]
            pose.cache["rates"] = rates
        along_e = pose.cache["rates"]  # [dof][body]: d J_b / dt while moving at the dof's unit velocity
        along_v = [sum(v[i] * along_e[i][k] for i in self._turning_dofs) for k in range(len(pose.J))]
        b, B = np.zeros(n), np.zeros((n, n))
        for k, (m, R, J) in enumerate(zip(self.members, pose.R, pose.J)):
            Mb = _body_mass(m.body, R)
            inertia = Mb[3:, 3:]
            omega = J[3:] @ v
            b += J.T @ (Mb @ (along_v[k] @ v) + np.concatenate([np.zeros(3), skew(omega) @ (inertia @ omega)]))
            cross = along_v[k] + np.column_stack([d[k] @ v for d in along_e])  # d(J_dot(v) v)/dv
            gyro = (skew(omega) @ inertia - skew(inertia @ omega)) @ J[3:]  # d(omega x I omega)/dv
            B += J.T @ (Mb @ cross + np.vstack([np.zeros((3, n)), gyro]))
        return b, B

    def affine(self, s: SystemState, v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(M_q, Q0, D_q): the generalised load near v as Q0 - D_q v, and the mass matrix, at s's configuration and time."""
        pose = self.pose(s)
        n = self.n_dofs
        Q, D = np.zeros(n), np.zeros((n, n))
        for loads, x, R, J, held in zip(self.loads, pose.x, pose.R, pose.J, self.held):
            f, Dm = loads(x, R, s.t, J @ v)
            Q += J.T @ (f if held is None else f + held)
            if Dm is not None:
                D += J.T @ Dm @ J
        for g, law in zip(self.joints, self.laws):
            i = g.dofs.start
            Q[i] += law.force - law.stiffness * s.theta[g.coordinate]
            D[i, i] += law.damping
        M = self.inertia(pose)
        if self.radiation is not None:  # the memory's and the diffraction force
            Q += pose.stacked.T @ self.radiation.load(self.radiation.frames(pose), s.memory, s.t, pose.x)
        if self.needs_bias:  # b(v) ~ B0 v - b(v0) (b is quadratic: B0 v0 = 2 b(v0)); B0's columns exactly from b's
            b0, B = self.bias(s, v)
            Q, D = Q + b0, D + B
        return M, Q, D

    def kick(self, s: SystemState, h: float) -> SystemState:
        """v over h under M v_dot = Q0 - D v (linearised at s.v), solved exactly; each take-off's absorbed energy over it
        (its law's damper and force: the spring's energy is stored, E_spring)."""
        M, Q, D = self.affine(s, s.v)
        n, v0 = self.n_dofs, s.v
        held = [g.dofs.start for g, law in zip(self.joints, self.laws) if law.held]
        if held:  # a locked joint (a latch): its rate stays zero, the other coordinates move without it
            M, Q, D, v0 = M.copy(), Q.copy(), D.copy(), s.v.copy()
            M[held, :], M[:, held], D[held, :], D[:, held], Q[held], v0[held] = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
            M[held, held] = 1.0
        A = np.zeros((n + 1, n + 1))  # z = (v, 1): z_dot = A z
        A[:n, :n] = -np.linalg.solve(M, D)
        A[:n, n] = np.linalg.solve(M, Q)
        z = np.append(v0, 1.0)
        # Van Loan: expm([[A, z z^T], [0, -A^T]] h) has e^{Ah} ... and the integral of z z^T over the step
        big = np.zeros((2 * n + 2, 2 * n + 2))
        big[: n + 1, : n + 1], big[: n + 1, n + 1 :], big[n + 1 :, n + 1 :] = A, np.outer(z, z), -A.T
        from scipy.linalg import expm  # scipy.linalg takes 0.3 s to import: paid by the scenes that kick with it

        E = expm(big * h)
        gram = E[: n + 1, n + 1 :] @ E[: n + 1, : n + 1].T  # integral over the step of z z^T
        v = (E[: n + 1, : n + 1] @ z)[:n]
        absorbed = s.absorbed.copy()
        for g, law in zip(self.joints, self.laws):  # the damper's integral of v^2, the force's of v
            absorbed[g.coordinate] += law.damping * gram[g.dofs.start, g.dofs.start] - law.force * gram[g.dofs.start, n]
        return replace(s, v=v, absorbed=absorbed)

    def step(self, s: SystemState, h: float) -> SystemState:
        """One Stormer-Verlet step: half kick, drift (the radiation memory advanced with it), half kick (at the step's end time)."""
        half = self.kick(s, 0.5 * h)
        moved = replace(self.drifted(half, h), t=s.t + h)
        if self.radiation is not None:
            moved = self.radiation.drift(self, half, moved, h)
        return self.kick(moved, 0.5 * h)

    # energies

    def energies(self, s: SystemState) -> dict[str, float]:
        """E_kin (1/2 v^T M_q v), E_grav, E_hyd (exact: each body's mesh clipped at the surface), E_spring (the take-offs' springs), J."""
        pose = self.pose(s)
        g = self.water.g
        e_hyd = 0.0

        for m, loads, x, R in zip(self.members, self.loads, pose.x, pose.R):
            if isinstance(loads, LinearLoads):
                e_hyd += loads.energy(x, R)
            elif m.model.has("pressure"):
                e_hyd += hydrostatic_energy(self.water, wet_panels(m.body, self.water, x, R, s.t))
        M = self.inertia(pose)
        return {"E_kin": 0.5 * float(s.v @ M @ s.v),
                "E_grav": float(sum(m.body.mass * g * x[2] for m, x in zip(self.members, pose.x))), "E_hyd": e_hyd,
                "E_spring": float(sum(0.5 * law.stiffness * s.theta[j.coordinate] ** 2 for j, law in zip(self.joints, self.laws)))}  # fmt: skip


def _in_plane(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A planar joint's two directions of sliding: e1 the x axis projected on the plane normal to `normal` (y where x is
    normal to it), e2 = e1 x normal. For a normal along y: x and z (surge and heave; the turn about y is pitch)."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = helper - (helper @ normal) * normal
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(e1, normal)


def _carried(J: np.ndarray, r: np.ndarray) -> np.ndarray:
    """The Jacobian of the twist at a point r from the one J is at, on the same rigid frame: u + omega x r."""
    out = J.copy()
    out[:3] -= skew(r) @ J[3:]
    return out


def _body_mass(body: Body, R: np.ndarray) -> np.ndarray:
    """6x6 mass of a body in world axes: diag(m I, R I R^T)."""
    M = np.zeros((6, 6))
    M[:3, :3] = body.mass * np.eye(3)
    M[3:, 3:] = R @ np.diag(body.inertia) @ R.T
    return M


def build(scene: SceneConfig) -> tuple[System, SystemState]:
    """The system and its starting state from a scene with [[bodies]]: groups of welded bodies, their
    joints about the poses the scene gives (each starting at its `start` coordinate, 0 unless given), the bodies' given velocities projected on the joints' (kinetic-energy metric)."""

    water = make_water(scene.waves, scene.fluid.rho, scene.fluid.g, scene.water.current, scene.base_dir)
    names = [e.name for e in scene.bodies]
    starts, models = [], []
    for e in scene.bodies:
        fluid = e.fluid_of(scene.fluid)  # its own force model and terms' parameters
        body = replace(make_body(e.body, scene.base_dir, fluid.forces == "panels"), name=e.name)
        models.append(Model(body, water, fluid))
        starts.append(initial_state(body, replace(scene, initial=e.initial)))
    group_of: list[int] = []
    heads: list[int] = []  # the first body of each group
    for i, e in enumerate(scene.bodies):
        if e.constraint.joint == "fixed" and e.parent != "world":
            group_of.append(group_of[names.index(e.parent)])
        else:
            group_of.append(len(heads))
            heads.append(i)
    groups, order, dof, n_free, n_joints = [], [None] * len(names), 0, 0, 0
    for gi, head in enumerate(heads):
        e = scene.bodies[head]
        idx = [i for i in range(len(names)) if group_of[i] == gi]
        mass = sum(models[i].body.mass for i in idx)
        origin = sum(models[i].body.mass * starts[i].x_world for i in idx) / mass
        members = []
        for k, i in enumerate(idx):
            members.append(Member(names[i], models[i], starts[i].x_world - origin, starts[i].R_world_body))
            order[i] = (gi, k)
        c = e.constraint
        parent = -1 if e.parent == "world" else group_of[names.index(e.parent)]
        parent_origin = np.zeros(3) if parent < 0 else groups[parent].origin
        axis = np.asarray(c.axis, float)
        kind = c.joint
        width = {"free": 6, "fixed": 0, "prismatic": 1, "revolute": 1, "planar": 3}[kind]
        coordinate = n_free if kind == "free" else (n_joints if width else -1)
        n_free += kind == "free"
        n_joints += width if kind != "free" else 0
        group = Group(e.name, tuple(members), kind, parent, axis / max(np.linalg.norm(axis), 1e-300),
                      starts[head].x_world + np.asarray(c.pivot, float) - parent_origin, origin - parent_origin, float(c.pto_stiffness),
                      float(c.pto_damping), slice(dof, dof + width), coordinate, origin,
                      _in_plane(axis / np.linalg.norm(axis)) if kind == "planar" else ())  # fmt: skip
        groups.append(group)
        dof += width
    radiation = None
    if drifting(scene) and sum(g.parent < 0 for g in groups) != 1:
        raise ConfigError("[waves] drift = true takes bodies joined in one tree (the far field gives the drift of them all together); "
                          f"this scene has {sum(g.parent < 0 for g in groups)} on the world: each one's own drift is not built")  # fmt: skip
    if scene.fluid.radiation == "bem":
        radiation = SystemRadiation.of(models, starts, scene.fluid, water if diffracting(scene) else None,
                                       moored_lowest(scene, models, starts), scene.base_dir, far_field=drifting(scene))  # fmt: skip
    system = System(groups, order, water, scene.fluid, radiation)
    if scene.fluid.hydro == "linear":
        system.loads = [LinearLoads(m, s.x_world, s.R_world_body) for m, s in zip(models, starts)]
    x_free = np.array([g.origin for g in groups if g.kind == "free"]).reshape(-1, 3)
    q_free = np.tile([1.0, 0.0, 0.0, 0.0], (n_free, 1))
    theta = np.zeros(n_joints)  # each joint's start ([constraint] start): a planar joint's on its turn
    for g, e in zip(groups, (scene.bodies[h] for h in heads)):
        if e.constraint.start is not None:
            theta[g.coordinate + (2 if g.kind == "planar" else 0)] = e.constraint.start
    rest = SystemState(0.0, x_free, q_free, theta, np.zeros(system.n_dofs), np.zeros(n_joints),
                       np.zeros(0 if radiation is None else radiation.states))  # fmt: skip
    if radiation is not None and drifting(scene):
        attach_drift(system, replace(rest, theta=np.zeros_like(theta)), water)
    return system, replace(rest, v=_projected(system, rest, starts))


def drifting(scene) -> bool:
    """Whether the scene's bodies feel the waves' drift force: asked for, with radiation from the BEM, in waves."""
    return bool(scene.waves.drift) and scene.fluid.radiation == "bem" and scene.waves.kind != "still"


def attach_drift(system: System, rest: SystemState, water) -> None:
    """The drift force of the bodies together (drift.Drift, from the solve's far field with the bodies moving as the
    linear system does: system_frequency.raos) on the root of their one tree, about its centre of mass. The far field
    gives the total on them all; bodies apart (several trees) would need each body's own, from the near field."""

    roots = [i for i, g in enumerate(system.groups) if g.parent < 0]  # one (build checks)
    rad = system.radiation
    rad.wave_drift = Drift(rad.coefficients, water, raos(system, rest))
    rad.drift_root = system.order.index((roots[0], 0))
    rad.drift_lever = np.asarray(system.pose(rest).x[rad.drift_root], float)[:2].copy()


def moored_body(scene) -> int | None:
    """The index of the body the scene's mooring lines hold ([moorings] body, else the first); None without lines."""

    if not moored(scene):
        return None
    return [e.name for e in scene.bodies].index(scene.moorings.body) if scene.moorings.body else 0


def lines_scene(scene, k: int):
    """The scene as the lines of body k see it: its [initial] table is that body's (where their fairleads start); a body
    alone's scene is its own."""
    return replace(scene, initial=scene.bodies[k].initial) if scene.bodies else scene


def moored_lowest(scene, models: list, starts: list) -> float | None:
    """Where a moored scene's solve grid starts: below half the lines' natural frequency for all the bodies' mass
    (the slowest swing carries every body the joints hold; the whole mass errs low, the safe side); None unmoored.
    The scene's start is its rest with the lines in place (a preset sets the moored body's mass so that it is)."""

    k = moored_body(scene)
    if k is None or scene.moorings.attach:  # (lines on several bodies: the grid is not extended for their slow swing)
        return None
    q = np.asarray(scene.bodies[k].initial.orientation, float)
    return lowest_frequency(
        lines_scene(scene, k), sum(m.body.mass for m in models), starts[k].x_world, quat_to_matrix(q / np.linalg.norm(q))
    )


def _projected(system: System, s: SystemState, starts) -> np.ndarray:
    """The generalised velocities nearest the bodies' given twists in the kinetic-energy metric: M_q^-1 sum_b J_b^T M_b nu_b."""
    if not system.n_dofs:
        return np.zeros(0)
    pose = system.pose(s)
    rhs = np.zeros(system.n_dofs)
    for m, R, J, st in zip(system.members, pose.R, pose.J, starts):
        omega = R @ ((R.T @ st.L_world) / m.body.inertia)
        rhs += J.T @ _body_mass(m.body, R) @ np.concatenate([st.u_world, omega])
    return np.linalg.solve(system.mass_matrix(pose), rhs)

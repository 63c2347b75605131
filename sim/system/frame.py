"""What a run shows at one instant, for viewers, CSV and tests: one Frame for every scene. Its Readings: each joint's
take-off (joint_reading), the mooring lines' pull, shape and energy (lines_reading), the radiated energy; each body's
BodyFrame (its pose and twist; observed: its loads, wet surface and energies, `observe`); the energies of all. Its `row`
is the CSV's, by `csv_line` (a body alone's columns since the start; several bodies' each body's pose and twist)."""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from sim.bodies.rotation import matrix_to_quat, normalized
from sim.bodies.state import State, angular_momentum, angular_velocity
from sim.bodies.surface import wet_panels
from sim.hydro.forces import Model, hydrostatic_energy
from sim.system.tree import System, SystemState

CSV_COLUMNS = (
    "t,x,y,z,qw,qx,qy,qz,ux,uy,uz,wx,wy,wz,Lx,Ly,Lz,Fx,Fy,Fz,Tx,Ty,Tz,E_kin,E_grav,E_hyd,E_total,A_sub,V_sub,eta,E_rad,E_hyd_model,P_diff,"
    "Fx_moor,Fy_moor,Fz_moor,T_fair_max,P_pto,E_pto,F_pto".split(",")
)


def csv_line(values) -> str:
    """One CSV line of a frame's `columns` or `row`: the one format of `floatsim run --out` and the viewer's recording."""
    return ",".join(v if isinstance(v, str) else f"{v:.12g}" for v in values)


def joint_reading(name: str, law, theta: float, rate: float, absorbed: float) -> tuple:
    """A joint's (name, theta, rate, P_pto, E_pto, F_pto) under its take-off's law F = f - k theta - c theta_dot
    (control/laws.Law): P_pto the power it absorbs, (c theta_dot - f) theta_dot (its spring's is stored, not absorbed),
    E_pto the energy absorbed so far, F_pto its force on the coordinate (N, a hinge's N m)."""
    return (name, theta, rate, (law.damping * rate - law.force) * rate, absorbed, law.at(theta, rate))


def lines_reading(moorings, shapes: bool = True) -> dict:
    """The Readings of the mooring lines (lines/moorings.Moorings, or None): their pull on the bodies, each fairlead's
    tension, their energy, and (if `shapes`) line_shapes."""
    if moorings is None:
        return {}
    each = moorings.fairlead_tensions()
    total = moorings.loads[:, :3].sum(axis=0) if len(moorings.bodies) > 1 else moorings.load[:3]
    out = dict(
        mooring=(*(float(f) for f in total), float(each.max(initial=0.0)), *(float(t) for t in each)), line_energy=moorings.energy_now()
    )
    return {**out, **line_shapes(moorings)} if shapes else out


def line_shapes(moorings) -> dict:
    """Each line's nodes and their tensions (Readings.lines and line_tensions): asked of MoorDyn node by node, so only
    for a frame that is shown."""
    return dict(lines=tuple(moorings.lines()), line_tensions=tuple(moorings.line_tensions()))


@dataclass(frozen=True, eq=False, kw_only=True)
class Readings:
    """What every scene's frame reads, whatever its bodies: the joints' take-offs, the mooring lines, the radiated energy.
    World frame, SI units."""

    t: float
    joints: tuple = ()
    """Each joint's (name, theta, rate, P_pto, E_pto, F_pto) (joint_reading), in the order of the system's joints."""
    joint_axes: tuple = ()
    """Each joint's axis: (a point on it, its unit direction), world frame: the axis a prismatic joint slides along or a
    revolute one turns about (none when free or fixed)."""
    mooring: tuple = ()
    """The lines' pull on the bodies (Fx, Fy, Fz, N), the largest fairlead tension and each fairlead's, in the order of
    the lines' input (N); empty without lines."""
    lines: tuple = ()
    """Each mooring line's nodes, (segments + 1, 3), world frame, m: anchor end first."""
    line_tensions: tuple = ()
    """Each mooring line's tension at those nodes, (segments + 1,), N."""
    line_energy: tuple = ()
    """(E_lines, D_lines): the energy the lines store and have dissipated, J ([moorings] energy; empty otherwise):
    E_total + E_pto + E_lines + D_lines is conserved in still water without damping, drag or radiation."""
    E_rad: float = 0.0
    """Energy carried away by the radiated waves so far, J (E_total + E_rad is conserved without damping and drag)."""
    gauges: tuple = ()
    """Each wave gauge's (name, x, y, eta, record or None): where it stands, the sea's elevation there, m, and a
    measured record's (scene/gauges.py), in the scene's order."""

    @property
    def E_pto(self) -> float:
        """The energy the take-offs have absorbed so far, J."""
        return sum(j[4] for j in self.joints)


@dataclass(frozen=True, eq=False, kw_only=True)
class BodyFrame:
    """One body at an instant: its pose and twist, and where it is observed (every body of Simulation.parts, a body
    alone's run always) its loads, wet surface and energies. World frame, SI units."""

    name: str = "body"
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
    force_world: np.ndarray | None = None
    """(3,) total force including gravity, N (None: not observed, as each of several bodies in the run's own frame)."""
    torque_world: np.ndarray | None = None
    """(3,) total torque about the centre of mass, N m."""
    E_kin: float = 0.0
    E_grav: float = 0.0
    E_hyd: float = 0.0
    """The physical hydrostatic potential rho g * integral of (-z) dV over the body's mesh clipped at
    the water surface, J: exact, and the same whatever the force model."""
    submerged_area: float = 0.0
    """m^2."""
    submerged_volume: float = 0.0
    """m^3 (from the samples, by the divergence theorem)."""
    wet_index: np.ndarray | None = None
    """Indices of the samples under the water surface (for either force model)."""
    eta: float = 0.0
    """Water surface elevation at the centre of mass's (x, y), m."""
    E_hyd_model: float | None = None
    """The force model's own hydrostatic potential, -(rho g / 2) * sum of w z^2 nu_z over its wet nodes, J:
    E_hyd for panels; for points and cells their quadrature of it (None: as E_hyd)."""
    P_diff: float = 0.0
    """The power of the diffraction force on the body, F_d . (u, omega), W (0 without diffraction)."""

    @property
    def E_hyd_of_model(self) -> float:
        """The hydrostatic energy the running force model conserves (the sampled models' own), J."""
        return self.E_hyd if self.E_hyd_model is None else self.E_hyd_model

    @property
    def E_total(self) -> float:
        """Kinetic, gravity and exact hydrostatic energy, J (constant without damping, drag, waves or radiation)."""
        return self.E_kin + self.E_grav + self.E_hyd


BODY_FIELDS = frozenset(f.name for f in fields(BodyFrame)) | {"E_hyd_of_model"}
"""What a frame of one body reads of its body (Frame.__getattr__)."""


@dataclass(frozen=True, eq=False, kw_only=True)
class Frame(Readings):
    """What a run shows at one instant, for every scene: its Readings, each body's BodyFrame and the energies of all. A
    frame of one body (a body alone's run, or one of several in Simulation.parts) reads that body's fields as its own:
    frame.x_world, frame.force_world, frame.wet_index. World frame, SI units."""

    bodies: tuple = ()
    """Each body's BodyFrame, in the scene's order."""
    E_kin: float = 0.0
    """The bodies' kinetic energy, the water moving with them included (1/2 nu^T A_inf nu where radiating), J."""
    E_grav: float = 0.0
    E_hyd: float = 0.0
    """The exact hydrostatic potential of all the bodies, J (BodyFrame.E_hyd)."""
    E_spring: float = 0.0
    """The energy the take-offs' springs of several bodies hold, J (a body alone's take-off: in E_pto's stead, 0)."""
    alone: bool = True
    """A body alone's run: its CSV has the body's columns since the start (several bodies: each body's pose and twist)."""

    def __getattr__(self, name: str):
        bodies = self.__dict__.get("bodies", ())
        if name in BODY_FIELDS and len(bodies) == 1:
            return getattr(bodies[0], name)
        raise AttributeError(f"{name!r}: a frame of several bodies reads each body's in .bodies" if name in BODY_FIELDS else name)

    @property
    def mooring_force(self) -> np.ndarray:
        """(3,) the mooring lines' pull on the bodies, N (in a body's force_world too; zero without lines)."""
        return np.array(self.mooring[:3]) if self.mooring else np.zeros(3)

    @property
    def fairlead_tensions(self) -> np.ndarray:
        """(k,) each fairlead's tension, N."""
        return np.array(self.mooring[4:])

    @property
    def P_pto(self) -> float:
        """The power the first joint's take-off absorbs, W (0 without a joint that moves)."""
        return self.joints[0][3] if self.joints else 0.0

    @property
    def F_pto(self) -> float:
        """The first take-off's force on its joint's coordinate, N (a hinge's moment, N m), by its controller's law."""
        return self.joints[0][5] if self.joints else 0.0

    @property
    def joint_axis(self) -> tuple | None:
        """(point, unit direction), world frame: the first joint's axis (None: free or fixed)."""
        return self.joint_axes[0] if self.joint_axes else None

    @property
    def E_total(self) -> float:
        """Kinetic, gravity, exact hydrostatic and the take-offs' springs, J (E_total + E_pto + E_rad is conserved without
        damping, drag and waves)."""
        return self.E_kin + self.E_grav + self.E_hyd + self.E_spring

    def columns(self) -> list[str]:
        """The CSV's header (`row` gives the values). A body alone: CSV_COLUMNS. Several bodies: t; each body's pose and
        twist; each joint's coordinate, rate, take-off power and energy; the lines' pull; the energies. Then E_lines and
        D_lines where the lines' energy is counted."""
        lines = ["E_lines", "D_lines"] if self.line_energy else []
        lines += [c for name, *_, record in self.gauges for c in (f"eta_{name}", *((f"record_{name}",) if record is not None else ()))]
        if self.alone:
            return list(CSV_COLUMNS) + lines
        cols = ["t"]
        for b in self.bodies:
            cols += [f"{b.name}_{c}" for c in ("x", "y", "z", "qw", "qx", "qy", "qz", "ux", "uy", "uz", "wx", "wy", "wz")]
        for name, *_ in self.joints:
            cols += [f"{name}_{c}" for c in ("theta", "rate", "P_pto", "E_pto", "F_pto")]
        if self.mooring:
            cols += ["Fx_moor", "Fy_moor", "Fz_moor", "T_fair_max", *(f"T_fair_{i + 1}" for i in range(len(self.mooring) - 4))]
        return cols + ["E_kin", "E_grav", "E_hyd", "E_spring", "E_pto", "E_total", "E_rad"] + lines

    def row(self) -> list[float]:
        """Values in `columns` order."""
        if self.alone:
            (b,) = self.bodies
            return [self.t, *b.x_world, *b.q_world_body, *b.u_world, *b.omega_world, *b.L_world, *b.force_world, *b.torque_world,
                    b.E_kin, b.E_grav, b.E_hyd, self.E_total, b.submerged_area, b.submerged_volume, b.eta, self.E_rad,
                    b.E_hyd_of_model, b.P_diff, *self.mooring_force, float(self.fairlead_tensions.max(initial=0.0)), self.P_pto, self.E_pto,
                    self.F_pto, *self.line_energy, *self.gauge_values]  # fmt: skip
        out = [self.t]
        for b in self.bodies:
            out += [*b.x_world, *b.q_world_body, *b.u_world, *b.omega_world]
        for _, *values in self.joints:
            out += values
        energies = [self.E_kin, self.E_grav, self.E_hyd, self.E_spring, self.E_pto, self.E_total, self.E_rad]
        return out + [*self.mooring, *energies, *self.line_energy, *self.gauge_values]

    @property
    def gauge_values(self) -> list[float]:
        """The gauges' columns' values: each one's eta, and its record where it has one."""
        return [v for *_, eta, record in self.gauges for v in (eta, *((record,) if record is not None else ()))]


def of_body(body: BodyFrame, t: float, **readings) -> Frame:
    """The frame of one body (a body alone's run with its `readings`, or one of several bodies by itself)."""
    return Frame(t=t, bodies=(body,), E_kin=body.E_kin, E_grav=body.E_grav, E_hyd=body.E_hyd, **readings)


def observe(model: Model, state: State, kernels=None, expand: bool = True, name: str = "body") -> BodyFrame:
    """All diagnostics of a state, from one wet surface (with `kernels`, a kernels.specialised copy for the
    model, from the compiled twin: the same numbers to round-off, or to the bound of its sea expansion;
    expand=False: the direct sum)."""
    body, water = model.body, model.water
    R = state.R_world_body
    omega = angular_velocity(body, R, state.L_world)
    E_kin = 0.5 * body.mass * float(state.u_world @ state.u_world) + 0.5 * float(omega @ state.L_world)
    E_grav = body.mass * water.g * float(state.x_world[2])
    if model.radiation is not None:  # the water moving with the body: 1/2 nu^T A_inf nu
        nu = np.concatenate([state.u_world, omega])
        E_kin += (
            0.5 * float(nu @ (model.radiation.mass_matrix(body, R) @ nu))
            - 0.5 * body.mass * float(state.u_world @ state.u_world)
            - 0.5 * float(omega @ state.L_world)
        )
    common = dict(name=name, x_world=state.x_world, q_world_body=state.q_world_body, u_world=state.u_world, omega_world=omega,
                  L_world=state.L_world, E_kin=E_kin, E_grav=E_grav, eta=float(water.elevation(state.x_world[:2], state.t)))  # fmt: skip
    if kernels is not None:
        from sim.kernels import Model as Packed  # numba's import (0.6 s): only where compiled kernels run
        from sim.kernels import pack, sea_pack  # numba's import (0.6 s): only where compiled kernels run

        wet = np.empty(body.n_samples, dtype=bool)
        packed = Packed(body.packed, body.mass, body.inertia, pack(model)[1])
        F, T, e_hyd, a_sub, v_sub = kernels.simulation.observe(state.x_world, R, state.t, state.u_world, omega, packed, sea_pack(water, body, expand),
                                                               wet)  # fmt: skip
        wet_index = np.flatnonzero(wet)
    else:
        wet = model.wetted(state.x_world, R, state.t)
        F, T = model.loads(wet, state.u_world, omega, state.t)
        e_hyd, a_sub, v_sub = model.hydrostatic_energy(wet), wet.submerged_area, wet.submerged_volume
        wet_index = (
            wet.index
            if wet.triangles is None
            else np.flatnonzero(water.height_above_surface(state.x_world + body.r_body @ R.T, state.t) < 0)
        )
    p_diff = 0.0
    if model.radiation is not None:
        f = model.radiation.load(R, state.memory, state.t, state.x_world)
        F, T = F + f[:3], T + f[3:]
        if model.radiation.diffraction is not None:
            p_diff = float(model.radiation.diffraction.force(state.t, state.x_world) @ np.concatenate([state.u_world, omega]))
    exact = e_hyd if model.fluid.forces == "panels" else physical_hydrostatic_energy(model, state.x_world, R, state.t, kernels)
    return BodyFrame(**common, force_world=F, torque_world=T, E_hyd=exact, submerged_area=a_sub, submerged_volume=v_sub, wet_index=wet_index,
                 E_hyd_model=None if model.fluid.forces == "panels" else e_hyd, P_diff=p_diff)  # fmt: skip


def physical_hydrostatic_energy(model: Model, x: np.ndarray, R: np.ndarray, t: float, kernels=None) -> float:
    """rho g * integral of (-z) dV over the body's mesh clipped at the water surface, J (0 without pressure)."""
    if not model.has("pressure"):
        return 0.0
    if kernels is not None and model.water.flat:
        return float(kernels.surface.exact_hydrostatic_energy(x, R, model.body.packed, model.water.rho * model.water.g))
    return hydrostatic_energy(model.water, wet_panels(model.body, model.water, x, R, t))


def body_frames(system: System, s: SystemState) -> list[BodyFrame]:
    """Each body's pose and twist (its BodyFrame, not observed), world frame."""
    pose = system.pose(s)
    out = []
    for m, x, R, J in zip(system.members, pose.x, pose.R, pose.J):
        nu = J @ s.v
        out.append(BodyFrame(name=m.name, x_world=x, q_world_body=normalized(matrix_to_quat(R)), u_world=nu[:3], omega_world=nu[3:],
                             L_world=angular_momentum(m.body, R, nu[3:])))  # fmt: skip
    return out


def system_frame(system: System, s: SystemState, moorings=None) -> Frame:
    """The frame of several bodies (system/tree.py) at the state s, with the mooring lines (lines/moorings.Moorings) or none."""
    joints = tuple(joint_reading(g.name, law, float(s.theta[g.coordinate]), float(s.v[g.dofs.start]), float(s.absorbed[g.coordinate]))
                   for g, law in zip(system.joints, system.laws))  # fmt: skip
    return Frame(t=s.t, joints=joints, joint_axes=tuple(system.joint_axes(s)), E_rad=float(s.E_rad), **lines_reading(moorings),
                 bodies=tuple(body_frames(system, s)), **system.energies(s), alone=False)  # fmt: skip

"""What a run shows at one instant, for viewers, CSV and tests: a body's Frame (pose, velocities, loads, energies), and a
scene of several bodies' AssemblyFrame (each body's pose and twist, each joint's take-off, the lines, the energies)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from sim.bodies.state import State, angular_velocity
from sim.bodies.surface import wet_panels
from sim.hydro.forces import Model, hydrostatic_energy
from sim.system.tree import body_frames

CSV_COLUMNS = (
    "t,x,y,z,qw,qx,qy,qz,ux,uy,uz,wx,wy,wz,Lx,Ly,Lz,Fx,Fy,Fz,Tx,Ty,Tz,E_kin,E_grav,E_hyd,E_total,A_sub,V_sub,eta,E_rad,E_hyd_model,P_diff,"
    "Fx_moor,Fy_moor,Fz_moor,T_fair_max,P_pto,E_pto,F_pto".split(",")
)


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
    """The physical hydrostatic potential rho g * integral of (-z) dV over the body's mesh clipped at
    the water surface, J: exact, and the same whatever the force model."""
    submerged_area: float
    """m^2."""
    submerged_volume: float
    """m^3 (from the samples, by the divergence theorem)."""
    wet_index: np.ndarray
    """Indices of the samples under the water surface (for either force model)."""
    eta: float = 0.0
    """Water surface elevation at the centre of mass's (x, y), m."""
    E_rad: float = 0.0
    """Energy carried away by the radiated waves so far, J (E_total + E_rad is conserved without damping and drag)."""
    E_hyd_model: float | None = None
    """The force model's own hydrostatic potential, -(rho g / 2) * sum of w z^2 nu_z over its wet nodes, J:
    E_hyd for panels; for points and cells their quadrature of it (None: as E_hyd)."""
    P_diff: float = 0.0
    """The power of the diffraction force on the body, F_d . (u, omega), W (0 without diffraction)."""
    mooring_force: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))
    """(3,) the mooring lines' pull on the body, N (in force_world too; zero without lines)."""
    fairlead_tensions: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    """(k,) each fairlead's tension, N."""
    lines: tuple = ()
    """Each mooring line's nodes, (segments + 1, 3), world frame, m: anchor end first."""
    line_tensions: tuple = ()
    """Each mooring line's tension at those nodes, (segments + 1,), N."""
    line_energy: tuple = ()
    """(E_lines, D_lines): the energy the lines store and have dissipated, J ([moorings] energy; empty otherwise):
    E_total + E_lines + D_lines is conserved in still water without damping, drag or radiation."""
    P_pto: float = 0.0
    """The power the joint's take-off absorbs, (c theta_dot - f) theta_dot of its law F = f - k theta - c theta_dot, W (its
    spring's power is stored, not absorbed; 0 without a joint)."""
    E_pto: float = 0.0
    """The energy it has absorbed so far, J."""
    F_pto: float = 0.0
    """The take-off's force on the joint's coordinate, N (a hinge's moment, N m), by its controller's law."""
    joint_axis: tuple | None = None
    """(point, unit direction), world frame: the axis a prismatic joint slides along or a revolute one turns
    about (None: free or fixed)."""

    @property
    def joint_axes(self) -> list:
        """The joint's axis as a list (none when free or fixed), as a scene of several bodies lists its joints'."""
        return [] if self.joint_axis is None else [self.joint_axis]

    @property
    def E_hyd_of_model(self) -> float:
        """The hydrostatic energy the running force model conserves (the sampled models' own), J."""
        return self.E_hyd if self.E_hyd_model is None else self.E_hyd_model

    @property
    def E_total(self) -> float:
        """Kinetic, gravity and exact hydrostatic energy, J (constant without damping, drag, waves or radiation)."""
        return self.E_kin + self.E_grav + self.E_hyd

    def columns(self) -> list[str]:
        """The CSV's header (CSV_COLUMNS, then E_lines and D_lines where the lines' energy is counted): `row` gives the values."""
        return list(CSV_COLUMNS) + (["E_lines", "D_lines"] if self.line_energy else [])

    def row(self) -> list[float]:
        """Values in CSV_COLUMNS order."""
        return [self.t, *self.x_world, *self.q_world_body, *self.u_world, *self.omega_world, *self.L_world, *self.force_world, *self.torque_world,
                self.E_kin, self.E_grav, self.E_hyd, self.E_total, self.submerged_area, self.submerged_volume, self.eta, self.E_rad,
                self.E_hyd_of_model, self.P_diff, *self.mooring_force, float(self.fairlead_tensions.max(initial=0.0)), self.P_pto, self.E_pto,
                self.F_pto, *self.line_energy]  # fmt: skip


def observe(model: Model, state: State, kernels=None, expand: bool = True) -> Frame:
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
    common = dict(t=state.t, x_world=state.x_world, q_world_body=state.q_world_body, u_world=state.u_world, omega_world=omega,
                  L_world=state.L_world, E_kin=E_kin, E_grav=E_grav, eta=float(water.elevation(state.x_world[:2], state.t)), E_rad=state.E_rad)  # fmt: skip
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
    return Frame(**common, force_world=F, torque_world=T, E_hyd=exact, submerged_area=a_sub, submerged_volume=v_sub, wet_index=wet_index,
                 E_hyd_model=None if model.fluid.forces == "panels" else e_hyd, P_diff=p_diff)  # fmt: skip


def physical_hydrostatic_energy(model: Model, x: np.ndarray, R: np.ndarray, t: float, kernels=None) -> float:
    """rho g * integral of (-z) dV over the body's mesh clipped at the water surface, J (0 without pressure)."""
    if not model.has("pressure"):
        return 0.0
    if kernels is not None and model.water.flat:
        return float(kernels.surface.exact_hydrostatic_energy(x, R, model.body.packed, model.water.rho * model.water.g))
    return hydrostatic_energy(model.water, wet_panels(model.body, model.water, x, R, t))


@dataclass(frozen=True, eq=False)
class AssemblyFrame:
    t: float
    bodies: list
    """Each body's dict: name, x, q, u, omega (body_frames)."""
    joints: list
    """Each joint's (name, theta, rate, P_pto, E_pto, F_pto): P_pto the power its take-off absorbs (its law's damper and
    force: the spring's is stored, E_spring), F_pto its force by its controller's law."""
    energies: dict
    joint_axes: list = field(default_factory=list)
    """Each joint's axis: (a point on it, its unit direction), world frame (System.joint_axes)."""
    lines: tuple = ()
    """Each mooring line's nodes, (segments + 1, 3), world frame (none without lines)."""
    mooring: tuple = ()
    """The lines' pull on the moored body (Fx, Fy, Fz, N), the largest fairlead tension and each fairlead's, in the order of
    the lines' input (N); empty without lines."""
    E_rad: float = 0.0
    """Energy the radiated waves have carried away so far, J (0 without radiation)."""
    line_tensions: tuple = ()
    """Each mooring line's tension at its nodes, (segments + 1,), N (none without lines)."""
    line_energy: tuple = ()
    """(E_lines, D_lines): the energy the lines store and have dissipated, J ([moorings] energy; empty otherwise)."""

    @property
    def E_pto(self) -> float:
        return sum(j[4] for j in self.joints)

    @property
    def E_total(self) -> float:
        """Kinetic, gravity, hydrostatic and the take-offs' springs, J (E_total + E_pto is conserved without damping, drag and waves)."""
        return sum(self.energies.values())

    def columns(self) -> list[str]:
        """The CSV's header: t; each body's pose and twist; each joint's coordinate, rate, take-off power and energy; the lines'
        pull; the energies, E_rad the radiated waves' (as the one-body CSV's: E_total + E_pto + E_rad is conserved without
        damping, drag and waves)."""
        cols = ["t"]
        for b in self.bodies:
            cols += [f"{b['name']}_{c}" for c in ("x", "y", "z", "qw", "qx", "qy", "qz", "ux", "uy", "uz", "wx", "wy", "wz")]
        for name, *_ in self.joints:
            cols += [f"{name}_{c}" for c in ("theta", "rate", "P_pto", "E_pto", "F_pto")]
        if self.mooring:
            cols += ["Fx_moor", "Fy_moor", "Fz_moor", "T_fair_max", *(f"T_fair_{i + 1}" for i in range(len(self.mooring) - 4))]
        return (
            cols
            + ["E_kin", "E_grav", "E_hyd", "E_spring", "E_pto", "E_total", "E_rad"]
            + (["E_lines", "D_lines"] if self.line_energy else [])
        )

    def row(self) -> list[float]:
        out = [self.t]
        for b in self.bodies:
            out += [*b["x"], *b["q"], *b["u"], *b["omega"]]
        for _, *values in self.joints:
            out += values
        out += list(self.mooring)
        e = self.energies
        return out + [e["E_kin"], e["E_grav"], e["E_hyd"], e["E_spring"], self.E_pto, self.E_total, self.E_rad, *self.line_energy]


def assembly_frame(system, s, moorings=None) -> AssemblyFrame:
    """The frame of several bodies (system/tree.py) at the state s, with the mooring lines (lines/moorings.Moorings) or none."""
    joints = []
    for g, law in zip(system.joints, system.laws):
        theta, rate = float(s.theta[g.coordinate]), float(s.v[g.dofs.start])
        joints.append((g.name, theta, rate, (law.damping * rate - law.force) * rate, float(s.absorbed[g.coordinate]), law.at(theta, rate)))
    lines, pull, tensions, energy = (), (), (), ()
    if moorings is not None:
        energy = moorings.energy_now()
        lines, tensions = tuple(moorings.lines()), tuple(moorings.line_tensions())
        each = moorings.fairlead_tensions()
        total = moorings.loads[:, :3].sum(axis=0) if len(moorings.bodies) > 1 else moorings.load[:3]
        pull = (*total, float(each.max()), *(float(t) for t in each))
    return AssemblyFrame(s.t, body_frames(system, s), joints, system.energies(s), system.joint_axes(s), lines, pull, float(s.E_rad), tensions,
                         energy)  # fmt: skip

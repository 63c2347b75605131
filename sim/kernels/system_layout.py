"""The array contract of the compiled system step (kinematics.py, system/tree.py): a system.System packed once into
arrays. Plain Python, no numba.

`Tree`: the groups in tree order (a parent before its children) and the bodies in the scene's order. `Linear`: the
bodies' linear loads (linear_hydro.LinearLoads), empty where the loads come from elsewhere. `Memory`: the radiation's
added mass, its memory's exact step over a drift (sparse rows) and the diffraction force, empty without radiation.
Every vector is in world axes unless said otherwise; joint axes, pivots, offsets and plane directions in the parent's
frame as in system.Group.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from sim.hydro.linear_hydro import LinearLoads
from sim.hydro.radiation import held_step

FREE, FIXED, PRISMATIC, REVOLUTE, PLANAR = 0, 1, 2, 3, 4
KINDS = {"free": FREE, "fixed": FIXED, "prismatic": PRISMATIC, "revolute": REVOLUTE, "planar": PLANAR}
EPS = 1e-5
"""The central differences' step of the velocity-product term (System.bias's)."""


class Tree(NamedTuple):
    kind: np.ndarray
    """(g,) int64, KINDS."""
    parent: np.ndarray
    """(g,) int64, -1: the world."""
    axis: np.ndarray
    """(g, 3) unit joint axis."""
    pivot: np.ndarray
    """(g, 3) a point on a revolute axis, m."""
    offset: np.ndarray
    """(g, 3) the group's origin at theta = 0 from its parent's, m."""
    plane: np.ndarray
    """(g, 2, 3) a planar joint's two directions of sliding (zeros for the others)."""
    dof: np.ndarray
    """(g,) int64 its first column in v."""
    width: np.ndarray
    """(g,) int64 its number of columns in v (free 6, planar 3, one-dof 1, fixed 0)."""
    coordinate: np.ndarray
    """(g,) int64 its index in x_free / q_free (free) or in theta (joints), -1: none."""
    stiffness: np.ndarray
    """(g,) the take-off's spring, N/m or N m/rad."""
    damping: np.ndarray
    """(g,) the take-off's damper, N s/m or N m s/rad."""
    force: np.ndarray
    """(g,) the take-off's force held over the step, N or N m (a controller's: control/laws.py)."""
    held: np.ndarray
    """(g,) 1.0 where the joint is locked over the step (a latch), else 0.0."""
    joints: np.ndarray
    """(j,) int64 the groups with a take-off (prismatic and revolute: System.joints)."""
    group: np.ndarray
    """(k,) int64 each body's group."""
    member_offset: np.ndarray
    """(k, 3) each body's centre of mass from its group's origin, group frame, m."""
    member_rotation: np.ndarray
    """(k, 3, 3) each body's principal frame in its group's."""
    mass: np.ndarray
    """(k,) kg."""
    inertia: np.ndarray
    """(k, 3) principal moments, kg m^2."""
    turning: np.ndarray
    """(t,) int64 the velocities that change some Jacobian (System._turning_dofs)."""
    n_dofs: int
    needs_bias: bool


class Linear(NamedTuple):
    on: bool
    """Whether the bodies' loads are these (else they come per kick from outside)."""
    f0: np.ndarray
    """(k, 6) the pose loads at rest in still water."""
    C: np.ndarray
    """(k, 6, 6) -df/dxi at rest."""
    D0: np.ndarray
    """(k, 6, 6) the linear damping at rest (zeros: none)."""
    x0: np.ndarray
    """(k, 3) rest centres of mass, m."""
    R0: np.ndarray
    """(k, 3, 3) rest orientations."""
    X_re: np.ndarray
    """(k, n, 6) each component's Froude-Krylov amplitude, real part."""
    X_im: np.ndarray
    """(k, n, 6) imaginary part."""
    k: np.ndarray
    """(n, 2) wave vectors, rad/m."""
    omega: np.ndarray
    """(n,) frequencies as met, rad/s."""
    ramp: float
    """The sea's ramp, s."""


class Memory(NamedTuple):
    on: bool
    added: np.ndarray
    """(6k, 6k) the added mass at infinite frequency (SystemRadiation.added_mass_inf)."""
    R0: np.ndarray
    """(k, 3, 3) each body's starting orientation (the fit's axes)."""
    Phi: tuple
    """The memory's exact step over a drift, sparse rows (indptr, indices, values) (radiation.held_step)."""
    Gamma: tuple
    """Its input over the drift, sparse rows."""
    H: tuple
    """Its output mu = H x, sparse rows."""
    diffracting: bool
    A_re: np.ndarray
    """(n, 6k) the diffraction amplitudes referred to the world's origin, real part (diffraction.Diffraction.amplitude)."""
    A_im: np.ndarray
    """(n, 6k) imaginary part."""
    k: np.ndarray
    """(n, 2) wave vectors, rad/m."""
    omega: np.ndarray
    """(n,) rad/s."""
    ramp: float
    drifting: bool
    """Whether the waves' drift force acts (SystemRadiation.wave_drift: drift.Drift of the bodies together)."""
    E_re: np.ndarray
    """(m, 6) its envelope's real parts (drift.Drift.envelope: A and A' of F_x, F_y, M_z in turn), m components."""
    E_im: np.ndarray
    """(m, 6) imaginary parts."""
    drift_k: np.ndarray
    """(m, 2) the components' wave vectors, rad/m."""
    drift_omega: np.ndarray
    """(m,) rad/s."""
    drift_ramp: float
    drift_root: int
    """The body it acts on (scene order)."""
    drift_lever: np.ndarray
    """(2,) where that body starts: the yaw moment is moved there from the world's origin."""


def sparse_rows(M: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(indptr, indices, values) of M's nonzero entries, row by row: the memory is block diagonal."""
    M = np.asarray(M, float)
    rows, cols = np.nonzero(M)
    indptr = np.zeros(M.shape[0] + 1, np.int64)
    np.add.at(indptr, rows + 1, 1)
    return np.cumsum(indptr), cols.astype(np.int64), np.ascontiguousarray(M[rows, cols])


def take_offs(system) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(stiffness, damping, force, held) of each group's take-off: its joint's law over the next step (System.laws), zeros
    for the rest."""
    out = np.zeros((4, len(system.groups)))
    for g, law in zip(system.joints, system.laws):
        out[:, system.groups.index(g)] = (law.stiffness, law.damping, law.force, float(law.held))
    return out[0], out[1], out[2], out[3]


def tree_pack(system) -> Tree:
    groups, members = system.groups, system.members
    g, k = len(groups), len(members)
    plane = np.zeros((g, 2, 3))
    for i, gr in enumerate(groups):
        if gr.plane:
            plane[i] = gr.plane
    three = lambda attr: np.array([getattr(gr, attr) for gr in groups], float).reshape(g, 3)  # noqa: E731
    ints = lambda values: np.array(values, np.int64).reshape(-1)  # noqa: E731
    return Tree(ints([KINDS[gr.kind] for gr in groups]), ints([gr.parent for gr in groups]), three("axis"), three("pivot"), three("offset"),
                plane, ints([gr.dofs.start for gr in groups]), ints([gr.dofs.stop - gr.dofs.start for gr in groups]),
                ints([gr.coordinate for gr in groups]), *take_offs(system), ints([groups.index(j) for j in system.joints]),
                ints([gi for gi, _ in system.order]), np.array([m.offset for m in members], float).reshape(k, 3),
                np.array([m.rotation for m in members], float).reshape(k, 3, 3), np.array([m.body.mass for m in members], float),
                np.array([m.body.inertia for m in members], float).reshape(k, 3), ints(system._turning_dofs), int(system.n_dofs),
                bool(system.needs_bias))  # fmt: skip


def linear_pack(system) -> Linear:
    """The bodies' linear loads where every body has them (`[fluid] hydro = "linear"`), else an empty pack."""
    loads, k = system.loads, len(system.loads)
    if not all(isinstance(lo, LinearLoads) for lo in loads):
        return Linear(False, np.zeros((k, 6)), np.zeros((k, 6, 6)), np.zeros((k, 6, 6)), np.zeros((k, 3)), np.zeros((k, 3, 3)),
                      np.zeros((k, 0, 6)), np.zeros((k, 0, 6)), np.zeros((0, 2)), np.zeros(0), 0.0)  # fmt: skip
    n = len(loads[0].omega)
    return Linear(True, np.array([lo.f0 for lo in loads]), np.array([lo.C for lo in loads]),
                  np.array([np.zeros((6, 6)) if lo.D0 is None else lo.D0 for lo in loads]), np.array([lo.x0 for lo in loads]),
                  np.array([lo.R0 for lo in loads]), np.array([lo.X.real for lo in loads]).reshape(k, n, 6),
                  np.array([lo.X.imag for lo in loads]).reshape(k, n, 6), np.ascontiguousarray(loads[0].k, dtype=float).reshape(-1, 2),
                  np.asarray(loads[0].omega, float), float(system.water.ramp if n else 0.0))  # fmt: skip


def memory_pack(system, dt: float) -> Memory:
    """The radiation's arrays for drifts of dt (an empty pack without radiation)."""
    rad, k = system.radiation, len(system.members)
    none = sparse_rows(np.zeros((0, 0)))
    if rad is None:
        return Memory(False, np.zeros((6 * k, 6 * k)), np.zeros((k, 3, 3)), none, none, none, False, np.zeros((0, 6 * k)),
                      np.zeros((0, 6 * k)), np.zeros((0, 2)), np.zeros(0), 0.0, *drift_pack(None))  # fmt: skip
    Phi, Gamma = held_step(rad.F, rad.G, dt)
    d = rad.diffraction
    if d is None:
        amplitude, wave_k, omega, ramp = np.zeros((0, 6 * k), complex), np.zeros((0, 2)), np.zeros(0), 0.0
    else:
        amplitude, wave_k, omega, ramp = d.amplitude, d.k, d.omega, d.ramp
    return Memory(True, np.ascontiguousarray(rad.added_mass_inf, dtype=float), np.array(rad.R0, float).reshape(k, 3, 3), sparse_rows(Phi),
                  sparse_rows(Gamma), sparse_rows(rad.H), d is not None, np.ascontiguousarray(amplitude.real),
                  np.ascontiguousarray(amplitude.imag), np.ascontiguousarray(wave_k, dtype=float).reshape(-1, 2),
                  np.asarray(omega, float), float(ramp), *drift_pack(rad))  # fmt: skip


def drift_pack(rad) -> tuple:
    """Memory's drift fields: the radiation's wave drift (SystemRadiation.wave_drift), or none."""
    drift = None if rad is None else rad.wave_drift
    if drift is None:
        return False, np.zeros((0, 6)), np.zeros((0, 6)), np.zeros((0, 2)), np.zeros(0), 0.0, 0, np.zeros(2)
    re, im = drift.kernel_arrays()
    return (True, re, im, np.ascontiguousarray(drift.k, dtype=float).reshape(-1, 2), np.asarray(drift.omega, float), float(drift.ramp),
            int(rad.drift_root), np.asarray(rad.drift_lever, float).copy())  # fmt: skip

"""The radiation memory of the Cummins equation as a small linear system fitted to BEM coefficients.

Cummins (1962): the water's reaction to a body's motion nu(t) (6 dofs) is
    -A_inf nu' - integral_0^t K(t - s) nu(s) ds,   K(t) = (2/pi) integral_0^inf B(omega) cos(omega t) d omega,
whose transfer function is K(i omega) = B(omega) + i omega (A(omega) - A_inf) (Ogilvie's relations).
The memory is fitted passive (B_fit(omega) positive semi-definite at every frequency: hydro/memory_fit.py) as one
block-diagonal state-space system x' = F x + G nu, mu = H x, the memory force being -mu: a few states per
entry and pole replace the convolution over the whole past.
"""

from __future__ import annotations

import math

import numpy as np

from sim.bodies.rotation import quat_to_matrix
from sim.errors import ConfigError
from sim.hydro import bem
from sim.hydro.diffraction import NO_DIFFRACTION, Diffraction
from sim.hydro.drift import NO_DRIFT, Drift, body_rao
from sim.hydro.equilibrium import pull_stiffness, scene_rest
from sim.hydro.forces import Model
from sim.hydro.linear_hydro import LinearLoads
from sim.hydro.memory_fit import EntryFit, RadiationMemory, fit_memory, transfer
from sim.lines.moorings import moored
from sim.water.seas import StillWater

__all__ = ["EntryFit", "Radiation", "RadiationMemory", "fit_memory", "held_step", "make_radiation", "transfer"]


def held_step(F: np.ndarray, G: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """(Phi, Gamma): x' = F x + G nu over dt with nu held constant, exactly: x(dt) = Phi x + Gamma nu."""
    from scipy.linalg import expm

    n, d = G.shape
    aug = np.zeros((n + d, n + d))
    aug[:n, :n], aug[:n, n:] = F, G
    E = expm(aug * dt)
    return E[:n, :n], E[:n, n:]


class Radiation:
    """A body's added mass and radiation memory in its own frame, for the integrators.

    In the Cummins equation (M_RB + A_inf) nu' = f - mu, mu = H x the memory force, x' = F x + G nu:
    A_inf and the memory are linear about the rest pose and ride with the body, so the generalised
    mass rotates with it. The memory keeps the axes it was fitted in (the world's at rest, R0 from
    the body frame), where each state is fed by one twist component and feeds one load component;
    twists and loads are turned into those axes and back. The gyroscopic terms of the added mass
    (Munk moments) are left out: second order in the motion, like the linearisation itself."""

    def __init__(self, added_mass_body: np.ndarray, memory: RadiationMemory, R0: np.ndarray, diffraction=None, coefficients=None,
                 drift=None):  # fmt: skip
        T0 = self._frame(np.asarray(R0, float))  # the fit's residual mass (hydro/memory_fit.py), turned into the body frame
        added = added_mass_body + T0.T @ memory.residual_mass @ T0 if memory.residual_mass.size else added_mass_body
        self.added_mass_body = 0.5 * (added + added.T)  # symmetric in theory; the BEM's is to ~1e-4
        self.F, self.G, self.H = memory.F, memory.G, memory.H
        self.memory = memory
        self.R0 = np.asarray(R0, float)
        self.diffraction = diffraction
        """diffraction.Diffraction (the scattered waves' force in the scene's sea), or None."""
        self.coefficients = coefficients
        """bem.Coefficients the memory was fitted to (world axes at rest), or None."""
        self.drift = drift
        """drift.Drift (the waves' mean and slow drift force), or None."""
        self._steps: dict[float, tuple[np.ndarray, np.ndarray]] = {}

    @property
    def states(self) -> int:
        return self.F.shape[0]

    @staticmethod
    def _frame(R: np.ndarray) -> np.ndarray:
        T = np.zeros((6, 6))
        T[:3, :3] = T[3:, 3:] = R
        return T

    def mass_matrix(self, body, R: np.ndarray) -> np.ndarray:
        """(6, 6) M_RB + A_inf in world axes: diag(M, R I R^T) plus the rotated added mass."""
        T = self._frame(R)
        Mg = T @ self.added_mass_body @ T.T
        Mg[:3, :3] += body.mass * np.eye(3)
        Mg[3:, 3:] += (R * body.inertia) @ R.T
        return Mg

    def force(self, R: np.ndarray, x: np.ndarray) -> np.ndarray:
        """(6,) the memory's force and torque on the body, world frame: -mu turned from the fit's axes."""
        return -self._frame(R @ self.R0.T) @ (self.H @ x)

    def load(self, R: np.ndarray, x: np.ndarray, t: float, position: np.ndarray) -> np.ndarray:
        """(6,) every load of the BEM model at time t: the memory's force, plus the diffraction and drift forces in waves
        with the centre of mass at `position` (world, m)."""
        f = self.force(R, x)
        if self.diffraction is not None:
            f = f + self.diffraction.force(t, position)
        return f if self.drift is None else f + self.drift.force(t, position)

    def rate(self, R: np.ndarray, x: np.ndarray, nu: np.ndarray) -> np.ndarray:
        """x' = F x + G nu_fit."""
        return self.F @ x + self.G @ self.fit_velocity(R, nu)

    def advance(self, x: np.ndarray, nu_fit: np.ndarray, dt: float) -> np.ndarray:
        """The memory after dt with a constant twist (in the fit's axes), exactly (zero-order hold)."""
        if dt not in self._steps:
            self._steps = {dt: held_step(self.F, self.G, dt)}  # one dt at a time
        Phi, Gamma = self._steps[dt]
        return Phi @ x + Gamma @ nu_fit

    def fit_velocity(self, R: np.ndarray, nu: np.ndarray) -> np.ndarray:
        """A world twist in the fit's axes (the rest pose's world axes, riding with the body)."""
        return self._frame(R @ self.R0.T).T @ nu

    def kernel_arrays(self, body, dt: float) -> tuple:
        """(Minv_b, W_b, S_b, Phi, F, start, col, row, gamma, g, h, R0, Xre, Xim, waves, ramp) for the compiled kernels
        (kernels/radiation.py). The memory is block diagonal, one block per fitted entry, each block
        fed by one twist component and feeding one load component: Phi and F go as bands (row i holds
        its block's columns start[i], start[i] + 1, ...), Gamma, G and H as one number per state with
        its twist component col[i] and load component row[i]; then the diffraction force's (diffraction.Diffraction.kernel_arrays:
        empty without diffraction) and the drift force's (drift.Drift.kernel_arrays)."""
        Mb = self.added_mass_body + np.diag([body.mass] * 3 + list(body.inertia))
        lam, V = np.linalg.eigh(Mb)
        self.advance(np.zeros(self.states), np.zeros(6), dt)  # fills the exact step for dt
        Phi, Gamma = self._steps[dt]
        entries = self.memory.entries
        sizes = [len(e.G) for e in entries]
        start = np.repeat(np.cumsum([0, *sizes[:-1]]), sizes).astype(np.int64)
        col = np.repeat([e.col for e in entries], sizes).astype(np.int64)
        row = np.repeat([e.row for e in entries], sizes).astype(np.int64)
        states = np.arange(self.states)
        offsets = np.arange(max(sizes))
        inside = offsets < np.repeat(sizes, sizes)[:, None]
        cols = np.where(inside, start[:, None] + offsets, 0)
        band = lambda M: np.where(inside, M[states[:, None], cols], 0.0)  # noqa: E731
        dense = (np.linalg.inv(Mb), (V / np.sqrt(lam)) @ V.T, (V * np.sqrt(lam)) @ V.T, band(Phi), band(self.F))
        per_state = (Gamma[states, col], self.G[states, col], self.H[row, states])

        waves = NO_DIFFRACTION if self.diffraction is None else self.diffraction.kernel_arrays()
        if self.drift is not None and self.diffraction is None:  # the components' phases without a diffraction force
            d = self.drift
            waves = (np.zeros((0, 6)), np.zeros((0, 6)), np.ascontiguousarray(np.column_stack([d.omega, d.k])), d.ramp)
        drift = NO_DRIFT if self.drift is None else self.drift.kernel_arrays()
        return (*(np.ascontiguousarray(a, dtype=float) for a in dense), start, col, row, *(np.ascontiguousarray(a, dtype=float) for a in per_state),
                np.ascontiguousarray(self.R0), *waves, *drift)  # fmt: skip


MOORED_QUANTUM = 1e-3
"""A moored body's BEM solve is about its rest height rounded to this share of its size (the draft's effect on the
coefficients is that share of them: far below the solve's own accuracy)."""


def lowest_frequency(scene, mass: float, rest: np.ndarray, R_input: np.ndarray) -> float | None:
    """Below half the slowest natural frequency the mooring lines give a body of `mass` at rest (its centre of mass at
    `rest`, its lines' frame R_input to world), rad/s: sqrt(k / M) / 2, k their smaller horizontal stiffness (the added
    mass lowers the true one by less than half while A_11 < 3 M), down to a quarter octave (lines changed a little keep
    the grid); None when the lines do not hold it horizontally."""

    try:
        K = pull_stiffness(scene, rest, R_input)
    except ValueError:  # lines that cannot reach: their own check says so, before the run
        return None
    k = float(np.linalg.eigvalsh(0.5 * (K + K.T)).min())
    if not k > 0.0:
        return None
    return float(2.0 ** (np.floor(4 * np.log2(0.5 * np.sqrt(k / mass))) / 4))


def passive_memory(c, **fit):
    """The radiation memory fitted to the solve `c` (memory_fit.fit_memory); a solve no passive memory fits is one
    ConfigError line, not a traceback."""

    try:
        return fit_memory(c, **fit)
    except ValueError as e:
        raise ConfigError(f"radiation = 'bem': {e} from this solve's coefficients (a finer mesh, or bodies further apart than "
                          "their panels are long, may mend the solve)") from None  # fmt: skip


def longest_wave(fluid, lowest: float | None) -> float | None:
    """The solve grid's lowest frequency: the lines' (`lowest`) or the scene's bem_max_period's, whichever is lower."""
    if fluid.bem_max_period is None:
        return lowest
    asked = 2.0 * math.pi / fluid.bem_max_period
    return asked if lowest is None else min(asked, lowest)


def make_radiation(body, scene, R0: np.ndarray, progress: bool = True, water=None, drift=None, joint_at=None) -> Radiation:
    """The body's radiation model about its rest pose at orientation R0 in the scene (BEM coefficients from the
    shipped files, the cache or Capytaine; then the memory fit), in the body frame. The rest pose holds the mooring
    lines' pull too, and the frequency grid reaches down past their slowest natural frequency. With `water` (waves),
    also the diffraction force in that sea (phased where the body is at each instant); with `drift` (waves), the
    mean and slow drift force in that sea (drift.Drift, the body moving with its linear response); `joint_at(rest)`: the
    body's joint to the world at that rest pose (dynamics.joints.WorldJoint.of_scene's, or None), which that response needs."""
    fluid = scene.fluid
    rest = scene_rest(body, scene, R0)
    z = round(float(rest[2]), 9)  # to the nanometre: the same rest pose gives the same mesh and cache key
    if moored(scene):  # to a thousandth of the body's size: lines changed a little (a stiffer line, more segments) keep the solve
        z = round(z / (MOORED_QUANTUM * body.radius)) * MOORED_QUANTUM * body.radius
    vertices = body.mesh_vertices @ R0.T + [0.0, 0.0, z]
    omega = None
    if fluid.bem_min_period is not None or fluid.bem_max_period is not None or moored(scene):
        lowest = lowest_frequency(scene, body.mass, rest, R0 @ quat_to_matrix(body.q_input_body).T) if moored(scene) else None
        lowest = longest_wave(fluid, lowest)
        omega = bem.default_frequencies(float(np.ptp(vertices, axis=0).max()), fluid.g, min_period=fluid.bem_min_period, lowest=lowest)
    c = bem.radiation_coefficients(vertices, body.mesh_faces, fluid.rho, fluid.g, omega=omega, progress=progress, center=(0.0, 0.0, z),
                               excitation=water is not None, far_field=drift is not None)  # fmt: skip
    memory = passive_memory(c)
    T0 = Radiation._frame(R0)  # world-at-rest dofs = T0 body dofs
    if not memory.entries:
        raise ConfigError("radiation = 'bem': this body radiates no waves here (no damping in the BEM results; is g zero?)")
    drifting = (
        None if drift is None else Drift(c, drift, linear_response(body, scene, c, rest, R0, None if joint_at is None else joint_at(rest)))
    )
    return Radiation(T0.T @ c.added_mass_inf @ T0, memory, R0, None if water is None else Diffraction(c, water), c, drifting)


def linear_response(body, scene, c, rest: np.ndarray, R0: np.ndarray, joint=None) -> np.ndarray:
    """(n, m, 6) the body's motion per unit wave amplitude at the solve's frequencies and headings (drift.body_rao):
    its rigid-body mass, the stiffness and linear damping of its own force model at rest (linear_hydro.LinearLoads:
    the exact pressure's hydrostatics), its `joint` to the world (dynamics.joints.WorldJoint) and take-off. The mooring lines' stiffness is left out: their
    natural frequencies lie far below the waves'."""

    still = LinearLoads(Model(body, StillWater(scene.fluid.rho, scene.fluid.g), scene.fluid), rest, R0)
    mass = np.zeros((6, 6))
    mass[:3, :3] = body.mass * np.eye(3)
    mass[3:, 3:] = (R0 * body.inertia) @ R0.T
    damping = np.zeros((6, 6)) if still.D0 is None else still.D0
    stiffness = still.C.copy()
    J = None
    if joint is not None:
        J = np.zeros((6, 0)) if joint.dofs == 0 else joint.jacobian(rest).reshape(6, joint.dofs)  # held: no motion
        stiffness += joint.stiffness * (J @ J.T)
        damping = damping + joint.damping * (J @ J.T)
    return body_rao(c, mass, stiffness, damping, J)


def misfit_note(memory, tol: float = 0.02) -> str | None:
    """A line for a run's summary when the memory's fit misses `tol` (fit_memory's): how far its B and A are from the
    BEM's somewhere on the grid, each against its entry's peak; None when it holds."""
    error_B, error_A = memory.error
    if max(error_B, error_A) <= tol:
        return None
    why = " (bodies apart, as in a farm: their interaction oscillates with frequency; docs/farms.md)" if memory.G.shape[1] > 6 else ""
    return (
        f"radiation memory: the fit ({memory.states} states) misses the BEM's damping by up to {error_B:.0%} and its added mass by "
        f"up to {error_A:.0%} of their peaks somewhere on the grid (asked {tol:.0%}): the time-domain radiation is that far off "
        f"at those frequencies{why}"
    )

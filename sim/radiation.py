"""The radiation memory of the Cummins equation as a small linear system fitted to BEM coefficients.

Cummins (1962): the water's reaction to a body's motion nu(t) (6 dofs) is
    -A_inf nu' - integral_0^t K(t - s) nu(s) ds,   K(t) = (2/pi) integral_0^inf B(omega) cos(omega t) d omega,
whose transfer function is K(i omega) = B(omega) + i omega (A(omega) - A_inf) (Ogilvie's relations).
Each entry K_ij that matters is fitted by a stable rational function of s = i omega with relative
degree 1 and a zero at s = 0 (K vanishes at both ends of the spectrum), by frequency-domain least
squares with Sanathanan-Koerner reweighting (Perez & Fossen, 2009, Ocean Engineering 36: 1130-1140),
raising the order until the fit reproduces B and A within the tolerance asked. The entries become
one block-diagonal state-space system x' = F x + G nu, mu = H x, the memory force being -mu: a few
states per entry replace the convolution over the whole past.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .bem import Coefficients


@dataclass(frozen=True, eq=False)
class EntryFit:
    """K_ij(s) = P(s) / Q(s) for one (row i, column j), as a state-space block."""

    row: int
    col: int
    F: np.ndarray
    """(n, n) system matrix (companion form), eigenvalues in the left half plane."""
    G: np.ndarray
    """(n,) input vector (the velocity nu_j enters here)."""
    H: np.ndarray
    """(n,) output vector (mu_i = H x)."""
    error: float
    """Largest misfit of B and A over the grid, relative to the entry's largest |K(i omega)|."""

    def response(self, omega: np.ndarray) -> np.ndarray:
        """K(i omega) of the fitted block."""
        n = len(self.G)
        return np.array([self.H @ np.linalg.solve(1j * w * np.eye(n) - self.F, self.G) for w in omega])


@dataclass(frozen=True, eq=False)
class RadiationMemory:
    """Every fitted entry stacked: x' = F x + G nu, memory force (d,) = -H x (d = 6 per body)."""

    F: np.ndarray
    G: np.ndarray
    """(states, d)"""
    H: np.ndarray
    """(d, states)"""
    entries: tuple[EntryFit, ...]
    added_mass_inf: np.ndarray

    @property
    def states(self) -> int:
        return self.F.shape[0]

    def response(self, omega: np.ndarray) -> np.ndarray:
        """(n, d, d) K(i omega) of the whole fitted system (d = 6 per body)."""
        d = self.G.shape[1]
        out = np.zeros((len(omega), d, d), complex)
        for e in self.entries:
            out[:, e.row, e.col] = e.response(omega)
        return out


def transfer(c: Coefficients) -> np.ndarray:
    """(n, 6, 6) K(i omega) = B(omega) + i omega (A(omega) - A_inf) from BEM coefficients."""
    return c.damping + 1j * c.omega[:, None, None] * (c.added_mass - c.added_mass_inf)


def _fit_rational(omega: np.ndarray, K: np.ndarray, order: int, iterations: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """(p, q): K(s) ~ s (p[0] + p[1] s + ... ) / (q[0] + q[1] s + ... + s^order), least squares in
    the complex plane with Sanathanan-Koerner weights; unstable poles reflected into the left half plane."""
    s = 1j * omega
    scale = np.abs(K).max()
    weight = np.ones(len(omega))
    n_p = order - 1  # numerator s * (degree order - 2): relative degree 1, zero at s = 0
    for _ in range(iterations):
        # unknowns p_0..p_{n_p-1}, q_0..q_{order-1}:  s P~(s) - K Q~(s) = K s^order
        cols = [s ** (k + 1) for k in range(n_p)] + [-K / scale * s**k for k in range(order)]
        M = np.array(cols).T * weight[:, None]
        rhs = K / scale * s**order * weight
        sol, *_ = np.linalg.lstsq(np.vstack([M.real, M.imag]), np.concatenate([rhs.real, rhs.imag]), rcond=None)
        p, q = sol[:n_p] * scale, np.append(sol[n_p:], 1.0)
        weight = 1.0 / np.abs(np.polyval(q[::-1], s))
    poles = np.roots(q[::-1])
    if np.any(poles.real >= 0):  # reflect, then refit the numerator for the stable denominator
        poles = -np.maximum(np.abs(poles.real), 1e-6 * np.abs(poles)) + 1j * poles.imag  # strictly inside
        q = np.real(np.poly(poles))[::-1]
        Q = np.polyval(q[::-1], s)
        M = np.array([s ** (k + 1) / Q for k in range(n_p)]).T
        sol, *_ = np.linalg.lstsq(np.vstack([M.real, M.imag]), np.concatenate([K.real, K.imag]), rcond=None)
        p = sol
    return p, q


def _companion(p: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """State-space (F, G, H) of s P~(s) / Q(s) in controllable canonical form."""
    n = len(q) - 1
    F = np.zeros((n, n))
    F[:-1, 1:] = np.eye(n - 1)
    F[-1, :] = -q[:-1]
    G = np.zeros(n)
    G[-1] = 1.0
    H = np.zeros(n)
    H[1 : len(p) + 1] = p  # numerator coefficients of s^1 .. s^(n-1)
    return F, G, H


def _misfit(c: Coefficients, i: int, j: int, Kfit: np.ndarray) -> float:
    K = transfer(c)[:, i, j]
    return float(np.abs(Kfit - K).max() / np.abs(K).max())


def fit_memory(c: Coefficients, tol: float = 0.02, max_order: int = 10, length: float = 1.0) -> RadiationMemory:
    """Fit every entry whose damping matters with the lowest order meeting `tol`. A diagonal entry
    matters when its peak |B_ii| is above 1e-3 of the largest translational one (rotations: times
    length^2, the body's size, so a sphere's numerical-noise roll damping is left out); a coupling
    (i, j) when both its diagonals matter and its peak is above 5 % of sqrt(B_ii B_jj). So no coupling
    is fitted without the damping that keeps the whole passive."""
    K = transfer(c)
    d = K.shape[1]
    peak = np.abs(c.damping).max(axis=0)
    diag = np.diag(peak)
    scale = diag.reshape(-1, 6)[:, :3].max()
    keep = diag > 1e-3 * scale * np.tile([1.0, 1.0, 1.0, length**2, length**2, length**2], d // 6)
    entries = []
    for i in range(d):
        for j in range(d):
            if not (keep[i] and keep[j]) or (i != j and peak[i, j] <= 0.05 * np.sqrt(diag[i] * diag[j])):
                continue
            best = None
            for order in range(2, max_order + 1):
                p, q = _fit_rational(c.omega, K[:, i, j], order)
                F, G, H = _companion(p, q)
                trial = EntryFit(i, j, F, G, H, 0.0)
                err = _misfit(c, i, j, trial.response(c.omega))
                if best is None or err < best.error:
                    best = EntryFit(i, j, F, G, H, err)
                if err <= tol:
                    break
            entries.append(best)
    n = sum(len(e.G) for e in entries)
    F, G, H = np.zeros((n, n)), np.zeros((n, d)), np.zeros((d, n))
    k = 0
    for e in entries:
        m = len(e.G)
        F[k : k + m, k : k + m] = e.F
        G[k : k + m, e.col] = e.G
        H[e.row, k : k + m] = e.H
        k += m
    return RadiationMemory(F, G, H, tuple(entries), c.added_mass_inf)


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

    def __init__(self, added_mass_body: np.ndarray, memory: RadiationMemory, R0: np.ndarray, diffraction=None):
        self.added_mass_body = 0.5 * (added_mass_body + added_mass_body.T)  # symmetric in theory; the BEM's is to ~1e-4
        self.F, self.G, self.H = memory.F, memory.G, memory.H
        self.memory = memory
        self.R0 = np.asarray(R0, float)
        self.diffraction = diffraction
        """diffraction.Diffraction (the scattered waves' force in the scene's sea), or None."""
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

    def load(self, R: np.ndarray, x: np.ndarray, t: float) -> np.ndarray:
        """(6,) every load of the BEM model at time t: the memory's force, plus the diffraction force in waves."""
        f = self.force(R, x)
        return f if self.diffraction is None else f + self.diffraction.force(t)

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
        """(Minv_b, W_b, S_b, Phi, F, start, col, row, gamma, g, h, R0, Xre, Xim, omega) for the compiled kernels
        (kernels/radiation.py). The memory is block diagonal, one block per fitted entry, each block
        fed by one twist component and feeding one load component: Phi and F go as bands (row i holds
        its block's columns start[i], start[i] + 1, ...), Gamma, G and H as one number per state with
        its twist component col[i] and load component row[i]; then the diffraction force's complex amplitude per
        wave component, real and imaginary parts, and the components' frequencies (empty without diffraction)."""
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
        d = self.diffraction
        waves = (d.amplitude.real, d.amplitude.imag, d.omega) if d is not None else (np.zeros((0, 6)), np.zeros((0, 6)), np.zeros(0))
        return (*(np.ascontiguousarray(a, dtype=float) for a in dense), start, col, row, *(np.ascontiguousarray(a, dtype=float) for a in per_state),
                np.ascontiguousarray(self.R0), *(np.ascontiguousarray(a, dtype=float) for a in waves))  # fmt: skip


def make_radiation(body, fluid, R0: np.ndarray, progress: bool = True, water=None, rest_xy=(0.0, 0.0)) -> Radiation:
    """The body's radiation model about its rest pose at orientation R0 (BEM coefficients from the
    shipped files, the cache or Capytaine; then the memory fit), in the body frame. With `water` (waves),
    also the diffraction force in that sea, referenced to the rest position `rest_xy`."""
    from .bem import default_frequencies, radiation_coefficients
    from .diffraction import Diffraction
    from .equilibrium import rest_height
    from .errors import ConfigError

    z = round(rest_height(body, fluid, R0), 9)  # to the nanometre: the same rest pose gives the same mesh and cache key
    vertices = body.mesh_vertices @ R0.T + [0.0, 0.0, z]
    omega = (
        None
        if fluid.bem_min_period is None
        else default_frequencies(float(np.ptp(vertices, axis=0).max()), fluid.g, min_period=fluid.bem_min_period)
    )
    c = radiation_coefficients(vertices, body.mesh_faces, fluid.rho, fluid.g, omega=omega, progress=progress, center=(0.0, 0.0, z),
                               excitation=water is not None)  # fmt: skip
    memory = fit_memory(c)
    T0 = Radiation._frame(R0)  # world-at-rest dofs = T0 body dofs
    if not memory.entries:
        raise ConfigError("radiation = 'bem': this body radiates no waves here (no damping in the BEM results; is g zero?)")
    return Radiation(T0.T @ c.added_mass_inf @ T0, memory, R0, None if water is None else Diffraction(c, water, rest_xy))

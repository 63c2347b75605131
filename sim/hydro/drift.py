"""The mean wave drift force: the steady push a regular wave gives a body, from the far field of the waves it sends out.

A body in a wave of amplitude a scatters and radiates waves; the momentum they carry away to infinity is taken from
the incident wave, and the body feels the difference as a steady horizontal force and yaw moment proportional to a²
(Maruo 1960; Newman 1967 for the yaw moment; Mei, Stiassnie & Yue, Theory and Applications of Ocean Surface Waves,
ch. 7). With H(θ) the Kochin function of all the waves the body sends out in a unit wave of heading β (Capytaine's
convention: bem.Coefficients.kochin_*), H = i (H_diffraction + Σ_j H_radiation,j X_j) for the body moving with the
complex motion X per unit wave amplitude (0 when held still), and k the wavenumber:

    F_x / a² = −2π ρ ω cos β Im H(β) − C ∮ |H(θ)|² cos θ dθ
    F_y / a² = −2π ρ ω sin β Im H(β) − C ∮ |H(θ)|² sin θ dθ
    M_z / a² = (2π ρ ω / k) Re H′(β) − (C / k) ∮ Im(conj(H) H′) dθ

with C = 2π ρ k² in deep water (at depth h: 2π ρ k (k₀h)² / (h ((kh)² − (k₀h)² + k₀h)), k₀ = ω²/g): the first term
the interference of the sent-out wave with the incident one ahead, the second the momentum flux of the sent-out wave.
These are Capytaine's (post_pro.far_field_mean_drift_force, issue 42 checks the two agree), with the integrals as the
periodic trapezoid rule on the solve's KOCHIN_ANGLES directions and H′ by spectral differentiation. The moment is
about the solve's origin (one body: its centre of mass at rest, on the z axis).

Valid for linear waves on a body whose motions are linear (the far field is first order); the mean force is
second order, exact to that order whatever the body's shape (it needs no pressure on the hull). Only the horizontal
components: the mean heave force, roll and pitch moments need the near field and are left out.
"""

from __future__ import annotations

import math

import numpy as np

from sim.hydro.bem import Coefficients
from sim.hydro.diffraction import transfer_at
from sim.water.seas import ramp_factor, wavenumber


def flux_coefficient(omega: np.ndarray, rho: float, g: float, depth: float) -> tuple[np.ndarray, np.ndarray]:
    """(k, C): each frequency's wavenumber and the far-field momentum flux's coefficient (module docstring)."""
    k = wavenumber(omega, g, depth)
    if math.isinf(depth) or np.all(k * depth > 20.0):
        return k, 2 * math.pi * rho * k**2
    k0 = omega**2 / g
    return k, 2 * math.pi * rho * k * (k0 * depth) ** 2 / (depth * ((k * depth) ** 2 - (k0 * depth) ** 2 + k0 * depth))


def mean_drift(c: Coefficients, rao: np.ndarray | None = None, g: float = 9.81) -> np.ndarray:
    """(n, m, 3) real: the mean drift force (F_x, F_y) and yaw moment M_z per unit wave amplitude squared, N/m² and
    N m/m², at each of the solve's frequencies and headings, for the body held still (rao None) or moving with
    `rao` ((n, m, 6k) complex motion per unit wave amplitude, time factor e^(-i omega t))."""
    if not c.has_far_field:
        raise ValueError("the solve has no far field (Kochin functions): solve with far_field=True")
    H = c.kochin_diffraction.astype(complex)  # (n, m, A)
    if rao is not None:
        H = H + np.einsum("nmj,nja->nma", rao, c.kochin_radiation)
    H = 1j * H
    angles = H.shape[-1]
    theta = 2 * math.pi * np.arange(angles) / angles
    modes = np.fft.fftfreq(angles, 1.0 / angles)
    dH = np.fft.ifft(1j * modes * np.fft.fft(H, axis=-1), axis=-1)  # dH/dtheta, exact for the resolved modes
    at = np.rint(np.asarray(c.headings) / (2 * math.pi / angles)).astype(int) % angles
    if not np.allclose(theta[at], np.mod(c.headings, 2 * math.pi), atol=1e-9):
        raise ValueError("the headings are not among the far field's directions")
    m = len(c.headings)
    H_beta = H[:, np.arange(m), at]  # (n, m): each heading's own far field ahead of it
    dH_beta = dH[:, np.arange(m), at]
    k, C = flux_coefficient(np.asarray(c.omega, float), c.rho, g, c.depth)
    k, C, w = k[:, None], C[:, None], np.asarray(c.omega, float)[:, None]
    weight = 2 * math.pi / angles  # the periodic trapezoid rule
    energy = np.abs(H) ** 2
    beta = np.asarray(c.headings)[None, :]
    out = np.empty((len(c.omega), m, 3))
    out[..., 0] = -2 * math.pi * c.rho * w * np.cos(beta) * H_beta.imag - C * weight * (energy * np.cos(theta)).sum(-1)
    out[..., 1] = -2 * math.pi * c.rho * w * np.sin(beta) * H_beta.imag - C * weight * (energy * np.sin(theta)).sum(-1)
    out[..., 2] = 2 * math.pi * c.rho * w / k * dH_beta.real - C / k * weight * (np.conj(H) * dH).imag.sum(-1)
    return out


def body_rao(c: Coefficients, mass: np.ndarray, stiffness: np.ndarray, damping: np.ndarray | None = None,
             joint: np.ndarray | None = None) -> np.ndarray:  # fmt: skip
    """(n, m, 6) complex motion per unit wave amplitude of one body at each of the solve's frequencies and headings:
    [-omega² (M + A) - i omega (B + D) + C] X = X_FK + X_d, M the 6x6 rigid-body mass, C the stiffness and D the linear
    damping at rest (world axes, about the solve's centre), restricted to the twists J ((6, d); None: free, d = 6;
    d = 0: held) with q = J xi; a joint's take-off is in C and D."""
    J = np.eye(6) if joint is None else np.asarray(joint, float).reshape(6, -1)
    out = np.zeros((len(c.omega), len(c.headings), 6), complex)
    if J.shape[1] == 0:
        return out
    D = np.zeros((6, 6)) if damping is None else damping
    for i, w in enumerate(np.asarray(c.omega, float)):
        Z = J.T @ (-(w**2) * (mass + c.added_mass[i]) - 1j * w * (c.damping[i] + D) + stiffness) @ J
        X = (c.froude_krylov[i] + c.diffraction[i]) @ J  # (m, d)
        out[i] = np.linalg.solve(Z, X.T).T @ J.T
    return out


class Drift:
    """The mean and slow drift force of one body in one sea, Newman's approximation (Newman 1974): with D_i the mean
    drift per unit amplitude squared of component i (its frequency and heading, `mean_drift` interpolated) and
    psi_i = k_i . x - omega_i t + phi_i its phase where the body's centre of mass is,

        F(t) = r(t)² Re{ A(t) conj(A'(t)) },  A = sum_i a_i sqrt|D_i| e^(i psi_i),  A' = sum_i a_i sgn(D_i) sqrt|D_i| e^(i psi_i),

    per component (F_x, F_y, M_z): sum_ij a_i a_j sqrt(D_i D_j) cos(psi_i - psi_j) where D_i and D_j have one sign
    (Newman's geometric mean of the diagonal for the off-diagonal transfer function), 0 where they differ; the
    difference frequencies only (the complex envelope leaves out the sum frequencies). Its mean is sum_i a_i² D_i, in
    a regular wave the steady a² D. Valid where the slow drift's frequencies are low against the waves' (Newman's
    approximation: the transfer function varies little over them); the sea's ramp r(t) scales it as a².
    D comes from the solve's far field with the body moving as `rao`, or as a file gives it (bem.Coefficients.mean_drift:
    the body moving as that run had it). D is 0 at omega = 0, linear up to the solve's lowest frequency, and held at its highest past it (short waves are
    reflected as from a wall: the drift tends to a constant). Headings interpolate linearly (periodic)."""

    def __init__(self, c: Coefficients, water, rao: np.ndarray | None = None):

        table = (mean_drift(c, rao, water.g) if c.mean_drift is None else c.mean_drift).astype(complex)
        top = np.asarray(water.omega, float).clip(max=float(c.omega[-1]))
        D = transfer_at(c, table, top, water.direction).real  # (n, 3)
        self.per_amplitude_squared = D
        """(n, 3) D_i: (F_x, F_y, M_z) per unit amplitude squared of each component, N/m², N m/m²."""
        root = np.sqrt(np.abs(D))
        q = water.amplitude * np.exp(1j * water.phase)
        self.envelope = np.empty((len(q), 6), complex)
        self.envelope[:, 0::2] = q[:, None] * root
        self.envelope[:, 1::2] = q[:, None] * np.sign(D) * root
        """(n, 6) complex: A and A' of F_x, F_y, M_z in turn, each component's share at the origin at t = 0."""
        self.k = np.column_stack([water.k * np.cos(water.direction), water.k * np.sin(water.direction)])
        self.omega = np.asarray(water.omega, float)
        self.ramp = float(water.ramp)

    @property
    def mean(self) -> np.ndarray:
        """(3,) the mean (F_x, F_y, M_z) of the whole sea at full height: sum_i a_i² D_i."""
        return (self.envelope[:, 0::2] * np.conj(self.envelope[:, 1::2])).real.sum(axis=0)

    def force(self, t: float, at) -> np.ndarray:
        """(6,) the drift force and moment (F_x, F_y, 0, 0, 0, M_z), world frame, at time t with the centre of mass at `at`."""
        turn = np.exp(1j * (self.k @ np.asarray(at, float)[:2] - self.omega * t))
        A = turn @ self.envelope  # (6,)
        F = (A[0::2] * np.conj(A[1::2])).real * ramp_factor(t, self.ramp) ** 2
        return np.array([F[0], F[1], 0.0, 0.0, 0.0, F[2]])

    def kernel_arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """(re, im) of `envelope` for the compiled kernels (kernels/radiation.py)."""
        return tuple(np.ascontiguousarray(a, dtype=float) for a in (self.envelope.real, self.envelope.imag))


NO_DRIFT = (np.zeros((0, 6)), np.zeros((0, 6)))
"""Drift.kernel_arrays of a body without drift."""

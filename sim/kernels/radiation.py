"""Compiled twin of the radiation terms the integrators use (radiation.Radiation, integrators.kick,
with_memory, drift_memory and exact_linear_flow's generalised mass).

`rad` is layout.radiation_pack's tuple (Minv_b, W_b, S_b, Phi, F, start, col, row, gamma, g, h, R0, Xre, Xim, waves, ramp, Dre,
Dim): the
inverse, the inverse square root and the square root of M_RB + A_inf in the body frame (6, 6); the
memory's exact step over dt and its system as bands (n, w), row i holding columns start[i] + j (the
memory is block diagonal, one small block per fitted entry); and per state i the twist component
col[i] feeding it (through gamma[i] over a step, g[i] in the system) and the load component row[i]
it feeds (through h[i]), all in the axes the memory was fitted in: the rest pose's world axes, R0
from the body frame; then the diffraction force's complex amplitude per wave component referred to the world's
origin (real and imaginary parts, (n, 6), world axes), each component's (omega, k_x, k_y) (n, 3) (none without
diffraction nor drift) and the sea's ramp, s (diffraction.Diffraction.kernel_arrays); last the drift force's envelopes
per component, (n, 6) real and imaginary parts (drift.Drift.kernel_arrays; none without drift).
Without radiation `rad` is None: numba compiles that case apart and prunes every radiation branch
(`rad is None` tests on an argument are resolved at compile time), so still scenes pay nothing. Vectors in the body frame are R^T times the world ones.
"""

from __future__ import annotations

import math

import numpy as np

from .jit import JIT, njit
from .rotation import mtv, mv
from .water import ramp_factor


@njit(**JIT)
def to_world(R, Mb):
    """R6 Mb R6^T, R6 = diag(R, R): a body-frame 6x6 matrix in world axes."""
    out = np.empty((6, 6))
    for bi in range(2):
        for bj in range(2):
            for i in range(3):
                for j in range(3):
                    acc = 0.0
                    for k in range(3):
                        for m in range(3):
                            acc += R[i, k] * Mb[3 * bi + k, 3 * bj + m] * R[j, m]
                    out[3 * bi + i, 3 * bj + j] = acc
    return out


@njit(**JIT)
def band_matvec(band, start, x):
    """M x for a block-diagonal M stored as a band: row i's entries sit in columns start[i] + j."""
    out = np.empty(band.shape[0])
    for i in range(band.shape[0]):
        acc = 0.0
        for j in range(band.shape[1]):
            acc += band[i, j] * x[min(start[i] + j, x.shape[0] - 1)]
        out[i] = acc
    return out


@njit(inline="always", **JIT)  # no call: passing the rad tuple costs a reference count per array
def memory_output(rad, x):
    """mu = H x (6,): each state adds h[i] x[i] to its load component."""
    mu = np.zeros(6)
    row, h = rad[7], rad[10]
    for i in range(x.shape[0]):
        mu[row[i]] += h[i] * x[i]
    return mu


@njit(**JIT)
def matvec(M, x):
    out = np.zeros(M.shape[0])
    for i in range(M.shape[0]):
        acc = 0.0
        for j in range(M.shape[1]):
            acc += M[i, j] * x[j]
        out[i] = acc
    return out


@njit(**JIT)
def body_twist(R, u, L, inertia):
    """(u_b, omega_b) stacked: the twist in the body frame."""
    nu = np.empty(6)
    nu[:3] = mtv(R, u)
    nu[3:] = mtv(R, L) / inertia
    return nu


@njit(**JIT)
def fit_twist(R, R0, u, L, inertia):
    """The twist in the memory's axes: R0 times the body-frame one."""
    nb = body_twist(R, u, L, inertia)
    nu = np.empty(6)
    nu[:3] = mv(R0, nb[:3].copy())
    nu[3:] = mv(R0, nb[3:].copy())
    return nu


@njit(**JIT)
def fit_to_world(R, R0, mu):
    """A load in the memory's axes, in the world: R R0^T mu."""
    return mv(R, mtv(R0, mu[:3].copy())), mv(R, mtv(R0, mu[3:].copy()))


@njit(inline="always", **JIT)  # no call: passing the rad tuple costs a reference count per array
def kick(rad, R, u, L, F, T, h, inertia):
    """(u, L) after the impulse h (F, T) through the generalised mass (integrators.kick)."""
    fb = np.empty(6)
    fb[:3] = mtv(R, F)
    fb[3:] = mtv(R, T)
    d = h * matvec(rad[0], fb)
    return u + mv(R, d[:3].copy()), L + mv(R, inertia * d[3:])


@njit(inline="always", **JIT)  # no call: passing the rad tuple costs a reference count per array
def memory_load(rad, R, x, t, p):
    """The memory's force and torque on the body, world frame: -R (H x); plus, in waves, the diffraction
    and drift forces at time t with the centre of mass at p (radiation.Radiation.load)."""
    Fm, Tm = fit_to_world(R, rad[11], memory_output(rad, x))
    Fm, Tm = -Fm, -Tm
    re, im, waves = rad[12], rad[13], rad[14]
    r = ramp_factor(t, rad[15]) if waves.shape[0] else 0.0
    for i in range(re.shape[0]):  # r Re{(re + i im) e^(-i psi)} = r (re cos + im sin), psi = omega t - k . p
        psi = waves[i, 0] * t - waves[i, 1] * p[0] - waves[i, 2] * p[1]
        c, s = r * math.cos(psi), r * math.sin(psi)
        for j in range(3):
            Fm[j] += re[i, j] * c + im[i, j] * s
            Tm[j] += re[i, 3 + j] * c + im[i, 3 + j] * s
    if rad[16].shape[0]:
        drift_load(rad[16], rad[17], waves, t, p, r * r, Fm, Tm)
    return Fm, Tm


@njit(**JIT)
def drift_load(dre, dim, waves, t, p, r2, F, T):
    """Adds the drift force (drift.Drift.force) to F and T: r^2 Re{A conj(A')} for F_x, F_y and M_z, the envelopes A and
    A' the sums of (dre + i dim) e^(-i psi) over the components, psi = omega t - k . p."""
    env_re, env_im = np.zeros(6), np.zeros(6)
    for i in range(dre.shape[0]):
        psi = waves[i, 0] * t - waves[i, 1] * p[0] - waves[i, 2] * p[1]
        cs, sn = math.cos(psi), math.sin(psi)
        for j in range(6):
            env_re[j] += dre[i, j] * cs + dim[i, j] * sn
            env_im[j] += dim[i, j] * cs - dre[i, j] * sn
    F[0] += r2 * (env_re[0] * env_re[1] + env_im[0] * env_im[1])
    F[1] += r2 * (env_re[2] * env_re[3] + env_im[2] * env_im[3])
    T[2] += r2 * (env_re[4] * env_re[5] + env_im[4] * env_im[5])


@njit(inline="always", **JIT)  # no call: passing the rad tuple costs a reference count per array
def drift_memory(rad, R0, R1, u, L, x, e_rad, dt, inertia):
    """(memory, E_rad) after a drift (integrators.drift_memory): the memory advanced exactly with the
    twist in its axes averaged over the drift's two orientations; the energy as dt nu . mu averaged."""
    nu0 = fit_twist(R0, rad[11], u, L, inertia)
    nu1 = fit_twist(R1, rad[11], u, L, inertia)
    xn = band_matvec(rad[3], rad[5], x)
    col, gamma = rad[6], rad[8]
    for i in range(xn.shape[0]):
        xn[i] += gamma[i] * 0.5 * (nu0[col[i]] + nu1[col[i]])
    mu0, mu1 = memory_output(rad, x), memory_output(rad, xn)
    power = 0.0
    for i in range(6):
        power += 0.5 * (nu0[i] * mu0[i] + nu1[i] * mu1[i])
    return xn, e_rad + dt * power


@njit(inline="always", **JIT)  # no call: passing the rad tuple costs a reference count per array
def frames(rad, R):
    """(W, S): the inverse square root and the square root of M_RB + A_inf in world axes at R
    (empty without radiation); computed once per pose and shared by its half steps."""
    if rad is None:
        return np.zeros((0, 0)), np.zeros((0, 0))
    return to_world(R, rad[1]), to_world(R, rad[2])


@njit(**JIT)
def general_modes(D, WS):
    """K = W D W with W = (M_RB + A_inf)^(-1/2) in world axes (damping_modes with the added mass)."""
    W = WS[0]
    WD = np.zeros((6, 6))
    for i in range(6):
        for k in range(6):
            for j in range(6):
                WD[i, j] += W[i, k] * D[k, j]
    K = np.zeros((6, 6))
    for i in range(6):
        for k in range(6):
            for j in range(6):
                K[i, j] += WD[i, k] * W[k, j]
    return K


@njit(inline="always", **JIT)
def to_scaled(WS, R, u, L, F, T, inertia):
    """(y, g) = (S nu, W f): the twist and the forcing in mass-normalised coordinates."""
    nu = np.empty(6)
    nu[:3] = u
    nu[3:] = mv(R, mtv(R, L) / inertia)
    f = np.empty(6)
    f[:3] = F
    f[3:] = T
    return matvec(WS[1], nu), matvec(WS[0], f)


@njit(inline="always", **JIT)
def from_scaled(WS, R, y, inertia):
    """(u, L) from y = S nu."""
    nu = matvec(WS[0], y)
    return nu[:3].copy(), mv(R, inertia * mtv(R, nu[3:].copy()))


@njit(inline="always", **JIT)  # no call: passing the rad tuple costs a reference count per array
def derivative_extra(rad, R, u, L, F, T, x, t, inertia, p):
    """For rk4: (du/dt, dL/dt, dx/dt, dE_rad/dt) with the generalised mass and the memory, the centre of mass at p
    (integrators.derivative): (M_RB + A_inf) nu' = f - mu - (0, omega x L), L' = I nu'_omega + omega x L."""
    w = mv(R, mtv(R, L) / inertia)
    spin = np.array([w[1] * L[2] - w[2] * L[1], w[2] * L[0] - w[0] * L[2], w[0] * L[1] - w[1] * L[0]])
    Fm, Tm = memory_load(rad, R, x, t, p)
    fb = np.empty(6)
    fb[:3] = mtv(R, F + Fm)
    fb[3:] = mtv(R, T + Tm - spin)
    d = matvec(rad[0], fb)
    nub = fit_twist(R, rad[11], u, L, inertia)
    mu = memory_output(rad, x)
    e_rate = 0.0
    for i in range(6):
        e_rate += nub[i] * mu[i]
    dx = band_matvec(rad[4], rad[5], x)
    col, g = rad[6], rad[9]
    for i in range(dx.shape[0]):
        dx[i] += g[i] * nub[col[i]]
    return mv(R, d[:3].copy()), mv(R, inertia * d[3:]) + spin, dx, e_rate

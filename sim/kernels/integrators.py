"""Compiled twin of dynamics/integrators.py: the flows, kicks and derivative the schemes (schemes.py) are built of.

The same arithmetic as the reference written as plain loops, so the two agree to round-off
(tests compare them stage by stage and step by step).
"""

from __future__ import annotations

import math

import numpy as np

from sim.dynamics.integrators import RELINEARISE, RELINEARISE_TOL

from .forces import linearised, nonlinear_acting, pose_loads, twist_loads
from .jit import JIT, njit
from .modes import damping_modes, exact_modes, mat6v
from .radiation import derivative_extra, frames, from_scaled, general_modes, memory_load, to_scaled
from .radiation import kick as rad_kick
from .rotation import mtv, mv, normalized, quat_multiply, quat_to_matrix
from .state import angular_velocity


@njit(inline="always", **JIT)
def kick(rad, R, u, L, F, T, h, mass, inertia):
    """(u, L) after the impulse h (F, T) (integrators.kick): through the added mass when radiating."""
    if rad is not None:
        return rad_kick(rad, R, u, L, F, T, h, inertia)
    return u + h * F / mass, L + h * T


@njit(**JIT)
def modes(D, R, mass, inertia, rad, WS):
    """K = W D W, W the inverse square root of the (generalised) mass (WS: its frames at R, radiation.frames)."""
    if rad is not None:
        return general_modes(D, WS)
    return damping_modes(D, R, mass, inertia)


@njit(**JIT)
def twist_flow(K, R, u, L, h, mass, inertia, rad, WS):
    """(u, L) after h of linear damping alone by one explicit midpoint step (integrators.twist_flow
    when damping is the only twist term), in mass-normalised coordinates (the generalised mass's
    when radiating)."""
    if rad is not None:
        y, _ = to_scaled(WS, R, u, L, u, u, inertia)
        y_mid = y - 0.5 * h * mat6v(K, y)
        return from_scaled(WS, R, y - h * mat6v(K, y_mid), inertia)
    sqrt_m = math.sqrt(mass)
    w_half = np.sqrt(inertia)
    y = np.empty(6)
    y[:3] = sqrt_m * u
    y[3:] = mv(R, mtv(R, L) / w_half)
    y_mid = y - 0.5 * h * mat6v(K, y)
    y = y - h * mat6v(K, y_mid)
    return y[:3] / sqrt_m, mv(R, w_half * mtv(R, y[3:]))


@njit(inline="always", **JIT)
def damped_kick(K, WS, R, u, L, F, T, h, inertia, damping_first):
    """Splitting's half step with radiation and linear damping: the damping's explicit midpoint
    flow and the kick h (F, T), both in the generalised mass's normalised coordinates y = S nu
    (there the kick is y + h W f), so the twist is converted once (twist_flow, then kick, in one)."""
    y, g = to_scaled(WS, R, u, L, F, T, inertia)
    if not damping_first:
        y = y + h * g
    y_mid = y - 0.5 * h * mat6v(K, y)
    y = y - h * mat6v(K, y_mid)
    if damping_first:
        y = y + h * g
    return from_scaled(WS, R, y, inertia)


@njit(**JIT)
def general_twist_flow(x, R, u, L, h, model, D, s, rad):
    """integrators.twist_flow with nonlinear twist terms, in waves or with radiation: explicit midpoint
    on the twist terms, pose frozen."""
    mass, inertia = model.mass, model.inertia
    F, T = np.zeros(3), np.zeros(3)
    twist_loads(x, R, u, angular_velocity(R, L, inertia), model, D, True, s, F, T)
    u_mid, L_mid = kick(rad, R, u, L, F, T, 0.5 * h, mass, inertia)
    F[:], T[:] = 0.0, 0.0
    twist_loads(x, R, u_mid, angular_velocity(R, L_mid, inertia), model, D, True, s, F, T)
    return kick(rad, R, u, L, F, T, h, mass, inertia)


@njit(**JIT)
def linear_flow(K, lam, V, R, u, L, F, T, h, mass, inertia, wet, rad, WS):
    """(u, L) after h under the linearised loads f - D (u, omega) at a frozen pose, exactly, as in
    integrators.linear_flow: y(h) = exp(-hK) y0 + h phi(hK) W f (W: the generalised mass's when radiating)."""
    if not wet:
        return kick(rad, R, u, L, F, T, h, mass, inertia)
    sqrt_m = math.sqrt(mass)
    w_half = np.sqrt(inertia)
    if rad is not None:
        y, gv = to_scaled(WS, R, u, L, F, T, inertia)
    else:
        y = np.empty(6)
        y[:3] = sqrt_m * u
        y[3:] = mv(R, mtv(R, L) / w_half)
        gv = np.empty(6)
        gv[:3] = F / sqrt_m
        gv[3:] = mv(R, mtv(R, T) / w_half)
    if lam[0] < 0.0:  # mild (see exact_modes): both series, sum (-hK)^n y/n! + h (-hK)^n g/(n+1)!
        a = y.copy()
        b = h * gv
        ka = np.empty(6)
        kb = np.empty(6)
        scale = 0.0
        for i in range(6):
            y[i] = a[i] + b[i]
            scale = max(scale, abs(a[i]), abs(b[i]))
        for n in range(1, 40):  # in place: this runs twice a step
            ca, cb = -h / n, -h / (n + 1)
            for i in range(6):
                sa = 0.0
                sb = 0.0
                for j in range(6):
                    sa += K[i, j] * a[j]
                    sb += K[i, j] * b[j]
                ka[i] = ca * sa
                kb[i] = cb * sb
            biggest = 0.0
            for i in range(6):
                a[i], b[i] = ka[i], kb[i]
                y[i] += a[i] + b[i]
                biggest = max(biggest, abs(a[i]), abs(b[i]))
            if biggest <= 1e-17 * scale:
                break
    else:  # stiff: through the eigenmodes
        c = np.zeros(6)
        for j in range(6):
            cy = 0.0
            cg = 0.0
            for i in range(6):
                cy += V[i, j] * y[i]
                cg += V[i, j] * gv[i]
            x = h * max(lam[j], 0.0)
            phi = -math.expm1(-x) / x if x > 1e-12 else 1.0 - 0.5 * x
            c[j] = math.exp(-x) * cy + h * phi * cg
        for i in range(6):
            acc = 0.0
            for j in range(6):
                acc += V[i, j] * c[j]
            y[i] = acc
    if rad is not None:
        return from_scaled(WS, R, y, inertia)
    return y[:3] / sqrt_m, mv(R, w_half * mtv(R, y[3:]))


@njit(**JIT)
def _flow_about(x, R, u, L, uc, Lc, h, model, F, T, D, wet, s, rad):
    """(u, L) after h under the loads linearised about the twist (uc, omega(Lc)), exactly."""
    mass, inertia = model.mass, model.inertia
    f, Dt = linearised(x, R, uc, angular_velocity(R, Lc, inertia), model, F, T, D, wet, s)
    lam, V = np.zeros(6), np.eye(6)
    K = np.zeros((6, 6))
    WS = frames(rad, R)
    if wet:
        K = modes(Dt, R, mass, inertia, rad, WS)
        lam, V = exact_modes(K, h)
    return linear_flow(K, lam, V, R, u, L, f[:3], f[3:], h, mass, inertia, wet, rad, WS)


@njit(**JIT)
def relinearised_flow(x, R, u, L, h, model, F, T, D, wet, s, rad):
    """integrators.linear_flow with nonlinear twist terms (drag): linearised about the end twist of the
    half step, found by fixed-point iteration from the start twist."""
    un, Ln = _flow_about(x, R, u, L, u, L, h, model, F, T, D, wet, s, rad)
    if not nonlinear_acting(model) or not wet:
        return un, Ln
    inertia = model.inertia
    scale = math.sqrt(max(inertia[0], inertia[1], inertia[2]) / model.mass)
    for _ in range(RELINEARISE):
        u2, L2 = _flow_about(x, R, u, L, un, Ln, h, model, F, T, D, wet, s, rad)
        dw = angular_velocity(R, L2 - Ln, inertia)
        w2 = angular_velocity(R, L2, inertia)
        change = max(np.abs(u2 - un).max(), scale * np.abs(dw).max())
        un, Ln = u2, L2
        if change <= RELINEARISE_TOL * (np.abs(un).max() + scale * np.abs(w2).max()):
            break
    return un, Ln


@njit(**JIT)
def free_rotation(q, L, h, inertia):
    """integrators.free_rotation as scalar code: the DLM split, each sub-step a rotation about one
    body axis by h L_body[axis] / I[axis], with L_body[axis] = (column `axis` of R) . L."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    for axis, frac in ((0, 0.5), (1, 0.5), (2, 1.0), (1, 0.5), (0, 0.5)):
        if axis == 0:
            lb = (1 - 2 * (y * y + z * z)) * L[0] + 2 * (x * y + w * z) * L[1] + 2 * (x * z - w * y) * L[2]
        elif axis == 1:
            lb = 2 * (x * y - w * z) * L[0] + (1 - 2 * (x * x + z * z)) * L[1] + 2 * (y * z + w * x) * L[2]
        else:
            lb = 2 * (x * z + w * y) * L[0] + 2 * (y * z - w * x) * L[1] + (1 - 2 * (x * x + y * y)) * L[2]
        half = 0.5 * frac * h * lb / inertia[axis]
        c, s = math.cos(half), math.sin(half)
        if axis == 0:  # q * (c, s, 0, 0)
            w, x, y, z = w * c - x * s, w * s + x * c, y * c + z * s, z * c - y * s
        elif axis == 1:  # q * (c, 0, s, 0)
            w, x, y, z = w * c - y * s, x * c - z * s, w * s + y * c, z * c + x * s
        else:  # q * (c, 0, 0, s)
            w, x, y, z = w * c - z * s, x * c + y * s, y * c - x * s, w * s + z * c
    return normalized(np.array([w, x, y, z]))


@njit(**JIT)
def derivative(y, t, model, s, sea, rad):
    """d/dt of the state vector (integrators.derivative); with radiation also of the memory and E_rad."""
    x, q, u, L = y[0:3], y[3:7], y[7:10], y[10:13]
    mass, inertia = model.mass, model.inertia
    R = quat_to_matrix(q)
    w = angular_velocity(R, L, inertia)
    F, T, D, wet = pose_loads(x, R, t, model, s, sea)
    twist_loads(x, R, u, w, model, D, wet, s, F, T)
    out = np.empty(y.shape[0])
    out[0:3] = u
    out[3:7] = 0.5 * quat_multiply(np.array([0.0, w[0], w[1], w[2]]), normalized(q))
    if rad is not None:
        du, dL, dx, de = derivative_extra(rad, R, u, L, F, T, y[13:-1], t, inertia, x)
        out[7:10], out[10:13], out[13:-1], out[-1] = du, dL, dx, de
        return out
    out[7:10] = F / mass
    out[10:13] = T
    return out


@njit(**JIT)
def with_memory(rad, R, F, T, x, t, p):
    """The loads plus the radiation memory's force and the diffraction force at t, the centre of mass at p (integrators.with_memory)."""
    if rad is None:
        return F, T
    Fm, Tm = memory_load(rad, R, x, t, p)
    return F + Fm, T + Tm

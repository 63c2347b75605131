"""Compiled twin of the fixed-step schemes: one step function per scheme and `advance`, only the loop.

This copy of the kernels is compiled for one scheme (spec.SCHEME): `step` keeps that scheme's branch
and numba drops the others before it compiles. A step maps the state vector y and the carry (what the
last step left that the next one reuses: the pose's rotation, loads and damping modes) to the new ones.
"""

from __future__ import annotations

import math

import numpy as np

from sim.bodies.body import make_box

from .forces import nonlinear_acting, pose_loads, twist_loads
from .integrators import (
    damped_kick,
    derivative,
    exact_modes,
    free_rotation,
    general_twist_flow,
    kick,
    linear_flow,
    modes,
    relinearised_flow,
    twist_flow,  # fmt: skip
    with_memory,
)
from .jit import JIT, njit
from .layout import COEF_SIZE, HELD, Model, Scratch
from .radiation import drift_memory, frames
from .rotation import normalized, quat_multiply, quat_to_matrix, rotation_quat
from .simulation import linearised_loads, observe
from .spec import EULER, HOLDING, IMPLICIT, MOVING, RADIATING, SCHEME, SPEC, SPLITTING, WAVES
from .state import angular_velocity
from .surface import exact_hydrostatic_energy, workspace


@njit(**JIT)
def scratch(geom):
    return Scratch(np.zeros(geom[0].shape[0], dtype=np.bool_), np.zeros(34), workspace(geom))


@njit(inline="always", **JIT)
def _state(y, xn, qn, un, Ln, memn, e_radn, rad):
    yn = np.empty(y.shape[0])
    yn[0:3], yn[3:7], yn[7:10], yn[10:13] = xn, qn, un, Ln
    if rad is not None:
        yn[13:-1], yn[-1] = memn, e_radn
    return yn


@njit(**JIT)
def start(y, t, dt, model, s, sea, rad):
    """The carry at the first step: (R, F, T, D, wet, K, lam, V, WS) at y's pose."""
    R = quat_to_matrix(y[3:7])
    WS = frames(rad, R)
    F, T, D, wet = pose_loads(y[0:3], R, t, model, s, sea)
    K = modes(D, R, model.mass, model.inertia, rad, WS)
    lam, V = np.zeros(6), np.eye(6)
    if wet and SCHEME == IMPLICIT and not nonlinear_acting(model):
        lam, V = exact_modes(K, 0.5 * dt)
    return R, F, T, D, wet, K, lam, V, WS


@njit(inline="always", **JIT)  # into advance's loop: no call passing some 30 arrays each step
def euler_step(y, t, dt, carry, model, s, sea, rad):
    """Drift, exact rotation, every load at the new pose, kick (integrators.SymplecticEuler)."""
    x, q, u, L = y[0:3], y[3:7], y[7:10], y[10:13]
    R, F, T, D, wet, K, lam, V, WS = carry
    mass, inertia = model.mass, model.inertia
    mem, e_rad = (y[13:-1], y[-1]) if rad is not None else (y[:0], 0.0)
    w = angular_velocity(R, L, inertia)
    xn = x + dt * u
    qn = normalized(quat_multiply(rotation_quat(dt * w), q))
    Rn = quat_to_matrix(qn)
    memn, e_radn = mem, e_rad
    if rad is not None:
        memn, e_radn = drift_memory(rad, R, Rn, u, L, mem, e_rad, dt, inertia)
    Fc, Tc, Dn, wetn = pose_loads(xn, Rn, t + dt, model, s, sea)
    twist_loads(xn, Rn, u, angular_velocity(Rn, L, inertia), model, Dn, wetn, s, Fc, Tc)  # euler carries no loads over
    Fk, Tk = with_memory(rad, Rn, Fc, Tc, memn, t + dt, xn)
    un, Ln = kick(rad, Rn, u, L, Fk, Tk, dt, mass, inertia)
    return _state(y, xn, qn, un, Ln, memn, e_radn, rad), (Rn, Fc, Tc, Dn, wetn, K, lam, V, WS)


@njit(inline="always", **JIT)
def _drift(x, q, R, un, Ln, mem, e_rad, t, dt, model, s, sea, rad, WS):
    """C(dt) of the splitting and implicit schemes: the free drift and exact rotation, the radiation memory
    over it and the new pose's mass frames, then the loads at the new pose."""
    xn = x + dt * un
    qn = free_rotation(q, Ln, dt, model.inertia)
    Rn = quat_to_matrix(qn)
    memn, e_radn = mem, e_rad
    if rad is not None:
        WS = frames(rad, Rn)
        memn, e_radn = drift_memory(rad, R, Rn, un, Ln, mem, e_rad, dt, model.inertia)
    Fc, Tc, Dn, wetn = pose_loads(xn, Rn, t + dt, model, s, sea)
    return xn, qn, Rn, memn, e_radn, WS, Fc, Tc, Dn, wetn


@njit(inline="always", **JIT)  # into advance's loop: no call passing some 30 arrays each step
def splitting_step(y, t, dt, carry, model, s, sea, rad):
    """B(h) A(h) C(dt) A(h) B(h), loads carried over (integrators.Splitting)."""
    x, q, u, L = y[0:3], y[3:7], y[7:10], y[10:13]
    R, F, T, D, wet, K, lam, V, WS = carry
    mass, inertia = model.mass, model.inertia
    mem, e_rad = (y[13:-1], y[-1]) if rad is not None else (y[:0], 0.0)
    h = 0.5 * dt
    un, Ln = u, L
    general = MOVING or nonlinear_acting(model)  # drag at a zero coefficient: the linear path, as a spec without it
    if rad is None:  # a literal test on the argument: numba compiles each case apart
        if wet and general:
            un, Ln = general_twist_flow(x, R, un, Ln, h, model, D, s, rad)
        elif wet:
            un, Ln = twist_flow(K, R, un, Ln, h, mass, inertia, rad, WS)
        un, Ln = kick(rad, R, un, Ln, F, T, h, mass, inertia)
    else:
        Fk, Tk = with_memory(rad, R, F, T, mem, t, x)
        if wet and not general:
            un, Ln = damped_kick(K, WS, R, un, Ln, Fk, Tk, h, inertia, True)
        else:
            if wet:
                un, Ln = general_twist_flow(x, R, un, Ln, h, model, D, s, rad)
            un, Ln = kick(rad, R, un, Ln, Fk, Tk, h, mass, inertia)
    xn, qn, Rn, memn, e_radn, WS, Fc, Tc, Dn, wetn = _drift(x, q, R, un, Ln, mem, e_rad, t, dt, model, s, sea, rad, WS)
    if rad is None:
        un, Ln = kick(rad, Rn, un, Ln, Fc, Tc, h, mass, inertia)
        if wetn and general:
            un, Ln = general_twist_flow(xn, Rn, un, Ln, h, model, Dn, s, rad)
        elif wetn:
            K = modes(Dn, Rn, mass, inertia, rad, WS)
            un, Ln = twist_flow(K, Rn, un, Ln, h, mass, inertia, rad, WS)
    else:
        Fk, Tk = with_memory(rad, Rn, Fc, Tc, memn, t + dt, xn)
        if wetn and not general:
            K = modes(Dn, Rn, mass, inertia, rad, WS)
            un, Ln = damped_kick(K, WS, Rn, un, Ln, Fk, Tk, h, inertia, False)
        else:
            un, Ln = kick(rad, Rn, un, Ln, Fk, Tk, h, mass, inertia)
            if wetn:
                un, Ln = general_twist_flow(xn, Rn, un, Ln, h, model, Dn, s, rad)
    return _state(y, xn, qn, un, Ln, memn, e_radn, rad), (Rn, Fc, Tc, Dn, wetn, K, lam, V, WS)


@njit(inline="always", **JIT)  # into advance's loop: no call passing some 30 arrays each step
def implicit_step(y, t, dt, carry, model, s, sea, rad):
    """P(h) C(dt) P(h), P = every load linearised and solved exactly (integrators.Implicit); the
    water's motion makes damping affine: its part d u_water (ws[4]) joins the loads."""
    x, q, u, L = y[0:3], y[3:7], y[7:10], y[10:13]
    R, F, T, D, wet, K, lam, V, WS = carry
    mass, inertia = model.mass, model.inertia
    mem, e_rad = (y[13:-1], y[-1]) if rad is not None else (y[:0], 0.0)
    h = 0.5 * dt
    affine = s.ws[4]
    Fk, Tk = with_memory(rad, R, F, T, mem, t, x)
    relinearise = nonlinear_acting(model)  # drag at a zero coefficient: the linear path, as a spec without it
    if relinearise:
        un, Ln = relinearised_flow(x, R, u, L, h, model, Fk, Tk, D, wet, s, rad)
    else:
        Fa, Ta = (Fk + affine[:3], Tk + affine[3:]) if MOVING else (Fk, Tk)
        un, Ln = linear_flow(K, lam, V, R, u, L, Fa, Ta, h, mass, inertia, wet, rad, WS)
    xn, qn, Rn, memn, e_radn, WS, Fc, Tc, Dn, wetn = _drift(x, q, R, un, Ln, mem, e_rad, t, dt, model, s, sea, rad, WS)
    Fk, Tk = with_memory(rad, Rn, Fc, Tc, memn, t + dt, xn)
    if relinearise:
        un, Ln = relinearised_flow(xn, Rn, un, Ln, h, model, Fk, Tk, Dn, wetn, s, rad)
    else:
        if wetn:  # the same modes serve the next step's first half, at this pose
            K = modes(Dn, Rn, mass, inertia, rad, WS)
            lam, V = exact_modes(K, h)
        Fa, Ta = (Fk + affine[:3], Tk + affine[3:]) if MOVING else (Fk, Tk)
        un, Ln = linear_flow(K, lam, V, Rn, un, Ln, Fa, Ta, h, mass, inertia, wetn, rad, WS)
    return _state(y, xn, qn, un, Ln, memn, e_radn, rad), (Rn, Fc, Tc, Dn, wetn, K, lam, V, WS)


@njit(inline="always", **JIT)  # into advance's loop: no call passing some 30 arrays each step
def rk4_step(y, t, dt, carry, model, s, sea, rad):
    """Classical Runge-Kutta on (x, q, u, L[, memory, E_rad]), q renormalised (integrators.RK4)."""
    k1 = derivative(y, t, model, s, sea, rad)
    k2 = derivative(y + 0.5 * dt * k1, t + 0.5 * dt, model, s, sea, rad)
    k3 = derivative(y + 0.5 * dt * k2, t + 0.5 * dt, model, s, sea, rad)
    k4 = derivative(y + dt * k3, t + dt, model, s, sea, rad)
    yn = y + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    yn[3:7] = normalized(yn[3:7])
    return yn, carry  # rk4 uses no carry


@njit(inline="always", **JIT)  # into advance's loop or step_held: a spec compiles one of the two (warm_up)
def step(y, t, dt, carry, model, s, sea, rad):
    """One step of this copy's scheme (the others are dropped before compiling)."""
    if SCHEME == EULER:
        return euler_step(y, t, dt, carry, model, s, sea, rad)
    if SCHEME == SPLITTING:
        return splitting_step(y, t, dt, carry, model, s, sea, rad)
    if SCHEME == IMPLICIT:
        return implicit_step(y, t, dt, carry, model, s, sea, rad)
    return rk4_step(y, t, dt, carry, model, s, sea, rad)


@njit(**JIT)
def _finite(y):
    for v in y:
        if not math.isfinite(v):
            return False
    return True


@njit(**JIT)
def advance(y0, t0, n_steps, dt, model, sea, rad):
    """Advance the state vector (layout.py; with radiation followed by the memory and E_rad) at time t0
    by up to n_steps in the water `sea` (layout.sea_pack) with the radiation `rad` (layout.radiation_pack,
    None without); stop before the first non-finite state. Returns (state, steps done)."""
    s = scratch(model.geom)  # the wet flags and sums start afresh
    y = y0.copy()
    carry = start(y, t0, dt, model, s, sea, rad)
    for i in range(n_steps):
        yn, carry = step(y, t0 + i * dt, dt, carry, model, s, sea, rad)
        if not _finite(yn):
            return y, i
        y = yn
    return y, n_steps


@njit(**JIT)
def fairleads(y, R, inertia, levers, pos, vel):
    """The fairleads' positions and velocities, flat (3 k,), at the state y with rotation R: x + R r and u + omega x (R r)."""
    w = angular_velocity(R, y[10:13], inertia)
    for i in range(levers.shape[0]):
        lever = R @ levers[i]
        pos[3 * i : 3 * i + 3] = y[0:3] + lever
        vel[3 * i : 3 * i + 3] = y[7:10] + np.cross(w, lever)


def held_start(y, t, dt, model, sea, rad, levers, pos, vel):
    """What step_held keeps from step to step, at y's pose: the scratch and the carry (its wet flag as a (1,) array, its
    mass frames apart), and the fairleads' kinematics for the first step into pos and vel. The carry is made by step_held
    itself (`first`): an entry point of its own would hold another copy of the loads' machine code (5-7 CPU s of a moored
    compile)."""
    s = scratch(model.geom)
    frame = (6, 6) if rad is not None else (0, 0)
    keep = (np.eye(3), np.zeros(3), np.zeros(3), np.zeros((6, 6)), np.zeros(1, dtype=np.bool_), np.zeros((6, 6)), np.zeros(6), np.eye(6),
            np.zeros(frame), np.zeros(frame))  # fmt: skip
    step_held(y, t, dt, model, sea, rad, s, keep, np.zeros((len(levers), 3)), np.zeros((len(levers), 3)), levers, pos, vel, True)
    return s, keep


@njit(**JIT)
def step_held(y, t, dt, model, sea, rad, s, keep, now, ahead, levers, pos, vel, first):
    """One step with the held load (layout.HELD) the mean of the lines' pull at both ends of it: now and ahead (k, 3)
    on the fairleads (body frame levers (k, 3)), their moment taken at the step's starting pose. `keep` (held_start)
    is updated in place, and pos and vel get the fairleads' kinematics for the next step: a moored run calls this once
    a step, with MoorDyn's step between calls, and nothing is rebuilt. Returns (y at t + dt, True), or (y, False)
    where the step is not finite (nothing updated). `first`: no step; `keep` gets the carry at y's pose (schemes.start)
    and pos and vel the fairleads' kinematics there."""
    R, F, T, D, flag, K, lam, V, W, S = keep
    if first:
        R0, F0, T0, D0, wet0, K0, lam0, V0, WS0 = start(y, t, dt, model, s, sea, rad)
        R[:], F[:], T[:], D[:], K[:], lam[:], V[:], W[:], S[:] = R0, F0, T0, D0, K0, lam0, V0, WS0[0], WS0[1]
        flag[0] = wet0
        fairleads(y, R, model.inertia, levers, pos, vel)
        return y, True
    held = np.zeros(6)
    for i in range(levers.shape[0]):
        pull = 0.5 * (now[i] + ahead[i])
        held[:3] += pull
        held[3:] += np.cross(R @ levers[i], pull)
    c = model.coef
    for i in range(6):  # the carried loads hold the last step's pull: swap it for this one's
        if i < 3:
            F[i] += held[i] - c[HELD + i]
        else:
            T[i - 3] += held[i] - c[HELD + i]
        c[HELD + i] = held[i]
    yn, carry = step(y, t, dt, (R, F, T, D, flag[0], K, lam, V, (W, S)), model, s, sea, rad)
    if not _finite(yn):
        return y, False
    Rn, Fn, Tn, Dn, wetn, Kn, lamn, Vn, WSn = carry
    R[:], F[:], T[:], D[:], K[:], lam[:], V[:], W[:], S[:] = Rn, Fn, Tn, Dn, Kn, lamn, Vn, WSn[0], WSn[1]
    flag[0] = wetn
    fairleads(yn, Rn, model.inertia, levers, pos, vel)
    return yn, True


@njit(**JIT)
def advance_many(Y, t0, n_steps, dt, geom, masses, inertias, coefs, sea, rad):
    """advance() for B bodies of one shape (rows of Y; their own mass, inertia and coefficients).
    Returns the new states and each body's steps done (< n_steps where it diverged)."""
    out = np.empty_like(Y)
    done = np.empty(Y.shape[0], dtype=np.int64)
    for b in range(Y.shape[0]):
        out[b], done[b] = advance(Y[b], t0, n_steps, dt, Model(geom, masses[b], inertias[b], coefs[b]), sea, rad)
    return out, done


def warm_up() -> None:
    """Compile (first run ever) or load from the disk cache this copy's step and frame kernels."""
    body = make_box((1.0, 1.0, 1.0), 1, 1.0)
    y = np.array([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    coef = np.ones(COEF_SIZE)
    comps = np.zeros((1 if WAVES else 0, 8))
    sea = (comps, math.inf, True, 1.0, np.zeros(3), 0.0)
    rad = None
    if RADIATING:  # the types only
        eye, one, index, zero = np.eye(6), np.ones((1, 1)), np.zeros(1, dtype=np.int64), np.zeros(1)
        no_waves = (np.zeros((0, 6)), np.zeros((0, 6)), np.zeros((0, 3)), 0.0)
        rad = (eye, eye, eye, one, -one, index, index, index, zero, zero, zero, np.eye(3), *no_waves, np.zeros((0, 6)), np.zeros((0, 6)))
        y = np.concatenate([y, np.zeros(2)])
    model = Model(body.packed, body.mass, body.inertia, coef)
    if SPEC.system:  # one of several bodies: the system's kick asks its loads only
        linearised_loads(y[0:3], np.eye(3), 0.0, y[7:10], y[7:10], model, sea)
        return
    if not HOLDING:  # (a moored body steps by step_held alone: system/single.py, Single._moored)
        advance(y, 0.0, 1, 0.01, model, sea, rad)
    else:
        levers, pos, vel = np.zeros((1, 3)), np.zeros(3), np.zeros(3)
        s, keep = held_start(y, 0.0, 0.01, model, sea, rad, levers, pos, vel)
        step_held(y, 0.0, 0.01, model, sea, rad, s, keep, np.zeros((1, 3)), np.zeros((1, 3)), levers, pos, vel, False)
    observe(y[0:3], np.eye(3), 0.0, y[7:10], y[7:10], model, sea, np.empty(body.n_samples, dtype=np.bool_))
    exact_hydrostatic_energy(y[0:3].copy(), np.eye(3), body.packed, 1.0)  # the energy check of every frame

"""Compiled twin of system.py's step (System.affine, kick, step; SystemRadiation.load and drift) and of the bodies'
linear loads (linear_hydro.LinearLoads): Stormer-Verlet on the tree, each half kick solved exactly by a matrix
exponential (expm.py) with Van Loan's integral for the take-offs' absorbed energy.

A configuration's kinematics (`configure`: poses, Jacobians, the mass matrix with the added mass, the velocity-product
term's rates) is computed once and serves the kick at a step's end and the next step's first. The bodies' loads
come from the linear pack (`advance`: n steps in one call) or from outside, one call a kick (`first_half` and
`kick`: the bodies' own compiled or numpy loads, called from Python between them). Arrays follow system_layout.py.
"""

from __future__ import annotations

import math

import numpy as np

from .expm import expm, matmul, solve
from .jit import JIT, njit
from .kinematics import bias, body_poses, drifted, inertia_matrix, mm3, rates
from .water import ramp_factor


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
def sparse_matvec(rows, x):
    indptr, indices, values = rows
    out = np.zeros(indptr.shape[0] - 1)
    for i in range(out.shape[0]):
        acc = 0.0
        for p in range(indptr[i], indptr[i + 1]):
            acc += values[p] * x[indices[p]]
        out[i] = acc
    return out


@njit(**JIT)
def add_transposed(Q, J, f):
    """Q += J^T f."""
    for c in range(J.shape[1]):
        acc = 0.0
        for i in range(J.shape[0]):
            acc += J[i, c] * f[i]
        Q[c] += acc


@njit(**JIT)
def add_sandwich(D, J, Db):
    """D += J^T Db J (J (6, n))."""
    n = J.shape[1]
    DJ = np.zeros((6, n))
    for i in range(6):
        for m in range(6):
            d = Db[i, m]
            if d != 0.0:
                for c in range(n):
                    DJ[i, c] += d * J[m, c]
    for a in range(n):
        for c in range(n):
            acc = 0.0
            for i in range(6):
                acc += J[i, a] * DJ[i, c]
            D[a, c] += acc


@njit(**JIT)
def configure(tree, mem, x_free, q_free, theta):
    """What depends on the configuration only: (x, R, J) of each body, M_q with the added mass, T^T J (the twists in the
    radiation fit's axes) and dJ/dt along each unit velocity (empty without a velocity-product term)."""
    x, R, J = body_poses(tree, x_free, q_free, theta)
    M, G = inertia_matrix(tree, R, J, mem.added, mem.R0, mem.on)
    along = rates(tree, x_free, q_free, theta) if tree.needs_bias else np.zeros((0, R.shape[0], 6, tree.n_dofs))
    return x, R, J, M, G, along


@njit(**JIT)
def rotation_vector(R):
    """linear_hydro.rotation_vector: phi with R = exp(skew(phi)), through the quaternion near a half turn."""
    c = 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0)
    if c < -0.9:
        q = matrix_to_quat(R)
        w, v = (q[0], q[1:].copy()) if q[0] >= 0 else (-q[0], -q[1:])
        s = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
        return v * (2.0 * math.atan2(s, w) / s)
    v = 0.5 * np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    s = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    return v * (math.atan2(s, c) / s if s > 1e-12 else 1.0)


@njit(**JIT)
def matrix_to_quat(R):
    """rotation.matrix_to_quat (Shepperd's method), w >= 0."""
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    k, best = 0, tr
    for i in range(3):
        if R[i, i] > best:
            k, best = i + 1, R[i, i]
    q = np.empty(4)
    if k == 0:
        s = 2.0 * math.sqrt(1.0 + tr)
        q[0], q[1], q[2], q[3] = s / 4, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s
    else:
        i = k - 1
        j, m = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * math.sqrt(1.0 + R[i, i] - R[j, j] - R[m, m])
        q[0], q[1 + i], q[1 + j], q[1 + m] = (R[m, j] - R[j, m]) / s, s / 4, (R[j, i] + R[i, j]) / s, (R[m, i] + R[i, m]) / s
    q /= math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    return q if q[0] >= 0 else -q


@njit(**JIT)
def linear_loads(lin, x, R, t):
    """(f (k, 6), D (k, 6, 6)): each body's linear loads (LinearLoads.__call__): f0 - C xi + the Froude-Krylov force."""
    k = x.shape[0]
    f, D = np.empty((k, 6)), lin.D0.copy()
    r = ramp_factor(t, lin.ramp)
    xi = np.empty(6)
    for b in range(k):
        xi[:3] = x[b] - lin.x0[b]
        xi[3:] = rotation_vector(mm3(R[b], lin.R0[b].T))
        wave = np.zeros(6)
        for i in range(lin.omega.shape[0]):
            psi = lin.k[i, 0] * (x[b, 0] - lin.x0[b, 0]) + lin.k[i, 1] * (x[b, 1] - lin.x0[b, 1]) - lin.omega[i] * t
            c, s = math.cos(psi), math.sin(psi)
            for j in range(6):
                wave[j] += c * lin.X_re[b, i, j] - s * lin.X_im[b, i, j]
        for j in range(6):
            acc = 0.0
            for m in range(6):
                acc += lin.C[b, j, m] * xi[m]
            f[b, j] = lin.f0[b, j] - acc + r * wave[j]
    return f, D


@njit(**JIT)
def radiation_load(mem, G, J, x, memory, t):
    """(n,) the memory's load and the diffraction force, generalised: J^T (-T H x + f_d(t, x_b))."""
    Q = np.zeros(G.shape[1])
    add_transposed(Q, G, -sparse_matvec(mem.H, memory))
    if mem.diffracting:
        k = x.shape[0]
        f = np.zeros(6 * k)
        for i in range(mem.omega.shape[0]):
            for b in range(k):
                psi = mem.k[i, 0] * x[b, 0] + mem.k[i, 1] * x[b, 1] - mem.omega[i] * t
                c, s = math.cos(psi), math.sin(psi)
                for j in range(6 * b, 6 * b + 6):
                    f[j] += c * mem.A_re[i, j] - s * mem.A_im[i, j]
        r = ramp_factor(t, mem.ramp)
        for b in range(k):
            add_transposed(Q, J[b], r * f[6 * b : 6 * b + 6])
    return Q


@njit(**JIT)
def kick(tree, mem, config, t, theta, v, absorbed, memory, f, D_b, held, h):
    """(v, absorbed) after h under M v_dot = Q0 - D v (linearised at v), solved exactly (System.kick); f, D_b: each body's
    loads near its twist J_b v, held: the load another model holds on each body (k, 6)."""
    x, R, J, M, G, along = config
    n = tree.n_dofs
    Q, D = np.zeros(n), np.zeros((n, n))
    for b in range(x.shape[0]):
        add_transposed(Q, J[b], f[b] + held[b])
        add_sandwich(D, J[b], D_b[b])
    for gi in tree.joints:
        i = tree.dof[gi]
        Q[i] -= tree.stiffness[gi] * theta[tree.coordinate[gi]]
        D[i, i] += tree.damping[gi]
    if mem.on:
        Q += radiation_load(mem, G, J, x, memory, t)
    if tree.needs_bias:
        b0, B = bias(tree, R, J, along, v)
        Q, D = Q + b0, D + B
    A = np.zeros((n + 1, n + 1))  # z = (v, 1): z_dot = A z
    A[:n, :n] = -solve(M, D)
    A[:n, n] = solve(M, Q.reshape(n, 1))[:, 0]
    z = np.ones(n + 1)
    z[:n] = v
    big = np.zeros((2 * n + 2, 2 * n + 2))  # Van Loan: its exponential holds e^{Ah} and the integral of z z^T over h
    big[: n + 1, : n + 1] = A
    big[: n + 1, n + 1 :] = np.outer(z, z)
    big[n + 1 :, n + 1 :] = -A.T
    E = expm(big * h)
    Phi = E[: n + 1, : n + 1]
    gram = matmul(E[: n + 1, n + 1 :], Phi.T)
    out = absorbed.copy()
    for gi in tree.joints:
        i = tree.dof[gi]
        out[tree.coordinate[gi]] += tree.damping[gi] * gram[i, i]
    return matvec(Phi, z)[:n], out


@njit(**JIT)
def memory_drift(mem, G0, G1, v, memory, E_rad, h):
    """The memory over a drift at v, driven by the twists in the fit's axes averaged over both ends, and the radiated
    energy h nu . mu likewise (SystemRadiation.drift)."""
    nu0, nu1 = matvec(G0, v), matvec(G1, v)
    after = sparse_matvec(mem.Phi, memory) + sparse_matvec(mem.Gamma, 0.5 * (nu0 + nu1))
    power = 0.5 * (np.dot(nu0, sparse_matvec(mem.H, memory)) + np.dot(nu1, sparse_matvec(mem.H, after)))
    return after, E_rad + h * power


@njit(**JIT)
def first_half(tree, mem, config, t, x_free, q_free, theta, v, absorbed, memory, E_rad, f, D_b, held, h):
    """A step up to its last kick: half kick with the loads f, D_b, drift, the memory with it; the new configuration's
    kinematics (its bodies' loads are asked next, then `kick`)."""
    v, absorbed = kick(tree, mem, config, t, theta, v, absorbed, memory, f, D_b, held, 0.5 * h)
    x_free, q_free, theta = drifted(tree, x_free, q_free, theta, v, h)
    moved = configure(tree, mem, x_free, q_free, theta)
    if mem.on:
        memory, E_rad = memory_drift(mem, config[4], moved[4], v, memory, E_rad, h)
    return moved, x_free, q_free, theta, v, absorbed, memory, E_rad


@njit(**JIT)
def finite(x_free, q_free, theta, v):
    return np.isfinite(x_free).all() and np.isfinite(q_free).all() and np.isfinite(theta).all() and np.isfinite(v).all()


@njit(**JIT)
def advance(tree, lin, mem, t, x_free, q_free, theta, v, absorbed, memory, E_rad, held, h, n):
    """n steps with the linear loads (lin.on), the held loads fixed; stops after a step that leaves the state non-finite.
    Returns the state and the steps taken."""
    config = configure(tree, mem, x_free, q_free, theta)
    taken = 0
    for _ in range(n):
        f, D_b = linear_loads(lin, config[0], config[1], t)
        config, x_free, q_free, theta, v, absorbed, memory, E_rad = first_half(
            tree, mem, config, t, x_free, q_free, theta, v, absorbed, memory, E_rad, f, D_b, held, h
        )
        t = t + h
        f, D_b = linear_loads(lin, config[0], config[1], t)
        v, absorbed = kick(tree, mem, config, t, theta, v, absorbed, memory, f, D_b, held, 0.5 * h)
        taken += 1
        if not finite(x_free, q_free, theta, v):
            break
    return t, x_free, q_free, theta, v, absorbed, memory, E_rad, taken

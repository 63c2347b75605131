"""Compiled twin of system/tree.py's step (System.affine, kick, step; SystemRadiation.load and drift) and of the bodies'
linear loads (linear_hydro.LinearLoads): Stormer-Verlet on the tree, each half kick solved exactly by a matrix
exponential (expm.py) with Van Loan's integral for the take-offs' absorbed energy.

A configuration's kinematics (`configure`: poses, Jacobians, the mass matrix with the added mass, the velocity-product
term's rates) is computed once and serves the kick at a step's end and the next step's first. The bodies' loads
come from the linear pack (`advance`: n steps in one call) or from outside, one call a kick (`half_step`, with and
without its drift: the bodies' own compiled or numpy loads, called from Python between them). Arrays follow system_layout.py.
`advance` works in place on buffers made once a call (Work); the other entry points keep their signatures and make
theirs a call.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .expm import expm_into, solve_into
from .jit import JIT, njit
from .kinematics import Kinematics, bias_into, bodies_into, drift_into, inertia_into, mm3, poses_into, rates_into, work
from .water import ramp_factor


class Work(NamedTuple):
    """The step's work buffers, made once a call (`scratch`): nothing is allocated step by step."""

    kin: Kinematics
    Q: np.ndarray
    D: np.ndarray
    rhs: np.ndarray
    """(n, n + 1) M^-1 [D | Q]."""
    LU: np.ndarray
    big: np.ndarray
    """(2n + 2, 2n + 2) Van Loan's matrix."""
    E: np.ndarray
    expm: np.ndarray
    z: np.ndarray
    DJ: np.ndarray
    b: np.ndarray
    B: np.ndarray
    rows3: np.ndarray
    mats: np.ndarray
    vecs: np.ndarray
    Qr: np.ndarray
    Hm: np.ndarray
    """H memory: the memory's output, kept with the memory."""
    fd: np.ndarray
    nu: np.ndarray
    """(3, 6k) the twists in the fit's axes at both ends of a drift and their mean."""
    after: np.ndarray
    phase: np.ndarray
    """(k, c, 2) cos and sin of each component's phase at each body, from the linear loads (c = 0: not shared)."""
    shift: np.ndarray
    """(k, c, 2) cos and sin of k . x0_b: the diffraction's phase at x_b is the linear loads' shifted by it."""


@njit(**JIT)
def scratch(tree, mem, memory, c):
    """The work buffers; c: the components whose phases the linear loads and the diffraction share (0: none; shifts_into)."""
    n, k = tree.n_dofs, tree.group.shape[0]
    m, k6 = 2 * n + 2, 6 * k if mem.on else 0
    return Work(work(tree, k6), np.zeros(n), np.zeros((n, n)), np.zeros((n, n + 1)), np.zeros((n, n)), np.zeros((m, m)), np.zeros((m, m)),
                np.zeros((7, m, m)), np.zeros(n + 1), np.zeros((6, n)), np.zeros(n), np.zeros((n, n)), np.zeros((3, 6, n)),
                np.zeros((4, 3, 3)), np.zeros((2, 6)), np.zeros(n), np.zeros(mem.H[0].shape[0] - 1), np.zeros(6 * k),
                np.zeros((3, 6 * k)), np.zeros(memory.shape[0]), np.zeros((k, c, 2)), np.zeros((k, c, 2)))  # fmt: skip


@njit(**JIT)
def shifts_into(lin, mem, shift):
    """shift = cos and sin of k . x0_b (Work.shift)."""
    for b in range(shift.shape[0]):
        for i in range(shift.shape[1]):
            psi = mem.k[i, 0] * lin.x0[b, 0] + mem.k[i, 1] * lin.x0[b, 1]
            shift[b, i, 0], shift[b, i, 1] = math.cos(psi), math.sin(psi)


@njit(**JIT)
def shared_sea(lin, mem):
    """Whether the linear loads and the diffraction sum the same components (the same sea): one cos and sin each."""
    if not (lin.on and mem.on and mem.diffracting) or lin.omega.shape[0] != mem.omega.shape[0] or lin.ramp != mem.ramp:
        return False
    for i in range(lin.omega.shape[0]):
        if lin.omega[i] != mem.omega[i] or lin.k[i, 0] != mem.k[i, 0] or lin.k[i, 1] != mem.k[i, 1]:
            return False
    return True


@njit(**JIT)
def sparse_matvec(rows, x):
    out = np.zeros(rows[0].shape[0] - 1)
    sparse_into(rows, x, out, False)
    return out


@njit(**JIT)
def sparse_into(rows, x, out, add):
    """out = rows x (add: out += rows x)."""
    indptr, indices, values = rows
    for i in range(out.shape[0]):
        acc = 0.0
        for p in range(indptr[i], indptr[i + 1]):
            acc += values[p] * x[indices[p]]
        out[i] = out[i] + acc if add else acc


@njit(**JIT)
def add_transposed(Q, J, f):
    """Q += J^T f."""
    for c in range(J.shape[1]):
        acc = 0.0
        for i in range(J.shape[0]):
            acc += J[i, c] * f[i]
        Q[c] += acc


@njit(**JIT)
def add_sandwich(D, J, Db, DJ):
    """D += J^T Db J (J (6, n)); DJ (6, n) work."""
    n = J.shape[1]
    DJ[:] = 0.0
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
    config = new_config(tree, mem)
    configure_into(tree, mem, x_free, q_free, theta, config, work(tree, config[4].shape[0]), np.empty((3, 3)))
    return config


@njit(**JIT)
def new_config(tree, mem):
    k, n = tree.group.shape[0], tree.n_dofs
    along = np.zeros((n if tree.needs_bias else 0, k, 6, n))
    return np.zeros((k, 3)), np.zeros((k, 3, 3)), np.zeros((k, 6, n)), np.zeros((n, n)), np.zeros((6 * k, n)), along


@njit(**JIT)
def configure_into(tree, mem, x_free, q_free, theta, config, kin, I3):
    """configure's, into config's arrays (the rates' rows of the unturning velocities stay zero)."""
    x, R, J, M, G, along = config
    poses_into(tree, x_free, q_free, theta, kin.xs, kin.Rs, kin.Js, kin.turn)
    bodies_into(tree, kin.xs, kin.Rs, kin.Js, x, R, J)
    inertia_into(tree, R, J, mem.added, mem.R0, mem.on, M, G, kin.MJ, kin.AG, I3)
    if tree.needs_bias:
        rates_into(tree, theta, kin, x, along)


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
    linear_into(lin, x, R, t, f, np.empty((2, 6)), np.empty((k, 0, 2)))
    return f, D


@njit(**JIT)
def linear_into(lin, x, R, t, f, vecs, phase):
    """f = linear_loads' (their D is lin.D0); vecs (2, 6) work; phase (k, c, 2): each cos and sin kept (c = 0: not)."""
    keep = phase.shape[1] > 0
    r = ramp_factor(t, lin.ramp)
    xi, wave = vecs[0], vecs[1]
    for b in range(x.shape[0]):
        xi[:3] = x[b] - lin.x0[b]
        xi[3:] = rotation_vector(mm3(R[b], lin.R0[b].T))
        wave[:] = 0.0
        for i in range(lin.omega.shape[0]):
            psi = lin.k[i, 0] * (x[b, 0] - lin.x0[b, 0]) + lin.k[i, 1] * (x[b, 1] - lin.x0[b, 1]) - lin.omega[i] * t
            c, s = math.cos(psi), math.sin(psi)
            if keep:
                phase[b, i, 0], phase[b, i, 1] = c, s
            for j in range(6):
                wave[j] += c * lin.X_re[b, i, j] - s * lin.X_im[b, i, j]
        for j in range(6):
            acc = 0.0
            for m in range(6):
                acc += lin.C[b, j, m] * xi[m]
            f[b, j] = lin.f0[b, j] - acc + r * wave[j]


@njit(**JIT)
def radiation_load(mem, G, J, x, memory, t):
    """(n,) the memory's load and the diffraction force, generalised: J^T (-T H x + f_d(t, x_b))."""
    Q = np.zeros(G.shape[1])
    none = np.zeros((x.shape[0], 0, 2))
    radiation_into(mem, G, J, x, sparse_matvec(mem.H, memory), t, Q, np.zeros(6 * x.shape[0]), none, none)
    return Q


@njit(**JIT)
def radiation_into(mem, G, J, x, Hm, t, Q, f, phase, shift):
    """Q = radiation_load's from the memory's output Hm = H x; f (6k) work; phase and shift (Work's): the diffraction's
    phases from the linear loads' (cos (a + b) = cos a cos b - sin a sin b), else from their own cos and sin."""
    Q[:] = 0.0
    for c in range(G.shape[1]):  # Q = G^T (-Hm)
        acc = 0.0
        for i in range(G.shape[0]):
            acc += G[i, c] * -Hm[i]
        Q[c] += acc
    if mem.diffracting:
        k = x.shape[0]
        f[:] = 0.0
        for i in range(mem.omega.shape[0]):
            for b in range(k):
                if shift.shape[1] > 0:
                    a, d, ca, sa = phase[b, i, 0], phase[b, i, 1], shift[b, i, 0], shift[b, i, 1]
                    c, s = a * ca - d * sa, d * ca + a * sa
                else:
                    psi = mem.k[i, 0] * x[b, 0] + mem.k[i, 1] * x[b, 1] - mem.omega[i] * t
                    c, s = math.cos(psi), math.sin(psi)
                for j in range(6 * b, 6 * b + 6):
                    f[j] += c * mem.A_re[i, j] - s * mem.A_im[i, j]
        r = ramp_factor(t, mem.ramp)
        for b in range(k):
            for c in range(J.shape[2]):
                acc = 0.0
                for i in range(6):
                    acc += J[b, i, c] * (r * f[6 * b + i])
                Q[c] += acc
    if mem.drifting:
        wave_drift_into(mem, J, x, t, Q)


@njit(**JIT)
def wave_drift_into(mem, J, x, t, Q):
    """Q += J_root^T F: the drift force of the bodies together on the root (SystemRadiation.load's, drift.Drift.force)."""
    b = mem.drift_root
    A = np.zeros(6)
    B = np.zeros(6)
    for i in range(mem.drift_omega.shape[0]):
        psi = mem.drift_k[i, 0] * x[b, 0] + mem.drift_k[i, 1] * x[b, 1] - mem.drift_omega[i] * t
        c, s = math.cos(psi), math.sin(psi)
        for j in range(6):
            A[j] += c * mem.E_re[i, j] - s * mem.E_im[i, j]
            B[j] += s * mem.E_re[i, j] + c * mem.E_im[i, j]
    r = ramp_factor(t, mem.drift_ramp)
    F = np.zeros(6)
    for j in range(3):  # Re{A conj(A')} of F_x, F_y, M_z
        F[(0, 1, 5)[j]] = (A[2 * j] * A[2 * j + 1] + B[2 * j] * B[2 * j + 1]) * r * r
    F[5] -= mem.drift_lever[0] * F[1] - mem.drift_lever[1] * F[0]
    for c in range(J.shape[2]):
        acc = 0.0
        for i in range(6):
            acc += J[b, i, c] * F[i]
        Q[c] += acc


@njit(**JIT)
def kick_into(tree, mem, config, t, theta, v, absorbed, f, D_b, held, h, w):
    """kick's, v and absorbed updated in place; the memory's output in w.Hm."""
    x, R, J, M, G, along = config
    n = tree.n_dofs
    Q, D = w.Q, w.D
    Q[:] = 0.0
    D[:] = 0.0
    for b in range(x.shape[0]):
        for c in range(n):  # Q += J_b^T (f_b + held_b)
            acc = 0.0
            for i in range(6):
                acc += J[b, i, c] * (f[b, i] + held[b, i])
            Q[c] += acc
        add_sandwich(D, J[b], D_b[b], w.DJ)
    for gi in tree.joints:
        i = tree.dof[gi]
        Q[i] += tree.force[gi] - tree.stiffness[gi] * theta[tree.coordinate[gi]]
        D[i, i] += tree.damping[gi]
    if mem.on:
        radiation_into(mem, G, J, x, w.Hm, t, w.Qr, w.fd, w.phase, w.shift)
        Q += w.Qr
    if tree.needs_bias:
        bias_into(tree, R, J, along, v, w.b, w.B, w.rows3, w.mats, w.vecs)
        Q += w.b
        D += w.B
    w.LU[:] = M  # [-M^-1 D | M^-1 Q] in one elimination
    for gi in tree.joints:  # a locked joint (a latch): its rate stays zero, the other coordinates move without it
        if tree.held[gi] > 0.0:
            i = tree.dof[gi]
            v[i] = 0.0
            w.LU[i, :] = 0.0
            w.LU[:, i] = 0.0
            w.LU[i, i] = 1.0
            D[i, :] = 0.0
            D[:, i] = 0.0
            Q[i] = 0.0
    w.rhs[:, :n] = D
    w.rhs[:, n] = Q
    solve_into(w.LU, w.rhs)
    z, big = w.z, w.big
    z[:n] = v
    z[n] = 1.0
    big[:] = 0.0  # Van Loan: [[A, z z^T], [0, -A^T]] h, z = (v, 1): z_dot = A z; its exponential holds e^{Ah} and the integral of z z^T
    for i in range(n):
        for j in range(n):
            big[i, j] = -w.rhs[i, j] * h
            big[n + 1 + j, n + 1 + i] = w.rhs[i, j] * h
        big[i, n] = w.rhs[i, n] * h
        big[n + 1 + n, n + 1 + i] = -w.rhs[i, n] * h
    for i in range(n + 1):
        for j in range(n + 1):
            big[i, n + 1 + j] = z[i] * z[j] * h
    E = w.E
    expm_into(big, E, w.expm)
    for gi in tree.joints:  # the take-off's diagonal of the gram E_12 Phi^T (the damper's), and its last column (the force's)
        i = tree.dof[gi]
        acc = 0.0
        for m in range(n + 1):
            if E[i, n + 1 + m] != 0.0:
                acc += E[i, n + 1 + m] * E[i, m]
        absorbed[tree.coordinate[gi]] += tree.damping[gi] * acc - tree.force[gi] * E[i, 2 * n + 1]
    for i in range(n):
        acc = 0.0
        for j in range(n + 1):
            acc += E[i, j] * z[j]
        v[i] = acc


@njit(**JIT)
def memory_drift(mem, G0, G1, v, memory, E_rad, h):
    """The memory over a drift at v, driven by the twists in the fit's axes averaged over both ends, and the radiated
    energy h nu . mu likewise (SystemRadiation.drift)."""
    w = scratch_drift(mem, G0, memory)
    memory = memory.copy()
    sparse_into(mem.H, memory, w[0], False)
    return memory, memory_into(mem, G0, G1, v, memory, E_rad, h, w[0], w[1], w[2])


@njit(**JIT)
def scratch_drift(mem, G0, memory):
    return np.zeros(mem.H[0].shape[0] - 1), np.zeros((3, G0.shape[0])), np.zeros(memory.shape[0])


@njit(**JIT)
def memory_into(mem, G0, G1, v, memory, E_rad, h, Hm, nu, after):
    """memory_drift's in place (memory and its output Hm, which holds H memory on entry); returns E_rad."""
    nu0, nu1, mean = nu[0], nu[1], nu[2]
    for i in range(G0.shape[0]):
        a0, a1 = 0.0, 0.0
        for j in range(G0.shape[1]):
            a0 += G0[i, j] * v[j]
            a1 += G1[i, j] * v[j]
        nu0[i], nu1[i] = a0, a1
        mean[i] = 0.5 * (a0 + a1)
    sparse_into(mem.Phi, memory, after, False)
    sparse_into(mem.Gamma, mean, after, True)
    power = np.dot(nu0, Hm)
    sparse_into(mem.H, after, Hm, False)
    power = 0.5 * (power + np.dot(nu1, Hm))
    memory[:] = after
    return E_rad + h * power


CLOSE, OPEN, CONFIGURE = 0, 1, 2
"""half_step's parts: the closing half kick; the opening half kick and the drift; the configuration alone."""


@njit(**JIT)
def half_step(tree, mem, config, t, x_free, q_free, theta, v, absorbed, memory, E_rad, f, D_b, held, h, part):
    """Half a step of h: a half kick (h/2) under M v_dot = Q0 - D v (linearised at v), solved exactly (System.kick), with
    f, D_b each body's loads near its twist J_b v and held the load another model holds on each body (k, 6); then, for
    the OPEN part, the drift over h, the memory with it and the new configuration's kinematics (its bodies' loads are
    asked next, then the CLOSE part: the closing half kick). CONFIGURE: no kick, the configuration at (x_free, q_free,
    theta) alone (`config` any of the same types). One entry point for the three: each entry point optimises the code
    it links, so a kick or a configuration of its own would compile the kick or the kinematics twice."""
    if part == CONFIGURE:
        return configure(tree, mem, x_free, q_free, theta), x_free, q_free, theta, v, absorbed, memory, E_rad
    w = scratch(tree, mem, memory, 0)
    if mem.on:
        sparse_into(mem.H, memory, w.Hm, False)
    v, absorbed = v.copy(), absorbed.copy()
    kick_into(tree, mem, config, t, theta, v, absorbed, f, D_b, held, 0.5 * h, w)
    if part == CLOSE:
        return config, x_free, q_free, theta, v, absorbed, memory, E_rad
    x_free, q_free, theta = x_free.copy(), q_free.copy(), theta.copy()
    drift_into(tree, x_free, q_free, theta, v, h)
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
    Returns the state, the steps taken and the configuration reached (n = 0: the configuration at the state, and no
    configure entry point of its own, which would compile the kinematics a second time). Works in place on copies of the state and on buffers made once: two
    configurations (a step's start and end), swapped each step."""
    x_free, q_free, theta, v, absorbed, memory = x_free.copy(), q_free.copy(), theta.copy(), v.copy(), absorbed.copy(), memory.copy()
    w = scratch(tree, mem, memory, mem.omega.shape[0] if shared_sea(lin, mem) else 0)
    shifts_into(lin, mem, w.shift)
    now, moved = new_config(tree, mem), new_config(tree, mem)
    configure_into(tree, mem, x_free, q_free, theta, now, w.kin, w.mats[0])
    if mem.on:
        sparse_into(mem.H, memory, w.Hm, False)
    f, D_b = np.empty((now[0].shape[0], 6)), lin.D0.copy()
    taken = 0
    for _ in range(n):
        linear_into(lin, now[0], now[1], t, f, w.vecs, w.phase)
        kick_into(tree, mem, now, t, theta, v, absorbed, f, D_b, held, 0.5 * h, w)
        drift_into(tree, x_free, q_free, theta, v, h)
        configure_into(tree, mem, x_free, q_free, theta, moved, w.kin, w.mats[0])
        if mem.on:
            E_rad = memory_into(mem, now[4], moved[4], v, memory, E_rad, h, w.Hm, w.nu, w.after)
        now, moved = moved, now
        t = t + h
        linear_into(lin, now[0], now[1], t, f, w.vecs, w.phase)
        kick_into(tree, mem, now, t, theta, v, absorbed, f, D_b, held, 0.5 * h, w)
        taken += 1
        if not finite(x_free, q_free, theta, v):
            break
    return t, x_free, q_free, theta, v, absorbed, memory, E_rad, taken, now

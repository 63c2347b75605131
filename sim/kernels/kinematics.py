"""Compiled twin of system.py's kinematics (System.group_poses, _pose_of, drifted, mass_matrix, inertia, bias): the
tree packed as system_layout.Tree, each body's pose and twist Jacobian, the mass matrix with the radiation's added
mass, and the velocity-product load b(v) with its Jacobian, J_dot from the same central differences as the reference
(so the two agree to round-off, not to the differences' 1e-10)."""

from __future__ import annotations

import math

import numpy as np

from .jit import JIT, njit
from .rotation import cross, mv, quat_multiply, quat_to_matrix, rotation_quat
from .system_layout import EPS, FREE, PLANAR, PRISMATIC, REVOLUTE


@njit(**JIT)
def turn_about(axis, angle):
    """Rodrigues (joints._rotation): I + sin K + (1 - cos) K^2, K = skew(axis)."""
    K = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    s, c = math.sin(angle), 1.0 - math.cos(angle)
    out = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            out[i, j] = (1.0 if i == j else 0.0) + s * K[i, j] + c * (K[i, 0] * K[0, j] + K[i, 1] * K[1, j] + K[i, 2] * K[2, j])
    return out


@njit(**JIT)
def mm3(A, B):
    out = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            out[i, j] = A[i, 0] * B[0, j] + A[i, 1] * B[1, j] + A[i, 2] * B[2, j]
    return out


@njit(**JIT)
def carried(J, r):
    """The Jacobian of the twist at a point r from the one J is at, on the same rigid frame: u + omega x r."""
    out = J.copy()
    for c in range(J.shape[1]):
        w = J[3:, c]
        out[0, c] -= -r[2] * w[1] + r[1] * w[2]
        out[1, c] -= r[2] * w[0] - r[0] * w[2]
        out[2, c] -= -r[1] * w[0] + r[0] * w[1]
    return out


@njit(**JIT)
def group_poses(tree, x_free, q_free, theta):
    """(x (g, 3), R (g, 3, 3), J (g, 6, n)) of each group's origin: forward kinematics down the tree."""
    g, n = tree.kind.shape[0], tree.n_dofs
    xs, Rs, Js = np.zeros((g, 3)), np.zeros((g, 3, 3)), np.zeros((g, 6, n))
    for i in range(g):
        p, kind, c, d = tree.parent[i], tree.kind[i], tree.coordinate[i], tree.dof[i]
        if p < 0:
            xp, Rp, Jp = np.zeros(3), np.eye(3), np.zeros((6, n))
        else:
            xp, Rp, Jp = xs[p], Rs[p], Js[p]
        axis = tree.axis[i]
        if kind == FREE:
            x, R = x_free[c].copy(), quat_to_matrix(q_free[c])
            J = np.zeros((6, n))
            for k in range(6):
                J[k, d + k] = 1.0
        elif kind == PLANAR:
            e1, e2 = tree.plane[i, 0], tree.plane[i, 1]
            a, b, phi = theta[c], theta[c + 1], theta[c + 2]
            x, R = xp + mv(Rp, tree.offset[i] + a * e1 + b * e2), mm3(Rp, turn_about(axis, phi))
            J = carried(Jp, x - xp)
            J[:3, d] += mv(Rp, e1)
            J[:3, d + 1] += mv(Rp, e2)
            J[3:, d + 2] += mv(Rp, axis)
        else:
            th = theta[c] if c >= 0 else 0.0
            a = mv(Rp, axis)
            if kind == REVOLUTE:
                turn = turn_about(axis, th)
                x, R = xp + mv(Rp, tree.pivot[i] + mv(turn, tree.offset[i] - tree.pivot[i])), mm3(Rp, turn)
            else:
                x, R = xp + mv(Rp, tree.offset[i] + th * axis if kind == PRISMATIC else tree.offset[i]), Rp.copy()
            J = carried(Jp, x - xp)
            if kind == PRISMATIC:
                J[:3, d] += a
            elif kind == REVOLUTE:
                J[:3, d] += cross(a, x - (xp + mv(Rp, tree.pivot[i])))
                J[3:, d] += a
        xs[i], Rs[i], Js[i] = x, R, J
    return xs, Rs, Js


@njit(**JIT)
def body_poses(tree, x_free, q_free, theta):
    """(x (k, 3), R (k, 3, 3), J (k, 6, n)) of each body (System.pose), the scene's order."""
    xg, Rg, Jg = group_poses(tree, x_free, q_free, theta)
    k, n = tree.group.shape[0], tree.n_dofs
    x, R, J = np.zeros((k, 3)), np.zeros((k, 3, 3)), np.zeros((k, 6, n))
    for b in range(k):
        gi = tree.group[b]
        x[b] = xg[gi] + mv(Rg[gi], tree.member_offset[b])
        R[b] = mm3(Rg[gi], tree.member_rotation[b])
        J[b] = carried(Jg[gi], x[b] - xg[gi])
    return x, R, J


@njit(**JIT)
def drifted(tree, x_free, q_free, theta, v, h):
    """The coordinates moved at velocity v for time h: free groups translated and turned by exp(h omega)."""
    x, q, th = x_free.copy(), q_free.copy(), theta.copy()
    for i in range(tree.kind.shape[0]):
        c, d = tree.coordinate[i], tree.dof[i]
        if tree.kind[i] == FREE:
            x[c] += h * v[d : d + 3]
            q[c] = quat_multiply(rotation_quat(h * v[d + 3 : d + 6]), q[c])
        elif c >= 0:
            th[c : c + tree.width[i]] += h * v[d : d + tree.width[i]]
    return x, q, th


@njit(**JIT)
def world_inertia(R, inertia):
    """R diag(inertia) R^T."""
    out = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            out[i, j] = R[i, 0] * inertia[0] * R[j, 0] + R[i, 1] * inertia[1] * R[j, 1] + R[i, 2] * inertia[2] * R[j, 2]
    return out


@njit(**JIT)
def turned(R, R0, J):
    """(6, n) T^T J for one body, T = diag(R R0^T, R R0^T): its twist in the radiation fit's axes."""
    T = mm3(R0, R.T)
    out = np.empty_like(J)
    for half in range(2):
        for i in range(3):
            for c in range(J.shape[1]):
                out[3 * half + i, c] = T[i, 0] * J[3 * half, c] + T[i, 1] * J[3 * half + 1, c] + T[i, 2] * J[3 * half + 2, c]
    return out


@njit(**JIT)
def inertia_matrix(tree, R, J, added, R0, radiating):
    """(n, n) sum_b J_b^T M_b J_b, plus J^T T A_inf T^T J with radiation; and (6k, n) T^T J (zeros without)."""
    k, n = R.shape[0], tree.n_dofs
    M = np.zeros((n, n))
    G = np.zeros((6 * k, n))
    MJ = np.empty((6, n))
    for b in range(k):
        I3 = world_inertia(R[b], tree.inertia[b])
        Jb = J[b]
        for c in range(n):
            for i in range(3):
                MJ[i, c] = tree.mass[b] * Jb[i, c]
                MJ[3 + i, c] = I3[i, 0] * Jb[3, c] + I3[i, 1] * Jb[4, c] + I3[i, 2] * Jb[5, c]
        transposed_product(M, Jb, MJ)
        if radiating:
            G[6 * b : 6 * b + 6] = turned(R[b], R0[b], Jb)
    if radiating:
        AG = np.zeros((6 * k, n))
        for i in range(6 * k):
            for m in range(6 * k):
                a = added[i, m]
                for c in range(n):
                    AG[i, c] += a * G[m, c]
        transposed_product(M, G, AG)
    return M, G


@njit(**JIT)
def transposed_product(M, A, B):
    """M += A^T B."""
    for a in range(A.shape[1]):
        for c in range(B.shape[1]):
            acc = 0.0
            for i in range(A.shape[0]):
                acc += A[i, a] * B[i, c]
            M[a, c] += acc


@njit(**JIT)
def rates(tree, x_free, q_free, theta):
    """(n, k, 6, n) dJ_b/dt while moving at each unit velocity (zeros where it changes no Jacobian): central differences."""
    n, k = tree.n_dofs, tree.group.shape[0]
    out = np.zeros((n, k, 6, n))
    for i in tree.turning:
        e = np.zeros(n)
        e[i] = 1.0
        ahead = body_poses(tree, *drifted(tree, x_free, q_free, theta, e, EPS))[2]
        behind = body_poses(tree, *drifted(tree, x_free, q_free, theta, e, -EPS))[2]
        out[i] = (ahead - behind) / (2 * EPS)
    return out


@njit(**JIT)
def bias(tree, R, J, along_e, v):
    """(b(v), db/dv) (System.bias): b = sum_b J_b^T (M_b J_b_dot v + (0, omega x I omega))."""
    n, k = tree.n_dofs, R.shape[0]
    b, B = np.zeros(n), np.zeros((n, n))
    along_v, crossed, rows = np.empty((6, n)), np.empty((6, n)), np.empty((6, n))
    a, omega, load = np.empty(6), np.empty(3), np.empty(6)
    for m in range(k):
        Jm = J[m]
        along_v[:] = 0.0
        for i in tree.turning:
            for r in range(6):
                for c in range(n):
                    along_v[r, c] += v[i] * along_e[i, m, r, c]
        for r in range(6):  # a = J_dot v; crossed = d(J_dot(v) v)/dv = J_dot(v) + [J_dot(e_i) v]_i
            acc = 0.0
            for c in range(n):
                acc += along_v[r, c] * v[c]
                crossed[r, c] = along_v[r, c]
            a[r] = acc
        for i in tree.turning:
            for r in range(6):
                acc = 0.0
                for c in range(n):
                    acc += along_e[i, m, r, c] * v[c]
                crossed[r, i] += acc
        for r in range(3):
            acc = 0.0
            for c in range(n):
                acc += Jm[3 + r, c] * v[c]
            omega[r] = acc
        I3 = world_inertia(R[m], tree.inertia[m])
        Iw = mv(I3, omega)
        spin = cross(omega, Iw)
        Ia = mv(I3, a[3:])
        for r in range(3):
            load[r] = tree.mass[m] * a[r]
            load[3 + r] = Ia[r] + spin[r]
        for c in range(n):
            acc = 0.0
            for r in range(6):
                acc += Jm[r, c] * load[r]
            b[c] += acc
        # gyro = (skew(omega) I3 - skew(I omega)) J_omega: d(omega x I omega)/dv
        W = np.array([[0.0, -omega[2], omega[1]], [omega[2], 0.0, -omega[0]], [-omega[1], omega[0], 0.0]])
        L = np.array([[0.0, -Iw[2], Iw[1]], [Iw[2], 0.0, -Iw[0]], [-Iw[1], Iw[0], 0.0]])
        P = mm3(W, I3) - L
        for c in range(n):
            for r in range(3):
                rows[r, c] = tree.mass[m] * crossed[r, c]
                rows[3 + r, c] = (I3[r, 0] * crossed[3, c] + I3[r, 1] * crossed[4, c] + I3[r, 2] * crossed[5, c]
                                  + P[r, 0] * Jm[3, c] + P[r, 1] * Jm[4, c] + P[r, 2] * Jm[5, c])  # fmt: skip
        transposed_product(B, Jm, rows)
    return b, B

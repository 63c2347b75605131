"""Compiled twin of system/tree.py's kinematics (System.group_poses, _pose_of, drifted, mass_matrix, inertia, bias): the
tree packed as system_layout.Tree, each body's pose and twist Jacobian, the mass matrix with the radiation's added
mass, and the velocity-product load b(v) with its Jacobian. J_dot is analytic (`rates`: the forward kinematics
differentiated along each turning unit velocity, omega x r terms down the tree), the limit of the reference's central
differences (`rates_by_differences`, which it meets to their 1e-10). The `_into` functions write into buffers made once
(`work`): at this size an allocation costs more than its arithmetic."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .jit import JIT, njit
from .rotation import quat_multiply, quat_to_matrix, rotation_quat
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
def rodrigues(axis, angle, out, rate):
    """out = turn_about(axis, angle) (rate False) or its derivative in the angle, cos K + sin K^2 (rate True), written out:
    K^2 = a a^T - I for a unit axis, with the reference's sums' order."""
    s, c = math.sin(angle), 1.0 - math.cos(angle)
    one = 1.0
    if rate:
        s, c, one = math.cos(angle), math.sin(angle), 0.0
    x, y, z = axis[0], axis[1], axis[2]
    out[0, 0], out[0, 1], out[0, 2] = one + c * (-z * z - y * y), -s * z + c * (y * x), s * y + c * (z * x)
    out[1, 0], out[1, 1], out[1, 2] = s * z + c * (x * y), one + c * (-z * z - x * x), -s * x + c * (z * y)
    out[2, 0], out[2, 1], out[2, 2] = -s * y + c * (x * z), s * x + c * (y * z), one + c * (-y * y - x * x)


@njit(**JIT)
def rot(R, a0, a1, a2):
    """R a as a tuple (no array: nothing allocated)."""
    return (R[0, 0] * a0 + R[0, 1] * a1 + R[0, 2] * a2, R[1, 0] * a0 + R[1, 1] * a1 + R[1, 2] * a2,
            R[2, 0] * a0 + R[2, 1] * a1 + R[2, 2] * a2)  # fmt: skip


@njit(**JIT)
def mm3_into(A, B, out):
    for i in range(3):
        for j in range(3):
            out[i, j] = A[i, 0] * B[0, j] + A[i, 1] * B[1, j] + A[i, 2] * B[2, j]


@njit(**JIT)
def carry_into(Jp, r0, r1, r2, J):
    """J = carried(Jp, r): u + omega x r."""
    for c in range(Jp.shape[1]):
        w0, w1, w2 = Jp[3, c], Jp[4, c], Jp[5, c]
        J[0, c] = Jp[0, c] - (-r2 * w1 + r1 * w2)
        J[1, c] = Jp[1, c] - (r2 * w0 - r0 * w2)
        J[2, c] = Jp[2, c] - (-r1 * w0 + r0 * w1)
        J[3, c], J[4, c], J[5, c] = w0, w1, w2


class Kinematics(NamedTuple):
    """Work buffers of the forward kinematics and its rates, made once (work)."""

    xs: np.ndarray
    Rs: np.ndarray
    Js: np.ndarray
    dxs: np.ndarray
    dRs: np.ndarray
    dJs: np.ndarray
    turn: np.ndarray
    dturn: np.ndarray
    MJ: np.ndarray
    AG: np.ndarray
    eye: np.ndarray
    """(3, 3) the world's axes; with zero3, zero33 and zeroJ the world as a parent at rest."""
    zero3: np.ndarray
    zero33: np.ndarray
    zeroJ: np.ndarray


@njit(**JIT)
def work(tree, k6):
    """The buffers of `configure_into` for a tree whose bodies' radiation has k6 rows (6 per body, 0 without)."""
    g, n = tree.kind.shape[0], tree.n_dofs
    return Kinematics(np.zeros((g, 3)), np.zeros((g, 3, 3)), np.zeros((g, 6, n)), np.zeros((g, 3)), np.zeros((g, 3, 3)),
                      np.zeros((g, 6, n)), np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((6, n)), np.zeros((k6, n)), np.eye(3),
                      np.zeros(3), np.zeros((3, 3)), np.zeros((6, n)))  # fmt: skip


@njit(**JIT)
def poses_into(tree, x_free, q_free, theta, xs, Rs, Js, turn):
    """Each group's origin (xs, Rs, Js): forward kinematics down the tree, in place."""
    for i in range(tree.kind.shape[0]):
        p, kind, c, d = tree.parent[i], tree.kind[i], tree.coordinate[i], tree.dof[i]
        x, R, J = xs[i], Rs[i], Js[i]
        if kind == FREE:
            x[:] = x_free[c]
            R[:] = quat_to_matrix(q_free[c])
            J[:] = 0.0
            for k in range(6):
                J[k, d + k] = 1.0
            continue
        axis, off, piv = tree.axis[i], tree.offset[i], tree.pivot[i]
        th = theta[c] if c >= 0 else 0.0
        if kind == PLANAR:  # the local point in the parent's frame, and the turn
            e1, e2 = tree.plane[i, 0], tree.plane[i, 1]
            a, b = theta[c], theta[c + 1]
            l0, l1, l2 = off[0] + a * e1[0] + b * e2[0], off[1] + a * e1[1] + b * e2[1], off[2] + a * e1[2] + b * e2[2]
            rodrigues(axis, theta[c + 2], turn, False)
        elif kind == REVOLUTE:
            rodrigues(axis, th, turn, False)
            t0, t1, t2 = rot(turn, off[0] - piv[0], off[1] - piv[1], off[2] - piv[2])
            l0, l1, l2 = piv[0] + t0, piv[1] + t1, piv[2] + t2
        else:
            l0, l1, l2 = off[0], off[1], off[2]
            if kind == PRISMATIC:
                l0, l1, l2 = off[0] + th * axis[0], off[1] + th * axis[1], off[2] + th * axis[2]
            turn[:] = 0.0
            turn[0, 0] = turn[1, 1] = turn[2, 2] = 1.0
        if p < 0:  # the world's origin and axes
            x[0], x[1], x[2] = l0, l1, l2
            R[:] = turn
            J[:] = 0.0
            _joint_columns(tree, i, True, turn, 0.0, 0.0, 0.0, x, J)
        else:
            Rp = Rs[p]
            r0, r1, r2 = rot(Rp, l0, l1, l2)
            x[0], x[1], x[2] = xs[p, 0] + r0, xs[p, 1] + r1, xs[p, 2] + r2
            mm3_into(Rp, turn, R)
            carry_into(Js[p], x[0] - xs[p, 0], x[1] - xs[p, 1], x[2] - xs[p, 2], J)
            _joint_columns(tree, i, False, Rp, xs[p, 0], xs[p, 1], xs[p, 2], x, J)


@njit(**JIT)
def _joint_columns(tree, i, world, Rp, q0, q1, q2, x, J):
    """The joint's own columns of J (world: on the world, else on a parent at q turned by Rp)."""
    kind, d, axis = tree.kind[i], tree.dof[i], tree.axis[i]
    a0, a1, a2 = (axis[0], axis[1], axis[2]) if world else rot(Rp, axis[0], axis[1], axis[2])
    if kind == PLANAR:
        e1, e2 = tree.plane[i, 0], tree.plane[i, 1]
        u0, u1, u2 = (e1[0], e1[1], e1[2]) if world else rot(Rp, e1[0], e1[1], e1[2])
        w0, w1, w2 = (e2[0], e2[1], e2[2]) if world else rot(Rp, e2[0], e2[1], e2[2])
        J[0, d] += u0
        J[1, d] += u1
        J[2, d] += u2
        J[0, d + 1] += w0
        J[1, d + 1] += w1
        J[2, d + 1] += w2
        J[3, d + 2] += a0
        J[4, d + 2] += a1
        J[5, d + 2] += a2
    elif kind == PRISMATIC:
        J[0, d] += a0
        J[1, d] += a1
        J[2, d] += a2
    elif kind == REVOLUTE:
        piv = tree.pivot[i]
        p0, p1, p2 = (piv[0], piv[1], piv[2]) if world else rot(Rp, piv[0], piv[1], piv[2])
        b0, b1, b2 = x[0] - (q0 + p0), x[1] - (q1 + p1), x[2] - (q2 + p2)
        J[0, d] += a1 * b2 - a2 * b1
        J[1, d] += a2 * b0 - a0 * b2
        J[2, d] += a0 * b1 - a1 * b0
        J[3, d] += a0
        J[4, d] += a1
        J[5, d] += a2


@njit(**JIT)
def bodies_into(tree, xs, Rs, Js, x, R, J):
    """Each body's (x, R, J) from its group's (System.pose), in place."""
    for b in range(tree.group.shape[0]):
        gi = tree.group[b]
        mo = tree.member_offset[b]
        r0, r1, r2 = rot(Rs[gi], mo[0], mo[1], mo[2])
        x[b, 0], x[b, 1], x[b, 2] = xs[gi, 0] + r0, xs[gi, 1] + r1, xs[gi, 2] + r2
        mm3_into(Rs[gi], tree.member_rotation[b], R[b])
        carry_into(Js[gi], x[b, 0] - xs[gi, 0], x[b, 1] - xs[gi, 1], x[b, 2] - xs[gi, 2], J[b])


@njit(**JIT)
def group_poses(tree, x_free, q_free, theta):
    """(x (g, 3), R (g, 3, 3), J (g, 6, n)) of each group's origin: forward kinematics down the tree."""
    g, n = tree.kind.shape[0], tree.n_dofs
    xs, Rs, Js = np.zeros((g, 3)), np.zeros((g, 3, 3)), np.zeros((g, 6, n))
    poses_into(tree, x_free, q_free, theta, xs, Rs, Js, np.zeros((3, 3)))
    return xs, Rs, Js


@njit(**JIT)
def body_poses(tree, x_free, q_free, theta):
    """(x (k, 3), R (k, 3, 3), J (k, 6, n)) of each body (System.pose), the scene's order."""
    xg, Rg, Jg = group_poses(tree, x_free, q_free, theta)
    k, n = tree.group.shape[0], tree.n_dofs
    x, R, J = np.zeros((k, 3)), np.zeros((k, 3, 3)), np.zeros((k, 6, n))
    bodies_into(tree, xg, Rg, Jg, x, R, J)
    return x, R, J


@njit(**JIT)
def drifted(tree, x_free, q_free, theta, v, h):
    """The coordinates moved at velocity v for time h (drift_into's on copies)."""
    x, q, th = x_free.copy(), q_free.copy(), theta.copy()
    drift_into(tree, x, q, th, v, h)
    return x, q, th


@njit(**JIT)
def drift_into(tree, x_free, q_free, theta, v, h):
    """The coordinates moved at velocity v for time h, in place: free groups translated and turned by exp(h omega)."""
    for i in range(tree.kind.shape[0]):
        c, d = tree.coordinate[i], tree.dof[i]
        if tree.kind[i] == FREE:
            for j in range(3):
                x_free[c, j] += h * v[d + j]
            q_free[c] = quat_multiply(rotation_quat(h * v[d + 3 : d + 6]), q_free[c])
        elif c >= 0:
            for j in range(tree.width[i]):
                theta[c + j] += h * v[d + j]


@njit(**JIT)
def world_inertia(R, inertia):
    """R diag(inertia) R^T."""
    out = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            out[i, j] = R[i, 0] * inertia[0] * R[j, 0] + R[i, 1] * inertia[1] * R[j, 1] + R[i, 2] * inertia[2] * R[j, 2]
    return out


@njit(**JIT)
def turned_into(R, R0, J, out):
    """out (6, n) = T^T J for one body, T = diag(R R0^T, R R0^T): its twist in the radiation fit's axes."""
    for i in range(3):
        t0 = R0[i, 0] * R[0, 0] + R0[i, 1] * R[0, 1] + R0[i, 2] * R[0, 2]  # (R0 R^T)[i, :]
        t1 = R0[i, 0] * R[1, 0] + R0[i, 1] * R[1, 1] + R0[i, 2] * R[1, 2]
        t2 = R0[i, 0] * R[2, 0] + R0[i, 1] * R[2, 1] + R0[i, 2] * R[2, 2]
        for half in range(2):
            for c in range(J.shape[1]):
                out[3 * half + i, c] = t0 * J[3 * half, c] + t1 * J[3 * half + 1, c] + t2 * J[3 * half + 2, c]


@njit(**JIT)
def inertia_matrix(tree, R, J, added, R0, radiating):
    """(n, n) sum_b J_b^T M_b J_b, plus J^T T A_inf T^T J with radiation; and (6k, n) T^T J (zeros without)."""
    k, n = R.shape[0], tree.n_dofs
    M, G = np.zeros((n, n)), np.zeros((6 * k, n))
    inertia_into(tree, R, J, added, R0, radiating, M, G, np.empty((6, n)), np.empty((6 * k, n)), np.empty((3, 3)))
    return M, G


@njit(**JIT)
def inertia_into(tree, R, J, added, R0, radiating, M, G, MJ, AG, I3):
    """M, G = inertia_matrix's, in place; MJ (6, n), AG (6k, n) and I3 (3, 3) work."""
    k, n = R.shape[0], tree.n_dofs
    M[:] = 0.0
    G[:] = 0.0
    for b in range(k):
        Rb, inertia = R[b], tree.inertia[b]
        for i in range(3):
            for j in range(3):
                I3[i, j] = Rb[i, 0] * inertia[0] * Rb[j, 0] + Rb[i, 1] * inertia[1] * Rb[j, 1] + Rb[i, 2] * inertia[2] * Rb[j, 2]
        Jb = J[b]
        for c in range(n):
            for i in range(3):
                MJ[i, c] = tree.mass[b] * Jb[i, c]
                MJ[3 + i, c] = I3[i, 0] * Jb[3, c] + I3[i, 1] * Jb[4, c] + I3[i, 2] * Jb[5, c]
        transposed_product(M, Jb, MJ)
        if radiating:
            turned_into(R[b], R0[b], Jb, G[6 * b : 6 * b + 6])
    if radiating:
        AG[:] = 0.0
        for i in range(6 * k):
            for m in range(6 * k):
                a = added[i, m]
                for c in range(n):
                    AG[i, c] += a * G[m, c]
        transposed_product(M, G, AG)


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
def rates_by_differences(tree, x_free, q_free, theta):
    """(n, k, 6, n) dJ_b/dt while moving at each unit velocity (zeros where it changes no Jacobian): central differences
    (System.bias's; `rates` is their limit)."""
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
def rates(tree, x_free, q_free, theta):
    """(n, k, 6, n) dJ_b/dt while moving at each unit velocity (zeros where it changes no Jacobian): analytic."""
    k, n = tree.group.shape[0], tree.n_dofs
    kin = work(tree, 0)
    poses_into(tree, x_free, q_free, theta, kin.xs, kin.Rs, kin.Js, kin.turn)
    x = np.zeros((k, 3))
    bodies_into(tree, kin.xs, kin.Rs, kin.Js, x, np.zeros((k, 3, 3)), np.zeros((k, 6, n)))
    out = np.zeros((n, k, 6, n))
    rates_into(tree, theta, kin, x, out)
    return out


@njit(**JIT)
def rates_into(tree, theta, kin, x, out):
    """out[i] = dJ_b/dt moving at the i-th unit velocity, for the turning ones (the others stay as they are: zeros), from
    the groups' poses in kin and the bodies' centres x: forward kinematics differentiated along that velocity."""
    for e in tree.turning:
        tangent_into(tree, theta, e, kin)
        for b in range(tree.group.shape[0]):
            gi = tree.group[b]
            mo = tree.member_offset[b]
            d0, d1, d2 = rot(kin.dRs[gi], mo[0], mo[1], mo[2])
            carry_rate(
                kin.Js[gi], kin.dJs[gi], x[b, 0] - kin.xs[gi, 0], x[b, 1] - kin.xs[gi, 1], x[b, 2] - kin.xs[gi, 2], d0, d1, d2, out[e, b]
            )


@njit(**JIT)
def carry_rate(Jp, dJp, r0, r1, r2, d0, d1, d2, dJ):
    """dJ = d/dt carried(Jp, r) = carried(dJp, r) + omega x r_dot, r_dot = d."""
    for c in range(Jp.shape[1]):
        w0, w1, w2 = Jp[3, c], Jp[4, c], Jp[5, c]
        v0, v1, v2 = dJp[3, c], dJp[4, c], dJp[5, c]
        dJ[0, c] = dJp[0, c] + (v1 * r2 - v2 * r1) + (w1 * d2 - w2 * d1)
        dJ[1, c] = dJp[1, c] + (v2 * r0 - v0 * r2) + (w2 * d0 - w0 * d2)
        dJ[2, c] = dJp[2, c] + (v0 * r1 - v1 * r0) + (w0 * d1 - w1 * d0)
        dJ[3, c], dJ[4, c], dJ[5, c] = v0, v1, v2


@njit(**JIT)
def tangent_into(tree, theta, e, kin):
    """d/dt of each group's (x, R, J) (kin.dxs, dRs, dJs) moving at the e-th unit velocity, from their poses in kin:
    poses_into differentiated (a free group turns in world axes: R_dot = skew(w) R, as drifted's exp(h w) R)."""
    turn, dturn = kin.turn, kin.dturn
    for i in range(tree.kind.shape[0]):
        p, kind, c, d = tree.parent[i], tree.kind[i], tree.coordinate[i], tree.dof[i]
        dx, dR, dJ = kin.dxs[i], kin.dRs[i], kin.dJs[i]
        if kind == FREE:
            dx[:] = 0.0
            dR[:] = 0.0
            dJ[:] = 0.0
            if d <= e < d + 3:
                dx[e - d] = 1.0
            elif d + 3 <= e < d + 6:
                j, R = e - d - 3, kin.Rs[i]
                for col in range(3):  # e_j x R[:, col]
                    dR[(j + 1) % 3, col] = -R[(j + 2) % 3, col]
                    dR[(j + 2) % 3, col] = R[(j + 1) % 3, col]
            continue
        axis, off, piv = tree.axis[i], tree.offset[i], tree.pivot[i]
        rate0 = 1.0 if e == d and tree.width[i] > 0 else 0.0  # a fixed group's dof is its successor's
        if kind == PLANAR:
            e1, e2 = tree.plane[i, 0], tree.plane[i, 1]
            a, b, rate1, rate2 = theta[c], theta[c + 1], 1.0 if e == d + 1 else 0.0, 1.0 if e == d + 2 else 0.0
            l0, l1, l2 = off[0] + a * e1[0] + b * e2[0], off[1] + a * e1[1] + b * e2[1], off[2] + a * e1[2] + b * e2[2]
            m0, m1, m2 = rate0 * e1[0] + rate1 * e2[0], rate0 * e1[1] + rate1 * e2[1], rate0 * e1[2] + rate1 * e2[2]
            rodrigues(axis, theta[c + 2], turn, False)
            rodrigues(axis, theta[c + 2], dturn, True)
            dturn *= rate2
        elif kind == REVOLUTE:
            rodrigues(axis, theta[c], turn, False)
            rodrigues(axis, theta[c], dturn, True)
            dturn *= rate0
            t0, t1, t2 = rot(turn, off[0] - piv[0], off[1] - piv[1], off[2] - piv[2])
            l0, l1, l2 = piv[0] + t0, piv[1] + t1, piv[2] + t2
            m0, m1, m2 = rot(dturn, off[0] - piv[0], off[1] - piv[1], off[2] - piv[2])
        else:
            th = theta[c] if c >= 0 else 0.0
            s = rate0 if kind == PRISMATIC else 0.0
            l0, l1, l2 = off[0], off[1], off[2]
            if kind == PRISMATIC:
                l0, l1, l2 = off[0] + th * axis[0], off[1] + th * axis[1], off[2] + th * axis[2]
            m0, m1, m2 = s * axis[0], s * axis[1], s * axis[2]
            turn[:] = kin.eye
            dturn[:] = 0.0
        if p < 0:
            xp, Rp, Jp, dxp, dRp, dJp = kin.zero3, kin.eye, kin.zeroJ, kin.zero3, kin.zero33, kin.zeroJ
        else:
            xp, Rp, Jp, dxp, dRp, dJp = kin.xs[p], kin.Rs[p], kin.Js[p], kin.dxs[p], kin.dRs[p], kin.dJs[p]
        u0, u1, u2 = rot(dRp, l0, l1, l2)
        w0, w1, w2 = rot(Rp, m0, m1, m2)
        dx[0], dx[1], dx[2] = dxp[0] + u0 + w0, dxp[1] + u1 + w1, dxp[2] + u2 + w2
        for r in range(3):
            for col in range(3):
                dR[r, col] = (dRp[r, 0] * turn[0, col] + dRp[r, 1] * turn[1, col] + dRp[r, 2] * turn[2, col]
                              + Rp[r, 0] * dturn[0, col] + Rp[r, 1] * dturn[1, col] + Rp[r, 2] * dturn[2, col])  # fmt: skip
        x = kin.xs[i]
        carry_rate(Jp, dJp, x[0] - xp[0], x[1] - xp[1], x[2] - xp[2], dx[0] - dxp[0], dx[1] - dxp[1], dx[2] - dxp[2], dJ)
        _joint_column_rates(tree, i, Rp, dRp, xp, dxp, x, dx, dJ)


@njit(**JIT)
def _joint_column_rates(tree, i, Rp, dRp, xp, dxp, x, dx, dJ):
    """d/dt of the joint's own columns of J (_joint_columns)."""
    kind, d, axis = tree.kind[i], tree.dof[i], tree.axis[i]
    a0, a1, a2 = rot(dRp, axis[0], axis[1], axis[2])
    if kind == PLANAR:
        e1, e2 = tree.plane[i, 0], tree.plane[i, 1]
        u0, u1, u2 = rot(dRp, e1[0], e1[1], e1[2])
        w0, w1, w2 = rot(dRp, e2[0], e2[1], e2[2])
        dJ[0, d] += u0
        dJ[1, d] += u1
        dJ[2, d] += u2
        dJ[0, d + 1] += w0
        dJ[1, d + 1] += w1
        dJ[2, d + 1] += w2
        dJ[3, d + 2] += a0
        dJ[4, d + 2] += a1
        dJ[5, d + 2] += a2
    elif kind == PRISMATIC:
        dJ[0, d] += a0
        dJ[1, d] += a1
        dJ[2, d] += a2
    elif kind == REVOLUTE:  # d/dt (a x (x - xp - Rp pivot))
        piv = tree.pivot[i]
        A0, A1, A2 = rot(Rp, axis[0], axis[1], axis[2])
        p0, p1, p2 = rot(Rp, piv[0], piv[1], piv[2])
        q0, q1, q2 = rot(dRp, piv[0], piv[1], piv[2])
        b0, b1, b2 = x[0] - (xp[0] + p0), x[1] - (xp[1] + p1), x[2] - (xp[2] + p2)
        c0, c1, c2 = dx[0] - (dxp[0] + q0), dx[1] - (dxp[1] + q1), dx[2] - (dxp[2] + q2)
        dJ[0, d] += (a1 * b2 - a2 * b1) + (A1 * c2 - A2 * c1)
        dJ[1, d] += (a2 * b0 - a0 * b2) + (A2 * c0 - A0 * c2)
        dJ[2, d] += (a0 * b1 - a1 * b0) + (A0 * c1 - A1 * c0)
        dJ[3, d] += a0
        dJ[4, d] += a1
        dJ[5, d] += a2


@njit(**JIT)
def bias(tree, R, J, along_e, v):
    """(b(v), db/dv) (System.bias): bias_into's."""
    n = tree.n_dofs
    b, B = np.zeros(n), np.zeros((n, n))
    bias_into(tree, R, J, along_e, v, b, B, np.empty((3, 6, n)), np.empty((4, 3, 3)), np.empty((2, 6)))
    return b, B


@njit(**JIT)
def bias_into(tree, R, J, along_e, v, b, B, rows3, mats, vecs):
    """b, B = b(v), db/dv (System.bias): b = sum_b J_b^T (M_b J_b_dot v + (0, omega x I omega)); rows3 (3, 6, n), mats
    (4, 3, 3) and vecs (2, 6) work."""
    n, k = tree.n_dofs, R.shape[0]
    b[:] = 0.0
    B[:] = 0.0
    along_v, crossed, rows = rows3[0], rows3[1], rows3[2]
    I3, W, L, P = mats[0], mats[1], mats[2], mats[3]
    a, load = vecs[0], vecs[1]
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
        o0, o1, o2 = 0.0, 0.0, 0.0
        for c in range(n):
            o0 += Jm[3, c] * v[c]
            o1 += Jm[4, c] * v[c]
            o2 += Jm[5, c] * v[c]
        Rm, inertia = R[m], tree.inertia[m]
        for i in range(3):
            for j in range(3):
                I3[i, j] = Rm[i, 0] * inertia[0] * Rm[j, 0] + Rm[i, 1] * inertia[1] * Rm[j, 1] + Rm[i, 2] * inertia[2] * Rm[j, 2]
        w0, w1, w2 = rot(I3, o0, o1, o2)
        s0, s1, s2 = o1 * w2 - o2 * w1, o2 * w0 - o0 * w2, o0 * w1 - o1 * w0
        i0, i1, i2 = rot(I3, a[3], a[4], a[5])
        load[0], load[1], load[2] = tree.mass[m] * a[0], tree.mass[m] * a[1], tree.mass[m] * a[2]
        load[3], load[4], load[5] = i0 + s0, i1 + s1, i2 + s2
        for c in range(n):
            acc = 0.0
            for r in range(6):
                acc += Jm[r, c] * load[r]
            b[c] += acc
        # gyro = (skew(omega) I3 - skew(I omega)) J_omega: d(omega x I omega)/dv
        W[0, 0], W[0, 1], W[0, 2], W[1, 0], W[1, 1], W[1, 2], W[2, 0], W[2, 1], W[2, 2] = 0.0, -o2, o1, o2, 0.0, -o0, -o1, o0, 0.0
        L[0, 0], L[0, 1], L[0, 2], L[1, 0], L[1, 1], L[1, 2], L[2, 0], L[2, 1], L[2, 2] = 0.0, -w2, w1, w2, 0.0, -w0, -w1, w0, 0.0
        mm3_into(W, I3, P)
        for i in range(3):
            for j in range(3):
                P[i, j] -= L[i, j]
        for c in range(n):
            for r in range(3):
                rows[r, c] = tree.mass[m] * crossed[r, c]
                rows[3 + r, c] = (I3[r, 0] * crossed[3, c] + I3[r, 1] * crossed[4, c] + I3[r, 2] * crossed[5, c]
                                  + P[r, 0] * Jm[3, c] + P[r, 1] * Jm[4, c] + P[r, 2] * Jm[5, c])  # fmt: skip
        transposed_product(B, Jm, rows)

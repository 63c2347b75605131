"""Compiled hot loop (numba): K steps of euler, splitting, implicit or rk4 in one call, GIL released.

The same arithmetic as the numpy reference (forces.py, integrators.py) written as plain loops, so the
results agree to round-off; tests compare the two. Compiled once and cached on disk (cache=True).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

JIT = {"cache": True, "nogil": True, "fastmath": False, "error_model": "numpy"}
SCHEMES = {"euler": 0, "splitting": 1, "implicit": 2, "rk4": 3}
MODELS = {"points": 0, "panels": 1}


@njit(**JIT)
def quat_mul(a, b):
    return np.array([
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ])  # fmt: skip


@njit(**JIT)
def quat_to_matrix(q):
    n = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    w, x, y, z = q[0] / n, q[1] / n, q[2] / n, q[3] / n
    R = np.empty((3, 3))
    R[0, 0], R[0, 1], R[0, 2] = 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)
    R[1, 0], R[1, 1], R[1, 2] = 2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)
    R[2, 0], R[2, 1], R[2, 2] = 2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)
    return R


@njit(**JIT)
def rotation_quat(v):
    theta2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
    if theta2 < 1e-8:
        half_sinc = 0.5 - theta2 / 48.0 + theta2 * theta2 / 3840.0
        cos_half = 1.0 - theta2 / 8.0 + theta2 * theta2 / 384.0
    else:
        theta = math.sqrt(theta2)
        half_sinc = math.sin(0.5 * theta) / theta
        cos_half = math.cos(0.5 * theta)
    return np.array([cos_half, half_sinc * v[0], half_sinc * v[1], half_sinc * v[2]])


@njit(**JIT)
def normalized(q):
    return q / math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])


@njit(**JIT)
def cross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


@njit(**JIT)
def mv(R, v):
    """R v for a 3x3 R (explicit: numba's @ would call BLAS, slow at this size)."""
    return np.array([R[0, 0] * v[0] + R[0, 1] * v[1] + R[0, 2] * v[2],
                     R[1, 0] * v[0] + R[1, 1] * v[1] + R[1, 2] * v[2],
                     R[2, 0] * v[0] + R[2, 1] * v[1] + R[2, 2] * v[2]])  # fmt: skip


@njit(**JIT)
def mtv(R, v):
    """R^T v for a 3x3 R."""
    return np.array([R[0, 0] * v[0] + R[1, 0] * v[1] + R[2, 0] * v[2],
                     R[0, 1] * v[0] + R[1, 1] * v[1] + R[2, 1] * v[2],
                     R[0, 2] * v[0] + R[1, 2] * v[1] + R[2, 2] * v[2]])  # fmt: skip


@njit(**JIT)
def rotate_tensor(R, Q):
    """R Q R^T for 3x3 matrices, written out (BLAS calls cost more than the arithmetic here)."""
    out = np.zeros((3, 3))
    for i in range(3):
        for j in range(3):
            acc = 0.0
            for k in range(3):
                for m in range(3):
                    acc += R[i, k] * Q[k, m] * R[j, m]
            out[i, j] = acc
    return out


@njit(**JIT)
def omega_of(R, L, inertia):
    return mv(R, mtv(R, L) / inertia)


@njit(**JIT)
def _crossing(a, b, x2):
    """Where the edge a->b (levers; heights x2 + a[2], x2 + b[2] of opposite signs) crosses z = 0."""
    za, zb = x2 + a[2], x2 + b[2]
    t = za / (za - zb)
    return (a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t)


@njit(**JIT)
def _triangle(p0, p1, p2, x2, nx, ny, nz, zn, zt, S, rr, need_rr):
    """Add one wet triangle's exact integrals (levers p0, p1, p2; heights x2 + p[2], clipped to <= 0)
    to the sums zn, zt, S, rr in place: integral f g dA = A/12 (sum f_i g_i + sum f_i sum g_i). Returns its area."""
    e10, e11, e12 = p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]
    e20, e21, e22 = p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]
    area = 0.5 * ((e11 * e22 - e12 * e21) * nx + (e12 * e20 - e10 * e22) * ny + (e10 * e21 - e11 * e20) * nz)
    z0, z1, z2 = min(x2 + p0[2], 0.0), min(x2 + p1[2], 0.0), min(x2 + p2[2], 0.0)
    sz = z0 + z1 + z2
    s0, s1, s2 = p0[0] + p1[0] + p2[0], p0[1] + p1[1] + p2[1], p0[2] + p1[2] + p2[2]
    w = area / 12.0
    za = area * sz / 3.0
    l0 = w * (z0 * p0[0] + z1 * p1[0] + z2 * p2[0] + sz * s0)
    l1 = w * (z0 * p0[1] + z1 * p1[1] + z2 * p2[1] + sz * s1)
    l2 = w * (z0 * p0[2] + z1 * p1[2] + z2 * p2[2] + sz * s2)
    zn[0] += za * nx
    zn[1] += za * ny
    zn[2] += za * nz
    zt[0] += l1 * nz - l2 * ny
    zt[1] += l2 * nx - l0 * nz
    zt[2] += l0 * ny - l1 * nx
    if need_rr:
        S[0] += area * s0 / 3.0
        S[1] += area * s1 / 3.0
        S[2] += area * s2 / 3.0
        for i in range(3):
            for j in range(3):
                rr[i, j] += w * (p0[i] * p0[j] + p1[i] * p1[j] + p2[i] * p2[j] + (s0, s1, s2)[i] * (s0, s1, s2)[j])
    return area


@njit(**JIT)
def wet_integrals(kind, x, R, r, nrm, area, verts, faces, fnormals, need_rr, moments, flags, acc):
    """Over the wet surface: integral of z nu dA, of (z r) x nu dA, the wet area, integral of r dA
    and of r r^T dA (the last two only if need_rr)."""
    zn = np.zeros(3)
    zt = np.zeros(3)
    S = np.zeros(3)
    rr = np.zeros((3, 3))
    A = 0.0
    if kind == 0:
        # Every wet sum is linear in z = x_z + R[2].r, so it is fixed by per-sample constants summed
        # over the wet set (Body.sample_moments): keep those sums and, each evaluation, only add or
        # remove the samples that crossed the water line since the last one.
        R20, R21, R22 = R[2, 0], R[2, 1], R[2, 2]
        for k in range(r.shape[0]):
            w = x[2] + (R20 * r[k, 0] + R21 * r[k, 1] + R22 * r[k, 2]) < 0.0
            if w != flags[k]:
                flags[k] = w
                sign = 1.0 if w else -1.0
                for j in range(34):
                    acc[j] += sign * moments[k, j]
        x2 = x[2]
        nb = np.empty(3)
        cb = np.empty(3)
        for i in range(3):
            nb[i] = x2 * acc[10 + i] + acc[13 + 3 * i] * R20 + acc[14 + 3 * i] * R21 + acc[15 + 3 * i] * R22
            cb[i] = x2 * acc[22 + i] + acc[25 + 3 * i] * R20 + acc[26 + 3 * i] * R21 + acc[27 + 3 * i] * R22
        zn = mv(R, nb)
        zt = mv(R, cb)
        if need_rr:
            A = acc[0]
            S = mv(R, acc[1:4].copy())
            Q = np.array([[acc[4], acc[5], acc[6]], [acc[5], acc[7], acc[8]], [acc[6], acc[8], acc[9]]])
            rr = rotate_tensor(R, Q)
        return zn, zt, A, S, rr
    nv = verts.shape[0]
    lev = np.empty((nv, 3))
    for v in range(nv):  # vertex levers and heights, once per evaluation
        for i in range(3):
            lev[v, i] = R[i, 0] * verts[v, 0] + R[i, 1] * verts[v, 1] + R[i, 2] * verts[v, 2]
    x2 = x[2]
    for f in range(faces.shape[0]):
        ids = (faces[f, 0], faces[f, 1], faces[f, 2])
        below = (x2 + lev[ids[0], 2] < 0.0) + (x2 + lev[ids[1], 2] < 0.0) + (x2 + lev[ids[2], 2] < 0.0)
        if below == 0:
            continue
        b0, b1, b2 = fnormals[f, 0], fnormals[f, 1], fnormals[f, 2]
        nx = R[0, 0] * b0 + R[0, 1] * b1 + R[0, 2] * b2
        ny = R[1, 0] * b0 + R[1, 1] * b1 + R[1, 2] * b2
        nz = R[2, 0] * b0 + R[2, 1] * b1 + R[2, 2] * b2
        # roll so the odd vertex (alone under water, or alone above it) comes first
        first = 0
        if below != 3:
            for i in range(3):
                if (x2 + lev[ids[i], 2] < 0.0) == (below == 1):
                    first = i
                    break
        v0, v1, v2 = ids[first], ids[(first + 1) % 3], ids[(first + 2) % 3]
        p0 = (lev[v0, 0], lev[v0, 1], lev[v0, 2])
        p1 = (lev[v1, 0], lev[v1, 1], lev[v1, 2])
        p2 = (lev[v2, 0], lev[v2, 1], lev[v2, 2])
        if below == 3:
            A += _triangle(p0, p1, p2, x2, nx, ny, nz, zn, zt, S, rr, need_rr)
            continue
        e01 = _crossing(p0, p1, x2)
        e20 = _crossing(p2, p0, x2)
        if below == 1:
            A += _triangle(p0, e01, e20, x2, nx, ny, nz, zn, zt, S, rr, need_rr)
        else:  # quadrilateral e01 -> p1 -> p2 -> e20
            A += _triangle(e01, p1, p2, x2, nx, ny, nz, zn, zt, S, rr, need_rr)
            A += _triangle(e01, p2, e20, x2, nx, ny, nz, zn, zt, S, rr, need_rr)
    return zn, zt, A, S, rr


@njit(**JIT)
def pose_loads(kind, x, R, geom, mass, rho, g, d, flags, acc):
    """Gravity + pressure force and torque at a pose, and the 6x6 damping matrix D (None-like: has_d False)."""
    r, nrm, area, verts, faces, fnormals, moments = geom
    F = np.zeros(3)
    F[2] = -mass * g
    T = np.zeros(3)
    D = np.zeros((6, 6))
    has_p = rho * g != 0.0
    has_d = d != 0.0 and rho != 0.0
    wet = False
    if has_p or has_d:
        zn, zt, A, S, rr = wet_integrals(kind, x, R, r, nrm, area, verts, faces, fnormals, has_d, moments, flags, acc)
        if has_p:
            F += (rho * g) * zn
            T += (rho * g) * zt
        if has_d and A > 0.0:
            wet = True
            tr = rr[0, 0] + rr[1, 1] + rr[2, 2]
            for i in range(3):
                D[i, i] = d * A
                for j in range(3):
                    D[3 + i, 3 + j] = d * ((tr if i == j else 0.0) - rr[i, j])
            # [S]x blocks: D[:3, 3:] = -[S]x, D[3:, :3] = [S]x
            D[0, 4], D[0, 5], D[1, 3], D[1, 5], D[2, 3], D[2, 4] = d * S[2], -d * S[1], -d * S[2], d * S[0], d * S[1], -d * S[0]
            D[4, 0], D[5, 0], D[3, 1], D[5, 1], D[3, 2], D[4, 2] = d * S[2], -d * S[1], -d * S[2], d * S[0], d * S[1], -d * S[0]
    return F, T, D, wet


@njit(**JIT)
def matmul6(A, B):
    """A B for 6x6 matrices, written out (a BLAS call costs more than the arithmetic here)."""
    out = np.zeros((6, 6))
    for i in range(6):
        for j in range(6):
            acc = 0.0
            for k in range(6):
                acc += A[i, k] * B[k, j]
            out[i, j] = acc
    return out


@njit(**JIT)
def damping_modes(D, R, mass, inertia):
    """K = W D W with W = diag(M, R I R^T)^(-1/2): the damping matrix in mass-normalised coordinates,
    whose eigenvalues are the damping rates."""
    W = np.zeros((6, 6))
    for i in range(3):
        W[i, i] = 1.0 / math.sqrt(mass)
        for j in range(3):  # R diag(I^-1/2) R^T
            W[3 + i, 3 + j] = R[i, 0] * R[j, 0] / math.sqrt(inertia[0]) + R[i, 1] * R[j, 1] / math.sqrt(inertia[1]) + R[i, 2] * R[j, 2] / math.sqrt(inertia[2])
    return matmul6(matmul6(W, D), W)


@njit(**JIT)
def mat6v(K, y):
    out = np.zeros(6)
    for i in range(6):
        for j in range(6):
            out[i] += K[i, j] * y[j]
    return out


@njit(**JIT)
def exact_modes(K, h):
    """Eigenmodes of K when h K is stiff; when h trace(K) <= 1/2 (trace >= the largest eigenvalue
    of this positive semi-definite K) the Taylor series of exp(-hK) converges to round-off in
    ~15 products and is cheaper than an eigensolver: flagged by lam[0] = -1."""
    if h * (K[0, 0] + K[1, 1] + K[2, 2] + K[3, 3] + K[4, 4] + K[5, 5]) <= 0.5:
        lam = np.zeros(6)
        lam[0] = -1.0
        return lam, np.eye(6)
    return np.linalg.eigh(K)


@njit(**JIT)
def damping_flow(K, R, u, L, h, mass, inertia):
    """(u, L) after h of damping alone by one explicit midpoint step, as in integrators.damping_flow."""
    sqrt_m = math.sqrt(mass)
    w_half = np.sqrt(inertia)
    y = np.empty(6)
    y[:3] = sqrt_m * u
    y[3:] = mv(R, mtv(R, L) / w_half)
    y_mid = y - 0.5 * h * mat6v(K, y)
    y = y - h * mat6v(K, y_mid)
    return y[:3] / sqrt_m, mv(R, w_half * mtv(R, y[3:]))


@njit(**JIT)
def forced_flow(K, lam, V, R, u, L, F, T, h, mass, inertia, wet):
    """(u, L) after h under the loads (F, T) and the damping together at a frozen pose, exactly,
    as in integrators.forced_damping_flow: y(h) = exp(-hK) y0 + h phi(hK) W f."""
    if not wet:
        return u + h * F / mass, L + h * T
    sqrt_m = math.sqrt(mass)
    w_half = np.sqrt(inertia)
    y = np.empty(6)
    y[:3] = sqrt_m * u
    y[3:] = mv(R, mtv(R, L) / w_half)
    gv = np.empty(6)
    gv[:3] = F / sqrt_m
    gv[3:] = mv(R, mtv(R, T) / w_half)
    if lam[0] < 0.0:  # mild (see exact_modes): both series, sum (-hK)^n y/n! + h (-hK)^n g/(n+1)!
        a = y.copy()  # term of the first series
        b = h * gv  # term of the second
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
    return y[:3] / sqrt_m, mv(R, w_half * mtv(R, y[3:]))


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
def twist_loads(F, T, D, wet, u, w):
    """Add the damping force -D (u, w) to the conservative loads."""
    if not wet:
        return F, T
    v = np.empty(6)
    v[:3] = u
    v[3:] = w
    fd = mat6v(D, v)
    return F - fd[:3], T - fd[3:]


@njit(**JIT)
def derivative(kind, y, geom, mass, inertia, rho, g, d, flags, acc):
    x, q, u, L = y[0:3], y[3:7], y[7:10], y[10:13]
    R = quat_to_matrix(q)
    w = omega_of(R, L, inertia)
    F, T, D, wet = pose_loads(kind, x, R, geom, mass, rho, g, d, flags, acc)
    F, T = twist_loads(F, T, D, wet, u, w)
    out = np.empty(13)
    out[0:3] = u
    out[3:7] = 0.5 * quat_mul(np.array([0.0, w[0], w[1], w[2]]), normalized(q))
    out[7:10] = F / mass
    out[10:13] = T
    return out


@njit(**JIT)
def _finite(y):
    for v in y:
        if not math.isfinite(v):
            return False
    return True


@njit(**JIT)
def advance(y0, n_steps, dt, scheme, kind, geom, mass, inertia, rho, g, d):
    """Advance the state vector (x, q, u, L) by up to n_steps; stop before the first non-finite
    state. Returns (state, steps done)."""
    y = y0.copy()
    flags = np.zeros(geom[0].shape[0], dtype=np.bool_)  # which samples are wet; the sums start afresh
    acc = np.zeros(34)
    x, q, u, L = y[0:3].copy(), y[3:7].copy(), y[7:10].copy(), y[10:13].copy()
    h = 0.5 * dt
    R = quat_to_matrix(q)
    F, T, D, wet = pose_loads(kind, x, R, geom, mass, rho, g, d, flags, acc)
    K = damping_modes(D, R, mass, inertia)
    lam, V = np.zeros(6), np.eye(6)
    if wet and scheme == 2:
        lam, V = exact_modes(K, h)
    for step in range(n_steps):
        if scheme == 0:  # euler: drift, exact rotation, forces at the new pose, kick
            w = omega_of(R, L, inertia)
            xn = x + dt * u
            qn = normalized(quat_mul(rotation_quat(dt * w), q))
            Rn = quat_to_matrix(qn)
            Fc, Tc, Dn, wetn = pose_loads(kind, xn, Rn, geom, mass, rho, g, d, flags, acc)
            Fn, Tn = twist_loads(Fc, Tc, Dn, wetn, u, omega_of(Rn, L, inertia))
            un, Ln = u + dt * Fn / mass, L + dt * Tn
        elif scheme == 1:  # splitting: B(h) A(h) C(dt) A(h) B(h), loads carried over
            un, Ln = u, L
            if wet:
                un, Ln = damping_flow(K, R, un, Ln, h, mass, inertia)
            un, Ln = un + h * F / mass, Ln + h * T
            xn = x + dt * un
            qn = free_rotation(q, Ln, dt, inertia)
            Rn = quat_to_matrix(qn)
            Fc, Tc, Dn, wetn = pose_loads(kind, xn, Rn, geom, mass, rho, g, d, flags, acc)
            un, Ln = un + h * Fc / mass, Ln + h * Tc
            if wetn:
                K = damping_modes(Dn, Rn, mass, inertia)
                un, Ln = damping_flow(K, Rn, un, Ln, h, mass, inertia)
        elif scheme == 2:  # implicit: P(h) C(dt) P(h), P = loads and damping solved exactly together
            un, Ln = forced_flow(K, lam, V, R, u, L, F, T, h, mass, inertia, wet)
            xn = x + dt * un
            qn = free_rotation(q, Ln, dt, inertia)
            Rn = quat_to_matrix(qn)
            Fc, Tc, Dn, wetn = pose_loads(kind, xn, Rn, geom, mass, rho, g, d, flags, acc)
            if wetn:  # the same modes serve the next step's first half, at this pose
                K = damping_modes(Dn, Rn, mass, inertia)
                lam, V = exact_modes(K, h)
            un, Ln = forced_flow(K, lam, V, Rn, un, Ln, Fc, Tc, h, mass, inertia, wetn)
        else:  # rk4 on (x, q, u, L), q renormalised
            k1 = derivative(kind, y, geom, mass, inertia, rho, g, d, flags, acc)
            k2 = derivative(kind, y + 0.5 * dt * k1, geom, mass, inertia, rho, g, d, flags, acc)
            k3 = derivative(kind, y + 0.5 * dt * k2, geom, mass, inertia, rho, g, d, flags, acc)
            k4 = derivative(kind, y + dt * k3, geom, mass, inertia, rho, g, d, flags, acc)
            yn = y + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
            xn, qn, un, Ln = yn[0:3].copy(), normalized(yn[3:7]), yn[7:10].copy(), yn[10:13].copy()
            Rn = quat_to_matrix(qn)
            Fc, Tc, Dn, wetn = F, T, D, wet  # unused by rk4
        yn = np.empty(13)
        yn[0:3], yn[3:7], yn[7:10], yn[10:13] = xn, qn, un, Ln
        if not _finite(yn):
            return y, step
        y, x, q, u, L, R = yn, xn, qn, un, Ln, Rn
        if scheme != 3:
            F, T, D, wet = Fc, Tc, Dn, wetn
    return y, n_steps


def warm_up() -> float:
    """Compile (first run ever) or load from the disk cache every kernel; returns the seconds taken."""
    import time

    from .body import make_box

    start = time.perf_counter()
    body = make_box((1.0, 1.0, 1.0), 1, 1.0)
    y = np.array([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    advance(y, 1, 0.01, 2, 0, body.packed, body.mass, body.inertia, 1000.0, 9.81, 1.0)
    return time.perf_counter() - start


@njit(**JIT)
def advance_many(Y, n_steps, dt, scheme, kind, geom, masses, inertias, rho, g, ds):
    """advance() for B bodies of one shape (rows of Y; their own mass, inertia and damping).
    Returns the new states and each body's steps done (< n_steps where it diverged)."""
    out = np.empty_like(Y)
    done = np.empty(Y.shape[0], dtype=np.int64)
    for b in range(Y.shape[0]):
        out[b], done[b] = advance(Y[b], n_steps, dt, scheme, kind, geom, masses[b], inertias[b], rho, g, ds[b])
    return out, done


@njit(**JIT)
def observe_points(x, R, u, w, r, nrm, area, mass, rho, g, d, wet):
    """The frame's diagnostics for the sampled model in one pass, as simulation.observe computes them
    with numpy: total force and torque (pressure, damping at (u, w), gravity), hydrostatic energy,
    wet area and submerged volume; marks the wet samples in `wet`. Scalar loop, no allocations."""
    R00, R01, R02, R10, R11, R12, R20, R21, R22 = R[0, 0], R[0, 1], R[0, 2], R[1, 0], R[1, 1], R[1, 2], R[2, 0], R[2, 1], R[2, 2]
    F0 = F1 = T0 = T1 = T2 = e_hyd = a_sub = v_sub = 0.0
    F2 = -mass * g
    rg = rho * g
    for k in range(r.shape[0]):
        a0, a1, a2 = r[k, 0], r[k, 1], r[k, 2]
        lz = R20 * a0 + R21 * a1 + R22 * a2
        z = x[2] + lz
        wet[k] = z < 0.0
        if z < 0.0:
            lx = R00 * a0 + R01 * a1 + R02 * a2
            ly = R10 * a0 + R11 * a1 + R12 * a2
            b0, b1, b2 = nrm[k, 0], nrm[k, 1], nrm[k, 2]
            nx = R00 * b0 + R01 * b1 + R02 * b2
            ny = R10 * b0 + R11 * b1 + R12 * b2
            nz = R20 * b0 + R21 * b1 + R22 * b2
            a = area[k]
            p = rg * z * a
            da = d * a
            fx = p * nx - da * (u[0] + w[1] * lz - w[2] * ly)
            fy = p * ny - da * (u[1] + w[2] * lx - w[0] * lz)
            fz = p * nz - da * (u[2] + w[0] * ly - w[1] * lx)
            F0 += fx
            F1 += fy
            F2 += fz
            T0 += ly * fz - lz * fy
            T1 += lz * fx - lx * fz
            T2 += lx * fy - ly * fx
            e_hyd += -0.5 * rg * z * z * a * nz
            a_sub += a
            v_sub += z * a * nz
    return np.array([F0, F1, F2]), np.array([T0, T1, T2]), e_hyd, a_sub, v_sub

"""Compiled twin of forces.py: each registered term as scalar code, and the loads of a scene's terms.

`terms` is the scene's mask and `coef` its coefficients (layout.py); bits and slots come from the
registry, so a term here reads its own with `bit(name)` and `slot(key)`.
"""

from __future__ import annotations

import numpy as np

from . import JIT, njit
from .layout import RHO, G, bit, slot
from .surface import clip, vertex_levers, wet_integrals

GRAVITY, PRESSURE, DAMPING, DRAG = bit("gravity"), bit("pressure"), bit("damping"), bit("drag")
C_DAMPING, C_DRAG = slot("damping"), slot("drag_coefficient")
WET_TERMS = PRESSURE | DAMPING | DRAG
TWIST_TERMS = DAMPING | DRAG
NONLINEAR = DRAG
"""Twist terms whose load is not affine in the twist (forces.Term.linear is False): summed by `nonlinear_loads`."""
DUNAVANT4 = np.array([[0.108103018168070, 0.445948490915965, 0.445948490915965], [0.445948490915965, 0.108103018168070, 0.445948490915965],
                      [0.445948490915965, 0.445948490915965, 0.108103018168070], [0.816847572980459, 0.091576213509771, 0.091576213509771],
                      [0.091576213509771, 0.816847572980459, 0.091576213509771], [0.091576213509771, 0.091576213509771, 0.816847572980459]])  # fmt: skip
DUNAVANT4_WEIGHTS = np.array([0.223381589678011] * 3 + [0.109951743655322] * 3)


@njit(**JIT)
def damping_matrix(coef, A, S, rr):
    """d [A Id, -[S]x; [S]x, tr(rr) Id - rr] from the wet integrals."""
    d = coef[C_DAMPING]
    D = np.zeros((6, 6))
    tr = rr[0, 0] + rr[1, 1] + rr[2, 2]
    for i in range(3):
        D[i, i] = d * A
        for j in range(3):
            D[3 + i, 3 + j] = d * ((tr if i == j else 0.0) - rr[i, j])
    D[0, 4], D[0, 5], D[1, 3], D[1, 5], D[2, 3], D[2, 4] = d * S[2], -d * S[1], -d * S[2], d * S[0], d * S[1], -d * S[0]
    D[4, 0], D[5, 0], D[3, 1], D[5, 1], D[3, 2], D[4, 2] = d * S[2], -d * S[1], -d * S[2], d * S[0], d * S[1], -d * S[0]
    return D


@njit(**JIT)
def pose_loads(kind, x, R, geom, mass, terms, coef, flags, acc):
    """Gravity and pressure at a pose, the linear damping matrix D there, and whether any twist
    term has a wet surface to act on."""
    r, nrm, area, verts, faces, fnormals, moments = geom
    F = np.zeros(3)
    if terms & GRAVITY:
        F[2] = -mass * coef[G]
    T = np.zeros(3)
    D = np.zeros((6, 6))
    wet = False
    if terms & WET_TERMS:
        zn, zt, A, S, rr = wet_integrals(kind, x, R, r, verts, faces, fnormals, moments, (terms & DAMPING) != 0, flags, acc)
        if terms & PRESSURE:
            rg = coef[RHO] * coef[G]
            F += rg * zn
            T += rg * zt
        wet = (terms & TWIST_TERMS) != 0 and A > 0.0
        if wet and terms & DAMPING:
            D = damping_matrix(coef, A, S, rr)
    return F, T, D, wet


@njit(**JIT)
def _drag_node(lx, ly, lz, nx, ny, nz, a, vn, half_rc, F, T, D, need_D):
    """Add one node's drag -(1/2) rho C_d a vn^2 n (vn > 0) to F, T, and its Jacobian to D."""
    f = -half_rc * a * vn * vn
    fx, fy, fz = f * nx, f * ny, f * nz
    F[0] += fx
    F[1] += fy
    F[2] += fz
    T[0] += ly * fz - lz * fy
    T[1] += lz * fx - lx * fz
    T[2] += lx * fy - ly * fx
    if need_D:
        c = 2.0 * half_rc * a * vn
        g = (nx, ny, nz, ly * nz - lz * ny, lz * nx - lx * nz, lx * ny - ly * nx)
        for i in range(6):
            for j in range(6):
                D[i, j] += c * g[i] * g[j]


@njit(**JIT)
def drag(kind, x, R, u, w, geom, coef, flags, need_D):
    """Quadratic drag on the wet surface moving into the water: force, torque and (need_D) its
    Jacobian D = -d(F, T)/d(u, omega). Points: the wet samples (`flags`, set by the pose's wet
    integrals). Panels: each wet triangle clipped again where v . n changes sign, with Dunavant's
    degree-4 rule (exact for the cubic torque integrand)."""
    r, nrm, area, verts, faces, fnormals, moments = geom
    half_rc = 0.5 * coef[RHO] * coef[C_DRAG]
    F = np.zeros(3)
    T = np.zeros(3)
    D = np.zeros((6, 6))
    if kind == 0:
        for k in range(r.shape[0]):
            if not flags[k]:
                continue
            a0, a1, a2 = r[k, 0], r[k, 1], r[k, 2]
            b0, b1, b2 = nrm[k, 0], nrm[k, 1], nrm[k, 2]
            lx, ly, lz = R[0, 0] * a0 + R[0, 1] * a1 + R[0, 2] * a2, R[1, 0] * a0 + R[1, 1] * a1 + R[1, 2] * a2, R[2, 0] * a0 + R[2, 1] * a1 + R[2, 2] * a2
            nx, ny, nz = R[0, 0] * b0 + R[0, 1] * b1 + R[0, 2] * b2, R[1, 0] * b0 + R[1, 1] * b1 + R[1, 2] * b2, R[2, 0] * b0 + R[2, 1] * b1 + R[2, 2] * b2
            vn = (u[0] + w[1] * lz - w[2] * ly) * nx + (u[1] + w[2] * lx - w[0] * lz) * ny + (u[2] + w[0] * ly - w[1] * lx) * nz
            if vn > 0.0:
                _drag_node(lx, ly, lz, nx, ny, nz, area[k], vn, half_rc, F, T, D, need_D)
        return F, T, D
    lev = vertex_levers(R, verts)
    P = np.empty((3, 3))
    h = np.empty(3)
    vn = np.empty(3)
    wet = np.empty((2, 3, 3))
    ahead = np.empty((2, 3, 3))
    for f in range(faces.shape[0]):
        for v in range(3):
            for i in range(3):
                P[v, i] = lev[faces[f, v], i]
            h[v] = x[2] + P[v, 2]
        m = clip(P, h, wet)
        if m == 0:
            continue
        b0, b1, b2 = fnormals[f, 0], fnormals[f, 1], fnormals[f, 2]
        nx, ny, nz = R[0, 0] * b0 + R[0, 1] * b1 + R[0, 2] * b2, R[1, 0] * b0 + R[1, 1] * b1 + R[1, 2] * b2, R[2, 0] * b0 + R[2, 1] * b1 + R[2, 2] * b2
        for k in range(m):
            for v in range(3):
                lx, ly, lz = wet[k, v, 0], wet[k, v, 1], wet[k, v, 2]
                vn[v] = -((u[0] + w[1] * lz - w[2] * ly) * nx + (u[1] + w[2] * lx - w[0] * lz) * ny + (u[2] + w[0] * ly - w[1] * lx) * nz)
            c = clip(wet[k], vn, ahead)
            for j in range(c):
                t = ahead[j]
                e10, e11, e12 = t[1, 0] - t[0, 0], t[1, 1] - t[0, 1], t[1, 2] - t[0, 2]
                e20, e21, e22 = t[2, 0] - t[0, 0], t[2, 1] - t[0, 1], t[2, 2] - t[0, 2]
                tri_area = 0.5 * ((e11 * e22 - e12 * e21) * nx + (e12 * e20 - e10 * e22) * ny + (e10 * e21 - e11 * e20) * nz)
                for q in range(6):
                    b = DUNAVANT4[q]
                    lx = b[0] * t[0, 0] + b[1] * t[1, 0] + b[2] * t[2, 0]
                    ly = b[0] * t[0, 1] + b[1] * t[1, 1] + b[2] * t[2, 1]
                    lz = b[0] * t[0, 2] + b[1] * t[1, 2] + b[2] * t[2, 2]
                    vq = (u[0] + w[1] * lz - w[2] * ly) * nx + (u[1] + w[2] * lx - w[0] * lz) * ny + (u[2] + w[0] * ly - w[1] * lx) * nz
                    if vq > 0.0:
                        _drag_node(lx, ly, lz, nx, ny, nz, tri_area * DUNAVANT4_WEIGHTS[q], vq, half_rc, F, T, D, need_D)
    return F, T, D


@njit(**JIT)
def nonlinear_loads(kind, x, R, u, w, geom, coef, terms, flags, need_D):
    """Force, torque and (need_D) Jacobian of the nonlinear twist terms the scene uses."""
    F = np.zeros(3)
    T = np.zeros(3)
    D = np.zeros((6, 6))
    if terms & DRAG:
        Fd, Td, Dd = drag(kind, x, R, u, w, geom, coef, flags, need_D)
        F += Fd
        T += Td
        D += Dd
    return F, T, D


@njit(**JIT)
def twist_loads(kind, x, R, u, w, geom, coef, terms, D, wet, flags, F, T):
    """Add the force and torque of the twist terms at (u, w) to F, T in place (no allocation in the
    hot loop): -D (u, w) for linear damping, plus the nonlinear ones."""
    if not wet:
        return
    if terms & DAMPING:
        for i in range(3):
            for j in range(3):
                F[i] -= D[i, j] * u[j] + D[i, 3 + j] * w[j]
                T[i] -= D[3 + i, j] * u[j] + D[3 + i, 3 + j] * w[j]
    if terms & NONLINEAR:
        Fn, Tn, _ = nonlinear_loads(kind, x, R, u, w, geom, coef, terms, flags, False)
        for i in range(3):
            F[i] += Fn[i]
            T[i] += Tn[i]


@njit(**JIT)
def linearised(kind, x, R, u, w, geom, coef, terms, F, T, D, wet, flags):
    """(f, D) with loads ~ f - D (u, w) near (u, w), as forces.Model.linearised: the pose loads
    (F, T) plus each nonlinear term's affine part, and the sum of the Jacobians. Linear only: (F, T), D."""
    f = np.empty(6)
    f[:3] = F
    f[3:] = T
    if not (wet and terms & NONLINEAR):
        return f, D
    Fn, Tn, Dn = nonlinear_loads(kind, x, R, u, w, geom, coef, terms, flags, True)
    for i in range(6):
        acc = 0.0
        for j in range(3):
            acc += Dn[i, j] * u[j] + Dn[i, 3 + j] * w[j]
        f[i] += (Fn[i] if i < 3 else Tn[i - 3]) + acc
    return f, D + Dn

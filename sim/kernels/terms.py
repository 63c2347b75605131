"""Compiled twin of the force terms: one function per `forces.TERMS` entry, same names, same order.

Each takes what its reference takes: the body (`model`, layout.Model), the wet surface's integrals at the
pose (`wet`, layout.Wet, from kernels/wet.py) and, for a term of the twist, the twist; it returns its load
as the reference does: a wrench (force and torque about the centre of mass, world frame, (6,)) and, for a
twist term, its Jacobian D = -d(load)/d(twist). layout.COMPILED_TERMS lists them (a test checks that list
against the registry); kernels/forces.py sums the scene's.
"""

from __future__ import annotations

import numpy as np

from .jit import JIT, njit
from .layout import RHO, G, slot
from .spec import CELLS, MODEL, MOVING, PANELS
from .surface import DUNAVANT4, DUNAVANT4_WEIGHTS, clip, world_normal

C_DAMPING, C_DRAG, C_HEAVE_DAMPING = slot("damping"), slot("drag_coefficient"), slot("heave_damping")


@njit(**JIT)
def gravity(model, wet):
    """-M g z_hat at the centre of mass (no torque)."""
    load = np.zeros(6)
    load[2] = -model.mass * model.coef[G]
    return load


@njit(**JIT)
def pressure(model, wet):
    """The water's pressure on the wet surface: the integral of -p nu dA and its torque, summed where the
    wet surface is found (kernels/wet.py), as the water's pressure is known there."""
    return wet.pressure


@njit(**JIT)
def damping_matrix(d, A, S, rr):
    """d [A Id, -[S]x; [S]x, tr(rr) Id - rr] from the wet integrals (forces.damping_matrix)."""
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
def damping(model, wet):
    """Linear viscous damping, -d (v - u_water) per unit wet area: (D, affine), load = affine - D (u, omega)."""
    d = model.coef[C_DAMPING]
    return damping_matrix(d, wet.area, wet.first, wet.second), d * wet.flow if MOVING else wet.flow  # water at rest: flow is zero


@njit(**JIT)
def _drag_node(lx, ly, lz, nx, ny, nz, a, vn, half_rc, F, T, D, need_D, g):
    """Add one node's drag -(1/2) rho C_d a vn^2 n (vn > 0) to F, T, and its Jacobian c g g^T (g = (n, l x n)) to
    D's upper triangle (_mirrored fills the lower one once); g: scratch (6,)."""
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
        g[0], g[1], g[2], g[3], g[4], g[5] = nx, ny, nz, ly * nz - lz * ny, lz * nx - lx * nz, lx * ny - ly * nx
        for i in range(6):
            ci = c * g[i]
            for j in range(i, 6):
                D[i, j] += ci * g[j]


@njit(**JIT)
def _mirrored(D):
    """D with its lower triangle set from its upper one."""
    for i in range(6):
        for j in range(i):
            D[i, j] = D[j, i]
    return D


@njit(**JIT)
def drag(x, R, u, w, model, s, need_D):
    """Quadratic drag on the wet surface moving into the water: force, torque and (need_D) its
    Jacobian D = -d(F, T)/d(u, omega). Points: the wet samples (`flags`, set by the pose's loads),
    each with the water's velocity there (ws[0]); cells: those, and the nodes of the cells the
    water line crosses (ws[6]). Panels: the pose's wet triangles (ws[1:4]), each
    clipped again where v_rel . n changes sign (v_rel linear across it, the water's velocity too),
    with Dunavant's degree-4 rule (exact for the cubic torque integrand)."""
    r, nrm, area = model.geom[0], model.geom[1], model.geom[2]
    flags, ws = s.flags, s.ws
    half_rc = 0.5 * model.coef[RHO] * model.coef[C_DRAG]
    F = np.zeros(3)
    T = np.zeros(3)
    D = np.zeros((6, 6))
    g = np.empty(6)
    if MODEL != PANELS:
        flow, nodes = ws[0], ws[6]
        for k in range(r.shape[0]):
            if MODEL == CELLS and nodes[k, 0] > 0.0:  # a cell the water line crosses: its node, still water
                lx, ly, lz = nodes[k, 1], nodes[k, 2], nodes[k, 3]
                nx, ny, nz = world_normal(R, nrm, k)
                vn = ((u[0] + w[1] * lz - w[2] * ly - flow[k, 0]) * nx + (u[1] + w[2] * lx - w[0] * lz - flow[k, 1]) * ny
                      + (u[2] + w[0] * ly - w[1] * lx - flow[k, 2]) * nz)  # fmt: skip
                if vn > 0.0:
                    _drag_node(lx, ly, lz, nx, ny, nz, nodes[k, 0], vn, half_rc, F, T, D, need_D, g)
                continue
            if not flags[k]:
                continue
            a0, a1, a2 = r[k, 0], r[k, 1], r[k, 2]
            lx, ly, lz = (
                R[0, 0] * a0 + R[0, 1] * a1 + R[0, 2] * a2,
                R[1, 0] * a0 + R[1, 1] * a1 + R[1, 2] * a2,
                R[2, 0] * a0 + R[2, 1] * a1 + R[2, 2] * a2,
            )
            nx, ny, nz = world_normal(R, nrm, k)
            vn = ((u[0] + w[1] * lz - w[2] * ly - flow[k, 0]) * nx + (u[1] + w[2] * lx - w[0] * lz - flow[k, 1]) * ny
                  + (u[2] + w[0] * ly - w[1] * lx - flow[k, 2]) * nz)  # fmt: skip
            if vn > 0.0:
                _drag_node(lx, ly, lz, nx, ny, nz, area[k], vn, half_rc, F, T, D, need_D, g)
        return F, T, _mirrored(D)
    tris, tnormals = ws[1], ws[2]
    vn = np.empty(3)
    ahead = np.empty((2, 3, 6))
    node = np.empty(6)
    for m in range(ws[3][0]):
        nx, ny, nz = tnormals[m, 0], tnormals[m, 1], tnormals[m, 2]
        wet = tris[m]
        for v in range(3):
            lx, ly, lz = wet[v, 0], wet[v, 1], wet[v, 2]
            vn[v] = -((u[0] + w[1] * lz - w[2] * ly - wet[v, 3]) * nx + (u[1] + w[2] * lx - w[0] * lz - wet[v, 4]) * ny
                      + (u[2] + w[0] * ly - w[1] * lx - wet[v, 5]) * nz)  # fmt: skip
        c = clip(wet, vn, ahead)
        for j in range(c):
            t = ahead[j]
            e10, e11, e12 = t[1, 0] - t[0, 0], t[1, 1] - t[0, 1], t[1, 2] - t[0, 2]
            e20, e21, e22 = t[2, 0] - t[0, 0], t[2, 1] - t[0, 1], t[2, 2] - t[0, 2]
            tri_area = 0.5 * ((e11 * e22 - e12 * e21) * nx + (e12 * e20 - e10 * e22) * ny + (e10 * e21 - e11 * e20) * nz)
            for q in range(6):
                b = DUNAVANT4[q]
                for i in range(6):
                    node[i] = b[0] * t[0, i] + b[1] * t[1, i] + b[2] * t[2, i]
                lx, ly, lz = node[0], node[1], node[2]
                vq = ((u[0] + w[1] * lz - w[2] * ly - node[3]) * nx + (u[1] + w[2] * lx - w[0] * lz - node[4]) * ny
                      + (u[2] + w[0] * ly - w[1] * lx - node[5]) * nz)  # fmt: skip
                if vq > 0.0:
                    _drag_node(lx, ly, lz, nx, ny, nz, tri_area * DUNAVANT4_WEIGHTS[q], vq, half_rc, F, T, D, need_D, g)
    return F, T, _mirrored(D)


@njit(**JIT)
def heave_damping(model, wet):
    """B_33, its Jacobian's one entry (at (2, 2)): -B_33 w on the centre of mass (forces.heave_damping); no affine part.
    (kernels/forces.py adds it into the pose's D in place: no 6 x 6 matrix a step where B_33 is 0.)"""
    return model.coef[C_HEAVE_DAMPING]

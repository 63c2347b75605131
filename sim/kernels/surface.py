"""Compiled twin of bodies/surface.py: in still water the integrals every term needs, straight from the pose.

The reference hands out quadrature nodes; here the same integrals are summed in place: the wet area
A, integral of z nu dA (zn), of (z r) x nu dA (zt), of r dA (S) and of r r^T dA (rr), r the lever
from the centre of mass, z the depth coordinate (negative under water). `clip` is the twin of
`surface.clip_triangles` for one triangle.
"""

from __future__ import annotations

import numpy as np

from .jit import JIT, njit
from .rotation import mv, rotate_tensor

DUNAVANT4 = np.array([[0.108103018168070, 0.445948490915965, 0.445948490915965], [0.445948490915965, 0.108103018168070, 0.445948490915965],
                      [0.445948490915965, 0.445948490915965, 0.108103018168070], [0.816847572980459, 0.091576213509771, 0.091576213509771],
                      [0.091576213509771, 0.816847572980459, 0.091576213509771], [0.091576213509771, 0.091576213509771, 0.816847572980459]])  # fmt: skip
DUNAVANT4_WEIGHTS = np.array([0.223381589678011] * 3 + [0.109951743655322] * 3)
"""Dunavant's degree-4 rule on a triangle: barycentric nodes and weights (surface.DUNAVANT4)."""


@njit(inline="always", **JIT)
def wet_points(x, R, r, need_rr, moments, flags, acc):
    """Integrals over the wet samples. Every one is linear in z = x_z + R[2].r, so it is fixed by
    per-sample constants summed over the wet set (layout.py): keep those sums in `acc` and, at each
    evaluation, add or remove only the samples that crossed the water line (`flags`: wet or not)."""
    R20, R21, R22 = R[2, 0], R[2, 1], R[2, 2]
    for k in range(r.shape[0]):
        w = x[2] + (R20 * r[k, 0] + R21 * r[k, 1] + R22 * r[k, 2]) < 0.0
        if w != flags[k]:
            flags[k] = w
            sign = 1.0 if w else -1.0
            for j in range(34):
                acc[j] += sign * moments[k, j]
    return sums_integrals(x, R, need_rr, acc)


@njit(inline="always", **JIT)
def sums_integrals(x, R, need_rr, acc):
    """(zn, zt, A, S, rr) from the running sums over a wet set (layout.py's sample moments)."""
    R20, R21, R22 = R[2, 0], R[2, 1], R[2, 2]
    x2 = x[2]
    nb = np.empty(3)
    cb = np.empty(3)
    for i in range(3):
        nb[i] = x2 * acc[10 + i] + acc[13 + 3 * i] * R20 + acc[14 + 3 * i] * R21 + acc[15 + 3 * i] * R22
        cb[i] = x2 * acc[22 + i] + acc[25 + 3 * i] * R20 + acc[26 + 3 * i] * R21 + acc[27 + 3 * i] * R22
    S = np.zeros(3)
    rr = np.zeros((3, 3))
    if need_rr:
        S = mv(R, acc[1:4].copy())
        Q = np.array([[acc[4], acc[5], acc[6]], [acc[5], acc[7], acc[8]], [acc[6], acc[8], acc[9]]])
        rr = rotate_tensor(R, Q)
    return mv(R, nb), mv(R, cb), acc[0], S, rr


@njit(**JIT)
def crossing(a, b, ha, hb):
    """Where the edge a -> b crosses the zero of a linear function with end values ha, hb (opposite signs)."""
    t = ha / (ha - hb)
    return (a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t)


@njit(**JIT)
def clip(p, h, out):
    """Write the part of triangle p (3, c) where the linear function with vertex values h is
    negative into out[0:count] (triangles, same winding); return count (0, 1 or 2). Columns past
    the position (c > 3: e.g. the water's velocity at the vertices) are interpolated alike."""
    below = (h[0] < 0.0) + (h[1] < 0.0) + (h[2] < 0.0)
    if below == 0:
        return 0
    if below == 3:
        out[0] = p
        return 1
    first = 0
    for i in range(3):  # roll so the odd vertex (alone below, or alone above) comes first
        if (h[i] < 0.0) == (below == 1):
            first = i
            break
    i0, i1, i2 = first, (first + 1) % 3, (first + 2) % 3
    t01 = h[i0] / (h[i0] - h[i1])
    t20 = h[i2] / (h[i2] - h[i0])
    for c in range(p.shape[1]):
        e01 = p[i0, c] + (p[i1, c] - p[i0, c]) * t01
        e20 = p[i2, c] + (p[i0, c] - p[i2, c]) * t20
        if below == 1:
            out[0, 0, c], out[0, 1, c], out[0, 2, c] = p[i0, c], e01, e20
        else:  # quadrilateral e01 -> p1 -> p2 -> e20
            out[0, 0, c], out[0, 1, c], out[0, 2, c] = e01, p[i1, c], p[i2, c]
            out[1, 0, c], out[1, 1, c], out[1, 2, c] = e01, p[i2, c], e20
    return 2 if below == 2 else 1


@njit(inline="always", **JIT)
def _triangle(p0, p1, p2, x2, nx, ny, nz, zn, zt, S, rr, need_rr):
    """Add one wet triangle's exact integrals (levers p0, p1, p2; heights x2 + p[2], clipped to <= 0)
    to zn, zt, S, rr in place: integral f g dA = A/12 (sum f_i g_i + sum f_i sum g_i). Returns its area."""
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


@njit(inline="always", **JIT)
def vertex_levers(R, verts):
    """(v, 3) mesh vertices rotated into the world frame (levers from the centre of mass)."""
    lev = np.empty((verts.shape[0], 3))
    for v in range(verts.shape[0]):
        for i in range(3):
            lev[v, i] = R[i, 0] * verts[v, 0] + R[i, 1] * verts[v, 1] + R[i, 2] * verts[v, 2]
    return lev


@njit(inline="always", **JIT)
def wet_panels(x, R, verts, faces, fnormals, need_rr):
    """Exact integrals over the mesh's triangles clipped at the still water line."""
    zn = np.zeros(3)
    zt = np.zeros(3)
    S = np.zeros(3)
    rr = np.zeros((3, 3))
    A = 0.0
    lev = vertex_levers(R, verts)
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
        first = 0
        if below != 3:  # roll so the odd vertex (alone under water, or alone above it) comes first
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
        e01 = crossing(p0, p1, x2 + p0[2], x2 + p1[2])
        e20 = crossing(p2, p0, x2 + p2[2], x2 + p0[2])
        if below == 1:
            A += _triangle(p0, e01, e20, x2, nx, ny, nz, zn, zt, S, rr, need_rr)
        else:  # quadrilateral e01 -> p1 -> p2 -> e20
            A += _triangle(e01, p1, p2, x2, nx, ny, nz, zn, zt, S, rr, need_rr)
            A += _triangle(e01, p2, e20, x2, nx, ny, nz, zn, zt, S, rr, need_rr)
    return zn, zt, A, S, rr


@njit(inline="always", **JIT)
def world_normal(R, fnormals, f):
    b0, b1, b2 = fnormals[f, 0], fnormals[f, 1], fnormals[f, 2]
    return (
        R[0, 0] * b0 + R[0, 1] * b1 + R[0, 2] * b2,
        R[1, 0] * b0 + R[1, 1] * b1 + R[1, 2] * b2,
        R[2, 0] * b0 + R[2, 1] * b1 + R[2, 2] * b2,
    )


@njit(**JIT)
def wet_triangles(x, R, verts, faces, fnormals, ws, current):
    """Store the mesh's triangles clipped at the still water line in the workspace (layout.workspace),
    with the water's velocity (the uniform current) at their vertices, for the terms that integrate over them (drag)."""
    tris, tnormals, count = ws[1], ws[2], ws[3]
    lev = vertex_levers(R, verts)
    P = np.zeros((3, 6))
    for v in range(3):
        P[v, 3], P[v, 4] = current[0], current[1]
    h = np.empty(3)
    m = 0
    for f in range(faces.shape[0]):
        for v in range(3):
            for i in range(3):
                P[v, i] = lev[faces[f, v], i]
            h[v] = x[2] + P[v, 2]
        c = clip(P, h, tris[m:])
        nx, ny, nz = world_normal(R, fnormals, f)
        for k in range(m, m + c):
            tnormals[k, 0], tnormals[k, 1], tnormals[k, 2] = nx, ny, nz
        m += c
    count[0] = m


@njit(inline="always", **JIT)
def _whole_cell(R, cell, out):
    """Area and centroid lever (world frame) of a whole cell, the fan of triangles (0, 1, 2) and (0, 2, 3), into out (4,)."""
    a = cx = cy = cz = 0.0
    for fan in range(2):
        i1, i2 = 1 + fan, 2 + fan
        e1 = (cell[i1, 0] - cell[0, 0], cell[i1, 1] - cell[0, 1], cell[i1, 2] - cell[0, 2])
        e2 = (cell[i2, 0] - cell[0, 0], cell[i2, 1] - cell[0, 1], cell[i2, 2] - cell[0, 2])
        q0, q1, q2 = e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]
        area = 0.5 * np.sqrt(q0 * q0 + q1 * q1 + q2 * q2)
        a += area
        cx += area * (cell[0, 0] + cell[i1, 0] + cell[i2, 0]) / 3.0
        cy += area * (cell[0, 1] + cell[i1, 1] + cell[i2, 1]) / 3.0
        cz += area * (cell[0, 2] + cell[i1, 2] + cell[i2, 2]) / 3.0
    out[0] = a
    if a > 0.0:  # the centroid in the body frame, then turned into the world's
        bx, by, bz = cx / a, cy / a, cz / a
        out[1] = R[0, 0] * bx + R[0, 1] * by + R[0, 2] * bz
        out[2] = R[1, 0] * bx + R[1, 1] * by + R[1, 2] * bz
        out[3] = R[2, 0] * bx + R[2, 1] * by + R[2, 2] * bz


@njit(inline="always", **JIT)
def cell_node(x2, R, cell, out, P, h, parts):
    """The wet part of one cell (4 corners, body frame) under the still water line: its area and
    centroid lever (world frame) into out (4,). The cell is taken as the fan of two triangles. A cell
    wholly on one side (most of those near the line: a face lying in the water plane has them all)
    is settled from its corner heights without clipping. P (3, 3), h (3,), parts (2, 3, 3): scratch."""
    lo, hi = np.inf, -np.inf
    for c in range(4):
        z = x2 + R[2, 0] * cell[c, 0] + R[2, 1] * cell[c, 1] + R[2, 2] * cell[c, 2]
        lo, hi = min(lo, z), max(hi, z)
    if lo >= 0.0:
        out[0] = 0.0
        return
    if hi < 0.0:
        _whole_cell(R, cell, out)
        return
    a = cx = cy = cz = 0.0
    for fan in range(2):
        for v in range(3):
            c = 0 if v == 0 else fan + v
            for i in range(3):
                P[v, i] = R[i, 0] * cell[c, 0] + R[i, 1] * cell[c, 1] + R[i, 2] * cell[c, 2]
            h[v] = x2 + P[v, 2]
        for j in range(clip(P, h, parts)):
            t = parts[j]
            e10, e11, e12 = t[1, 0] - t[0, 0], t[1, 1] - t[0, 1], t[1, 2] - t[0, 2]
            e20, e21, e22 = t[2, 0] - t[0, 0], t[2, 1] - t[0, 1], t[2, 2] - t[0, 2]
            q0, q1, q2 = e11 * e22 - e12 * e21, e12 * e20 - e10 * e22, e10 * e21 - e11 * e20
            area = 0.5 * np.sqrt(q0 * q0 + q1 * q1 + q2 * q2)
            a += area
            cx += area * (t[0, 0] + t[1, 0] + t[2, 0]) / 3.0
            cy += area * (t[0, 1] + t[1, 1] + t[2, 1]) / 3.0
            cz += area * (t[0, 2] + t[1, 2] + t[2, 2]) / 3.0
    out[0] = a
    if a > 0.0:
        out[1], out[2], out[3] = cx / a, cy / a, cz / a


@njit(inline="always", **JIT)
def wet_cells(x, R, r, nrm, cells, reach, need_rr, moments, flags, acc, nodes):
    """Integrals of the cells model: the samples whose whole cell is under water as running sums
    (like wet_points, `flags` marking them), plus one node per cell the water line crosses, at the
    centroid of its wet part and weighted by its area, kept in `nodes` (n, 4: area, lever; area 0
    for the others) for the twist terms."""
    x2 = x[2]
    R20, R21, R22 = R[2, 0], R[2, 1], R[2, 2]
    for k in range(r.shape[0]):  # the whole cells first: the sums are the points model's, on them
        z = x2 + R20 * r[k, 0] + R21 * r[k, 1] + R22 * r[k, 2]
        nodes[k, 0] = -1.0 if z - reach[k] < 0.0 <= z + reach[k] else 0.0  # -1: to clip below
        w = z + reach[k] < 0.0
        if w != flags[k]:
            flags[k] = w
            sign = 1.0 if w else -1.0
            for j in range(34):
                acc[j] += sign * moments[k, j]
    zn, zt, A, S, rr = sums_integrals(x, R, need_rr, acc)
    P, h, parts = np.empty((3, 3)), np.empty(3), np.empty((2, 3, 3))  # once per pose, not per cell
    for k in range(r.shape[0]):
        if nodes[k, 0] == 0.0:
            continue
        cell_node(x2, R, cells[k], nodes[k], P, h, parts)
        a = nodes[k, 0]
        if a == 0.0:
            continue
        lx, ly, lz = nodes[k, 1], nodes[k, 2], nodes[k, 3]
        nx, ny, nz = world_normal(R, nrm, k)
        za = a * (x2 + lz)
        zn[0] += za * nx
        zn[1] += za * ny
        zn[2] += za * nz
        zt[0] += za * (ly * nz - lz * ny)
        zt[1] += za * (lz * nx - lx * nz)
        zt[2] += za * (lx * ny - ly * nx)
        A += a
        if need_rr:
            lev = (lx, ly, lz)
            for i in range(3):
                S[i] += a * lev[i]
                for j in range(3):
                    rr[i, j] += a * lev[i] * lev[j]
    return zn, zt, A, S, rr


@njit(**JIT)
def workspace(geom):
    """Scratch a pose's loads leave for the twist terms of the same pose: the water's velocity at
    each sample (n, 3); the wet triangles as vertex levers and water velocities (2 f, 3, 6), their
    normals (2 f, 3), and how many there are (1,); damping's part from the water's motion (6,); in
    waves, the frame's integrals over the wet nodes: area, volume (z nu_z) and z^2 nu_z (3,); the
    cells model's nodes on the cells the water line crosses (n, 4: area, lever)."""
    n, f = geom[0].shape[0], geom[4].shape[0]
    return (np.zeros((n, 3)), np.zeros((2 * f, 3, 6)), np.zeros((2 * f, 3)), np.zeros(1, dtype=np.int64), np.zeros(6), np.zeros(3),
            np.zeros((n, 4)))  # fmt: skip


@njit(**JIT)
def mesh_integrals(x, R, geom):
    """(wet area, submerged volume, integral of z^2 nu_z) of the mesh clipped at the still water
    line, exact (Simpson-like closed forms on each clipped triangle)."""
    verts, faces, fnormals = geom[3], geom[4], geom[5]
    lev = vertex_levers(R, verts)
    P = np.empty((3, 3))
    h = np.empty(3)
    tris = np.empty((2, 3, 3))
    z2n = a_sub = v_sub = 0.0
    for f in range(faces.shape[0]):
        for v in range(3):
            for i in range(3):
                P[v, i] = lev[faces[f, v], i]
            h[v] = x[2] + P[v, 2]
        nz = R[2, 0] * fnormals[f, 0] + R[2, 1] * fnormals[f, 1] + R[2, 2] * fnormals[f, 2]
        nx = R[0, 0] * fnormals[f, 0] + R[0, 1] * fnormals[f, 1] + R[0, 2] * fnormals[f, 2]
        ny = R[1, 0] * fnormals[f, 0] + R[1, 1] * fnormals[f, 1] + R[1, 2] * fnormals[f, 2]
        for k in range(clip(P, h, tris)):
            t = tris[k]
            e10, e11, e12 = t[1, 0] - t[0, 0], t[1, 1] - t[0, 1], t[1, 2] - t[0, 2]
            e20, e21, e22 = t[2, 0] - t[0, 0], t[2, 1] - t[0, 1], t[2, 2] - t[0, 2]
            area = 0.5 * ((e11 * e22 - e12 * e21) * nx + (e12 * e20 - e10 * e22) * ny + (e10 * e21 - e11 * e20) * nz)
            z0, z1, z2 = min(x[2] + t[0, 2], 0.0), min(x[2] + t[1, 2], 0.0), min(x[2] + t[2, 2], 0.0)
            sz = z0 + z1 + z2
            a_sub += area
            v_sub += area * sz / 3.0 * nz
            z2n += area / 12.0 * (z0 * z0 + z1 * z1 + z2 * z2 + sz * sz) * nz  # integral of z^2 over the triangle, times nu_z
    return a_sub, v_sub, z2n


@njit(**JIT)
def exact_hydrostatic_energy(x, R, geom, rho_g):
    """The physical hydrostatic potential rho g * integral of (-z) dV over the mesh clipped at the
    still water line, J: the same for every force model."""
    return -0.5 * rho_g * mesh_integrals(x, R, geom)[2]

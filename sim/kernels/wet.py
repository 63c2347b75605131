"""The wet surface's integrals at a pose and time, which the force terms (kernels/terms.py) read: the twin of
the reference's wet surface (bodies/surface.py), summed in place instead of handed out as quadrature nodes.

Still water: the closed forms of kernels/surface.py (the pressure is rho g times the depth). Waves: the
water (kernels/water.py) asked at the wet nodes, its pressure and velocity integrated there.
"""

from __future__ import annotations

import numpy as np

from .jit import JIT, njit
from .layout import RHO, G, Wet
from .rotation import mv, rotate_tensor
from .spec import CELLS, CURRENT, DAMPING, DRAG, MODEL, PANELS, POINTS, PRESSURE, TWIST_TERMS, USED, WAVES
from .surface import DUNAVANT4, DUNAVANT4_WEIGHTS, clip, vertex_levers, wet_cells, wet_panels, wet_points, wet_triangles, world_normal
from .terms import C_DRAG
from .water import cluster_ex, clusters, elevations, fields, prepare


@njit(inline="always", **JIT)
def drag_on(coef):
    """Whether drag acts: its code is compiled always (kernels.EVERY_TERM), the wet triangles and the water's velocity
    it reads are made only at a nonzero coefficient (the panels model would pay for them every step)."""
    return (USED & DRAG) != 0 and coef[C_DRAG] != 0.0


@njit(**JIT)
def wet_integrals(x, R, geom, need_rr, flags, acc, ws):
    """(zn, zt, A, S, rr) of the scene's force model (spec.MODEL); S and rr only when need_rr."""
    r, nrm, verts, faces, fnormals, moments = geom[0], geom[1], geom[3], geom[4], geom[5], geom[6]
    if MODEL == POINTS:
        return wet_points(x, R, r, need_rr, moments, flags, acc)
    if MODEL == CELLS:
        return wet_cells(x, R, r, nrm, geom[7], geom[8], need_rr, moments, flags, acc, ws[6])
    return wet_panels(x, R, verts, faces, fnormals, need_rr)


@njit(inline="always", **JIT)  # once per pose: no call passing the body's and scratch's arrays
def wet_surface(x, R, t, model, s, sea):
    """The wet surface's integrals (layout.Wet) at a pose and time. Leaves in the scratch `s` what the twist
    terms of this pose need (surface.workspace): the wet samples' flags, the wet triangles (for drag) and, in
    waves, the water's velocity at the wet nodes and the frame's integrals. The sampled model's running wet
    sums belong to one sea: waves keep only the first 10, so start them afresh (as advance and observe do)
    when the water changes."""
    geom, coef = model.geom, model.coef
    if WAVES:
        load = np.zeros((2, 6))
        if MODEL == POINTS:
            A, S, rr = wave_points(x, R, sea, prepare(sea, t, x), geom, coef, s.flags, s.acc, s.ws, load)
        else:
            A, S, rr = wave_panels(x, R, t, sea, geom, coef, s.ws, load)
        return Wet(load[0].copy(), A, S, rr, load[1].copy())
    zn, zt, A, S, rr = wet_integrals(x, R, geom, (USED & DAMPING) != 0, s.flags, s.acc, s.ws)  # rr: damping's alone
    rg = coef[RHO] * coef[G]
    p = np.empty(6)
    p[:3] = rg * zn
    p[3:] = rg * zt
    flow = np.zeros(6)
    U = sea[4]
    if CURRENT:  # the integral of the uniform current over the wet surface, and its torque S x U
        flow[0], flow[1] = A * U[0], A * U[1]
        flow[3], flow[4], flow[5] = -S[2] * U[1], S[2] * U[0], S[0] * U[1] - S[1] * U[0]
        if drag_on(coef) and MODEL != PANELS:  # drag reads the water's velocity at each sample
            s.ws[0][:, 0], s.ws[0][:, 1] = U[0], U[1]
    if MODEL == PANELS and drag_on(coef) and A > 0.0:
        wet_triangles(x, R, geom[3], geom[4], geom[5], s.ws, U)
    return Wet(p, A, S, rr, flow)


@njit(inline="always", **JIT)
def _add_moments(t, area, sums):
    """Add a flat triangle's (levers t (3, 3)) area, integral of r dA and of r r^T dA (exact) to sums (13,)."""
    s0, s1, s2 = t[0, 0] + t[1, 0] + t[2, 0], t[0, 1] + t[1, 1] + t[2, 1], t[0, 2] + t[1, 2] + t[2, 2]
    sums[0] += area
    sums[1] += area * s0 / 3.0
    sums[2] += area * s1 / 3.0
    sums[3] += area * s2 / 3.0
    w = area / 12.0
    xx = w * (t[0, 0] * t[0, 0] + t[1, 0] * t[1, 0] + t[2, 0] * t[2, 0] + s0 * s0)
    xy = w * (t[0, 0] * t[0, 1] + t[1, 0] * t[1, 1] + t[2, 0] * t[2, 1] + s0 * s1)
    xz = w * (t[0, 0] * t[0, 2] + t[1, 0] * t[1, 2] + t[2, 0] * t[2, 2] + s0 * s2)
    yy = w * (t[0, 1] * t[0, 1] + t[1, 1] * t[1, 1] + t[2, 1] * t[2, 1] + s1 * s1)
    yz = w * (t[0, 1] * t[0, 2] + t[1, 1] * t[1, 2] + t[2, 1] * t[2, 2] + s1 * s2)
    zz = w * (t[0, 2] * t[0, 2] + t[1, 2] * t[1, 2] + t[2, 2] * t[2, 2] + s2 * s2)
    sums[4] += xx
    sums[5] += xy
    sums[6] += xz
    sums[7] += xy
    sums[8] += yy
    sums[9] += yz
    sums[10] += xz
    sums[11] += yz
    sums[12] += zz


@njit(inline="always", **JIT)
def _triangle_load(x, nodes, out, first, area, nx, ny, nz, pressure_on, d, load, diag):
    """Add one flat triangle's Dunavant sums from its nodes first..first+5: the pressure's force -area (sum w p) n and
    torque -area (sum w p l) x n, l the lever (n is the same at every node); where d = 1 the water's velocity's
    integral and torque (damping); the frame's integrals (area, z nu_z and z^2 nu_z) to diag."""
    sp = spx = spy = spz = sz = szz = 0.0
    u0 = u1 = u2 = t0 = t1 = t2 = 0.0
    for q in range(6):
        w = DUNAVANT4_WEIGHTS[q]
        i = first + q
        lx, ly, lz = nodes[i, 0] - x[0], nodes[i, 1] - x[1], nodes[i, 2] - x[2]
        if pressure_on:
            wp = w * out[i, 0]
            sp += wp
            spx, spy, spz = spx + wp * lx, spy + wp * ly, spz + wp * lz
        sz += w * nodes[i, 2]
        szz += w * nodes[i, 2] * nodes[i, 2]
        if d != 0.0:
            ux, uy, uz = w * out[i, 1], w * out[i, 2], w * out[i, 3]
            u0, u1, u2 = u0 + ux, u1 + uy, u2 + uz
            t0, t1, t2 = t0 + ly * uz - lz * uy, t1 + lz * ux - lx * uz, t2 + lx * uy - ly * ux
    f = -area * sp
    load[0, 0] += f * nx
    load[0, 1] += f * ny
    load[0, 2] += f * nz
    load[0, 3] -= area * (spy * nz - spz * ny)
    load[0, 4] -= area * (spz * nx - spx * nz)
    load[0, 5] -= area * (spx * ny - spy * nx)
    if d != 0.0:
        for c, v in enumerate((u0, u1, u2, t0, t1, t2)):
            load[1, c] += area * v
    diag[0] += area
    diag[1] += area * sz * nz
    diag[2] += area * szz * nz


@njit(**JIT)
def _water_at(sea, ex, points, m, rho, g, need_flow):
    """[pressure, flow] (m, 4) at the first m points, in one call."""
    out = np.empty((m, 4))
    fields(sea, ex, points, np.empty(m), m, rho, g, need_flow, out, False)
    return out


@njit(**JIT)
def wave_points(x, R, sea, ex, geom, coef, flags, acc, ws, load):
    """The pressure on the samples below the wave surface and the water's velocity there (for damping),
    each integrated over them into load (2, 6); the samples' water velocity into ws. Returns the wet area and its moments
    (A, S, rr), kept as running sums like in still water (they depend only on which samples are wet)."""
    r, nrm, area, moments = geom[0], geom[1], geom[2], geom[6]
    n = r.shape[0]
    d = 1.0 if USED & DAMPING else 0.0  # the integral of u_water dA, for damping
    pressure_on = (USED & PRESSURE) != 0
    pts = np.empty((n, 3))
    for k in range(n):
        for i in range(3):
            pts[k, i] = x[i] + R[i, 0] * r[k, 0] + R[i, 1] * r[k, 1] + R[i, 2] * r[k, 2]
    eta = np.empty(n)
    elevations(sea, ex, pts, n, eta)
    wet = np.empty(n, dtype=np.int64)
    m = 0
    for k in range(n):
        w = pts[k, 2] - eta[k] < 0.0
        if w != flags[k]:
            flags[k] = w
            sign = 1.0 if w else -1.0
            for j in range(10):  # a, a r, a r r^T: the damping matrix's moments
                acc[j] += sign * moments[k, j]
        if w:
            pts[m, 0], pts[m, 1], pts[m, 2], eta[m], wet[m] = pts[k, 0], pts[k, 1], pts[k, 2], eta[k], k  # gathered in place: m <= k
            m += 1
    if m == 0:  # all dry: restart the running sums (no round-off residue says "wet")
        acc[:] = 0.0
    out = np.empty((m, 4))
    fields(sea, ex, pts, eta, m, coef[RHO], coef[G], (USED & TWIST_TERMS) != 0, out, True)
    flow = ws[0]
    fp0 = fp1 = fp2 = tp0 = tp1 = tp2 = fd0 = fd1 = fd2 = td0 = td1 = td2 = a_sub = v_sub = z2n = (
        0.0  # pressure, damping's flow part, frame integrals
    )
    for i in range(m):
        k = wet[i]
        p, ux, uy, uz = out[i, 0] if pressure_on else 0.0, out[i, 1], out[i, 2], out[i, 3]
        flow[k, 0], flow[k, 1], flow[k, 2] = ux, uy, uz
        nx, ny, nz = world_normal(R, nrm, k)
        lx, ly, lz = pts[i, 0] - x[0], pts[i, 1] - x[1], pts[i, 2] - x[2]
        a = area[k]
        fx, fy, fz = -p * a * nx, -p * a * ny, -p * a * nz
        fp0, fp1, fp2 = fp0 + fx, fp1 + fy, fp2 + fz
        tp0, tp1, tp2 = tp0 + ly * fz - lz * fy, tp1 + lz * fx - lx * fz, tp2 + lx * fy - ly * fx
        if d != 0.0:
            fx, fy, fz = d * a * ux, d * a * uy, d * a * uz
            fd0, fd1, fd2 = fd0 + fx, fd1 + fy, fd2 + fz
            td0, td1, td2 = td0 + ly * fz - lz * fy, td1 + lz * fx - lx * fz, td2 + lx * fy - ly * fx
        z = pts[i, 2]
        a_sub += a
        v_sub += a * z * nz
        z2n += a * z * z * nz
    load[0, 0], load[0, 1], load[0, 2], load[0, 3], load[0, 4], load[0, 5] = fp0, fp1, fp2, tp0, tp1, tp2
    load[1, 0], load[1, 1], load[1, 2], load[1, 3], load[1, 4], load[1, 5] = fd0, fd1, fd2, td0, td1, td2
    ws[5][0], ws[5][1], ws[5][2] = a_sub, v_sub, z2n
    Q = np.array([[acc[4], acc[5], acc[6]], [acc[5], acc[7], acc[8]], [acc[6], acc[8], acc[9]]])
    return acc[0], mv(R, acc[1:4].copy()), rotate_tensor(R, Q)


@njit(**JIT)
def wave_panels(x, R, t, sea, geom, coef, ws, load):
    """The pressure and the water's velocity (for damping) on the mesh clipped at the wave surface (the
    plane through the surface points above each triangle's vertices), by Dunavant's rule, integrated into
    load (2, 6); the wet triangles with the water's velocity at their vertices into ws when drag needs
    them. Returns the wet area and its moments (A, S, rr), exact for the clipped triangles.

    The triangles are taken a part of the body's tree at a time (water.clusters), each part with the water's series
    about its own centre: parts above the crests are skipped, parts below the troughs need no vertex elevations."""
    verts, faces, order, spans = geom[3], geom[4], geom[9], geom[10]
    need_flow = (USED & TWIST_TERMS) != 0
    cut = clusters(sea, t, x, R, spans, geom[11], need_flow)
    lev = vertex_levers(R, verts)
    nv, nf = verts.shape[0], faces.shape[0]
    hv = np.empty(nv)
    known = np.zeros(nv, dtype=np.bool_)
    scratch = (np.empty((nv, 3)), np.empty(nv), np.empty(nv, dtype=np.int64), np.empty((2 * nf, 3, 3)), np.empty((2 * nf, 3)))
    sums = np.zeros(13)  # A, S (3), rr (9)
    ws[5][:] = 0.0
    wet_count = 0
    for c in range(cut[0].shape[0]):
        ex = cluster_ex(cut, c)
        nd = cut[0][c]
        if cut[1][c] == 1:  # the water line may cross it: the surface above its vertices not asked yet
            _vertex_heights(x, sea, ex, lev, faces, order[spans[nd, 0] : spans[nd, 1]], hv, known, scratch)
        wet_count = _part_panels(x, R, sea, ex, geom, coef, order[spans[nd, 0] : spans[nd, 1]], cut[1][c] == 2, lev, hv, scratch, ws, load,
                                 sums, wet_count)  # fmt: skip
    if drag_on(coef):
        ws[3][0] = wet_count
    rr = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            rr[i, j] = sums[4 + 3 * i + j]
    return sums[0], sums[1:4].copy(), rr


@njit(**JIT)
def _vertex_heights(x, sea, ex, lev, faces, faces_of_part, hv, known, scratch):
    """hv[v] = z - eta at each vertex of these faces not asked before (known)."""
    pts, eta, ids = scratch[0], scratch[1], scratch[2]
    q = 0
    for f in faces_of_part:
        for v in range(3):
            vi = faces[f, v]
            if not known[vi]:
                known[vi] = True
                ids[q] = vi
                for i in range(3):
                    pts[q, i] = x[i] + lev[vi, i]
                q += 1
    elevations(sea, ex, pts, q, eta)
    for i in range(q):
        hv[ids[i]] = pts[i, 2] - eta[i]


@njit(**JIT)
def _part_panels(x, R, sea, ex, geom, coef, faces_of_part, all_wet, lev, hv, scratch, ws, load, sums, wet_count):
    """One part's triangles clipped (whole where all_wet), their Dunavant nodes' pressure and flow integrated into
    load, their integrals added to sums (A, S, rr row-major) and the frame's to ws[5]; the wet triangles and the
    water's velocity at their corners appended to ws[1], ws[2] from wet_count when drag needs them. Returns the new count."""
    faces, fnormals = geom[4], geom[5]
    rho, g = coef[RHO], coef[G]
    d = 1.0 if USED & DAMPING else 0.0  # the integral of u_water dA, for damping
    pressure_on = (USED & PRESSURE) != 0
    subs, normals = scratch[3], scratch[4]
    P = np.empty((3, 3))
    h = np.empty(3)
    m = 0
    for f in faces_of_part:
        a, b, e = faces[f, 0], faces[f, 1], faces[f, 2]
        if all_wet or (hv[a] < 0.0 and hv[b] < 0.0 and hv[e] < 0.0):  # whole: no clipping
            for i in range(3):
                subs[m, 0, i], subs[m, 1, i], subs[m, 2, i] = lev[a, i], lev[b, i], lev[e, i]
            c = 1
        elif hv[a] >= 0.0 and hv[b] >= 0.0 and hv[e] >= 0.0:
            continue
        else:
            for v in range(3):
                for i in range(3):
                    P[v, i] = lev[faces[f, v], i]
                h[v] = hv[faces[f, v]]
            c = clip(P, h, subs[m:])
        nx, ny, nz = world_normal(R, fnormals, f)
        for k in range(m, m + c):
            normals[k, 0], normals[k, 1], normals[k, 2] = nx, ny, nz
        m += c
    nodes = np.empty((6 * m, 3))
    for k in range(m):
        t = subs[k]
        for q in range(6):
            b = DUNAVANT4[q]
            for i in range(3):
                nodes[6 * k + q, i] = x[i] + b[0] * t[0, i] + b[1] * t[1, i] + b[2] * t[2, i]
    out = _water_at(sea, ex, nodes, 6 * m, rho, g, (USED & TWIST_TERMS) != 0)
    for k in range(m):
        t = subs[k]
        nx, ny, nz = normals[k, 0], normals[k, 1], normals[k, 2]
        e10, e11, e12 = t[1, 0] - t[0, 0], t[1, 1] - t[0, 1], t[1, 2] - t[0, 2]
        e20, e21, e22 = t[2, 0] - t[0, 0], t[2, 1] - t[0, 1], t[2, 2] - t[0, 2]
        area = 0.5 * ((e11 * e22 - e12 * e21) * nx + (e12 * e20 - e10 * e22) * ny + (e10 * e21 - e11 * e20) * nz)
        _add_moments(t, area, sums)
        _triangle_load(x, nodes, out, 6 * k, area, nx, ny, nz, pressure_on, d, load, ws[5])
    if drag_on(coef):  # the wet triangles and the water's velocity at their vertices
        corners = np.empty((3 * m, 3))
        for k in range(m):
            for v in range(3):
                for i in range(3):
                    corners[3 * k + v, i] = x[i] + subs[k, v, i]
        flow = _water_at(sea, ex, corners, 3 * m, rho, g, True)
        tris, tnormals = ws[1], ws[2]
        for k in range(m):
            for v in range(3):
                for i in range(3):
                    tris[wet_count + k, v, i] = subs[k, v, i]
                    tris[wet_count + k, v, 3 + i] = flow[3 * k + v, 1 + i]
            tnormals[wet_count + k] = normals[k]
    return wet_count + m

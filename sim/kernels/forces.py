"""Compiled twin of forces.py: each registered term as scalar code, and the loads of a scene's terms.

`terms` is the scene's mask and `coef` its coefficients (layout.py); bits and slots come from the
registry, so a term here reads its own with `bit(name)` and `slot(key)`.
"""

from __future__ import annotations

import numpy as np

from . import JIT, njit
from .layout import RHO, G, bit, slot
from .rotation import mv, rotate_tensor
from .surface import clip, vertex_levers, wet_integrals, wet_triangles, world_normal
from .water import elevations, fields, prepare

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


@njit(inline="always", **JIT)
def pose_loads(kind, x, R, t, geom, mass, terms, coef, sea, flags, acc, ws):
    """Gravity and pressure at a pose and time, the linear damping matrix D there, and whether any
    twist term has a wet surface to act on. Leaves in the workspace `ws` what the twist terms of this
    pose need (surface.workspace): the wet triangles (for drag) and, in waves, the water's velocity.
    flags and acc (the sampled model's running wet sums) belong to one sea: waves keep only the
    first 10 sums, so start them afresh (as advance and observe do) when the water changes."""
    if sea[0].shape[0] > 0:
        return wave_pose_loads(kind, x, R, t, geom, mass, terms, coef, sea, flags, acc, ws)
    verts, faces, fnormals = geom[3], geom[4], geom[5]
    F = np.zeros(3)
    if terms & GRAVITY:
        F[2] = -mass * coef[G]
    T = np.zeros(3)
    D = np.zeros((6, 6))
    wet = False
    if terms & WET_TERMS:
        zn, zt, A, S, rr = wet_integrals(kind, x, R, geom, (terms & DAMPING) != 0, flags, acc, ws)
        if terms & PRESSURE:
            rg = coef[RHO] * coef[G]
            F += rg * zn
            T += rg * zt
        wet = (terms & TWIST_TERMS) != 0 and A > 0.0
        if wet and terms & DAMPING:
            D = damping_matrix(coef, A, S, rr)
        if wet and kind == 1 and terms & DRAG:
            wet_triangles(x, R, verts, faces, fnormals, ws)
    return F, T, D, wet


@njit(inline="always", **JIT)
def _node_load(lx, ly, lz, nx, ny, nz, a, p, d, ux, uy, uz, load):
    """Add one wet node's pressure force -p a n to load[0] and damping's part from the water's
    motion, d a u_water, to load[1] (each force and torque, (6,))."""
    for row, fx, fy, fz in ((0, -p * a * nx, -p * a * ny, -p * a * nz), (1, d * a * ux, d * a * uy, d * a * uz)):
        load[row, 0] += fx
        load[row, 1] += fy
        load[row, 2] += fz
        load[row, 3] += ly * fz - lz * fy
        load[row, 4] += lz * fx - lx * fz
        load[row, 5] += lx * fy - ly * fx


@njit(inline="always", **JIT)
def _diagnostics(diag, a, z, nz):
    """Add a wet node's share of the frame's integrals: area, volume (z nu_z, divergence theorem) and z^2 nu_z."""
    diag[0] += a
    diag[1] += a * z * nz
    diag[2] += a * z * z * nz


@njit(**JIT)
def _water_at(sea, ex, points, m, rho, g, need_flow):
    """[pressure, flow] (m, 4) at the first m points, in one call."""
    out = np.empty((m, 4))
    fields(sea, ex, points, np.empty(m), m, rho, g, need_flow, out, False)
    return out


@njit(**JIT)
def _wave_points(x, R, sea, ex, geom, terms, coef, flags, acc, ws, load):
    """Pressure and the water-motion part of damping on the samples below the wave surface, summed
    into load (2, 6); the samples' water velocity into ws. Returns the wet area and its moments
    (A, S, rr), kept as running sums like in still water (they depend only on which samples are wet)."""
    r, nrm, area, moments = geom[0], geom[1], geom[2], geom[6]
    n = r.shape[0]
    d = coef[C_DAMPING] if terms & DAMPING else 0.0
    pressure_on = (terms & PRESSURE) != 0
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
    fields(sea, ex, pts, eta, m, coef[RHO], coef[G], (terms & TWIST_TERMS) != 0, out, True)
    flow = ws[0]
    fp0 = fp1 = fp2 = tp0 = tp1 = tp2 = fd0 = fd1 = fd2 = td0 = td1 = td2 = a_sub = v_sub = z2n = 0.0  # pressure, damping's flow part, frame integrals
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
def _wave_panels(x, R, sea, ex, geom, terms, coef, ws, load):
    """Pressure and the water-motion part of damping on the mesh clipped at the wave surface (the
    plane through the surface points above each triangle's vertices), by Dunavant's rule, summed into
    load (2, 6); the wet triangles with the water's velocity at their vertices into ws when drag needs
    them. Returns the wet area and its moments (A, S, rr), exact for the clipped triangles."""
    verts, faces, fnormals = geom[3], geom[4], geom[5]
    rho, g = coef[RHO], coef[G]
    d = coef[C_DAMPING] if terms & DAMPING else 0.0
    pressure_on = (terms & PRESSURE) != 0
    lev = vertex_levers(R, verts)
    nv = verts.shape[0]
    pv = np.empty((nv, 3))
    for v in range(nv):
        for i in range(3):
            pv[v, i] = x[i] + lev[v, i]
    hv = np.empty(nv)
    elevations(sea, ex, pv, nv, hv)
    for v in range(nv):
        hv[v] = pv[v, 2] - hv[v]
    P = np.zeros((3, 3))
    h = np.empty(3)
    nf = faces.shape[0]
    subs = np.empty((2 * nf, 3, 3))
    normals = np.empty((2 * nf, 3))
    m = 0
    for f in range(nf):
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
    out = _water_at(sea, ex, nodes, 6 * m, rho, g, (terms & TWIST_TERMS) != 0)
    A = 0.0
    S = np.zeros(3)
    rr = np.zeros((3, 3))
    ws[5][:] = 0.0
    for k in range(m):
        t = subs[k]
        nx, ny, nz = normals[k, 0], normals[k, 1], normals[k, 2]
        e10, e11, e12 = t[1, 0] - t[0, 0], t[1, 1] - t[0, 1], t[1, 2] - t[0, 2]
        e20, e21, e22 = t[2, 0] - t[0, 0], t[2, 1] - t[0, 1], t[2, 2] - t[0, 2]
        area = 0.5 * ((e11 * e22 - e12 * e21) * nx + (e12 * e20 - e10 * e22) * ny + (e10 * e21 - e11 * e20) * nz)
        A += area
        s0, s1, s2 = t[0, 0] + t[1, 0] + t[2, 0], t[0, 1] + t[1, 1] + t[2, 1], t[0, 2] + t[1, 2] + t[2, 2]
        S[0] += area * s0 / 3.0
        S[1] += area * s1 / 3.0
        S[2] += area * s2 / 3.0
        for i in range(3):
            for j in range(3):
                rr[i, j] += area / 12.0 * (t[0, i] * t[0, j] + t[1, i] * t[1, j] + t[2, i] * t[2, j] + (s0, s1, s2)[i] * (s0, s1, s2)[j])
        for q in range(6):
            o = out[6 * k + q]
            nd = nodes[6 * k + q]
            _diagnostics(ws[5], area * DUNAVANT4_WEIGHTS[q], nd[2], nz)
            _node_load(nd[0] - x[0], nd[1] - x[1], nd[2] - x[2], nx, ny, nz, area * DUNAVANT4_WEIGHTS[q], o[0] if pressure_on else 0.0, d,
                       o[1], o[2], o[3], load)  # fmt: skip
    if terms & DRAG:  # the wet triangles and the water's velocity at their vertices
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
                    tris[k, v, i] = subs[k, v, i]
                    tris[k, v, 3 + i] = flow[3 * k + v, 1 + i]
            tnormals[k] = normals[k]
        ws[3][0] = m
    return A, S, rr


@njit(**JIT)
def wave_pose_loads(kind, x, R, t, geom, mass, terms, coef, sea, flags, acc, ws):
    """pose_loads in waves: every integrand asks the water (kernels/water.py) at the wet nodes. The
    water's motion makes linear damping affine, -D (v - u_water): its part d u_water is kept in
    ws[4] for twist_loads and linearised, so the pose loads stay those of the pose terms."""
    F = np.zeros(3)
    if terms & GRAVITY:
        F[2] = -mass * coef[G]
    T = np.zeros(3)
    D = np.zeros((6, 6))
    if not terms & WET_TERMS:
        return F, T, D, False
    ex = prepare(sea, t, x)
    load = np.zeros((2, 6))
    if kind == 0:
        A, S, rr = _wave_points(x, R, sea, ex, geom, terms, coef, flags, acc, ws, load)
    else:
        A, S, rr = _wave_panels(x, R, sea, ex, geom, terms, coef, ws, load)
    F += load[0, :3]
    T += load[0, 3:]
    wet = (terms & TWIST_TERMS) != 0 and A > 0.0
    if wet and terms & DAMPING:
        D = damping_matrix(coef, A, S, rr)
    ws[4][:] = load[1]
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
def drag(kind, x, R, u, w, geom, coef, flags, need_D, ws):
    """Quadratic drag on the wet surface moving into the water: force, torque and (need_D) its
    Jacobian D = -d(F, T)/d(u, omega). Points: the wet samples (`flags`, set by the pose's loads),
    each with the water's velocity there (ws[0]); cells: those, and the nodes of the cells the
    water line crosses (ws[6]). Panels: the pose's wet triangles (ws[1:4]), each
    clipped again where v_rel . n changes sign (v_rel linear across it, the water's velocity too),
    with Dunavant's degree-4 rule (exact for the cubic torque integrand)."""
    r, nrm, area = geom[0], geom[1], geom[2]
    half_rc = 0.5 * coef[RHO] * coef[C_DRAG]
    F = np.zeros(3)
    T = np.zeros(3)
    D = np.zeros((6, 6))
    if kind != 1:
        flow, nodes = ws[0], ws[6]
        for k in range(r.shape[0]):
            if kind == 2 and nodes[k, 0] > 0.0:  # a cell the water line crosses: its node, still water
                lx, ly, lz = nodes[k, 1], nodes[k, 2], nodes[k, 3]
                nx, ny, nz = world_normal(R, nrm, k)
                vn = (u[0] + w[1] * lz - w[2] * ly) * nx + (u[1] + w[2] * lx - w[0] * lz) * ny + (u[2] + w[0] * ly - w[1] * lx) * nz
                if vn > 0.0:
                    _drag_node(lx, ly, lz, nx, ny, nz, nodes[k, 0], vn, half_rc, F, T, D, need_D)
                continue
            if not flags[k]:
                continue
            a0, a1, a2 = r[k, 0], r[k, 1], r[k, 2]
            lx, ly, lz = R[0, 0] * a0 + R[0, 1] * a1 + R[0, 2] * a2, R[1, 0] * a0 + R[1, 1] * a1 + R[1, 2] * a2, R[2, 0] * a0 + R[2, 1] * a1 + R[2, 2] * a2
            nx, ny, nz = world_normal(R, nrm, k)
            vn = ((u[0] + w[1] * lz - w[2] * ly - flow[k, 0]) * nx + (u[1] + w[2] * lx - w[0] * lz - flow[k, 1]) * ny
                  + (u[2] + w[0] * ly - w[1] * lx - flow[k, 2]) * nz)  # fmt: skip
            if vn > 0.0:
                _drag_node(lx, ly, lz, nx, ny, nz, area[k], vn, half_rc, F, T, D, need_D)
        return F, T, D
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
                    _drag_node(lx, ly, lz, nx, ny, nz, tri_area * DUNAVANT4_WEIGHTS[q], vq, half_rc, F, T, D, need_D)
    return F, T, D


@njit(**JIT)
def nonlinear_loads(kind, x, R, u, w, geom, coef, terms, flags, need_D, ws):
    """Force, torque and (need_D) Jacobian of the nonlinear twist terms the scene uses."""
    F = np.zeros(3)
    T = np.zeros(3)
    D = np.zeros((6, 6))
    if terms & DRAG:
        Fd, Td, Dd = drag(kind, x, R, u, w, geom, coef, flags, need_D, ws)
        F += Fd
        T += Td
        D += Dd
    return F, T, D


@njit(inline="always", **JIT)
def twist_loads(kind, x, R, u, w, geom, coef, terms, D, wet, flags, F, T, ws):
    """Add the force and torque of the twist terms at (u, w) to F, T in place (no allocation in the
    hot loop): d u_water - D (u, w) for linear damping (ws[4], zero in still water), plus the nonlinear ones."""
    if not wet:
        return
    if terms & DAMPING:
        affine = ws[4]
        for i in range(3):
            F[i] += affine[i] - (D[i, 0] * u[0] + D[i, 1] * u[1] + D[i, 2] * u[2] + D[i, 3] * w[0] + D[i, 4] * w[1] + D[i, 5] * w[2])
            T[i] += affine[3 + i] - (D[3 + i, 0] * u[0] + D[3 + i, 1] * u[1] + D[3 + i, 2] * u[2] + D[3 + i, 3] * w[0] + D[3 + i, 4] * w[1]
                                     + D[3 + i, 5] * w[2])  # fmt: skip
    if terms & NONLINEAR:
        Fn, Tn, _ = nonlinear_loads(kind, x, R, u, w, geom, coef, terms, flags, False, ws)
        for i in range(3):
            F[i] += Fn[i]
            T[i] += Tn[i]


@njit(**JIT)
def linearised(kind, x, R, u, w, geom, coef, terms, F, T, D, wet, flags, ws):
    """(f, D) with loads ~ f - D (u, w) near (u, w), as forces.Model.linearised: the pose loads
    (F, T), damping's part from the water's motion, plus each nonlinear term's affine part, and the
    sum of the Jacobians. Linear only: those, D."""
    f = np.empty(6)
    f[:3] = F
    f[3:] = T
    if wet and terms & DAMPING:
        f += ws[4]
    if not (wet and terms & NONLINEAR):
        return f, D
    Fn, Tn, Dn = nonlinear_loads(kind, x, R, u, w, geom, coef, terms, flags, True, ws)
    for i in range(6):
        acc = 0.0
        for j in range(3):
            acc += Dn[i, j] * u[j] + Dn[i, 3 + j] * w[j]
        f[i] += (Fn[i] if i < 3 else Tn[i - 3]) + acc
    return f, D + Dn

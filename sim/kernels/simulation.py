"""Compiled twin of system/frame.py's observe: a frame's diagnostics (in still water, the sampled model in one pass)."""

from __future__ import annotations

import numpy as np

from .forces import linearised, nonlinear_acting, nonlinear_loads, pose_loads, twist_loads
from .jit import JIT, njit
from .layout import RHO, G, Scratch
from .spec import CELLS, CURRENT, DAMPING, GRAVITY, HEAVE_DAMPING, MODEL, POINTS, PRESSURE, USED, WAVES, WET_TERMS
from .surface import cell_node, mesh_integrals, workspace
from .terms import C_DAMPING, C_HEAVE_DAMPING
from .water import elevations, prepare


@njit(**JIT)
def observe(x, R, t, u, w, model, sea, wet):
    """(force, torque, hydrostatic energy, wet area, submerged volume) at a state and time, every
    used term included; marks the wet samples in `wet` (for either model: the viewer colours samples)."""
    if WAVES:
        return observe_waves(x, R, t, u, w, model, sea, wet)
    if CURRENT:  # flat water in a uniform current U: every load depends on the body's velocity relative to it
        u = u - sea[4]
    if MODEL == POINTS:
        return observe_points(x, R, u, w, model, wet)
    if MODEL == CELLS:
        return observe_cells(x, R, u, w, model, wet)
    return observe_panels(x, R, u, w, model, wet)


@njit(**JIT)
def linearised_loads(x, R, t, u, w, model, sea):
    """(f, D): one body's loads near its twist (u, w) as f - D (u, w), at a pose and time, as forces.Model.linearised
    (the kick of several bodies on joints, system/tree.py)."""
    s = Scratch(np.zeros(model.geom[0].shape[0], dtype=np.bool_), np.zeros(34), workspace(model.geom))
    F, T, D, is_wet = pose_loads(x, R, t, model, s, sea)
    return linearised(x, R, u, w, model, F, T, D, is_wet, s)


@njit(**JIT)
def observe_panels(x, R, u, w, model, wet):
    geom, coef = model.geom, model.coef
    r = geom[0]
    F, T = _loads(x, R, u, w, model)
    for k in range(r.shape[0]):
        wet[k] = x[2] + R[2, 0] * r[k, 0] + R[2, 1] * r[k, 1] + R[2, 2] * r[k, 2] < 0.0
    a_sub, v_sub, z2n = mesh_integrals(x, R, geom)
    e_hyd = -0.5 * coef[RHO] * coef[G] * z2n if USED & PRESSURE else 0.0
    return F, T, e_hyd, a_sub, v_sub


@njit(**JIT)
def _loads(x, R, u, w, model):
    """Force and torque of every used term at a state in still water, as the integrators see them."""
    s = Scratch(np.zeros(model.geom[0].shape[0], dtype=np.bool_), np.zeros(34), workspace(model.geom))
    still = (np.zeros((0, 8)), np.inf, True, 0.0, np.zeros(3))
    F, T, D, is_wet = pose_loads(x, R, 0.0, model, s, still)
    twist_loads(x, R, u, w, model, D, is_wet, s, F, T)
    return F, T


@njit(**JIT)
def observe_cells(x, R, u, w, model, wet):
    """observe for the cells model: the loads as the integrators see them, then the frame's
    integrals over its nodes (whole wet cells at their samples, cut cells at their wet centroids)."""
    geom, coef = model.geom, model.coef
    r, nrm, cells = geom[0], geom[1], geom[7]
    F, T = _loads(x, R, u, w, model)
    node, P, h, parts = np.empty(4), np.empty((3, 3)), np.empty(3), np.empty((2, 3, 3))
    z2n = a_sub = v_sub = 0.0
    for k in range(r.shape[0]):
        cell_node(x[2], R, cells[k], node, P, h, parts)
        wet[k] = node[0] > 0.0
        if wet[k]:
            z = x[2] + node[3]
            nz = R[2, 0] * nrm[k, 0] + R[2, 1] * nrm[k, 1] + R[2, 2] * nrm[k, 2]
            a_sub += node[0]
            v_sub += node[0] * z * nz
            z2n += node[0] * z * z * nz
    e_hyd = -0.5 * coef[RHO] * coef[G] * z2n if USED & PRESSURE else 0.0
    return F, T, e_hyd, a_sub, v_sub


@njit(**JIT)
def observe_points(x, R, u, w, model, wet):
    """Total force and torque (every used term at (u, w)), hydrostatic energy, wet area and
    submerged volume of the sampled model; marks the wet samples in `wet`. One scalar loop for the
    terms linear in the pose and twist, then the nonlinear ones."""
    geom, mass, coef = model.geom, model.mass, model.coef
    r, nrm, area = geom[0], geom[1], geom[2]
    R00, R01, R02, R10, R11, R12, R20, R21, R22 = R[0, 0], R[0, 1], R[0, 2], R[1, 0], R[1, 1], R[1, 2], R[2, 0], R[2, 1], R[2, 2]
    F0 = F1 = T0 = T1 = T2 = e_hyd = a_sub = v_sub = 0.0
    F2 = -mass * coef[G] if USED & GRAVITY else 0.0
    rg = coef[RHO] * coef[G] if USED & WET_TERMS else 0.0
    d = coef[C_DAMPING] if USED & DAMPING else 0.0
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
            vx, vy, vz = u[0] + w[1] * lz - w[2] * ly, u[1] + w[2] * lx - w[0] * lz, u[2] + w[0] * ly - w[1] * lx
            da = d * a
            fx = p * nx - da * vx
            fy = p * ny - da * vy
            fz = p * nz - da * vz
            F0 += fx
            F1 += fy
            F2 += fz
            T0 += ly * fz - lz * fy
            T1 += lz * fx - lx * fz
            T2 += lx * fy - ly * fx
            e_hyd += -0.5 * rg * z * z * a * nz
            a_sub += a
            v_sub += z * a * nz
    if not USED & PRESSURE:
        e_hyd = 0.0
    if USED & HEAVE_DAMPING and a_sub > 0.0:  # (forces.heave_damping, while wet)
        F2 -= coef[C_HEAVE_DAMPING] * u[2]
    F, T = np.array([F0, F1, F2]), np.array([T0, T1, T2])
    if nonlinear_acting(model):  # their own pass over the wet samples just marked
        Fn, Tn, _ = nonlinear_loads(x, R, u, w, model, Scratch(wet, np.zeros(34), workspace(model.geom)), False)  # still water: no flow
        F += Fn
        T += Tn
    return F, T, e_hyd, a_sub, v_sub


@njit(**JIT)
def observe_waves(x, R, t, u, w, model, sea, wet):
    """observe in waves: the loads as the integrators see them, the integrals over the model's wet
    nodes, and the samples under the wave surface."""
    geom, coef = model.geom, model.coef
    r = geom[0]
    s = Scratch(np.zeros(r.shape[0], dtype=np.bool_), np.zeros(34), workspace(geom))
    ws = s.ws
    F, T, D, is_wet = pose_loads(x, R, t, model, s, sea)  # leaves the nodes' integrals in ws[5]
    twist_loads(x, R, u, w, model, D, is_wet, s, F, T)
    a_sub, v_sub, z2n = ws[5][0], ws[5][1], ws[5][2]
    pts = np.empty((r.shape[0], 3))
    for k in range(r.shape[0]):
        for i in range(3):
            pts[k, i] = x[i] + R[i, 0] * r[k, 0] + R[i, 1] * r[k, 1] + R[i, 2] * r[k, 2]
    eta = np.empty(r.shape[0])
    elevations(sea, prepare(sea, t, x), pts, r.shape[0], eta)
    for k in range(r.shape[0]):
        wet[k] = pts[k, 2] - eta[k] < 0.0
    e_hyd = -0.5 * coef[RHO] * coef[G] * z2n if USED & PRESSURE else 0.0
    return F, T, e_hyd, a_sub, v_sub

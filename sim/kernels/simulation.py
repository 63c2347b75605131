"""Compiled twin of simulation.observe for the sampled model: a frame's diagnostics in one pass."""

from __future__ import annotations

import numpy as np

from . import JIT, njit
from .forces import C_DAMPING, DAMPING, NONLINEAR, PRESSURE, WET_TERMS, nonlinear_loads
from .layout import RHO, G


@njit(**JIT)
def observe(x, R, u, w, geom, mass, terms, coef, wet):
    """Total force and torque (every used term at (u, w)), hydrostatic energy, wet area and
    submerged volume of the sampled model; marks the wet samples in `wet`. One scalar loop for the
    terms linear in the pose and twist, then the nonlinear ones."""
    r, nrm, area = geom[0], geom[1], geom[2]
    R00, R01, R02, R10, R11, R12, R20, R21, R22 = R[0, 0], R[0, 1], R[0, 2], R[1, 0], R[1, 1], R[1, 2], R[2, 0], R[2, 1], R[2, 2]
    F0 = F1 = T0 = T1 = T2 = e_hyd = a_sub = v_sub = 0.0
    F2 = -mass * coef[G]
    rg = coef[RHO] * coef[G] if terms & WET_TERMS else 0.0
    d = coef[C_DAMPING] if terms & DAMPING else 0.0
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
    if not terms & PRESSURE:
        e_hyd = 0.0
    F, T = np.array([F0, F1, F2]), np.array([T0, T1, T2])
    if terms & NONLINEAR:  # their own pass over the wet samples just marked
        Fn, Tn, _ = nonlinear_loads(0, x, R, u, w, geom, coef, terms, wet, False)
        F += Fn
        T += Tn
    return F, T, e_hyd, a_sub, v_sub

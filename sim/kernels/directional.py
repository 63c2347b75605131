"""The sea's series about a centre for a short-crested sea (components from many directions), deep water.

Component j near the centre is W_j e^(k_j zeta_j), zeta_j = Z + i (cos theta_j X + sin theta_j Y) in the scaled offsets
(Z the stretched depth below the centre's, X + iY the horizontal offset, all times k_s, the largest wavenumber).
With xi = X + iY, i (cos theta X + sin theta Y) = (i/2)(e^(-i theta) xi + e^(i theta) conj(xi)), so truncated at
degree P the sum over components is

    Phi = sum_(p + a + b <= P) Z^p / p! (i xi / 2)^a / a! (i conj(xi) / 2)^b / b! N[p + a + b, a - b],
    N[n, m] = sum_j W_j q_j^n e^(-i m theta_j),  q_j = k_j / k_s,

exact algebra of the same truncated power series as the long-crested one (kernels/water.py), so the same bound on
the truncation error holds (|k_j zeta_j| <= k_j rho). The moments are one matrix product a pose; each point then
costs about P^3 / 6 complex multiply-adds, against a sine, a cosine and an exponential per component: the series
wins for many components (4096 components, P = 12: 455 terms). The velocity's horizontal parts take the moments of
W cos theta and W sin theta, which are those of W at m -+ 1.
"""

from __future__ import annotations

import math

import numpy as np

from .jit import JIT, njit
from .layout import COS, OMEGA, SIN, K

BLOCK = 128
"""Points a pass takes at a time."""


@njit(**JIT)
def directional_moments(comps, E, z0, P, k_scale, need_flow):
    """(Me, Mp, Mv) flattened (row n, column m + P): the elevation's (W = E), the pressure's (W = E e^(k z0)) and
    the flow's (W = E omega e^(k z0): its vertical part, then the horizontal x and y parts), each (P + 1)(2 P + 1)."""
    n = comps.shape[0]
    Wd = 2 * P + 1
    table = np.empty((P + 1, n))
    for j in range(n):
        term, q = 1.0, comps[j, K] / k_scale
        for p in range(P + 1):
            table[p, j] = term
            term *= q
    cols = 2 * (2 * Wd + (2 * P + 3 if need_flow else 0))
    F = np.empty((n, cols))
    for j in range(n):
        rot = complex(comps[j, COS], -comps[j, SIN])  # e^(-i theta)
        e = E[j]
        d = e * math.exp(comps[j, K] * z0)
        v = d * comps[j, OMEGA]
        phase = 1.0 + 0j  # e^(-i m theta) from m = -(P + 1) upward
        for _ in range(P + 1):
            phase *= rot.conjugate()
        for i in range(2 * P + 3):
            m = i - (P + 1)
            if -P <= m <= P:
                c = m + P
                a, b = e * phase, d * phase
                F[j, 2 * c], F[j, 2 * c + 1] = a.real, a.imag
                F[j, 2 * Wd + 2 * c], F[j, 2 * Wd + 2 * c + 1] = b.real, b.imag
            if need_flow:
                w = v * phase
                F[j, 4 * Wd + 2 * i], F[j, 4 * Wd + 2 * i + 1] = w.real, w.imag
            phase *= rot
    M = np.dot(table, F)
    Me = np.empty((P + 1) * Wd, dtype=np.complex128)
    Mp = np.empty((P + 1) * Wd, dtype=np.complex128)
    Mv = np.zeros(3 * (P + 1) * Wd, dtype=np.complex128)
    size = (P + 1) * Wd
    for p in range(P + 1):
        for c in range(Wd):
            Me[p * Wd + c] = complex(M[p, 2 * c], M[p, 2 * c + 1])
            Mp[p * Wd + c] = complex(M[p, 2 * Wd + 2 * c], M[p, 2 * Wd + 2 * c + 1])
            if need_flow:  # the flow's columns start at m = -(P + 1): m - 1, m, m + 1 are its c, c + 1, c + 2
                f = 4 * Wd + 2 * c
                lo, mid, hi = complex(M[p, f], M[p, f + 1]), complex(M[p, f + 2], M[p, f + 3]), complex(M[p, f + 4], M[p, f + 5])
                Mv[p * Wd + c] = mid
                Mv[size + p * Wd + c] = 0.5 * (lo + hi)
                Mv[2 * size + p * Wd + c] = (lo - hi) / 2j
    return Me, Mp, Mv


@njit(**JIT)
def _series_block(N, P, off, Z, Xr, Xi, zero_z, out_r, out_i):
    """out = Phi at a block of points from the moments N[off:] (P, flattened), Z = 0 where zero_z."""
    L = Xr.shape[0]
    Wd = 2 * P + 1
    Gr, Gi = np.empty((P + 1, L)), np.empty((P + 1, L))  # (i xi / 2)^a / a!
    Hr, Hi = np.empty((P + 1, L)), np.empty((P + 1, L))  # (i conj(xi) / 2)^b / b!
    for i in range(L):
        Gr[0, i], Gi[0, i], Hr[0, i], Hi[0, i] = 1.0, 0.0, 1.0, 0.0
    for a in range(1, P + 1):
        f = 0.5 / a
        for i in range(L):  # i xi / 2 = (-Y + i X) / 2, i conj(xi) / 2 = (Y + i X) / 2
            Gr[a, i] = f * (-Xi[i] * Gr[a - 1, i] - Xr[i] * Gi[a - 1, i])
            Gi[a, i] = f * (-Xi[i] * Gi[a - 1, i] + Xr[i] * Gr[a - 1, i])
            Hr[a, i] = f * (Xi[i] * Hr[a - 1, i] - Xr[i] * Hi[a - 1, i])
            Hi[a, i] = f * (Xi[i] * Hi[a - 1, i] + Xr[i] * Hr[a - 1, i])
    Sr, Si = np.empty(L), np.empty(L)
    for i in range(L):
        out_r[i], out_i[i] = 0.0, 0.0
    for a in range(P + 1):
        for b in range(P + 1 - a):
            col = a - b + P
            top = 0 if zero_z else P - a - b
            c = N[off + (top + a + b) * Wd + col]
            for i in range(L):
                Sr[i], Si[i] = c.real, c.imag
            for p in range(top - 1, -1, -1):  # sum_p Z^p / p! N[p + a + b, a - b], by Horner's rule
                c = N[off + (p + a + b) * Wd + col]
                f = 1.0 / (p + 1)
                for i in range(L):
                    t = Z[i] * f
                    Sr[i] = c.real + Sr[i] * t
                    Si[i] = c.imag + Si[i] * t
            for i in range(L):
                gr = Gr[a, i] * Hr[b, i] - Gi[a, i] * Hi[b, i]
                gi = Gr[a, i] * Hi[b, i] + Gi[a, i] * Hr[b, i]
                out_r[i] += gr * Sr[i] - gi * Si[i]
                out_i[i] += gr * Si[i] + gi * Sr[i]


@njit(**JIT)
def _series(N, P, off, Z, Xr, Xi, m, zero_z, out_r, out_i):
    for start in range(0, m, BLOCK):
        end = min(m, start + BLOCK)
        _series_block(N, P, off, Z[start:end], Xr[start:end], Xi[start:end], zero_z, out_r[start:end], out_i[start:end])


@njit(**JIT)
def _offsets_of(ex, points, m):
    k_scale = ex[5]
    Xr, Xi = np.empty(m), np.empty(m)
    for i in range(m):
        Xr[i] = k_scale * (points[i, 0] - ex[2])
        Xi[i] = k_scale * (points[i, 1] - ex[3])
    return Xr, Xi


@njit(**JIT)
def directional_elevations(sea, ex, points, m, out):
    """out[i] = eta at points[i], i < m (the series with Z = 0)."""
    Xr, Xi = _offsets_of(ex, points, m)
    im = np.empty(m)
    _series(ex[6], ex[0], 0, np.zeros(m), Xr, Xi, m, True, out, im)


@njit(**JIT)
def directional_fields(sea, ex, points, eta, m, rho, g, need_flow, out, known):
    """fields (kernels/water.py) from the short-crested series: the elevation (unless known), the stretched depth, the
    pressure's series and, with need_flow, the flow's three."""
    U = sea[4]
    P, z0, k_scale, Mp, Mv = ex[0], ex[4], ex[5], ex[7], ex[8]
    Xr, Xi = _offsets_of(ex, points, m)
    re, im = np.empty(m), np.empty(m)
    if not known:
        _series(ex[6], P, 0, np.zeros(m), Xr, Xi, m, True, eta, im)
    Z = np.empty(m)
    for i in range(m):
        Z[i] = k_scale * (min(points[i, 2] - eta[i], 0.0) - z0)
    _series(Mp, P, 0, Z, Xr, Xi, m, False, re, im)
    for i in range(m):
        out[i, 0] = rho * g * (re[i] - points[i, 2])
        out[i, 1], out[i, 2], out[i, 3] = U[0], U[1], 0.0
    if need_flow:
        size = (P + 1) * (2 * P + 1)
        _series(Mv, P, 0, Z, Xr, Xi, m, False, re, im)
        for i in range(m):
            out[i, 3] = im[i]
        _series(Mv, P, size, Z, Xr, Xi, m, False, re, im)
        for i in range(m):
            out[i, 1] += re[i]
        _series(Mv, P, 2 * size, Z, Xr, Xi, m, False, re, im)
        for i in range(m):
            out[i, 2] += re[i]

"""Compiled twin of water.Waves: the surface elevation, pressure and flow at points, for the kernels.

The sea is `layout.sea_pack`'s tuple (components, depth, long_crested, radius, current, ramp). At each pose the
kernels call `prepare` once, then ask `elevations` and `fields` at batches of nodes (every component's amplitude
times the ramp's factor at that time, water.ramp_factor). Two ways to answer:

- the direct sum over components, the same arithmetic as the reference (a sine, a cosine and an
  exponential per node and component);
- a local expansion about the body, used for long-crested deep-water seas of many components. Each
  component at a point near the centre c is E_j e^(k_j w), E_j its complex amplitude at c (and at
  the reference depth z0), w = (z* - z0) + i s, s the distance along the waves from c. So the sum
  over components is one power series in w, sum_n M_n w^n with M_n = sum_j E_j k_j^n / n!: its
  moments cost a few multiplications per component, and each node a Horner evaluation, with no
  transcendental function. Truncating at degree P errs by at most |k w|^(P+1) / (P+1)! e^(k |w|) per
  unit amplitude; P is chosen at each pose from the body's radius so that bound is below TOL, and the
  direct sum takes over if no P <= PMAX does (a body large against the shortest wave).
"""

from __future__ import annotations

import math

import numpy as np

from .jit import JIT, njit

A, OMEGA, KX, KY, K, PHASE, COS, SIN = range(8)
"""Columns of the components array."""
TOL = 1e-13
"""Bound on the expansion's truncation error, relative to the sum of the amplitudes."""
PMAX = 40


@njit(**JIT)
def _degree(rho):
    """The smallest degree P whose truncation bound rho^(P+1) / (P+1)! e^rho is below TOL (-1: none up to PMAX)."""
    term = math.exp(rho)
    for p in range(PMAX + 1):
        term *= rho / (p + 1)
        if term <= TOL:
            return p
    return -1


@njit(**JIT)
def _moments(comps, weight, P, k_scale):
    """M_n = sum_j weight_j k_j^n / n!, n = 0..P (scaled by k_scale^n, so every moment is O(1))."""
    M = np.zeros(P + 1, dtype=np.complex128)
    for j in range(comps.shape[0]):
        term = weight[j]
        q = comps[j, K] / k_scale
        for n in range(P + 1):
            M[n] += term
            term *= q / (n + 1)
    return M


@njit(**JIT)
def ramp_factor(t, ramp):
    """water.ramp_factor: (1 - cos(pi t / ramp)) / 2 for 0 <= t < ramp, 0 before, 1 after (ramp 0: 1)."""
    if ramp <= 0.0 or t >= ramp:
        return 1.0
    return 0.0 if t <= 0.0 else 0.5 - 0.5 * math.cos(math.pi * t / ramp)


@njit(**JIT)
def prepare(sea, t, x):
    """What `elevations` and `fields` need at time t for a body centred at x: each component's phase
    offset phi_j - (omega_j + k_j . U) t (U the current, which carries the waves), the ramp's factor, and (when the
    expansion serves) its centre, scale and moments."""
    comps, depth, long_crested, radius, current, ramp = sea
    n = comps.shape[0]
    offset = np.empty(n)
    for j in range(n):
        offset[j] = comps[j, PHASE] - (comps[j, OMEGA] + comps[j, KX] * current[0] + comps[j, KY] * current[1]) * t
    r = ramp_factor(t, ramp)
    empty = np.zeros(0, dtype=np.complex128)
    none = (-1, offset, 0.0, 0.0, 0.0, 1.0, empty, empty, empty, r)
    if not long_crested or n < 4 or not math.isinf(depth):
        return none
    E = np.empty(n, dtype=np.complex128)
    eta_c = slope = k_max = 0.0
    for j in range(n):
        a = r * comps[j, A]
        psi = comps[j, KX] * x[0] + comps[j, KY] * x[1] + offset[j]
        E[j] = a * complex(math.cos(psi), math.sin(psi))
        eta_c += E[j].real
        slope += a * comps[j, K]
        k_max = max(k_max, comps[j, K])
    # where the stretched depths z* = z - eta of the body's nodes can lie: z within radius of x[2],
    # eta within slope * radius of eta_c; clamped to the surface like the pressure's
    z_lo = x[2] - radius - eta_c - slope * radius
    z_hi = min(0.0, x[2] + radius - eta_c + slope * radius)
    z_lo = min(z_lo, z_hi)
    z0, dz = 0.5 * (z_lo + z_hi), 0.5 * (z_hi - z_lo)
    P = _degree(k_max * math.sqrt(radius * radius + dz * dz))
    if P < 0:
        return none
    Me = _moments(comps, E, P, k_max)
    for j in range(n):
        E[j] *= math.exp(comps[j, K] * z0)
    Mp = _moments(comps, E, P, k_max)
    for j in range(n):
        E[j] *= comps[j, OMEGA]
    Mv = _moments(comps, E, P, k_max)
    return (P, offset, x[0], x[1], z0, k_max, Me, Mp, Mv, r)


@njit(inline="always", **JIT)
def _horner(M, w):
    acc = M[M.shape[0] - 1]
    for n in range(M.shape[0] - 2, -1, -1):
        acc = acc * w + M[n]
    return acc


@njit(**JIT)
def elevations(sea, ex, points, m, out):
    """out[i] = eta at the horizontal position of points[i], i < m."""
    comps = sea[0]
    P, offset, cx, cy, k_scale, Me, r = ex[0], ex[1], ex[2], ex[3], ex[5], ex[6], ex[9]
    c, s = comps[0, COS], comps[0, SIN]
    for i in range(m):
        X, Y = points[i, 0], points[i, 1]
        if P >= 0:
            out[i] = _horner(Me, complex(0.0, k_scale * (c * (X - cx) + s * (Y - cy)))).real
            continue
        eta = 0.0
        for j in range(comps.shape[0]):
            eta += comps[j, A] * math.cos(comps[j, KX] * X + comps[j, KY] * Y + offset[j])
        out[i] = r * eta


@njit(**JIT)
def fields(sea, ex, points, eta, m, rho, g, need_flow, out, known):
    """out[i] = (pressure, flow x, y, z) at points[i], i < m: water.Waves.field, with Wheeler's
    stretching, the current added to the flow. known: eta[i] holds the elevation there; else it is computed
    here and stored (on the direct sum sharing each component's cosine between elevation and pressure)."""
    comps, depth, U = sea[0], sea[1], sea[4]
    P, offset, cx, cy, z0, k_scale, Me, Mp, Mv, r = ex[0], ex[1], ex[2], ex[3], ex[4], ex[5], ex[6], ex[7], ex[8], ex[9]
    deep = math.isinf(depth)
    cb, sb = comps[0, COS], comps[0, SIN]
    n = comps.shape[0]
    cosines = np.empty(n if P < 0 else 0)
    for i in range(m):
        X, Y, Z = points[i, 0], points[i, 1], points[i, 2]
        s = cb * (X - cx) + sb * (Y - cy)
        if not known:
            if P >= 0:
                eta[i] = _horner(Me, complex(0.0, k_scale * s)).real
            else:
                e = 0.0
                for j in range(n):
                    cosines[j] = math.cos(comps[j, KX] * X + comps[j, KY] * Y + offset[j])
                    e += comps[j, A] * cosines[j]
                eta[i] = r * e
        zs = Z - eta[i] if deep else (Z - eta[i]) * depth / (depth + eta[i])
        zc = min(zs, 0.0)
        p = ux = uy = uz = 0.0
        if P >= 0:
            w = complex(k_scale * (zc - z0), k_scale * s)
            p = _horner(Mp, w).real
            if need_flow:
                v = _horner(Mv, w)
                ux, uy, uz = v.real * cb, v.real * sb, v.imag
        else:
            for j in range(n):
                a, k = comps[j, A], comps[j, K]
                psi = comps[j, KX] * X + comps[j, KY] * Y + offset[j]
                c = math.cos(psi) if known else cosines[j]
                e = math.exp(k * zc)
                if deep:
                    dp = dh = dv = e
                else:
                    far = math.exp(-k * (2 * depth) - k * zc)
                    h2 = math.exp(-2 * k * depth)
                    dp, dh, dv = (e + far) / (1 + h2), (e + far) / (1 - h2), (e - far) / (1 - h2)
                p += a * dp * c
                if need_flow:
                    aw = a * comps[j, OMEGA]
                    ux += dh * c * aw * comps[j, COS]
                    uy += dh * c * aw * comps[j, SIN]
                    uz += dv * math.sin(psi) * aw
            p, ux, uy, uz = r * p, r * ux, r * uy, r * uz  # (the expansion's moments carry the ramp already)
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = rho * g * (p - Z), ux + U[0], uy + U[1], uz

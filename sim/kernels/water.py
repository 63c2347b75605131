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

from .directional import directional_elevations, directional_fields, directional_moments
from .jit import JIT, njit
from .layout import COS, KX, KY, OMEGA, PHASE, SIN, A, K  # noqa: F401  (the components' columns)

TOL = 1e-13
"""Bound on the expansion's truncation error, relative to the sum of the amplitudes."""
PMAX = 40
KR = 4.0
KR_SPREAD = 2.0
"""The same in a short-crested sea, whose series costs about P^3 / 6 terms a point."""
"""Where `clusters` cuts a body's tree in an expandable sea: at parts no wider than KR / k_max (k_max the largest
wavenumber), so that each part's series needs a modest degree."""


@njit(**JIT)
def ramp_factor(t, ramp):
    """water.ramp_factor: (1 - cos(pi t / ramp)) / 2 for 0 <= t < ramp, 0 before, 1 after (ramp 0: 1)."""
    if ramp <= 0.0 or t >= ramp:
        return 1.0
    return 0.0 if t <= 0.0 else 0.5 - 0.5 * math.cos(math.pi * t / ramp)


@njit(**JIT)
def expandable(sea):
    """Whether the sea's field may be summed as a power series about a centre (deep water, the series allowed)."""
    return sea[2] and sea[0].shape[0] >= 1 and math.isinf(sea[1])


@njit(**JIT)
def long_crested(comps):
    """Whether every component runs the same way (then the series is in one complex variable)."""
    for j in range(1, comps.shape[0]):
        if comps[j, COS] != comps[0, COS] or comps[j, SIN] != comps[0, SIN]:
            return False
    return True


@njit(**JIT)
def _pays(P, n):
    """Whether a short-crested series of degree P (about P^3 / 6 terms a point) costs less than the direct sum over n
    components."""
    return (P + 1) * (P + 2) * (P + 3) <= 12 * n


@njit(**JIT)
def _offsets(sea, t):
    """Each component's phase offset phi_j - (omega_j + k_j . U) t at time t (U the current, which carries the waves)."""
    comps, current = sea[0], sea[4]
    offset = np.empty(comps.shape[0])
    for j in range(comps.shape[0]):
        offset[j] = comps[j, PHASE] - (comps[j, OMEGA] + comps[j, KX] * current[0] + comps[j, KY] * current[1]) * t
    return offset


BLOCK = 256
"""Points a series pass takes at a time (their arrays stay in the first-level cache)."""
BANDS = 8
"""Wavenumber bands of the degree's bound: band b holds the components with k_max 2^-(b+1) < k <= k_max 2^-b (the
last, all below), each bounded by its top wavenumber."""


@njit(**JIT)
def _bands(comps, k_max):
    """Each component's band (BANDS) and each band's top wavenumber."""
    band = np.empty(comps.shape[0], dtype=np.int64)
    for j in range(comps.shape[0]):
        k = comps[j, K]
        band[j] = BANDS - 1 if k <= 0.0 else min(BANDS - 1, int(math.floor(math.log2(k_max / k))))
    top = np.empty(BANDS)
    for b in range(BANDS):
        top[b] = k_max * 2.0**-b
    return band, top


@njit(**JIT)
def _banded_degree(weight, top, rho, limit):
    """The smallest degree P whose truncation bound sum_b W_b (k_b rho)^(P+1) / (P+1)! e^(k_b rho) is below limit
    (-1: none up to PMAX), W_b the band's summed weights and k_b its top wavenumber: each band its own bound, so a deep
    centre, where the short waves have faded, needs a low degree."""
    term = np.empty(BANDS)
    for b in range(BANDS):
        term[b] = weight[b] * math.exp(top[b] * rho)
    for p in range(PMAX + 1):
        total = 0.0
        for b in range(BANDS):
            term[b] *= top[b] * rho / (p + 1)
            total += term[b]
        if total <= limit:
            return p
    return -1


@njit(**JIT)
def _cut(x, R, spans, spheres, reach, size):
    """The parts of a body's tree (bodies/clusters.py) at a pose, the elevation everywhere within +-reach: (node, status, world
    centre) of each. A part lies wholly above every crest (dropped), or is cut from the tree where it is a leaf or,
    with size > 0, no wider than size; with size 0, where it lies wholly below every trough (status 2: no clipping to
    do, no vertex elevations) rather than across the water line (1)."""
    m = spans.shape[0]
    stack = np.empty(m, dtype=np.int64)
    node = np.empty(m, dtype=np.int64)
    status = np.empty(m, dtype=np.int64)
    centre = np.empty((m, 3))
    top, parts = 1, 0
    stack[0] = 0
    while top > 0:
        top -= 1
        nd = stack[top]
        c0, c1, c2 = spheres[nd, 0], spheres[nd, 1], spheres[nd, 2]
        cz = x[2] + R[2, 0] * c0 + R[2, 1] * c1 + R[2, 2] * c2
        rho = spheres[nd, 3]
        if cz - rho > reach:
            continue
        wet = cz + rho < -reach
        if spans[nd, 2] >= 0 and (rho > size if size > 0.0 else not wet):
            stack[top], stack[top + 1] = spans[nd, 3], spans[nd, 2]  # the left child next: the tree's order kept
            top += 2
            continue
        node[parts], status[parts] = nd, 2 if wet else 1
        for i in range(3):
            centre[parts, i] = x[i] + R[i, 0] * c0 + R[i, 1] * c1 + R[i, 2] * c2
        parts += 1
    return node[:parts], status[:parts], centre[:parts]


@njit(inline="always", **JIT)
def _scales(comps, r):
    """(sum a, sum a omega, the slope bound r sum a k, k_max) of a sea's components: the bounds' scales."""
    amp = amp_w = slope = k_max = 0.0
    for j in range(comps.shape[0]):
        amp += comps[j, A]
        amp_w += comps[j, A] * comps[j, OMEGA]
        slope += r * comps[j, A] * comps[j, K]
        k_max = max(k_max, comps[j, K])
    return amp, amp_w, slope, k_max


@njit(**JIT)
def clusters(sea, t, x, R, spans, spheres, need_flow):
    """The body's tree of triangles (bodies/clusters.py) cut at this pose (_cut), and a local expansion about each part.

    In an expandable sea the parts are no wider than KR / k_max, and each gets the sharper bounds of its own
    elevation and the sea's slope: dry (dropped), wet (status 2) or crossing (1), and its series' degrees from the
    weighted bound. Returns (node, status, P, Pe (elevation degree), centre x, y, z0, Me, Mp, Mv (parts, P+1) complex,
    offset, ramp factor, k_max); P = -1 where a part takes the direct sum (every part, in other seas)."""
    comps = sea[0]
    offset = _offsets(sea, t)
    r = ramp_factor(t, sea[5])
    expand = expandable(sea)
    amp, amp_w, slope, k_max = _scales(comps, r)
    spread = not long_crested(comps)
    node, status, centre = _cut(x, R, spans, spheres, r * amp, (KR_SPREAD if spread else KR) / k_max if expand else 0.0)
    return _with_series(comps, offset, r, amp, amp_w, slope, k_max, spheres, need_flow, node, status, centre, expand, spread, True)


@njit(**JIT)
def _with_series(comps, offset, r, amp, amp_w, slope, k_max, spheres, need_flow, node, status, centre, expand, spread, drop):
    """The parts' tuple of `clusters` (their series where expand, parts above the water dropped where drop)."""
    n, parts = comps.shape[0], node.shape[0]
    P = np.full(parts, -1, dtype=np.int64)
    Pe = np.full(parts, -1, dtype=np.int64)
    z0 = np.zeros(parts)
    E = np.empty((n, parts), dtype=np.complex128)
    kept = parts
    if expand:
        kept = _expansions(comps, offset, r, amp, amp_w, slope, k_max, spheres, need_flow, node, status, centre, P, Pe, z0, E, spread, drop)
    Me, Mp, Mv = _cluster_moments(comps, E[:, :kept], z0[:kept], P[:kept], Pe[:kept], k_max, need_flow, spread)
    return (node[:kept], status[:kept], P[:kept], Pe[:kept], centre[:kept, 0].copy(), centre[:kept, 1].copy(), z0[:kept], Me, Mp, Mv,
            offset, r, k_max, spread)  # fmt: skip


@njit(**JIT)
def _expansions(comps, offset, r, amp, amp_w, slope, k_max, spheres, need_flow, node, status, centre, P, Pe, z0, E, spread, drop):
    """Each part's components at its centre (E), sharper status, series centre depth z0 and degrees P (pressure, flow)
    and Pe (elevation; P in a short-crested sea), the parts above the water dropped (where drop): compacted in place;
    returns how many are kept. A short-crested series that would cost more than the direct sum is not taken (P = -1)."""
    n = comps.shape[0]
    curvature = 0.0  # |d2 eta / dh2| <= sum r a k^2 along any horizontal line
    for j in range(n):
        curvature += r * comps[j, A] * comps[j, K] * comps[j, K]
    band, tops = _bands(comps, k_max)
    weight = np.zeros((3, BANDS))  # per band: amplitude; at the centre's depth; times omega
    for j in range(n):
        weight[0, band[j]] += r * comps[j, A]
    kept = 0  # kept <= c
    for c in range(node.shape[0]):
        rho = spheres[node[c], 3]
        eta_c = gx = gy = 0.0
        for j in range(n):
            psi = comps[j, KX] * centre[c, 0] + comps[j, KY] * centre[c, 1] + offset[j]
            E[j, kept] = r * comps[j, A] * complex(math.cos(psi), math.sin(psi))
            eta_c += E[j, kept].real
            gx -= comps[j, KX] * E[j, kept].imag
            gy -= comps[j, KY] * E[j, kept].imag
        cz = centre[c, 2]
        # Over the part, |eta - eta_c| <= sigma |dh|: sigma the slope at the centre plus the curvature's bound times
        # half the radius (Taylor), or the sea's slope bound, whichever is smaller. A point (h, z) within rho of the
        # centre has its stretched depth z* = z - eta within |dz| + sigma |dh| of the centre's, so (dh, dz*) lies within
        # rho sqrt(lambda), lambda the largest eigenvalue of [[1 + sigma^2, sigma], [sigma, 1]]; clamping z* to the
        # surface (as the pressure does) only brings it nearer a centre at or below it.
        sigma = min(slope, math.hypot(gx, gy) + 0.5 * curvature * rho)
        stretch = math.sqrt(1.0 + 0.5 * sigma * sigma + sigma * math.sqrt(1.0 + 0.25 * sigma * sigma))
        if drop and cz - rho > eta_c + sigma * rho:  # above the water over its whole extent
            continue
        node[kept], status[kept] = node[c], 2 if cz + rho < eta_c - sigma * rho else status[c]
        centre[kept] = centre[c]
        # the smaller of two bounds on |w - w0|: the stretch's, or the box of z* clamped to the surface
        z0[kept], rho_w = min(cz - eta_c, 0.0), rho * stretch
        z_hi = min(0.0, cz + rho - eta_c + sigma * rho)
        z_lo = min(cz - rho - eta_c - sigma * rho, z_hi)
        if math.hypot(rho, 0.5 * (z_hi - z_lo)) < rho_w:
            z0[kept], rho_w = 0.5 * (z_lo + z_hi), math.hypot(rho, 0.5 * (z_hi - z_lo))
        weight[1:] = 0.0
        for j in range(n):
            a = r * comps[j, A] * math.exp(comps[j, K] * z0[kept])
            weight[1, band[j]] += a
            weight[2, band[j]] += a * comps[j, OMEGA]
        Pe[kept] = _banded_degree(weight[0], tops, rho, TOL * amp)
        P[kept] = _banded_degree(weight[1], tops, rho_w, TOL * amp)
        if need_flow and P[kept] >= 0:
            P[kept] = max(P[kept], _banded_degree(weight[2], tops, rho_w, TOL * amp_w))
        if spread:
            Pe[kept] = P[kept]
        if Pe[kept] < 0 or P[kept] < 0 or (spread and not _pays(P[kept], n)):
            P[kept] = Pe[kept] = -1
        kept += 1
    return kept


@njit(**JIT)
def _cluster_moments(comps, E, z0, P, Pe, k_scale, need_flow, spread):
    """Every part's moments at once: M[c, p] = sum_j E_jc w_jc (k_j / k_scale)^p / p!, the weights w 1 (elevation),
    e^(k_j z0_c) (pressure), omega_j e^(k_j z0_c) (flow): one matrix product with the table of (k_j / k_scale)^p / p!.
    Short-crested: each part's (kernels/directional.py), flattened."""
    n, parts = E.shape
    top = 0  # (a table of one row when every part takes the direct sum)
    for c in range(parts):
        top = max(top, P[c], Pe[c])
    if spread:
        size = (top + 1) * (2 * top + 1)
        out = np.zeros((parts, 5 * size), dtype=np.complex128)
        for c in range(parts):
            if P[c] >= 0:
                Me, Mp, Mv = directional_moments(comps, E[:, c].copy(), z0[c], P[c], k_scale, need_flow)
                out[c, : Me.shape[0]] = Me
                out[c, size : size + Mp.shape[0]] = Mp
                out[c, 2 * size : 2 * size + Mv.shape[0]] = Mv
        return out[:, :size], out[:, size : 2 * size], out[:, 2 * size :]
    table = np.empty((top + 1, n))
    for j in range(n):
        term, q = 1.0, comps[j, K] / k_scale
        for p in range(top + 1):
            table[p, j] = term
            term *= q / (p + 1)
    series = 3 if need_flow else 2
    F = np.zeros((n, 2 * series * parts))
    for c in range(parts):
        if P[c] < 0:
            continue
        for j in range(n):
            e = E[j, c]
            d = e * math.exp(comps[j, K] * z0[c])
            col = 2 * series * c
            F[j, col], F[j, col + 1], F[j, col + 2], F[j, col + 3] = e.real, e.imag, d.real, d.imag
            if need_flow:
                F[j, col + 4], F[j, col + 5] = comps[j, OMEGA] * d.real, comps[j, OMEGA] * d.imag
    out = np.zeros((parts, 3 * (top + 1)), dtype=np.complex128)
    if parts == 0:
        return out[:, : top + 1], out[:, top + 1 : 2 * (top + 1)], out[:, 2 * (top + 1) :]
    M = np.dot(table, F)
    for c in range(parts):
        for s in range(series):
            for p in range(top + 1):
                out[c, s * (top + 1) + p] = complex(M[p, 2 * series * c + 2 * s], M[p, 2 * series * c + 2 * s + 1])
    return out[:, : top + 1], out[:, top + 1 : 2 * (top + 1)], out[:, 2 * (top + 1) :]


@njit(**JIT)
def cluster_ex(cut, c):
    """The expansion of part c of `clusters` as `prepare` gives one (for elevations and fields)."""
    P, Pe, spread = cut[2][c], cut[3][c], cut[13]
    ne, n = (Pe + 1, P + 1) if not spread else ((P + 1) * (2 * P + 1), (P + 1) * (2 * P + 1))
    return (P, cut[10], cut[4][c], cut[5][c], cut[6][c], cut[12], cut[7][c, :ne].copy(), cut[8][c, :n].copy(),
            cut[9][c, : (3 if spread else 1) * n].copy(), cut[11], spread)  # fmt: skip


@njit(**JIT)
def prepare(sea, t, x):
    """What `elevations` and `fields` need at time t for a body centred at x (reaching sea[3] from it): each component's
    phase offset, the ramp's factor, and (when the series serves) its centre, scale, degree and moments: `clusters`
    with the body as one part."""
    comps = sea[0]
    r = ramp_factor(t, sea[5])
    amp, amp_w, slope, k_max = _scales(comps, r)
    spheres = np.array([[0.0, 0.0, 0.0, sea[3]]])
    one = np.zeros(1, dtype=np.int64)
    cut = _with_series(comps, _offsets(sea, t), r, amp, amp_w, slope, k_max, spheres, True, one, one + 1, x.reshape(1, 3).copy(),
                       expandable(sea), not long_crested(comps), False)  # fmt: skip
    return cluster_ex(cut, 0)


@njit(**JIT)
def _series_elevations(sea, ex, points, m, out):
    """out[i] = eta at points[i], i < m, from the expansion: sum_n Re(i^n Me_n) s^n, a real polynomial in the scaled
    distance s along the waves (returned), for a block of points a degree at a time (loops the compiler vectorises)."""
    cb, sb = sea[0][0, COS], sea[0][0, SIN]
    cx, cy, k_scale, Me = ex[2], ex[3], ex[5], ex[6]
    s = np.empty(m)
    for i in range(m):
        s[i] = k_scale * (cb * (points[i, 0] - cx) + sb * (points[i, 1] - cy))
    c = np.empty(Me.shape[0])
    for n in range(Me.shape[0]):  # Re(i^n M): i^n cycles through 1, i, -1, -i
        c[n] = (Me[n].real, -Me[n].imag, -Me[n].real, Me[n].imag)[n % 4]
    for start in range(0, m, BLOCK):
        end = min(m, start + BLOCK)
        _polynomial(c, s[start:end], out[start:end])
    return s


@njit(**JIT)
def _polynomial(c, s, out):
    """out = sum_n c_n s^n (a block of points, one degree at a time)."""
    top = c.shape[0] - 1
    for i in range(s.shape[0]):
        out[i] = c[top]
    for n in range(top - 1, -1, -1):
        cn = c[n]
        for i in range(s.shape[0]):
            out[i] = out[i] * s[i] + cn


@njit(**JIT)
def _series_at(M, wr, wi, m, ar, ai):
    """(ar + i ai)[i] = sum_n M_n (wr + i wi)[i]^n, i < m: Horner's rule, a block of points a degree at a time."""
    for start in range(0, m, BLOCK):
        end = min(m, start + BLOCK)
        _horner_block(M, wr[start:end], wi[start:end], ar[start:end], ai[start:end])


@njit(**JIT)
def _horner_block(M, wr, wi, ar, ai):
    top = M.shape[0] - 1
    for i in range(ar.shape[0]):
        ar[i], ai[i] = M[top].real, M[top].imag
    for n in range(top - 1, -1, -1):
        mr, mi = M[n].real, M[n].imag
        for i in range(ar.shape[0]):
            re = ar[i] * wr[i] - ai[i] * wi[i] + mr
            ai[i] = ar[i] * wi[i] + ai[i] * wr[i] + mi
            ar[i] = re


@njit(**JIT)
def _series_fields(sea, ex, points, eta, m, rho, g, need_flow, out, known):
    """fields from the expansion (deep water), in passes over all m points at once: the elevation (unless known),
    the stretched depth, then the pressure's series (and the flow's)."""
    U = sea[4]
    cb, sb = sea[0][0, COS], sea[0][0, SIN]
    z0, k_scale, Mp, Mv = ex[4], ex[5], ex[7], ex[8]
    if known:
        wi = np.empty(m)
        for i in range(m):
            wi[i] = k_scale * (cb * (points[i, 0] - ex[2]) + sb * (points[i, 1] - ex[3]))
    else:
        wi = _series_elevations(sea, ex, points, m, eta)
    wr = np.empty(m)
    for i in range(m):
        wr[i] = k_scale * (min(points[i, 2] - eta[i], 0.0) - z0)
    ar, ai = np.empty(m), np.empty(m)
    _series_at(Mp, wr, wi, m, ar, ai)
    for i in range(m):
        out[i, 0] = rho * g * (ar[i] - points[i, 2])
    if need_flow:
        _series_at(Mv, wr, wi, m, ar, ai)
    for i in range(m):
        vr, vi = (ar[i], ai[i]) if need_flow else (0.0, 0.0)
        out[i, 1], out[i, 2], out[i, 3] = vr * cb + U[0], vr * sb + U[1], vi


@njit(**JIT)
def elevations(sea, ex, points, m, out):
    """out[i] = eta at the horizontal position of points[i], i < m."""
    comps = sea[0]
    P, offset, r = ex[0], ex[1], ex[9]
    if P >= 0:
        if ex[10]:
            directional_elevations(sea, ex, points, m, out)
        else:
            _series_elevations(sea, ex, points, m, out)
        return
    for i in range(m):
        X, Y = points[i, 0], points[i, 1]
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
    P, offset, r = ex[0], ex[1], ex[9]
    if P >= 0:
        if ex[10]:
            directional_fields(sea, ex, points, eta, m, rho, g, need_flow, out, known)
        else:
            _series_fields(sea, ex, points, eta, m, rho, g, need_flow, out, known)
        return
    deep = math.isinf(depth)
    n = comps.shape[0]
    cosines = np.empty(n)
    for i in range(m):
        X, Y, Z = points[i, 0], points[i, 1], points[i, 2]
        if not known:
            e = 0.0
            for j in range(n):
                cosines[j] = math.cos(comps[j, KX] * X + comps[j, KY] * Y + offset[j])
                e += comps[j, A] * cosines[j]
            eta[i] = r * e
        zs = Z - eta[i] if deep else (Z - eta[i]) * depth / (depth + eta[i])
        zc = min(zs, 0.0)
        p = ux = uy = uz = 0.0
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
        p, ux, uy, uz = r * p, r * ux, r * uy, r * uz
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = rho * g * (p - Z), ux + U[0], uy + U[1], uz

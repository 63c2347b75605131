"""The water a body floats in: where its surface is, how it moves, and its pressure.

Every wet test and every force term asks a `Water`, never the plane z = 0 itself. Still water is
the first kind; waves plug in as further kinds with the same three questions. World frame, SI units.

Two properties say what a kind can skip: `flat` (the surface is z = 0 at all times and the pressure
hydrostatic: the kernels' closed forms hold) and `at_rest` (the water does not move: damping and drag
act on the body's own velocity). A uniform current U = (u, v, 0) is a property of the water, not a force
term: the whole water moves with it (its waves too, as seen from the seabed: Galilean invariance), so
the velocity everywhere gains U and a wave component's phase advances at omega + k . U.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass

import numpy as np

from sim.water.records import components, measured, peak_period


@dataclass(frozen=True)
class StillWater:
    """Calm water, surface z = 0, at rest: hydrostatic pressure p = -rho g z below the surface.

    Still water is time-independent and its pressure is linear in z, which lets the compiled
    kernels keep running sums over the wet set and integrate panels in closed form."""

    rho: float = 1000.0
    """Water density, kg/m^3."""
    g: float = 9.81
    """Gravitational acceleration, m/s^2."""
    current: tuple[float, float] = (0.0, 0.0)
    """Uniform current (u, v), m/s, world frame."""

    kind = "still"
    flat = True

    @property
    def at_rest(self) -> bool:
        """Whether the water does not flow (no current)."""
        return self.current == (0.0, 0.0)

    def elevation(self, xy: np.ndarray, t: float) -> np.ndarray:
        """Surface height eta(x, y, t) at (..., 2) horizontal positions, m."""
        return np.zeros(np.shape(xy)[:-1])

    def velocity(self, points: np.ndarray, t: float) -> np.ndarray:
        """Fluid velocity at (..., 3) points under the surface, m/s."""
        return np.broadcast_to(np.array([*self.current, 0.0]), np.shape(points)).copy()

    def pressure(self, points: np.ndarray, t: float) -> np.ndarray:
        """Gauge pressure at (..., 3) points under the surface, Pa (zero on the surface)."""
        return -self.rho * self.g * points[..., 2]

    def height_above_surface(self, points: np.ndarray, t: float) -> np.ndarray:
        """z - eta at (..., 3) points: negative where they are wet."""
        return points[..., 2] - self.elevation(points[..., :2], t)

    def field(self, points: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(pressure, velocity) at the same points, in one pass."""
        return self.pressure(points, t), self.velocity(points, t)


BLOCK = 1 << 21
"""Points x components the numpy reference evaluates at once (16 MiB a float array): more points are taken in blocks,
so a fine body in a broad sea needs the memory of a block, not of every point (issue 59: 60 000 samples in 4096
components took 6 GB)."""


def _blocked(method):
    """`method(self, points, t)` over the points (the last axis their coordinates) in blocks of at most BLOCK points x
    components; fewer at once: as it is."""

    @functools.wraps(method)
    def in_blocks(self, points, t):
        points = np.asarray(points, float)
        rows = max(1, BLOCK // max(len(self.omega), 1))
        flat = points.reshape(-1, points.shape[-1])
        if flat.shape[0] <= rows:
            return method(self, points, t)
        parts = [method(self, flat[i : i + rows], t) for i in range(0, flat.shape[0], rows)]
        lead = points.shape[:-1]
        if isinstance(parts[0], tuple):
            return tuple(np.concatenate([p[j] for p in parts]).reshape(*lead, *parts[0][j].shape[1:]) for j in range(len(parts[0])))
        return np.concatenate(parts).reshape(*lead, *parts[0].shape[1:])

    return in_blocks


@dataclass(frozen=True, eq=False)
class Waves:
    """Linear (Airy) waves: a sum of components, each a_i cos(k_i . x - omega_i t + phi_i), with
    omega^2 = g k tanh(k h). Pressure p = -rho g z + sum rho g a_i E_i(z*) cos(psi_i) and velocity
    from the same potential, evaluated with Wheeler stretching z* = (z - eta) h / (h + eta) (deep
    water: z - eta) so that p = 0 on the surface itself. E = cosh(k (z* + h)) / cosh(k h) (deep: e^(k z*)).

    Valid for small steepness (H / wavelength well below the breaking limit 1/7) and, for the body,
    as the Froude-Krylov part of the wave load only: the body does not diffract or radiate waves."""

    rho: float
    g: float
    amplitude: np.ndarray
    """(n,) a_i, m."""
    omega: np.ndarray
    """(n,) angular frequencies, rad/s."""
    k: np.ndarray
    """(n,) wavenumbers, rad/m."""
    direction: np.ndarray
    """(n,) propagation directions, rad from +x."""
    phase: np.ndarray
    """(n,) phases phi_i, rad."""
    depth: float = math.inf
    """Water depth h, m (inf: deep water)."""
    current: tuple[float, float] = (0.0, 0.0)
    """Uniform current (u, v), m/s: the waves above are those seen moving with it."""
    ramp: float = 0.0
    """Seconds over which the sea grows from still water at t = 0 to full height (0: full height from the start)."""

    kind = "waves"
    flat = False
    at_rest = False

    @property
    def omega_met(self) -> np.ndarray:
        """(n,) each component's frequency as met at a fixed point: omega_i + k_i . U (carried by the current U)."""
        return self.omega + self.k * (np.cos(self.direction) * self.current[0] + np.sin(self.direction) * self.current[1])

    def ramped(self, t: float) -> float:
        """The ramp's factor on every wave quantity at time t: (1 - cos(pi t / ramp)) / 2 until t = ramp, then 1
        (value and slope continuous at both ends: the sea starts without a jolt; WEC-Sim's ramp)."""
        return ramp_factor(t, self.ramp)

    def _psi(self, xy: np.ndarray, t: float) -> np.ndarray:
        """(..., n) phases k_i . x - (omega_i + k_i . U) t + phi_i: the waves carried by the current U."""
        kx = self.k * np.cos(self.direction)
        ky = self.k * np.sin(self.direction)
        return xy[..., :1] * kx + xy[..., 1:2] * ky - self.omega_met * t + self.phase

    def pressure_amplitudes(self, points: np.ndarray) -> np.ndarray:
        """(m, n) complex: each component's linear (unstretched) dynamic pressure at (m, 3) points under z = 0, as the
        amplitude of e^(-i omega_met t): rho g a_i E_i(z) e^(i (k_i . x + phi_i)), Pa. The Froude-Krylov force of linear theory."""
        kx, ky = self.k * np.cos(self.direction), self.k * np.sin(self.direction)
        phase = np.multiply.outer(points[:, 0], kx) + np.multiply.outer(points[:, 1], ky) + self.phase
        return (self.rho * self.g * self.amplitude) * self._decay(points[:, 2], "cosh") * np.exp(1j * phase)

    @_blocked
    def elevation(self, xy: np.ndarray, t: float) -> np.ndarray:
        return np.cos(self._psi(np.asarray(xy, float), t)) @ (self.ramped(t) * self.amplitude)

    def elevation_on_grid(self, xs: np.ndarray, ys: np.ndarray, t: float, spacing_x=None, spacing_y=None) -> np.ndarray:
        """(nx, ny) eta at every (xs[i], ys[j]): the components factor over x and y, so a grid costs one small
        matrix product, not a cosine per point and component. Given each coordinate's grid spacing (m),
        components shorter than four spacings are left out and faded in up to eight, so that a coarse grid
        does not alias them into noise."""
        kx, ky = self.k * np.cos(self.direction), self.k * np.sin(self.direction)
        start = self.ramped(t) * self.amplitude * np.exp(1j * (self.phase - self.omega_met * t))
        X = np.exp(1j * np.multiply.outer(np.asarray(xs, float), kx)) * start
        Y = np.exp(1j * np.multiply.outer(np.asarray(ys, float), ky))
        if spacing_x is not None:
            X = X * self._resolved(spacing_x)
        if spacing_y is not None:
            Y = Y * self._resolved(spacing_y)
        return np.einsum("ik,jk->ij", X, Y).real  # (not BLAS: its threads would spin after each of these small products)

    def _resolved(self, spacing) -> np.ndarray:
        """(m, n) weights of the components a grid of these spacings shows (elevation_on_grid)."""
        return np.clip(2 * np.pi / (self.k * 4.0 * np.asarray(spacing, float)[:, None]) - 1.0, 0.0, 1.0)

    def _stretched(self, points: np.ndarray, t: float):
        """(psi, z*) with Wheeler's stretching of the depth coordinate."""
        psi = self._psi(points, t)
        eta = np.cos(psi) @ (self.ramped(t) * self.amplitude)
        z = points[..., 2]
        zs = z - eta if math.isinf(self.depth) else (z - eta) * self.depth / (self.depth + eta)
        return psi, zs

    def _decay(self, zs: np.ndarray, hyperbolic: str) -> np.ndarray:
        """(..., n) depth factors at stretched depth zs: 'cosh' gives cosh(k(z+h))/cosh(kh) (pressure),
        'cosh/sinh' cosh(k(z+h))/sinh(kh) and 'sinh/sinh' sinh(k(z+h))/sinh(kh) (velocity); in
        exponential form so that no cosh overflows (deep water: all e^(k z))."""
        kz = self.k * np.minimum(zs, 0.0)[..., None]
        if math.isinf(self.depth):
            return np.exp(kz)
        far = np.exp(-self.k * (2 * self.depth) - kz)  # e^(-k(z + 2h))
        h2 = np.exp(-2 * self.k * self.depth)
        num = np.exp(kz) + (far if hyperbolic != "sinh/sinh" else -far)
        den = 1 + h2 if hyperbolic == "cosh" else 1 - h2
        return num / den

    @_blocked
    def pressure(self, points: np.ndarray, t: float) -> np.ndarray:
        psi, zs = self._stretched(points, t)
        return self.rho * self.g * ((self._decay(zs, "cosh") * np.cos(psi)) @ (self.ramped(t) * self.amplitude) - points[..., 2])

    def velocity(self, points: np.ndarray, t: float) -> np.ndarray:
        return self.field(points, t)[1]

    def height_above_surface(self, points: np.ndarray, t: float) -> np.ndarray:
        return points[..., 2] - self.elevation(points[..., :2], t)

    @_blocked
    def field(self, points: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(pressure, velocity) at the same points, sharing the phases and depth factors."""
        psi, zs = self._stretched(points, t)
        cos, sin = np.cos(psi), np.sin(psi)
        a = self.ramped(t) * self.amplitude
        pressure = self.rho * self.g * ((self._decay(zs, "cosh") * cos) @ a - points[..., 2])
        aw = a * self.omega
        horizontal = self._decay(zs, "cosh/sinh") * cos * aw
        velocity = np.empty(np.shape(points))
        velocity[..., 0] = horizontal @ np.cos(self.direction)
        velocity[..., 1] = horizontal @ np.sin(self.direction)
        velocity[..., 2] = (self._decay(zs, "sinh/sinh") * sin) @ aw
        velocity[..., 0] += self.current[0]
        velocity[..., 1] += self.current[1]
        return pressure, velocity


def ramp_factor(t: float, ramp: float) -> float:
    """(1 - cos(pi t / ramp)) / 2 for 0 <= t < ramp, 0 before, 1 after (ramp 0: 1 from t = 0)."""
    if ramp <= 0.0 or t >= ramp:
        return 1.0
    return 0.0 if t <= 0.0 else 0.5 - 0.5 * math.cos(math.pi * t / ramp)


RAMP_PERIODS = 3.5
"""The default ramp, in periods of the sea (regular: its period; JONSWAP: the peak period). A half-cosine over
N + 1/2 periods switches a sinusoid on with no net impulse at its own frequency (docs/physics.md, the wave ramp)."""


def ramp_seconds(waves, base_dir: str = ".") -> float:
    """The ramp a scene's [waves] table asks for, s: its `ramp`, or RAMP_PERIODS periods of the sea when unset (0 in
    still water; a record: the period of its largest component)."""
    if waves.kind == "still":
        return 0.0
    if waves.ramp is not None:
        return float(waves.ramp)
    if waves.kind == "record":
        return RAMP_PERIODS * peak_period(*measured(waves, base_dir), waves.cutoff_period)
    return RAMP_PERIODS * float(waves.period if waves.kind == "regular" else waves.tp)


def wavenumber(omega: np.ndarray, g: float, depth: float) -> np.ndarray:
    """k from omega^2 = g k tanh(k h) (Newton from the deep-water value; deep water: omega^2 / g)."""
    omega = np.asarray(omega, float)
    k = omega**2 / g
    if math.isinf(depth):
        return k
    k = np.maximum(k, omega / math.sqrt(g * depth))  # start above the root (tanh <= 1, and the shallow limit)
    for _ in range(50):
        th = np.tanh(k * depth)
        f = g * k * th - omega**2
        k = k - f / (g * th + g * k * depth * (1 - th * th))
    return k


def regular_waves(
    rho: float, g: float, height: float, period: float, direction_deg: float = 0.0, depth: float = math.inf, phase: float = 0.0
) -> Waves:
    """One Airy component of crest-to-trough height H and period T."""
    omega = np.array([2 * math.pi / period])
    return Waves(rho, g, np.array([0.5 * height]), omega, wavenumber(omega, g, depth), np.array([math.radians(direction_deg)]),
                 np.array([phase]), depth)  # fmt: skip


def _jonswap_shape(omega: np.ndarray, wp: float, gamma: float) -> np.ndarray:
    sigma = np.where(omega <= wp, 0.07, 0.09)
    return omega**-5.0 * np.exp(-1.25 * (wp / omega) ** 4) * gamma ** np.exp(-0.5 * ((omega - wp) / (sigma * wp)) ** 2)


def jonswap_spectrum(omega: np.ndarray, hs: float, tp: float, gamma: float) -> np.ndarray:
    """S(omega), m^2 s/rad: the JONSWAP shape (gamma = 1: Pierson-Moskowitz) scaled so that 4 sqrt(m0) = Hs
    (DNV-RP-C205, 3.5.5)."""
    wp = 2 * math.pi / tp
    grid = np.linspace(0.2 * wp, 6.0 * wp, 4000)  # the normalising integral, far past where the shape matters
    s_grid = _jonswap_shape(grid, wp, gamma)
    m0 = float(np.sum(0.5 * (s_grid[1:] + s_grid[:-1]) * np.diff(grid)))
    return _jonswap_shape(np.asarray(omega, float), wp, gamma) * (hs / 4.0) ** 2 / m0


def jonswap_waves(rho: float, g: float, hs: float, tp: float, gamma: float = 3.3, components: int = 64, seed: int = 0, direction_deg: float = 0.0,
                  spreading: float = 0.0, depth: float = math.inf) -> Waves:  # fmt: skip
    """An irregular sea: `components` Airy waves at frequencies spread over [0.5, 3] omega_p, one per
    band of equal width at a random point in its band (so the record does not repeat), amplitude
    sqrt(2 S(omega) d omega), random phase; directions spread as cos^(2s)((theta - theta0)/2) when
    spreading s > 0 (long-crested when 0). Reproducible from `seed`."""
    rng = np.random.default_rng(seed)
    wp = 2 * math.pi / tp
    edges = np.linspace(0.5 * wp, 3.0 * wp, components + 1)
    omega = edges[:-1] + rng.random(components) * np.diff(edges)
    amplitude = np.sqrt(2 * jonswap_spectrum(omega, hs, tp, gamma) * np.diff(edges))
    phase = rng.uniform(0, 2 * math.pi, components)
    theta = np.full(components, math.radians(direction_deg))
    if spreading > 0:  # inverse-CDF sampling of cos^(2s)(dtheta / 2) on a fine grid
        grid = np.linspace(-math.pi, math.pi, 2001)
        cdf = np.cumsum(np.cos(grid / 2) ** (2 * spreading))
        theta = theta + np.interp(rng.random(components), cdf / cdf[-1], grid)
    return Waves(rho, g, amplitude, omega, wavenumber(omega, g, depth), theta, phase, depth)


def record_waves(rho: float, g: float, dt: float, eta: np.ndarray, direction_deg: float = 0.0, depth: float = math.inf,
                 point=(0.0, 0.0), cutoff_period: float | None = None) -> Waves:  # fmt: skip
    """The long-crested sea whose elevation at `point` is the record eta (samples dt apart, the first at t = 0),
    travelling in `direction_deg` (records.components: its periodic extension, less its mean)."""

    omega, amplitude, alpha = components(dt, eta, cutoff_period)
    k = wavenumber(omega, g, depth)
    theta = math.radians(direction_deg)
    # a cos(k . x_ref - omega t + phi) = a cos(omega t + alpha) at the reference point
    phase = -alpha - k * (math.cos(theta) * point[0] + math.sin(theta) * point[1])
    return Waves(rho, g, amplitude, omega, k, np.full(len(omega), theta), phase, depth)


def make_water(waves, rho: float, g: float, current=(0.0, 0.0), base_dir: str = "."):
    """The water a scene's [waves] table, [water] current and [fluid] rho, g describe (a record's file is found
    from `base_dir`, the scene file's folder)."""
    depth = math.inf if waves.depth is None else float(waves.depth)
    current = (float(current[0]), float(current[1]))
    if waves.kind == "regular":
        sea = regular_waves(rho, g, waves.height, waves.period, waves.direction, depth)
        return dataclasses.replace(sea, current=current, ramp=ramp_seconds(waves))
    if waves.kind == "jonswap":
        sea = jonswap_waves(rho, g, waves.hs, waves.tp, waves.gamma, waves.components, waves.seed, waves.direction, waves.spreading, depth)
        return dataclasses.replace(sea, current=current, ramp=ramp_seconds(waves))
    if waves.kind == "record":
        dt, eta = measured(waves, base_dir)
        sea = record_waves(rho, g, dt, eta, waves.direction, depth, waves.record_point, waves.cutoff_period)
        return dataclasses.replace(sea, current=current, ramp=ramp_seconds(waves, base_dir))
    return StillWater(rho, g, current)

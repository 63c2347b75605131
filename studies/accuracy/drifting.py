"""Part 9 of the accuracy report: drifting bodies (issue 38): the excitation where the body is, and the wave ramp.

The sphere preset (radiation and diffraction from its shipped BEM solve) in small regular waves:
- placed a quarter wave down-wave of where the scene starts it (before the waves rise, as a drift would carry it),
  free, its heave RAO against the same sphere on a vertical slide at its start (a prismatic joint) and against the
  linear frequency-domain RAO of the same coefficients (the diffraction force is phased at the body's current
  position, sim/hydro/diffraction.py: without that the free body's heave was off by -10 % and +12 % at T = 1.2 and 2.5 s);
- started at rest in waves at full height from t = 0 (`[waves] ramp = 0`, floatsim before the ramp) and with the
  default ramp (3.5 periods, a half-cosine: sim/water/seas.py), its horizontal motion: the part that flips with the wave's
  sign (a run started half a wave down-wave subtracted) is the first-order start-up kick; its drift per period after
  the ramp, against the wave amplitude.

The slow tests of tests/hydro/test_diffraction.py and tests/water/test_waves.py use the same functions.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

G = 9.81


@dataclass(frozen=True)
class DriftSettings:
    periods: tuple[float, ...] = (1.2, 1.8, 2.5)
    """Wave periods of the slide-against-free comparison, s."""
    height: float = 0.004
    """Their wave height, m (small: the mean force does not move the sphere on within the run)."""
    run: int = 12
    fit: int = 6
    """Periods run after the ramp, and the last ones the first harmonic is fitted on."""
    ramp_period: float = 2.5
    ramp_height: float = 0.02
    after: float = 6.5
    """The start-up runs: wave period, height, and periods run after the default ramp."""

    def jobs(self) -> int:
        return 2 * len(self.periods) + 4


FULL_DRIFT = DriftSettings()
QUICK_DRIFT = DriftSettings(periods=(1.2,), run=8, fit=4, ramp_period=1.2, after=4.0)


@dataclass
class SlideRow:
    period: float
    free: float
    slide: float
    frequency: float
    """|heave| per unit wave amplitude: free a quarter wave from its start, on the slide, the frequency domain."""

    @property
    def wavelength(self) -> float:
        return wavelength(self.period)


@dataclass
class StartUp:
    ramp: float
    """The wave ramp, s (0: full height from the start)."""
    t: np.ndarray
    x: np.ndarray
    """The run started at x = 0: its centre's x, m."""
    odd: np.ndarray
    """Each period's mean of the part of x that flips with the wave (the kick), m."""
    drift: float
    """The odd part's drift per period after the ramp (from one period past its end), m."""


@dataclass
class Drifting:
    settings: DriftSettings
    rows: list[SlideRow] = field(default_factory=list)
    starts: list[StartUp] = field(default_factory=list)
    curve: tuple[np.ndarray, np.ndarray] = (np.zeros(0), np.zeros(0))
    """(periods, |heave| per unit amplitude) of the frequency domain over the solve's grid, for the figure."""

    @property
    def amplitude(self) -> float:
        return 0.5 * self.settings.ramp_height


def wavelength(period: float) -> float:
    return G * period**2 / (2 * math.pi)


def sphere_in_waves(period: float, height: float, **overrides):
    """The sphere preset at rest at the origin, in regular waves (heading 0)."""
    from sim import load_scene, with_overrides

    return with_overrides(load_scene("sphere"), waves__kind="regular", waves__height=height, waves__period=period,
                          initial__position=(0.0, 0.0, 0.0), **overrides)  # fmt: skip


def heave_rao(scene, moved_by: float, periods: int = 12, fit: int = 6) -> float:
    """|first harmonic of z| / a over the last `fit` of `periods` wave periods after the ramp, the body placed `moved_by`
    metres down-wave of where the scene starts it before the first step (the waves still flat)."""
    from sim import Simulation

    sim = Simulation(scene)
    s = sim.body_state
    sim.reset(dataclasses.replace(s, x_world=s.x_world + [moved_by, 0.0, 0.0]))
    T, a = scene.waves.period, 0.5 * scene.waves.height
    t_end, chunk = sim.model.water.ramp + periods * T, 5
    times, z = [], []
    for _ in range(round(t_end / sim.dt / chunk)):
        sim.step(chunk)
        times.append(sim.state.t)
        z.append(sim.state.x_world[2])
    t, z = np.array(times), np.array(z)
    keep = t > t[-1] - fit * T
    w = 2 * np.pi / T
    basis = np.column_stack([np.ones(keep.sum()), t[keep], np.cos(w * t[keep]), np.sin(w * t[keep])])
    coef, *_ = np.linalg.lstsq(basis, z[keep], rcond=None)
    return float(np.hypot(coef[2], coef[3])) / a


def period_means(x: np.ndarray, per: int) -> np.ndarray:
    """The mean of x over each whole period of `per` samples (the samples evenly spaced, the first a step after t = 0)."""
    x = np.asarray(x)
    return x[: len(x) // per * per].reshape(-1, per).mean(axis=1)


def kick_drift(odd: np.ndarray, period: float, ramp: float) -> float:
    """The drift per period (m) of the period means `odd` from one period after the ramp's end on (a straight line's slope)."""
    middle = (np.arange(len(odd)) + 0.5) * period
    after = middle > ramp + period
    return float(np.polyfit(np.arange(after.sum()), odd[after], 1)[0])


def _start_run(scene, x0: float, t_end: float) -> tuple[np.ndarray, np.ndarray]:
    """(t, x - x0) every step of the sphere started at rest at x0."""
    from sim import Simulation

    sim = Simulation(scene)
    s = sim.body_state
    sim.reset(dataclasses.replace(s, x_world=s.x_world + [x0, 0.0, 0.0]))
    t, x = [], []
    for _ in range(round(t_end / sim.dt)):
        sim.step(1)
        t.append(sim.state.t)
        x.append(sim.state.x_world[0] - x0)
    return np.array(t), np.array(x)


def start_up(cfg: DriftSettings, ramp: float | None, tick) -> StartUp:
    """The sphere started at rest at x = 0 and half a wave down-wave, with the ramp `ramp` (None: the default): the
    first-order part of its period-mean surge and its drift after the ramp."""
    from sim.scene.config import wave_ramp

    T = cfg.ramp_period
    scene = sphere_in_waves(T, cfg.ramp_height, **({} if ramp is None else {"waves__ramp": ramp}))
    seconds, default = wave_ramp(scene), wave_ramp(sphere_in_waves(T, cfg.ramp_height))
    runs = []
    for x0 in (0.0, 0.5 * wavelength(T)):
        runs.append(_start_run(scene, x0, default + cfg.after * T))
        tick()
    (t, x), (_, x_half) = runs
    per = round(T / (t[1] - t[0]))
    odd = 0.5 * (period_means(x, per) - period_means(x_half, per))
    return StartUp(seconds, t, x, odd, kick_drift(odd, T, seconds))


def slide_row(cfg: DriftSettings, period: float, c, body, tick) -> SlideRow:
    """The free sphere a quarter wave from its start, the sphere on a slide, and the frequency domain, at `period`."""
    from sim import with_overrides

    from .excitation import SPHERE, linear_rao

    base = sphere_in_waves(period, cfg.height)
    free = heave_rao(base, 0.25 * wavelength(period), cfg.run, cfg.fit)
    tick()
    slide = heave_rao(with_overrides(base, constraint__joint="prismatic"), 0.0, cfg.run, cfg.fit)
    tick()
    return SlideRow(period, free, slide, float(abs(linear_rao(c, body, SPHERE.rest_z, 2 * math.pi / period)[2])))


def compute_drifting(cfg: DriftSettings, tick) -> Drifting:
    from sim import Simulation, with_overrides

    from .excitation import SPHERE, coefficients, linear_rao

    out = Drifting(cfg)
    c = coefficients(SPHERE)
    body = Simulation(with_overrides(SPHERE.base(), initial__position=(0.0, 0.0, SPHERE.rest_z)), backend="numpy").body
    for period in cfg.periods:
        out.rows.append(slide_row(cfg, period, c, body, tick))
    lo, hi = min(cfg.periods) / 1.5, max(cfg.periods) * 1.5
    grid = np.array([w for w in c.omega if lo <= 2 * math.pi / w <= hi])
    out.curve = (2 * math.pi / grid, np.array([abs(linear_rao(c, body, SPHERE.rest_z, w)[2]) for w in grid]))
    out.starts = [start_up(cfg, 0.0, tick), start_up(cfg, None, tick)]
    return out

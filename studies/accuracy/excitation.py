"""Part 7 of the accuracy report: what diffraction changes, wave period by wave period.

For the sphere and the cube presets with radiation from the shipped BEM solves, in small regular waves,
the response amplitude operators (motion per unit wave amplitude) of:
- time-domain runs (compiled; nonlinear Froude-Krylov on the exact wet surface, the fitted radiation
  memory) with the diffraction force on, and with it off (Froude-Krylov only);
- the linear frequency-domain solution with the same coefficients,
  [-omega^2 (M + A) - i omega B + C] xi = X_FK (+ X_d), C the exact mesh's hydrostatic stiffness at rest.

Each run starts on the linear steady state (its radiation memory's included; the waves at full height, no ramp), so a few periods suffice;
the first harmonic of the last `fit` periods is fitted, a drift removed, referred to the wave at the
body's mean position. The slow tests of tests/hydro/test_diffraction.py use the same functions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from sim import Simulation, State, load_scene, with_overrides

DOF_NAMES = ("surge", "sway", "heave", "roll", "pitch", "yaw")


@dataclass(frozen=True)
class Body:
    name: str
    scene: str
    overrides: dict
    rest_z: float
    dofs: tuple[int, ...]
    """The dofs the waves (heading 0) move: the others stay 0 by symmetry."""

    def base(self):
        return with_overrides(load_scene(self.scene), **self.overrides)


SPHERE = Body("sphere", "sphere", {}, 0.0, (0, 2))
CUBE = Body("cube", "rest", {"fluid__radiation": "bem", "fluid__forces": "panels"}, -0.4, (0, 2, 4))


@dataclass(frozen=True)
class ExcitationSettings:
    bodies: tuple[Body, ...]
    every: int
    """Every so many of the solve's frequencies in the band below is run."""
    lo: float = 1.5
    hi: float = 20.0
    """The band of wavelengths, in body lengths (the bodies are 1 m across)."""
    amplitude: float = 0.001
    periods: int = 30
    fit: int = 10

    def jobs(self) -> int:
        return sum(len(frequencies(coefficients(b), self)) for b in self.bodies) * 2


FULL_EXCITATION = ExcitationSettings((SPHERE, CUBE), every=2)
QUICK_EXCITATION = ExcitationSettings((SPHERE,), every=20, periods=12, fit=4)


@dataclass
class Response:
    body: str
    omega: float
    wavelength: float
    dofs: tuple[int, ...]
    time_full: np.ndarray
    time_fk: np.ndarray
    freq_full: np.ndarray
    freq_fk: np.ndarray
    """(6,) complex motion per unit wave amplitude (m/m, rad/m) each."""

    @property
    def period(self) -> float:
        return 2 * math.pi / self.omega

    def error(self, d: int, diffraction: bool = True) -> float:
        """|time - frequency| / the largest translation amplitude (the scale the RAO is read on)."""
        t, f = (self.time_full, self.freq_full) if diffraction else (self.time_fk, self.freq_fk)
        return float(abs(t[d] - f[d]) / np.abs(f[:3]).max())


@dataclass
class Excitation:
    settings: ExcitationSettings
    responses: list[Response] = field(default_factory=list)

    def of(self, body: str) -> list[Response]:
        return [r for r in self.responses if r.body == body]


def coefficients(body: Body):
    """The body's shipped BEM coefficients with the excitation, about its centre of mass at rest."""
    import sim.hydro.bem as bem

    b = Simulation(body.base(), backend="numpy").body
    return bem.radiation_coefficients(b.mesh_vertices + [0.0, 0.0, body.rest_z], b.mesh_faces, progress=False, center=(0.0, 0.0, body.rest_z),
                                      excitation=True)  # fmt: skip


def frequencies(c, cfg: ExcitationSettings) -> np.ndarray:
    """Indices of the solve's frequencies whose deep-water wavelength is in the band, every cfg.every-th."""
    lam = 2 * math.pi * 9.81 / c.omega**2
    return np.flatnonzero((lam >= cfg.lo) & (lam <= cfg.hi))[:: cfg.every]


def frequency_domain_rao(c, body, rest_z: float, i: int, diffraction: bool = True, rho: float = 1000.0, g: float = 9.81) -> np.ndarray:
    """(6,) complex response per unit wave amplitude (heading 0) at the solve's frequency i: the linear equation
    [-omega^2 (M + A) - i omega B + C] xi = X_FK (+ X_d), C the exact mesh's hydrostatic stiffness at rest
    (`body` a sim Body; its principal waterplane axes x and y, as the cube's and the sphere's)."""
    return linear_rao(c, body, rest_z, float(c.omega[i]), diffraction, rho, g)


def linear_rao(c, body, rest_z: float, w: float, diffraction: bool = True, rho: float = 1000.0, g: float = 9.81) -> np.ndarray:
    """frequency_domain_rao at any omega w in the solve's grid: A, B and X interpolated linearly between its
    frequencies (exactly the solve's at them)."""
    from sim.hydro.hydrostatics import hydrostatics

    h = hydrostatics(body, np.array([0.0, 0.0, rest_z]), np.eye(3))
    C = np.zeros((6, 6))
    C[2, 2] = rho * g * h.waterplane_area
    C[3, 3], C[4, 4] = rho * g * h.volume * h.gm
    M = np.diag([body.mass] * 3 + list(body.inertia))
    j = int(np.clip(np.searchsorted(c.omega, w, side="right") - 1, 0, len(c.omega) - 2))
    f = (w - c.omega[j]) / (c.omega[j + 1] - c.omega[j])
    at = lambda table: (1 - f) * table[j] + f * table[j + 1]  # noqa: E731
    X = at(c.froude_krylov[:, 0]) + (at(c.diffraction[:, 0]) if diffraction else 0.0)
    return np.linalg.solve(-(w**2) * (M + at(c.added_mass)) - 1j * w * at(c.damping) + C, X)


def time_domain_rao(base, rest_z: float, w: float, a: float, start: np.ndarray, periods: int = 30, fit: int = 10) -> np.ndarray:
    """(6,) complex first harmonic per unit amplitude of (x, y, z - z_rest, roll, pitch, yaw) over the last `fit`
    periods of a run in regular waves of amplitude a, started on the linear steady state `start` (position and
    velocity; the orientation stays the rest pose's, which the radiation is linear about), a drift removed, and
    referred to the wave at the body's mean x (it wanders a few cm in the first periods)."""
    T = 2 * np.pi / w
    x0, v0 = (a * start).real, (-1j * w * a * start).real
    scene = with_overrides(base, waves__kind="regular", waves__height=2 * a, waves__period=T, initial__position=(x0[0], x0[1], rest_z + x0[2]),
                           initial__velocity=tuple(v0[:3]), initial__omega=tuple(v0[3:]), fluid__damping=0.0, waves__ramp=0.0)  # fmt: skip
    sim = Simulation(scene)
    rad = sim.model.radiation  # its memory in steady state too (x' = F x + G nu at nu = -i omega xi), or the surge, which has no
    nu = -1j * w * a * start  # restoring force, keeps the offset of the memory's start-up and the body wanders from the waves' reference
    memory = np.linalg.solve(-1j * w * np.eye(rad.states) - rad.F, rad.G @ nu).real
    s = sim.state
    sim.reset(State(s.t, s.x_world, s.q_world_body, s.u_world, s.L_world, memory, 0.0))
    chunk = max(1, round(T / sim.dt / 64))
    times, motions = [], []
    for _ in range(round(periods * T / sim.dt / chunk)):
        sim.step(chunk)
        R = sim.state.R_world_body
        times.append(sim.state.t)
        motions.append(
            [*(sim.state.x_world - [0.0, 0.0, rest_z]), 0.5 * (R[2, 1] - R[1, 2]), 0.5 * (R[0, 2] - R[2, 0]), 0.5 * (R[1, 0] - R[0, 1])]
        )
    t, q = np.array(times), np.array(motions)
    keep = t > t[-1] - fit * T
    basis = np.column_stack([np.ones(keep.sum()), t[keep], np.cos(w * t[keep]), np.sin(w * t[keep])])
    coef, *_ = np.linalg.lstsq(basis, q[keep], rcond=None)
    k = w * w / 9.81
    return (coef[2] + 1j * coef[3]) / a * np.exp(-1j * k * q[keep, 0].mean())


def compute_excitation(cfg: ExcitationSettings, tick) -> Excitation:
    """Both bodies, every frequency of the band: time and frequency domain, with and without diffraction."""
    out = Excitation(cfg)
    for spec in cfg.bodies:
        c = coefficients(spec)
        base = spec.base()
        body = Simulation(with_overrides(base, initial__position=(0.0, 0.0, spec.rest_z)), backend="numpy").body
        for i in frequencies(c, cfg):
            w = float(c.omega[i])
            full, fk = frequency_domain_rao(c, body, spec.rest_z, i), frequency_domain_rao(c, body, spec.rest_z, i, diffraction=False)
            runs = []
            for diffraction, start in ((True, full), (False, fk)):
                scene = with_overrides(base, waves__diffraction=diffraction)
                runs.append(time_domain_rao(scene, spec.rest_z, w, cfg.amplitude, start, cfg.periods, cfg.fit))
                tick()
            out.responses.append(Response(spec.name, w, 2 * math.pi * 9.81 / w**2, spec.dofs, runs[0], runs[1], full, fk))
    return out

"""Part 6 of the accuracy report: where the sampled model's energy rises, and where it never comes to rest.

Two measurements on the cube:
- `energy_rises`: the largest rise of the energy over one step and above its start, for every force
  model and fixed-step integrator, on a tilted, damped cube (physics says it only falls);
- `leak_map`: over density and N, the cube started 5 degrees from upright at its draft with d = 100,
  run until it should have settled, then watched: the steady rocking (tilt range) and sideways drift
  the sampled models keep where the exact one comes to rest.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from sim import Simulation, load_scene, with_overrides

from .. import probes
from .compute import FIXED, quat_about_x

MODELS = ("points", "cells", "panels")
ROCKING = 0.1
"""Tilt range (deg) over the watch window above which a body counts as still rocking."""
DRIFT = 1e-3
"""Sideways speed (m/s) over the watch window above which a body counts as drifting."""


@dataclass(frozen=True)
class LeakSettings:
    densities: tuple[float, ...]
    ns: tuple[int, ...]
    settle: float
    """Time allowed to come to rest, s."""
    watch: float
    """Then watched for this long, s."""
    patience: float = 300.0
    """A body still moving then gets up to this much more time (in steps of `settle`), s."""
    damping: float = 100.0
    dt: float = 0.01
    tilt: float = 5.0
    """Initial tilt about x, degrees."""
    cases: tuple[float, ...] = (180.0, 215.0, 820.0)
    """Densities quoted one by one (at N = 10)."""
    energy_time: float = 30.0
    energy_dt: float = 0.005

    def jobs(self) -> int:
        return len(set(self.densities)) * (len(self.ns) * 2 + 1) + 2 * len(MODELS) * len(FIXED)


BANDS = tuple(float(d) for d in (*range(100, 301, 10), 215, *range(700, 901, 10)))
"""Densities mapped: the upright cube's two stability transitions and around. Between them every model
turns the cube corner-up, which takes longer than the settling time (that band is not mapped)."""
FULL_LEAK = LeakSettings(BANDS, (5, 10, 20, 40), settle=100.0, watch=20.0)
QUICK_LEAK = LeakSettings((180.0, 215.0, 820.0), (10,), settle=40.0, watch=10.0, energy_time=10.0)


@dataclass(frozen=True)
class Settled:
    """How one run ends: over the watch window, the tilt (deg) range and mean, and the sideways speed (m/s)."""

    density: float
    n: int
    forces: str
    tilt_min: float
    tilt_max: float
    speed: float
    force_x: float
    """Horizontal water force on the body held still in its final pose, N (zero at any true rest)."""
    t_end: float = 0.0
    """When the watch ended, s."""
    warned: bool = False
    """Whether the points model's warning (sim.hydro.hydrostatics.sampled_model_warning's band) covers this body."""

    @property
    def tilt(self) -> float:
        return 0.5 * (self.tilt_min + self.tilt_max)

    @property
    def rocking(self) -> float:
        return self.tilt_max - self.tilt_min

    @property
    def at_rest(self) -> bool:
        return self.rocking < ROCKING and self.speed < DRIFT


@dataclass
class EnergyRise:
    scene: str
    forces: str
    method: str
    per_step: float
    """Largest rise of E_total (the physical energy) over one step, J (<= 0: it never rose)."""
    climb: float
    """Largest rise of E_total over any stretch of the run, max of E(t) - min of E before t, J."""
    model_per_step: float
    """Largest one-step rise of the model's own energy (its own hydrostatic potential), J."""
    model_climb: float


@dataclass
class Leak:
    settings: LeakSettings
    runs: list[Settled] = field(default_factory=list)
    energy: list[EnergyRise] = field(default_factory=list)

    def at(self, density: float, n: int, forces: str) -> Settled:
        return next(r for r in self.runs if r.density == density and (r.n == n or forces == "panels") and r.forces == forces)


def tilt_deg(R: np.ndarray) -> float:
    """Angle between the vertical and the body axis nearest to it, degrees (0: a face up)."""
    return math.degrees(math.acos(min(1.0, float(np.abs(R[2]).max()))))


def settle(density: float, n: int, forces: str, cfg: LeakSettings) -> Settled:
    """The cube at its upright draft tilted by cfg.tilt about x, damped, run for `settle` seconds, then
    watched for `watch`. A body still moving gets up to `patience` more seconds, watched again at the
    end: near the transitions it can linger for minutes at a tilted saddle before rolling corner-up,
    and that slow passage is no leak (a leak is still there at the end)."""
    scene = with_overrides(load_scene("rest"), body__density=density, body__points_per_edge=n, fluid__forces=forces,
                           fluid__damping=cfg.damping, initial__position=(0.0, 0.0, 0.5 - density / 1000.0),
                           initial__orientation=tuple(quat_about_x(math.radians(cfg.tilt))), step__integrator="implicit", step__dt=cfg.dt)  # fmt: skip
    sim = Simulation(scene)
    sim.step(round(cfg.settle / cfg.dt))
    result = _watch(sim, density, n, forces, cfg)
    waited = 0.0
    while not result.at_rest and waited < cfg.patience:
        sim.step(round(cfg.settle / cfg.dt))
        waited += cfg.settle
        result = _watch(sim, density, n, forces, cfg)
    return result


def _watch(sim: Simulation, density: float, n: int, forces: str, cfg: LeakSettings) -> Settled:
    every = max(1, round(0.05 / cfg.dt))
    start = sim.state.x_world[:2].copy()
    tilts = []
    for _ in range(round(cfg.watch / cfg.dt / every)):
        sim.step(every)
        tilts.append(tilt_deg(sim.state.R_world_body))
    speed = float(np.linalg.norm(sim.state.x_world[:2] - start)) / cfg.watch
    held = dataclasses.replace(sim.body_state, u_world=np.zeros(3), L_world=np.zeros(3))
    force = probes.frame_at(sim, held).force_world
    margin = probes.leak_margin(sim)
    warned = margin is not None and margin < probes.leak_band()
    return Settled(density, n, forces, min(tilts), max(tilts), speed, float(np.linalg.norm(force[:2])), sim.state.t, warned)


def leak_map(cfg: LeakSettings, tick) -> list[Settled]:
    runs = []
    for density in sorted(set(cfg.densities)):
        runs.append(settle(density, cfg.ns[0], "panels", cfg))  # its trajectory does not depend on N
        tick()
        for n in cfg.ns:
            for forces in ("points", "cells"):
                runs.append(settle(density, n, forces, cfg))
                tick()
    return runs


ENERGY_SCENES = {"damped": "the `damped` scene (tumbling in, d = 10)", "transition": "the cube of 215 kg/m^3 tilted 5 deg, d = 100"}


def energy_scene(which: str, forces: str, method: str, cfg: LeakSettings):
    if which == "damped":
        scene = load_scene("damped")
    else:
        scene = with_overrides(load_scene("rest"), body__density=215.0, fluid__damping=100.0, initial__position=(0.0, 0.0, 0.5 - 0.215),
                               initial__orientation=tuple(quat_about_x(math.radians(5.0))))  # fmt: skip
    return with_overrides(scene, fluid__forces=forces, body__points_per_edge=10, step__integrator=method, step__dt=cfg.energy_dt)


def _rises(E: np.ndarray) -> tuple[float, float]:
    return float(np.diff(E).max()), float((E - np.minimum.accumulate(E)).max())


def energy_rise(which: str, forces: str, method: str, cfg: LeakSettings) -> EnergyRise:
    """How far the energy of one run ever climbs, step by step and over any stretch, N = 10."""
    sim = Simulation(energy_scene(which, forces, method, cfg))
    frames = [sim.frame()]
    for _ in range(round(cfg.energy_time / cfg.energy_dt)):
        sim.step(1)
        frames.append(sim.frame())
    E = np.array([f.E_total for f in frames])
    E_model = np.array([f.E_kin + f.E_grav + f.E_hyd_of_model for f in frames])
    return EnergyRise(which, forces, method, *_rises(E), *_rises(E_model))


def energy_rises(cfg: LeakSettings, tick) -> list[EnergyRise]:
    out = []
    for which in ENERGY_SCENES:
        for forces in MODELS:
            for method in FIXED:
                out.append(energy_rise(which, forces, method, cfg))
                tick()
    return out


def compute_leak(cfg: LeakSettings, tick) -> Leak:
    return Leak(cfg, leak_map(cfg, tick), energy_rises(cfg, tick))


def transitions(rho: float = 1000.0) -> tuple[float, float]:
    """Densities where the upright cube's metacentric height changes sign: s (1 - s) = 1/6, s = density/rho."""
    root = math.sqrt(1.0 / 4.0 - 1.0 / 6.0)
    return (rho * (0.5 - root), rho * (0.5 + root))

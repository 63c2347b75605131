"""`python -m sim gains`: a take-off's best gains in the scene's regular waves, from the frequency domain (control/gains.py):
complex-conjugate (reactive) control and its power |F a|^2 / 8 Re Z, the best damper alone; and the best latching pair
(latch time and damping together), searched in the time domain, since latching is not linear: runs of the scene on a grid
about (T - T_n) / 2 and between Re Z and |Z|, each absorbing over whole wave periods after the start's transient, the
damper alone (latch time 0) among them, so that the latching it recommends is measured against the best damper the same
way."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from sim.control.gains import body_port, system_port
from sim.errors import ConfigError
from sim.forked import results, worker_pool
from sim.scene.config import load_scene, with_overrides
from sim.simulation import Simulation

from .interrupt import stop_if_asked


@dataclass
class GainsArgs:
    """The best take-off gains in the scene's regular waves: the scene's own values to try them with ([constraint] or a
    [[bodies]] entry's controller, pto_stiffness, pto_damping, latch_time)."""

    scene: str = "point-absorber"
    """Preset name or path to a scene .toml (regular waves, radiation from the BEM, a body on a prismatic or revolute joint)."""
    body: str = ""
    """A scene of several bodies: the body whose joint has the take-off."""
    wave_period: float | None = None
    """Regular waves' period T, s (default: the scene's)."""
    wave_height: float | None = None
    """Regular waves' height H, m (default: the scene's)."""
    search: bool = True
    """Search the latching pair (latch time, damping) in the time domain where latching applies (T > T_n): 25 runs of
    18 wave periods, on all cores (about 40 s for point-absorber on two); --no-search: the rule (T - T_n) / 2 alone."""


SETTLE, MEASURE = 8, 10
"""Wave periods a search run lets pass after the sea's ramp (the start's transient), then absorbs over."""


def gains(args: GainsArgs) -> int:

    scene = load_scene(args.scene)
    changes = {k: v for k, v in (("waves__period", args.wave_period), ("waves__height", args.wave_height)) if v is not None}
    scene = with_overrides(scene, **changes)
    if scene.bodies and not args.body:
        raise ConfigError(f"scene {scene.name!r} has several bodies: name the one whose take-off to tune (--body NAME)")
    if args.body and not scene.bodies:
        raise ConfigError("--body is for a scene of several bodies: this one has one")
    sim = Simulation(scene, backend="numpy")
    try:
        p = system_port(sim, args.body) if scene.bodies else body_port(sim)
    finally:
        sim.close()
    a = 0.5 * float(scene.waves.height)
    k, c = p.reactive
    kind = next(g.kind for g in sim.system.joints if g.name == args.body) if scene.bodies else sim.joint.kind
    unit = "N s/m" if kind == "prismatic" else "N m s/rad"
    print(f"scene {scene.name}: the take-off on {args.body or 'the body'}'s joint, regular waves T = {scene.waves.period:g} s, "
          f"H = {scene.waves.height:g} m (omega {p.omega:.6g} rad/s)")  # fmt: skip
    print(f"the joint's impedance Z = {p.impedance.real:.6g} {p.impedance.imag:+.6g}i {unit}; the waves' force |F a| = {abs(p.force) * a:.6g}; "
          f"natural period T_n = {'none on the solve grid' if p.natural_period is None else f'{p.natural_period:.6g} s'}")  # fmt: skip
    print(f"reactive (complex-conjugate): pto_stiffness = {k:.6g}, pto_damping = {c:.6g} -> {p.optimum(a):.6g} W (|F a|^2 / 8 Re Z)")
    print(f"passive (the best damper): pto_damping = {p.passive:.6g} -> {p.power(0.0, p.passive, a):.6g} W")
    latch = p.latch_time()
    if latch is not None and args.search and not scene.bodies:
        stop_if_asked()  # a Ctrl-C a library swallowed while the scene set up (trimesh's imports): before 40 s of runs
        _search_latching(scene, latch, c, p.passive)
    elif latch is not None:
        print(f"latching: latch_time = {latch:.6g} s ((T - T_n) / 2, Babarit & Clement 2006), with pto_damping = {c:.6g}")
    elif p.natural_period is not None:
        half = 0.5 * (p.natural_period - 2 * math.pi / p.omega)
        print(f"latching: none (the waves are shorter than T_n); declutching: declutch_time about {half:.6g} s ((T_n - T) / 2)")
    return 0


def absorbed_power(scene, latch_time: float, damping: float) -> float:
    """The mean power the take-off absorbs in the time domain with latching (latch_time 0: the damper alone), over
    MEASURE whole wave periods after the ramp and SETTLE periods more, W."""
    latching = latch_time > 0.0
    run = Simulation(with_overrides(scene, constraint__controller="latching" if latching else "passive", constraint__pto_damping=damping,
                                    constraint__pto_stiffness=0.0, **({"constraint__latch_time": latch_time} if latching else {})),
                     backend="numpy")  # fmt: skip
    try:
        T = float(scene.waves.period)
        run.step(round((run.water.ramp + SETTLE * T) / run.dt))
        before, steps = run.pto_energy, round(MEASURE * T / run.dt)
        run.step(steps)
        return (run.pto_energy - before) / (steps * run.dt)
    finally:
        run.close()


def _search_latching(scene, latch: float, reactive_damping: float, damper: float) -> None:
    """The best (latch time, damping) of a 5 x 5 grid: latch times 0 (the damper alone) and 0.5, 0.75, 1 and 1.25 times
    (T - T_n) / 2, dampings from Re Z to |Z| (the best damper) evenly in their logarithm; printed with what it gains over
    the damper's best."""
    latches = latch * np.array([0.0, 0.5, 0.75, 1.0, 1.25])
    dampings = np.geomspace(reactive_damping, damper, 5) if damper > reactive_damping else np.array([damper])
    grid = [(L, c) for L in latches for c in dampings]
    print(f"latching: searching {len(grid)} pairs in the time domain ({SETTLE + MEASURE} wave periods each after the ramp) ...", flush=True)
    with worker_pool(min(len(grid), os.cpu_count() or 1)) as pool:  # (Ctrl-C ends its workers at once)
        powers = results([pool.submit(absorbed_power, scene, L, c) for L, c in grid])
    (L, c), best = max(zip(grid, powers), key=lambda pair: pair[1])
    plain = max(P for (L0, _), P in zip(grid, powers) if L0 == 0.0)
    if L == 0.0:
        ruled = max(P for (L0, _), P in zip(grid, powers) if L0 == latches[3])
        print(f"latching: none beats the damper alone at this period (its best {best:.6g} W at pto_damping = {c:.6g}, simulated; "
              f"latching at the rule's (T - T_n) / 2 = {latch:.6g} s at most {ruled:.6g} W): use the damper")  # fmt: skip
        return
    print(f"latching: latch_time = {L:.6g} s, pto_damping = {c:.6g} -> {best:.6g} W simulated, {best / plain:.3g} times the best "
          f"damper's {plain:.6g} W simulated the same way (the grid's best; the rule (T - T_n) / 2 = {latch:.6g} s, Babarit & Clement 2006)")  # fmt: skip

"""`python -m sim gains`: a take-off's best gains in the scene's regular waves, from the frequency domain (control/gains.py):
complex-conjugate (reactive) control and its power |F a|^2 / 8 Re Z, the best damper alone, and a latching time."""

from __future__ import annotations

import math
from dataclasses import dataclass

from sim.control.gains import body_port, system_port
from sim.errors import ConfigError
from sim.scene.config import load_scene, with_overrides
from sim.simulation import Simulation


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
    if latch is not None:
        print(f"latching: latch_time = {latch:.6g} s ((T - T_n) / 2, Babarit & Clement 2006), with pto_damping = {c:.6g}")
    elif p.natural_period is not None:
        half = 0.5 * (p.natural_period - 2 * math.pi / p.omega)
        print(f"latching: none (the waves are shorter than T_n); declutching: declutch_time about {half:.6g} s ((T_n - T) / 2)")
    return 0

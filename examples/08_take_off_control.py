"""Take-off control: the point absorber off resonance, passive, reactive, latched, and driven by your own function

The ice cube on its heave slide in waves 3.5 s long (it rings at 2.2 s). The frequency domain gives what each control
can take (sim.control.gains, the numbers `python -m sim gains` prints): the best damper alone, complex-conjugate control
(a negative spring that tunes the cube to the waves: |F a|^2 / 8 Re Z), latching for (T - T_n) / 2 at each stop. Each
run's mean power over its last ten periods is printed beside it, and a damper written as a Python function beside the
scene's own.
"""

from dataclasses import dataclass

import tyro

from sim import Simulation, load_scene, with_overrides
from sim.control.gains import body_port


@dataclass
class Args:
    period: float = 3.5
    """Wave period, s."""
    height: float = 0.004
    """Wave height, m (small: reactive control's stroke is many wave heights)."""
    t_end: float = 140.0
    """Simulated seconds (the last ten periods are measured)."""


def mean_power(scene, t_end: float, controller=None) -> float:
    """The take-off's mean power over the run's last ten periods, W."""
    sim = Simulation(scene, backend="numpy")
    if controller is not None:
        sim.control(controller)
    period = float(scene.waves.period)
    while sim.state.t < t_end - 10 * period - 1e-9:
        sim.step(1)
    start, t0 = sim.frame().E_pto, sim.state.t
    while sim.state.t < t_end - 1e-9:
        sim.step(1)
    return (sim.frame().E_pto - start) / (sim.state.t - t0)


def main(args: Args) -> None:
    base = with_overrides(load_scene("point-absorber"), waves__period=args.period, waves__height=args.height)
    port = body_port(Simulation(base, backend="numpy"))
    a = 0.5 * args.height
    k, c = port.reactive
    print(f"waves {args.period:g} s, {args.height * 1000:g} mm; the cube's natural period {port.natural_period:.3f} s")
    print(f"{'control':<34}{'run (W)':>12}{'frequency domain (W)':>24}")
    rows = [
        (f"best damper c = {port.passive:.0f} N s/m", dict(constraint__pto_damping=port.passive), port.power(0.0, port.passive, a)),
        (
            f"reactive k = {k:.0f} N/m, c = {c:.0f}",
            dict(constraint__controller="reactive", constraint__pto_stiffness=k, constraint__pto_damping=c),
            port.optimum(a),
        ),  # fmt: skip
    ]
    latch = port.latch_time()
    if latch is not None:
        rows.append((f"latching {latch:.3f} s, c = {c:.0f}", dict(constraint__controller="latching", constraint__latch_time=latch,
                                                                    constraint__pto_damping=c), None))  # fmt: skip
    for name, changes, predicted in rows:
        power = mean_power(with_overrides(base, **changes), args.t_end)
        print(f"{name:<34}{power:>12.4f}{'' if predicted is None else f'{predicted:.4f}':>24}")
    damper = port.passive
    power = mean_power(with_overrides(base, constraint__pto_damping=0.0), args.t_end, lambda t, joint, wave: -damper * joint.rate)
    print(f"{'the best damper as a Python function':<34}{power:>12.4f}{port.power(0.0, damper, a):>24.4f}")


if __name__ == "__main__":
    main(tyro.cli(Args, description=__doc__))

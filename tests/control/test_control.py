"""Take-off control (sim/control/laws.py, control_gains.py): the frequency domain's optimum, the latched oscillator's periodic
orbit, the PI loop's limit, a Python callable, a system of one against one body, and the one-line refusals."""

from __future__ import annotations

import math
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.commands.test_cli import read_csv
from tests.latched import periodic_power

ROOT = Path(__file__).resolve().parents[2]


def _cli(*args: str, backend: str = "numba") -> subprocess.CompletedProcess:
    env = dict(os.environ, FLOATSIM_BACKEND=backend)
    return subprocess.run([sys.executable, "-m", "sim", *args], cwd=ROOT, capture_output=True, text=True, timeout=900, env=env)


def _run(tmp_path, name: str, *flags: str, backend: str = "numba") -> dict:
    out = tmp_path / f"{name}.csv"
    done = _cli("run", *flags, "--every", "1", "--out", str(out), backend=backend)
    assert done.returncode == 0, done.stderr[-2000:]
    header, data = read_csv(out)
    return {column: data[:, i] for i, column in enumerate(header)}


def _gains(*flags: str) -> dict:
    done = _cli("gains", "--no-search", *flags)
    assert done.returncode == 0, done.stderr
    number = r"(-?[\d.]+(?:e[+-]?\d+)?)"
    k, c, best = re.search(
        rf"reactive \(complex-conjugate\): pto_stiffness = {number}, pto_damping = {number} -> {number} W", done.stdout
    ).groups()
    latch = re.search(rf"latch_time = {number} s", done.stdout)
    return {"k": float(k), "c": float(c), "P": float(best), "latch": float(latch.group(1)) if latch else None, "text": done.stdout}


def _mean_power(run: dict, energy: str, period: float, periods: int = 10) -> float:
    """The mean of the absorbed power over the last whole periods: the slope of the CSV's absorbed energy."""
    t, E = run["t"], run[energy]
    end = t[-1]
    return float((E[-1] - np.interp(end - periods * period, t, E)) / (periods * period))


@pytest.mark.slow
def test_reactive_control_of_the_point_absorber_absorbs_the_complex_conjugate_optimum(tmp_path):
    """The 1 m cube in waves 3.5 s long (its natural period is 2.2 s: the optimal spring is negative). `gains` gives
    complex-conjugate control's k and c and its power, which is |X3|^2 a^2 / (8 B33) of the BEM solve; the run with those
    gains absorbs it within 2 % (measured 0.1 %), and the best damper alone a twelfth of it."""
    from sim import Simulation
    from sim.hydro.diffraction import transfer_at
    from sim.scene.config import load_scene, with_overrides

    T, H = 3.5, 0.004  # small waves: the motion at the optimum stays well inside the cube's 0.1 m freeboard
    gains = _gains("--scene", "point-absorber", "--wave-period", str(T), "--wave-height", str(H))
    c = Simulation(with_overrides(load_scene("point-absorber"), waves__period=T), backend="numpy").model.radiation.coefficients
    w = 2 * math.pi / T
    B33 = np.interp(w, c.omega, c.damping[:, 2, 2])
    X3 = (transfer_at(c, c.froude_krylov, w, 0.0) + transfer_at(c, c.diffraction, w, 0.0))[0, 2]
    assert gains["k"] < 0.0
    assert gains["P"] == pytest.approx(abs(X3) ** 2 * (H / 2) ** 2 / (8 * B33), rel=1e-4)
    flags = ("--scene", "point-absorber", "--wave-period", str(T), "--wave-height", str(H), "--t-end", str(40 * T))
    run = _run(
        tmp_path, "reactive", *flags, "--controller", "reactive", "--pto-stiffness", repr(gains["k"]), "--pto-damping", repr(gains["c"])
    )
    assert _mean_power(run, "E_pto", T) == pytest.approx(gains["P"], rel=0.02)
    passive = float(re.search(r"passive \(the best damper\): pto_damping = \S+ -> (\S+) W", gains["text"]).group(1))
    assert passive < gains["P"] / 10


@pytest.mark.slow
def test_reactive_control_of_rm3_absorbs_the_two_body_optimum(tmp_path):
    """rm3's float on its spar (which heaves too) in waves 5.5 s long: the take-off sees the two bodies' impedance at its
    joint. Its optimum (a negative spring, inside the bound the spar's heave sets) is what the run absorbs within 2 %
    (measured 0.4 %); and the port's power formula agrees with the two-body frequency-domain solve with that take-off."""
    from dataclasses import replace

    from sim import Simulation
    from sim.control.gains import system_port
    from sim.scene.config import load_scene, with_overrides
    from sim.system.frequency import response

    T, H = 5.5, 0.2
    gains = _gains("--scene", "rm3", "--body", "float", "--wave-period", str(T), "--wave-height", str(H))
    assert gains["k"] < 0.0
    text = (ROOT / "assets" / "scenes" / "rm3.toml").read_text().replace("../meshes/", str(ROOT / "assets" / "meshes") + "/")
    text = (
        text.replace("height = 2.5", f"height = {H}").replace("period = 8.0", f"period = {T}").replace("t_end = 400.0", f"t_end = {50 * T}")
    )
    text = text.replace("pto_damping = 1.2e6", f'controller = "reactive"\npto_stiffness = {gains["k"]!r}\npto_damping = {gains["c"]!r}')
    scene = tmp_path / "rm3-reactive.toml"
    scene.write_text(text)
    run = _run(tmp_path, "rm3", "--scene", str(scene))
    assert _mean_power(run, "float_E_pto", T) == pytest.approx(gains["P"], rel=0.02)
    # the port against the whole system's solve, at a frequency of the solve's grid
    asm = Simulation(load_scene(str(scene)), backend="numpy")
    c = asm.system.radiation.coefficients
    i = int(np.argmin(abs(c.omega - 2 * math.pi / T)))
    asm.scene = with_overrides(asm.scene, waves__period=2 * math.pi / float(c.omega[i]))
    port = system_port(asm, "float")
    s0 = replace(asm.start, theta=np.zeros_like(asm.start.theta))
    xi = response(asm.system, s0, i)[1]  # the float's stroke per unit amplitude, with the take-off in the solve
    solved = 0.5 * gains["c"] * (float(c.omega[i]) * abs(xi)) ** 2
    assert port.power(gains["k"], gains["c"], 1.0) == pytest.approx(solved, rel=1e-6)


def _cube_oscillator(T: float, H: float) -> tuple[float, float, float, float]:
    """(m, C, F, omega) of the point-absorber's cube heaving without radiation: the mass, rho g L^2 and the Froude-Krylov
    force on its bottom (deep water, draft 0.9 m): rho g a e^(-k d) L (2 / k) sin(k L / 2)."""
    rho, g, L, d = 1000.0, 9.81, 1.0, 0.9
    omega = 2 * math.pi / T
    k = omega**2 / g
    return 900.0 * L**3, rho * g * L**2, rho * g * 0.5 * H * math.exp(-k * d) * L * 2 * math.sin(k * L / 2) / k, omega


@pytest.mark.slow
def test_the_latching_gains_recommends_beat_the_best_damper_and_run_as_said(tmp_path):
    """point-absorber in waves 3.5 s long (T_n 2.2 s): `gains` searches latch time and damping together in the time domain.
    Its damper alone (latch time 0) at |Z| absorbs the frequency domain's best damper power (within 1 %: measured 0.04 %);
    the latching pair it recommends beats it (measured 3x), and a run with that pair absorbs what it said (within 2 %)."""
    done = _cli("gains", "--scene", "point-absorber", "--wave-period", "3.5")
    assert done.returncode == 0, done.stderr
    number = r"(-?[\d.]+(?:e[+-]?\d+)?)"
    damper = float(re.search(rf"passive \(the best damper\): pto_damping = \S+ -> {number} W", done.stdout).group(1))
    latch, c, power, times, simulated = map(float, re.search(
        rf"latching: latch_time = {number} s, pto_damping = {number} -> {number} W simulated, {number} times the best damper's {number} W",
        done.stdout).groups())  # fmt: skip
    assert simulated == pytest.approx(damper, rel=0.01)
    assert power > 1.5 * damper and times == pytest.approx(power / simulated, rel=1e-3)
    run = _run(tmp_path, "latched", "--scene", "point-absorber", "--wave-period", "3.5", "--controller", "latching", "--latch-time",
               repr(latch), "--pto-damping", repr(c), "--t-end", "70", backend="numpy")  # fmt: skip
    assert _mean_power(run, "E_pto", 3.5) == pytest.approx(power, rel=0.02)


@pytest.mark.slow
def test_latching_and_declutching_follow_the_latched_oscillators_periodic_orbit(tmp_path):
    """The cube without radiation is the textbook oscillator m x'' + b x' + C x = F cos(omega t). In waves 3 s long (its
    natural period is 1.9 s), latching it for (T - T_n) / 2 at each stop (Babarit & Clement 2006) brings its motion into
    phase with the force: the run absorbs the periodic orbit's power (tests/latched.py) within 2 % (measured 0.5 % at
    dt = 5 ms; first order in dt, from the latch's timing), 16 times the best damper's F^2 / (4 |C / omega - m omega|).
    Declutching for 0.3 s after each stop follows its orbit likewise (measured 0.002 %)."""
    T, H, c = 3.0, 0.004, 300.0
    m, C, F, omega = _cube_oscillator(T, H)
    Tn = 2 * math.pi * math.sqrt(m / C)
    latch = 0.5 * (T - Tn)
    flags = ("--scene", "point-absorber", "--radiation", "none", "--wave-period", str(T), "--wave-height", str(H), "--dt", "0.005",
             "--t-end", str(60 * T), "--pto-damping", str(c))  # fmt: skip
    latched = _run(tmp_path, "latching", *flags, "--controller", "latching", "--latch-time", repr(latch))
    expected, _ = periodic_power(m, C, F, omega, [(None, latch), (c, T / 2 - latch)])
    assert _mean_power(latched, "E_pto", T) == pytest.approx(expected, rel=0.02)
    best_damper = F**2 / (4 * abs(C / omega - m * omega))
    assert _mean_power(latched, "E_pto", T) > 10 * best_damper
    held = np.abs(latched["uz"]) < 1e-12  # latched: the rate is zero, for about 2 t_L of every period
    assert np.mean(held[latched["t"] > 30 * T]) == pytest.approx(2 * latch / T, abs=0.01)
    declutched = _run(tmp_path, "declutching", *flags, "--controller", "declutching", "--declutch-time", "0.3")
    expected, _ = periodic_power(m, C, F, omega, [(0.0, 0.3), (c, T / 2 - 0.3)])
    assert _mean_power(declutched, "E_pto", T) == pytest.approx(expected, rel=0.02)
    free = declutched["F_pto"] == 0.0
    assert np.mean(free[declutched["t"] > 30 * T]) == pytest.approx(0.6 / T, abs=0.01)


SYSTEM_OF_ONE = """
[fluid]
forces = "panels"

[waves]
kind = "regular"
height = 0.004
period = 3.0

[[bodies]]
name = "cube"
shape = "cube"
size = 1.0
density = 900.0
position = [0.0, 0.0, -0.4]
joint = "prismatic"
axis = [0.0, 0.0, 1.0]
pto_damping = 300.0
controller = "latching"
latch_time = 0.5484

[step]
dt = 0.005
t_end = 60.0
"""


@pytest.mark.slow
@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_a_system_of_one_latches_as_the_body_does(tmp_path, backend):
    """The latching cube as one [[bodies]] entry (the system's kick, with the locked joint taken out of it; compiled,
    the law packed into its tree at each step) moves and absorbs as the one-body run does, to 1e-6 of its stroke and
    its energy."""
    scene = tmp_path / "latched-system.toml"
    scene.write_text(SYSTEM_OF_ONE)
    system = _run(tmp_path, f"system-{backend}", "--scene", str(scene), backend=backend)
    one = _run(tmp_path, "one", "--scene", "point-absorber", "--radiation", "none", "--wave-period", "3", "--wave-height", "0.004",
               "--dt", "0.005", "--t-end", "60", "--pto-damping", "300", "--controller", "latching", "--latch-time", "0.5484")  # fmt: skip
    stroke = one["z"] - one["z"][0]
    assert np.abs(stroke).max() > 0.01
    np.testing.assert_allclose(system["cube_theta"], stroke, atol=1e-6 * np.abs(stroke).max())
    np.testing.assert_allclose(system["cube_E_pto"], one["E_pto"], atol=1e-6 * one["E_pto"][-1])


@pytest.mark.slow
def test_a_latched_decay_keeps_the_energy_balance(tmp_path):
    """In still water, released 5 cm high with latching and a damper (no other damping): E_total + E_pto (the lock's
    share of the kinetic energy counted) stays the starting energy to the scheme's order, and the lock held the joint
    for part of the time."""
    from sim import Simulation
    from sim.scene.config import load_scene, with_overrides

    path = tmp_path / "latched-system.toml"
    path.write_text(SYSTEM_OF_ONE)
    gaps = []
    for dt in (0.004, 0.002):
        sim = Simulation(with_overrides(load_scene(str(path)), waves__kind="still", cube__start=0.05, step__dt=dt), backend="numpy")
        first, locked = sim.frame(), 0
        while sim.state.t < 6.0 - 1e-9:
            sim.step(1)
            locked += sim.system.laws[0].held
        last = sim.frame()
        gaps.append(abs(last.E_total + last.E_pto - first.E_total))
        assert locked > 0.1 * round(6.0 / dt) and last.E_pto > 0.5 * (first.E_total - last.E_total)
    assert gaps[1] < 5e-3 * last.E_pto and gaps[1] < gaps[0], gaps


@pytest.mark.slow
def test_the_pi_loop_is_the_reactive_law_until_its_limit_and_holds_the_limit(tmp_path):
    """PI on the rate (Kp = pto_damping, Ki = pto_stiffness) is the spring and damper about its start: the same run to
    round-off. With pto_max_force its force is held at the limit where the law would pass it (checked at each step's
    start: within a step the law's force runs on by at most one step's change)."""
    flags = ("--scene", "point-absorber", "--t-end", "10", "--pto-damping", "300", "--pto-stiffness", "2000")
    passive = _run(tmp_path, "passive", *flags)
    pi = _run(tmp_path, "pi", *flags, "--controller", "pi")
    np.testing.assert_allclose(pi["z"], passive["z"], atol=1e-9)
    np.testing.assert_allclose(pi["F_pto"], passive["F_pto"], atol=1e-6 * np.abs(passive["F_pto"]).max())
    limit = float(0.5 * np.abs(passive["F_pto"]).max())
    limited = _run(tmp_path, "limited", *flags, "--controller", "pi", "--pto-max-force", repr(limit))
    one_step = np.abs(np.diff(passive["F_pto"])).max()  # the limit holds at each step's start: within one, the law runs on
    assert limit < np.abs(limited["F_pto"]).max() <= limit + one_step
    assert np.mean(np.isclose(np.abs(limited["F_pto"]), limit, rtol=1e-12, atol=0.0)) > 0.05


def test_a_python_callable_drives_the_take_off():
    """`Simulation.control(fn)`: a damper written as a callable (its force held over each step, explicit) absorbs what
    the scene's damper does (implicit) within 1 %; the wave state it reads is the sea's surface over the body (the CSV's
    eta where the body started)."""
    from sim import Simulation
    from sim.scene.config import load_scene

    scene = load_scene("point-absorber")
    reference = Simulation(scene, backend="numpy")
    reference.step(1000)
    seen = {}

    def damper(t, joint, wave):
        seen[round(t, 9)] = wave.eta
        return -2000.0 * joint.rate

    sim = Simulation(scene, backend="numpy")
    sim.control(damper)
    frames = {}
    for _ in range(1000):
        frames[round(sim.state.t, 9)] = sim.frame().eta
        sim.step(1)
    assert sim.frame().E_pto == pytest.approx(reference.frame().E_pto, rel=0.01)
    times = sorted(frames)
    np.testing.assert_allclose([seen[t] for t in times], [frames[t] for t in times], atol=1e-12)
    assert np.ptp(list(seen.values())) > 0.09
    sim.control(None)  # back to the scene's damper
    assert sim.controller.name == "passive"


def test_a_limited_damper_is_coulomb_friction():
    """Past pto_max_force F a damper is Coulomb friction: amplitude falls 2F/k a half swing, P_pto = -F_pto z' (guards Law.at's sign)."""
    from sim import Simulation
    from sim.scene.config import load_scene, with_overrides

    m, k, limit, z0, dt = 500.0, 1000.0 * 9.81 * 1.0, 100.0, 0.1, 0.01  # the wall-sided cube: m z'' = -k z - F sign z' (Den Hartog)
    scene = with_overrides(load_scene("drop"), body__density=500.0, fluid__forces="panels", fluid__damping=0.0, step__dt=dt,
                           initial__position=(0.0, 0.0, z0), constraint__joint="prismatic", constraint__pto_damping=1e5,
                           constraint__pto_max_force=limit)  # fmt: skip
    sim = Simulation(scene, backend="numpy")
    t, z = [0.0], [z0]
    while sim.state.t < 2.5 - 1e-9:
        sim.step(1)
        f = sim.frame()
        t.append(f.t)
        z.append(f.x_world[2])
        assert f.P_pto == pytest.approx(-f.F_pto * sim.state.u_world[2], rel=1e-9, abs=1e-9)
    t, z = np.array(t), np.array(z)
    i = np.flatnonzero((np.abs(z[1:-1]) >= np.abs(z[:-2])) & (np.abs(z[1:-1]) > np.abs(z[2:]))) + 1  # the turning points
    a, b, c = z[i - 1], z[i], z[i + 1]
    d = 0.5 * (a - c) / (a - 2 * b + c)  # a parabola through each and its neighbours
    peaks, n = b - 0.25 * (a - c) * d, np.arange(1, len(i) + 1)
    assert len(i) == 3
    np.testing.assert_allclose(peaks, (-1.0) ** n * (z0 - 2.0 * n * limit / k), atol=0.01 * limit / k)  # 1 % of the offset F / k
    np.testing.assert_allclose(t[i] + d * dt, n * math.pi * math.sqrt(m / k), atol=dt)  # the undamped half period


@pytest.mark.parametrize(
    "flags, message",
    [
        (("--pto-stiffness", "-100"), 'needs controller = "reactive"'),
        (("--controller", "reactive", "--pto-stiffness", "-15000"), "keep pto_stiffness > -9810"),
        (("--controller", "latching"), "latching control needs [constraint] latch_time > 0"),
        (("--controller", "pi", "--joint", "free"), "it needs a prismatic or revolute joint"),
    ],
)
def test_a_controller_it_cannot_run_is_one_line(flags, message):
    done = _cli("run", "--scene", "point-absorber", "--t-end", "0.1", *flags)
    assert done.returncode == 2 and message in done.stderr and len(done.stderr.strip().splitlines()) == 1, done.stderr


def test_gains_refuses_what_it_cannot_tune_in_one_line():
    for flags, message in ((("--scene", "drop"), "regular waves"), (("--scene", "rm3"), "--body NAME")):
        done = _cli("gains", *flags)
        assert done.returncode == 2 and message in done.stderr and len(done.stderr.strip().splitlines()) == 1, done.stderr

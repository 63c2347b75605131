"""Farms ([farm], sim/scene/farm.py): the grid laid out as [[bodies]], each device's power (without radiation: the one
device's), the refusals and the BEM solve's memory limit."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from sim.errors import ConfigError
from sim.scene.config import load_scene, with_overrides

ROOT = Path(__file__).resolve().parents[2]


def test_the_farm_preset_is_its_device_on_a_grid():
    """Six copies d1..d6, row by row, 10 m apart from where the scene places its one device, each on its own slide with
    its own take-off; the [farm] table goes back to one device once laid out (validating again changes nothing)."""
    farm = load_scene("farm")
    device = load_scene("point-absorber")
    assert [e.name for e in farm.bodies] == [f"d{i}" for i in range(1, 7)]
    for i, e in enumerate(farm.bodies):
        row, column = divmod(i, 3)
        np.testing.assert_allclose(e.initial.position, np.add(device.initial.position, (10.0 * column, 10.0 * row, 0.0)))
        assert (e.constraint.joint, e.constraint.pto_damping, e.parent) == ("prismatic", 2000.0, "world")
    assert (farm.farm.rows, farm.farm.columns) == (1, 1)
    assert with_overrides(farm, d3__pto_damping=500.0).bodies[2].constraint.pto_damping == 500.0  # one device's own take-off
    rm3 = with_overrides(load_scene("rm3"), farm__columns=2, farm__spacing=100.0)  # a device of several bodies
    assert [(e.name, e.parent) for e in rm3.bodies] == [("d1_spar", "world"), ("d1_float", "d1_spar"), ("d2_spar", "world"),
                                                        ("d2_float", "d2_spar")]  # fmt: skip
    assert rm3.bodies[3].initial.position[0] == pytest.approx(100.0)


@pytest.mark.slow
def test_each_device_of_a_farm_without_radiation_takes_the_one_devices_power(tmp_path):
    """Two devices 10 m apart without radiation do not feel one another: each one's mean take-off power over the last
    five wave periods is the one device's (the point absorber alone, run on its own) within 1e-4 (their starts differ by the
    wave's phase between them, a transient gone to 1e-5 by then)."""
    env = dict(os.environ, FLOATSIM_BACKEND="numpy")
    flags = ["--radiation", "none", "--t-end", "22", "--every", "1"]
    one, two = tmp_path / "one.csv", tmp_path / "two.csv"
    scene = tmp_path / "pair.toml"
    text = (ROOT / "assets" / "scenes" / "farm.toml").read_text().replace("rows = 2", "rows = 1").replace("columns = 3", "columns = 2")
    scene.write_text(text.replace("damping = 100.0", "damping = 0.0"))
    for args, out in ((["--scene", str(scene)], two), (["--scene", "point-absorber", "--damping", "0"], one)):
        done = subprocess.run([sys.executable, "-m", "sim", "run", *args, *flags, "--out", str(out)], cwd=ROOT, env=env,
                              capture_output=True, text=True, timeout=600)  # fmt: skip
        assert done.returncode == 0, done.stderr[-1500:]
    a = np.genfromtxt(one, delimiter=",", names=True)
    b = np.genfromtxt(two, delimiter=",", names=True)

    def mean_power(t, E):
        return (E[-1] - np.interp(t[-1] - 5 * 2.2, t, E)) / (5 * 2.2)

    alone = mean_power(a["t"], a["E_pto"])
    assert alone > 0.1
    for d in ("d1", "d2"):
        assert mean_power(b["t"], b[f"{d}_E_pto"]) == pytest.approx(alone, rel=1e-4), d


def test_a_farm_it_cannot_build_is_one_line(tmp_path):
    text = (ROOT / "assets" / "scenes" / "moored-buoy.toml").read_text() + "\n[farm]\nrows = 2\n"
    scene = tmp_path / "moored-farm.toml"
    scene.write_text(text)
    done = subprocess.run([sys.executable, "-m", "sim", "run", "--scene", str(scene), "--t-end", "0.1"], cwd=ROOT, capture_output=True,
                          text=True, timeout=300)  # fmt: skip
    assert done.returncode == 2 and "[farm] with [moorings]" in done.stderr and len(done.stderr.strip().splitlines()) == 1, done.stderr


def test_a_solve_past_the_memory_is_refused_with_its_numbers(monkeypatch):
    """The joint solve's dense matrices, 32 N^2 bytes: refused past half the memory available, before any is made."""
    from sim import limits
    from sim.hydro import bem

    monkeypatch.setattr(limits, "available_bytes", lambda: 1.0e9)
    bem.check_panels(3000, 5)  # 288 MB: within 500 MB
    with pytest.raises(ConfigError, match="4000 wet panels: its matrices take about 0.512 GB, over the 0.5 GB"):
        bem.check_panels(4000, 6)


def _pair(spacing: float, omega: float | None = None):
    """point-absorber's farm of two, `spacing` apart along x (the waves' heading), in waves 10 cm high at the solve's
    frequency nearest 2 pi / 2.2 s (or at `omega`): (system, rest, frequency index)."""
    from sim.system.tree import build

    system, _ = build(with_overrides(load_scene("point-absorber"), farm__rows=1, farm__columns=2, farm__spacing=spacing))
    c = system.radiation.coefficients
    i = int(np.argmin(abs(c.omega - (2 * np.pi / 2.2 if omega is None else omega))))
    scene = with_overrides(load_scene("point-absorber"), farm__rows=1, farm__columns=2, farm__spacing=spacing,
                           waves__period=2 * np.pi / float(c.omega[i]), waves__ramp=0.0)  # fmt: skip
    system, rest = build(scene)
    return system, rest, i


def _mean_powers(system, start, omega: float, periods: int = 6, per_period: int = 110) -> np.ndarray:
    """Each take-off's mean power over `periods` wave periods from `start`, W."""
    dt, s = 2 * np.pi / omega / per_period, start
    for _ in range(periods * per_period):
        s = system.step(s, dt)
    return (s.absorbed - start.absorbed) / (s.t - start.t)


@pytest.mark.slow
def test_two_devices_close_together_take_the_pairs_frequency_domain_power(monkeypatch, tmp_path):
    """Two point absorbers 3 m apart in a row along the waves, solved together (the shipped solve: 2560 panels). Started on
    the pair's linear steady state, six periods of the time-domain run (the radiation memory coupling both devices, the
    diffraction, the exact hydrostatics) give each device's mean power within 2 % of the frequency-domain solve of the
    pair. The devices feel each other: each one's interaction factor q = P / P_alone (the lone device's power with its
    own solve) differs from 1 by more than the 2 % tolerance, the front one's and the back one's differently, and the run's
    q matches the frequency domain's within 2 %."""
    import sim.hydro.bem as bem
    from sim.system.frequency import response, steady_start
    from sim.system.tree import build

    monkeypatch.setenv("FLOATSIM_BEM_CACHE", str(tmp_path))
    monkeypatch.setattr(bem, "solve_parts", lambda *a, **k: pytest.fail("the shipped farm coefficients were not found"))
    a = 0.05
    system, rest, i = _pair(3.0)
    w = float(system.radiation.coefficients.omega[i])
    xi = response(system, rest, i)
    slides = sorted(system.joints, key=lambda g: g.name)
    expected = np.array([0.5 * g.damping * w * w * abs(a * xi[g.dofs.start]) ** 2 for g in slides])
    powers = _mean_powers(system, steady_start(system, rest, xi, w, a), w)
    got = np.array([powers[g.coordinate] for g in slides])
    from dataclasses import replace

    from sim.scene.config import BodyEntry, ConstraintConfig, InitialConfig, validate

    one = with_overrides(load_scene("point-absorber"), waves__period=2 * np.pi / w, waves__ramp=0.0)  # the lone device as a system of one
    alone_system, alone_rest = build(
        validate(
            replace(
                one,
                bodies=(BodyEntry("d1", "world", one.body, one.initial, one.constraint),),
                initial=InitialConfig(),
                constraint=ConstraintConfig(),
                body=type(one.body)(),
            )
        )
    )
    c1 = alone_system.radiation.coefficients
    j = int(np.argmin(abs(c1.omega - w)))
    assert abs(c1.omega[j] / w - 1) < 1e-3  # the same frequency in both solves
    alone = (
        0.5
        * alone_system.joints[0].damping
        * w
        * w
        * abs(a * response(alone_system, alone_rest, j)[alone_system.joints[0].dofs.start]) ** 2
    )
    q_expected, q_got = expected / alone, got / alone
    print(f"omega {w:.4f}: P alone {alone:.4g} W; pair expected {expected}, run {got}; q expected {q_expected}, run {q_got}")
    np.testing.assert_allclose(got, expected, rtol=0.02)
    assert np.all(abs(q_expected - 1) > 0.02) and abs(q_expected[0] - q_expected[1]) > 0.01
    np.testing.assert_allclose(q_got, q_expected, rtol=0.02)


def test_devices_that_would_overlap_are_refused_in_one_line(tmp_path):
    """Cubes 1 m wide on a grid 0.1 m apart would start inside one another (before: run without a word): refused in one
    line naming the spacing that clears them; 1 m apart (touching) they run. A turned cube reaches its half diagonal."""
    scene = tmp_path / "close.toml"
    scene.write_text((ROOT / "assets" / "scenes" / "farm.toml").read_text().replace("spacing = 10.0", "spacing = 0.1"))
    done = subprocess.run([sys.executable, "-m", "sim", "run", "--scene", str(scene), "--t-end", "0.01"], cwd=ROOT, capture_output=True,
                          text=True, timeout=120)  # fmt: skip
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert "neighbouring devices overlap along x" in done.stderr and "spacing >= 1 m" in done.stderr
    with_overrides(load_scene("farm"), farm__spacing=1.0)  # touching: accepted
    with pytest.raises(ConfigError, match=r"spacing >= 1.73"):
        with_overrides(load_scene("drop"), initial__orientation=(0.9238795, 0.3826834, 0.0, 0.0), farm__columns=2, farm__spacing=1.2)


def _two_cubes(tmp_path: Path, x: float, yaw_deg: float = 0.0, jointed: bool = False) -> str:
    """Two 1 m cubes, the second x metres along and turned yaw_deg about z (or jointed to the first by a fixed joint)."""
    w, z = np.cos(np.radians(yaw_deg) / 2), np.sin(np.radians(yaw_deg) / 2)
    second = 'parent = "a"\njoint = "fixed"\n' if jointed else ""
    scene = tmp_path / f"two_{x}_{yaw_deg}_{jointed}.toml"
    scene.write_text(f'[[bodies]]\nname = "a"\nshape = "cube"\nsize = 1.0\ndensity = 500.0\n\n[[bodies]]\nname = "b"\n{second}'
                     f'shape = "cube"\nsize = 1.0\ndensity = 500.0\nposition = [{x}, 0.0, 0.0]\norientation = [{w}, 0.0, 0.0, {z}]\n')  # fmt: skip
    return str(scene)


@pytest.mark.parametrize("x, yaw, jointed, inside", [
    (0.3, 0.0, False, 0.7),  # the campaign's case: 0.7 m into one another
    (1.0, 0.0, False, None),  # touching: apart
    (1.2, 45.0, False, 0.00711),  # turned 45 degrees it reaches its half diagonal, 0.7071 m: 0.0071 m in
    (1.25, 45.0, False, None),
    (0.3, 0.0, True, None),  # a body and its parent may meet at their joint
])  # fmt: skip
def test_bodies_that_would_start_inside_one_another_are_refused(tmp_path, x, yaw, jointed, inside):
    """Issue 59: [[bodies]] placed inside one another ran without a word. Two boxes are compared by the separating-axis
    test: refused in one line with how far they reach in, before anything is built."""
    scene = _two_cubes(tmp_path, x, yaw, jointed)
    if inside is None:
        load_scene(scene)
        return
    with pytest.raises(ConfigError, match=rf"\[\[bodies\]\] a and b start inside one another \(by {inside:.3g} m\)"):
        load_scene(scene)

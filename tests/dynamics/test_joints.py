"""Issue 26, joints to the world with a power take-off: closed forms (a wall-sided body's damped heave on a
prismatic joint, a hinged body's pendulum period at large amplitude), the energy the take-off absorbs
closing the balance to the scheme's order, stability for any take-off damping, a joint that never drifts,
and the user's path (flags, CSV, mistakes)."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.special import ellipk

from sim import Simulation, load_scene, with_overrides

ROOT = Path(__file__).resolve().parents[2]
RHO, G = 1000.0, 9.81


def heave_scene(dt: float, damping: float = 1000.0, stiffness: float = 0.0, z0: float = 0.1, **extra):
    """The 1 m cube at 500 kg/m^3 (floating half out, its walls vertical: a linear spring rho g A) on a vertical
    slide, released z0 above its rest, with a take-off of that damping and stiffness."""
    return with_overrides(load_scene("drop"), body__density=500.0, fluid__forces="panels", fluid__damping=0.0, initial__position=(0.0, 0.0, z0),
                          constraint__joint="prismatic", constraint__pto_damping=damping, constraint__pto_stiffness=stiffness, step__dt=dt,
                          **extra)  # fmt: skip


def heave(dt: float, damping: float, stiffness: float, t_end: float = 5.0) -> tuple[np.ndarray, np.ndarray, Simulation]:
    sim = Simulation(heave_scene(dt, damping, stiffness))
    t, z = [], []
    while sim.state.t < t_end - 1e-9:
        sim.step(1)
        t.append(sim.state.t)
        z.append(sim.state.x_world[2])
    return np.array(t), np.array(z), sim


def damped_heave(t: np.ndarray, z0: float, m: float, k: float, c: float) -> np.ndarray:
    w0 = math.sqrt(k / m)
    zeta = c / (2 * m * w0)
    wd = w0 * math.sqrt(1 - zeta**2)
    return z0 * np.exp(-zeta * w0 * t) * (np.cos(wd * t) + zeta * w0 / wd * np.sin(wd * t))


def test_a_sliding_wall_sided_body_heaves_as_the_damped_oscillator_at_second_order():
    """m z'' = -rho g A z - k (z - z0) - c z' (the take-off's spring about the starting pose): the closed form,
    with the error falling 4x per halved step."""
    m, A, k = 500.0, 1.0, 2000.0
    rest = k * 0.1 / (RHO * G * A + k)  # where the water's and the take-off's springs balance
    errors = []
    for dt in (0.01, 0.005, 0.0025):
        t, z, sim = heave(dt, damping=1000.0, stiffness=k)
        assert sim.body.mass == pytest.approx(m)
        errors.append(np.abs(z - rest - damped_heave(t, 0.1 - rest, m, RHO * G * A + k, 1000.0)).max())
    assert (
        errors[-1] < 2e-6 and errors[0] / errors[1] == pytest.approx(4.0, rel=0.1) and errors[1] / errors[2] == pytest.approx(4.0, rel=0.1)
    ), errors


def test_the_waters_damping_acts_along_the_slide():
    """The water's heave damping alone on the slide: m z'' = -rho g A z - B33 z' in closed form (guards J^T D J in joints._affine)."""
    B = 800.0
    sim = Simulation(heave_scene(0.01, damping=0.0, fluid__heave_damping=B), backend="numpy")
    t, z = [], []
    while sim.state.t < 3.0 - 1e-9:
        sim.step(1)
        t.append(sim.state.t)
        z.append(sim.state.x_world[2])
    error = np.abs(np.array(z) - damped_heave(np.array(t), 0.1, 500.0, RHO * G * 1.0, B)).max()
    assert error < 1e-4, error


def test_the_take_off_absorbs_what_the_body_loses():
    """Without other damping, E_total + the take-off spring's energy + E_pto stays the starting energy to the
    scheme's order (4x closer per halved step), and E_pto is the integral of P_pto."""
    gaps = []
    for dt in (0.01, 0.005):
        sim = Simulation(heave_scene(dt, damping=800.0, stiffness=1500.0))
        e0 = sim.frame().E_total
        powers, times = [sim.frame().P_pto], [0.0]
        while sim.state.t < 4.0 - 1e-9:
            sim.step(1)
            f = sim.frame()
            powers.append(f.P_pto)
            times.append(f.t)
        f = sim.frame()
        spring = 0.5 * 1500.0 * (f.x_world[2] - 0.1) ** 2
        gaps.append(abs(f.E_total + spring + f.E_pto - e0))
        assert f.E_pto == pytest.approx(np.trapezoid(powers, times), rel=5e-3)
        assert f.E_pto > 0.5 * (e0 - f.E_total - spring)  # most of the energy went to the take-off
    assert gaps[1] < gaps[0] / 3.0 and gaps[1] < 5e-3 * sim.frame().E_pto, gaps


def test_a_hinged_body_swings_with_the_pendulum_period_at_large_amplitude():
    """In air (rho = 0), the cube on a horizontal hinge 1 m above its centre, started 0.6 rad out: the exact
    period 4 sqrt(I_p / (m g d)) K(sin(theta_0 / 2)) of the physical pendulum, I_p = I + m d^2."""
    theta0, d = 0.6, 1.0
    q0 = (math.cos(theta0 / 2), math.sin(theta0 / 2), 0.0, 0.0)  # turned about x
    scene = with_overrides(load_scene("drop"), fluid__rho=0.0, fluid__forces="panels", initial__position=(0.0, d * math.sin(theta0), -d * math.cos(theta0)),
                           initial__orientation=q0, constraint__joint="revolute", constraint__axis=(1.0, 0.0, 0.0),
                           constraint__pivot=(0.0, -d * math.sin(theta0), d * math.cos(theta0)), step__dt=0.002)  # fmt: skip
    sim = Simulation(scene, backend="numpy")
    m, inertia = sim.body.mass, sim.body.inertia[0]
    k = math.sin(theta0 / 2) ** 2
    period = 4 * math.sqrt((inertia + m * d * d) / (m * G * d)) * ellipk(k)
    t, y = [], []
    while sim.state.t < 2.2 * period:
        sim.step(5)
        t.append(sim.state.t)
        y.append(sim.state.x_world[1])
    t, y = np.array(t), np.array(y)
    ups = [t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i]) for i in range(len(y) - 1) if y[i] < 0 <= y[i + 1]]
    assert len(ups) >= 2 and ups[1] - ups[0] == pytest.approx(period, rel=1e-4), (ups, period)
    pivot = np.array([0.0, 0.0, 0.0])
    assert np.linalg.norm(sim.state.x_world - pivot) == pytest.approx(d, abs=1e-12)  # on its circle


def test_a_hinge_winds_its_spring_up_through_whole_turns():
    """In air, the cube on a vertical hinge through its centre with a torsion spring k, started at rest with
    a spin of amplitude 4 rad (past half a turn): omega_z(t) = 4 W cos(W t), W = sqrt(k / I), whatever the
    amplitude. A coordinate read from the pose alone would flip the spring's pull at half a turn."""
    amplitude, k = 4.0, 2000.0
    scene = with_overrides(load_scene("drop"), fluid__rho=0.0, fluid__forces="panels", constraint__joint="revolute",
                           constraint__axis=(0.0, 0.0, 1.0), constraint__pto_stiffness=k, step__dt=0.002)  # fmt: skip
    inertia = Simulation(scene, backend="numpy").body.inertia[2]
    w = math.sqrt(k / inertia)
    sim = Simulation(with_overrides(scene, initial__omega=(0.0, 0.0, amplitude * w)), backend="numpy")
    t, spin, energy = [], [], []
    while sim.state.t < 1.6 * 2 * math.pi / w:
        sim.step(5)
        t.append(sim.state.t)
        spin.append(sim.frame().omega_world[2])
        energy.append(sim.frame().E_kin + 0.5 * k * sim.joint_theta**2)  # the spring's energy from the counted turns
    t, spin, energy = np.array(t), np.array(spin), np.array(energy)
    assert np.max(np.abs(spin - amplitude * w * np.cos(w * t))) < 1e-3 * amplitude * w
    assert np.ptp(energy) < 1e-4 * energy[0]
    assert sim.joint_theta == pytest.approx(amplitude * math.sin(w * sim.state.t), abs=1e-3 * amplitude)


def test_any_take_off_damping_is_stable_and_creeps_at_the_physical_rate():
    """c = 1e9 N s/m at dt = 0.01 s (c dt / m = 2e4): no blow-up; the body creeps down at the overdamped rate
    (rho g A) / c, its energy never rising."""
    sim = Simulation(heave_scene(0.01, damping=1e9))
    energies, z = [sim.frame().E_total], [sim.state.x_world[2]]
    for _ in range(100):
        sim.step(10)
        energies.append(sim.frame().E_total)
        z.append(sim.state.x_world[2])
    assert np.all(np.diff(energies) <= 1e-9) and np.all(np.diff(z) < 0) and z[-1] > 0
    rate = RHO * G * 1.0 / 1e9
    assert z[-1] == pytest.approx(0.1 * math.exp(-rate * sim.state.t), rel=1e-6)


@pytest.mark.slow
@pytest.mark.parametrize("joint", ["prismatic", "revolute", "fixed"])
def test_the_joint_never_drifts(joint):
    """In a JONSWAP sea with drag for 1000 s (dt 0.05 s, 20 000 steps), the body stays on its joint: a slide
    keeps x, y and the orientation exactly; a hinge keeps its distance to the axis and turns about it only."""
    base = with_overrides(load_scene("storm"), body__density=500.0, fluid__forces="panels", initial__position=(0.0, 0.0, 0.0),
                          constraint__joint=joint, constraint__axis=(0.0, 1.0, 0.0) if joint == "revolute" else (0.0, 0.0, 1.0),
                          constraint__pivot=(0.0, 0.0, 1.0), constraint__pto_damping=500.0, step__dt=0.05)  # fmt: skip
    sim = Simulation(base, backend="numpy")
    start_q, start_x = sim.state.q_world_body.copy(), sim.state.x_world.copy()
    moved = 0.0
    while sim.state.t < 1000.0 - 1e-9:
        sim.step(100)
        s = sim.state
        if joint == "prismatic":
            assert np.abs(s.x_world[:2] - start_x[:2]).max() < 1e-12 and np.abs(s.q_world_body - start_q).max() < 1e-12
        elif joint == "revolute":
            assert abs(np.linalg.norm(s.x_world - [0.0, 0.0, 1.0]) - 1.0) < 1e-9 and abs(s.x_world[1]) < 1e-12
            R = s.R_world_body
            assert abs(R[1, 1] - 1.0) < 1e-12  # turned about y only
        else:
            assert np.array_equal(s.x_world, start_x) and np.array_equal(s.q_world_body, start_q)
        moved = max(moved, float(np.abs(s.x_world - start_x).max()))
    assert (moved > 0.05) == (joint != "fixed")  # the sea moved it along its joint


def test_the_csv_carries_the_take_off_power_and_energy(tmp_path):
    out = tmp_path / "run.csv"
    done = subprocess.run([sys.executable, "-m", "sim", "run", "--scene", "drop", "--density", "500", "--forces", "panels", "--damping", "0",
                           "--joint", "prismatic", "--pto-damping", "1000", "--t-end", "2", "--every", "1", "--out", str(out)], cwd=ROOT,
                          capture_output=True, text=True, timeout=300)  # fmt: skip
    assert done.returncode == 0, done.stderr
    rows = np.genfromtxt(out, delimiter=",", names=True)
    assert "joint: prismatic to the seabed, take-off k 0, c 1000" in done.stdout, done.stdout
    assert f"take-off absorbed {rows['E_pto'][-1]:.6g} J" in done.stdout, done.stdout
    np.testing.assert_allclose(rows["P_pto"], 1000.0 * rows["uz"] ** 2, rtol=1e-9, atol=1e-12)
    assert np.all(np.diff(rows["E_pto"]) >= 0) and rows["E_pto"][-1] == pytest.approx(np.trapezoid(rows["P_pto"], rows["t"]), rel=2e-3)
    assert not np.any(rows["ux"]) and not np.any(rows["wx"])  # a slide: no sideways motion, no turning


@pytest.mark.parametrize("args, message", [
    (("--joint", "hinge"), "unknown joint 'hinge'"),
    (("--joint", "prismatic", "--axis", "0", "0", "0"), "axis must not be zero"),
    (("--joint", "prismatic", "--pto-damping", "-1"), "PTO damping must be >= 0"),
    (("--joint", "planar", "--axis", "0", "1", "0"), "joint 'planar' is for a [[bodies]] entry"),
])  # fmt: skip
def test_mistakes_are_one_line_and_exit_2(args, message):
    done = subprocess.run([sys.executable, "-m", "sim", "run", "--scene", "drop", "--t-end", "0.1", *args], cwd=ROOT, capture_output=True,
                          text=True, timeout=300)  # fmt: skip
    assert done.returncode == 2 and message in done.stderr and "Traceback" not in done.stderr, done.stderr


def test_a_joint_runs_on_the_reference_and_says_so():
    sim = Simulation(heave_scene(0.01))
    assert not sim.compiled and any("joint has no compiled twin" in n for n in sim.notes)
    assert not any("own scheme" in n for n in sim.notes)
    rk4 = Simulation(heave_scene(0.01, step__integrator="rk4"))
    assert any("own scheme" in n and "'rk4' is not used" in n for n in rk4.notes), rk4.notes


@pytest.mark.slow  # over 4 s (the marker's rule)
def test_a_heaving_converter_absorbs_the_frequency_domain_power():
    """The ice cube on a vertical slide with a take-off damper, radiation and diffraction from its shipped
    solve, in 1 cm regular waves: the heave amplitude and the mean absorbed power (1/2) c omega^2 |xi|^2 a^2
    match the one-dof frequency-domain solution xi = X_3 / (-omega^2 (m + A_33) - i omega (B_33 + c) + rho g A_wp)
    within 2 % (the run starts on the linear steady state, its radiation memory's too)."""
    import sim.hydro.bem as bem
    from sim.bodies.body import make_box

    c_pto, a, z_rest = 2000.0, 0.01, -0.4
    box = make_box((1.0, 1.0, 1.0), 10, 900.0)
    coef = bem.radiation_coefficients(box.mesh_vertices + [0.0, 0.0, z_rest], box.mesh_faces, progress=False, center=(0.0, 0.0, z_rest),
                                      excitation=True)  # fmt: skip
    lam = 2 * math.pi * G / coef.omega**2
    for i in np.flatnonzero((lam > 3.0) & (lam < 20.0))[::6]:
        w = float(coef.omega[i])
        T = 2 * math.pi / w
        m = 900.0
        X = coef.froude_krylov[i, 0, 2] + coef.diffraction[i, 0, 2]
        xi = X / (-(w**2) * (m + coef.added_mass[i, 2, 2]) - 1j * w * (coef.damping[i, 2, 2] + c_pto) + RHO * G * 1.0)
        z0, v0 = (a * xi).real, (-1j * w * a * xi).real
        scene = with_overrides(load_scene("rest"), fluid__radiation="bem", fluid__forces="panels", fluid__damping=0.0, waves__kind="regular",
                               waves__height=2 * a, waves__period=T, initial__position=(0.0, 0.0, z_rest + z0), initial__velocity=(0.0, 0.0, v0),
                               constraint__joint="prismatic", constraint__pto_damping=c_pto, step__dt=T / 200)  # fmt: skip
        sim = Simulation(scene)
        rad = sim.model.radiation
        nu = np.zeros(6, complex)
        nu[2] = -1j * w * a * xi
        memory = np.linalg.solve(-1j * w * np.eye(rad.states) - rad.F, rad.G @ nu).real  # the memory in steady state too
        s = sim.body_state
        sim.reset(type(s)(s.t, s.x_world, s.q_world_body, s.u_world, s.L_world, memory, 0.0))
        sim.step(200 * 8)  # 8 periods
        e0, t0 = sim.frame().E_pto, sim.state.t
        z = []
        for _ in range(200 * 4):
            sim.step(1)
            z.append(sim.state.x_world[2] - z_rest)
        power = (sim.frame().E_pto - e0) / (sim.state.t - t0)
        print(
            f"T = {T:.3f} s: heave {0.5 * (max(z) - min(z)) / abs(a * xi) - 1:+.2%}, power {power / (0.5 * c_pto * w * w * abs(a * xi) ** 2) - 1:+.2%}"
        )
        assert 0.5 * (max(z) - min(z)) == pytest.approx(abs(a * xi), rel=0.02), (T, max(z), abs(a * xi))
        assert power == pytest.approx(0.5 * c_pto * w * w * abs(a * xi) ** 2, rel=0.02), (T, power)


def test_a_slide_along_a_free_motion_changes_nothing():
    """The cube released 10 cm high with radiation heaves straight up and down when free (by symmetry, to its solve's
    accuracy): on a vertical slide it does the same, memory and radiated energy included."""
    base = with_overrides(load_scene("rest"), fluid__radiation="bem", fluid__forces="panels", fluid__damping=0.0, initial__position=(0.0, 0.0, -0.3),
                          step__dt=0.01)  # fmt: skip
    free = Simulation(base, backend="numpy")
    slide = Simulation(with_overrides(base, constraint__joint="prismatic"), backend="numpy")
    free.step(300)
    slide.step(300)
    # the free cube's sideways drift: its solve's numerical heave-surge coupling (1.6e-7 m in 3 s)
    np.testing.assert_allclose(slide.state.x_world, free.state.x_world, atol=1e-6)
    # the heave memory alike; the free cube's others only what its faceted faces' tiny yaw moment stirs (L_z ~ 1e-4 kg m2/s)
    heave = np.concatenate([np.full(len(e.G), e.col == 2) for e in free.model.radiation.memory.entries])
    np.testing.assert_allclose(slide.state.memory[heave], free.state.memory[heave], rtol=1e-7, atol=1e-8)
    assert np.abs(free.state.memory[~heave]).max() < 1e-5 * np.abs(free.state.memory[heave]).max()
    assert slide.state.E_rad == pytest.approx(free.state.E_rad, rel=1e-7) and free.state.E_rad > 1.0


def test_a_recording_shows_the_joint_axis():
    """The replay of a run on a hinge draws its axis where the frame puts it."""
    import base64
    import re

    import msgspec
    import zstandard

    from app.recording.replay import replay_html
    from app.recording.take import Take, shot_of

    sim = Simulation(with_overrides(heave_scene(0.01), constraint__joint="revolute", constraint__axis=(0.0, 1.0, 0.0),
                                    constraint__pivot=(0.0, 0.0, 0.6)), backend="numpy")  # fmt: skip
    take = Take()
    for _ in range(5):
        take.add(shot_of(sim))
        sim.step(5)
    raw = base64.b64decode(re.search(r'window.__VISER_EMBED_DATA__="([^"]+)"', replay_html(take)).group(1))
    inner = zstandard.ZstdDecompressor().decompress(raw[8:], max_output_size=int.from_bytes(raw[:8], "little"))
    doc = msgspec.msgpack.decode(inner[8 : 8 + int.from_bytes(inner[:8], "little")])
    assert [m for _, m in doc["messages"] if m.get("name") == "/world/joint" and m["type"] == "LineSegmentsMessage"]
    point, direction = sim.frame().joint_axis
    np.testing.assert_allclose(point, [0.0, 0.0, 0.7])
    np.testing.assert_allclose(direction, [0.0, 1.0, 0.0])

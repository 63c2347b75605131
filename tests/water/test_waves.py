"""Waves against exact answers: the surface has zero pressure, the dispersion relation holds, a
seeded JONSWAP sea has the asked Hs and Tp, zero amplitude is still water, the Froude-Krylov force
on a fixed box is linear theory's closed form, and a small cube follows long waves at the linear RAO."""

import math
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import trimesh

from sim import FluidConfig, Model, Simulation, StillWater, load_scene, with_overrides
from sim.bodies.body import make_mesh_body
from sim.scene.config import ConfigError
from sim.water.seas import jonswap_waves, ramp_factor, regular_waves, wavenumber
from studies.accuracy.drifting import kick_drift, period_means, wavelength

RHO, G = 1000.0, 9.81
ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("depth", [math.inf, 30.0, 5.0])
def test_surface_pressure_vanishes_and_deep_pressure_is_linear_theory(depth):
    w = jonswap_waves(RHO, G, 2.0, 8.0, components=16, seed=4, depth=depth, spreading=4.0)
    rng = np.random.default_rng(0)
    xy = rng.uniform(-50, 50, size=(40, 2))
    t = 7.3
    surface = np.column_stack([xy, w.elevation(xy, t)])
    np.testing.assert_allclose(w.pressure(surface, t), 0.0, atol=1e-9)
    # far below the surface stretching hardly matters: p - rho g (-z) -> rho g sum a_i E_i(z) cos(psi_i)
    small = regular_waves(RHO, G, 1e-4, 6.0, direction_deg=30.0, depth=depth)
    z = -min(0.5 * depth, 3.0)
    p = small.pressure(np.array([[1.0, 2.0, z]]), 0.4)[0] + RHO * G * z
    k = small.k[0]
    E = math.exp(k * z) if math.isinf(depth) else math.cosh(k * (z + depth)) / math.cosh(k * depth)
    psi = k * (math.cos(math.radians(30)) + 2 * math.sin(math.radians(30))) - small.omega[0] * 0.4
    assert p == pytest.approx(RHO * G * 0.5e-4 * E * math.cos(psi), rel=1e-4)


def test_dispersion_relation():
    omega = np.linspace(0.2, 5.0, 30)
    for depth in (1.0, 10.0, 200.0):
        k = wavenumber(omega, G, depth)
        np.testing.assert_allclose(G * k * np.tanh(k * depth), omega**2, rtol=1e-12)
    np.testing.assert_allclose(wavenumber(omega, G, math.inf), omega**2 / G)


def test_jonswap_sea_has_the_asked_hs_and_tp_and_is_reproducible():
    hs, tp = 3.0, 9.0
    sea = jonswap_waves(RHO, G, hs, tp, gamma=3.3, components=256, seed=7)
    t = np.arange(0.0, 6 * 3600.0, 0.25)
    eta = np.cos(-np.outer(t, sea.omega) + sea.phase) @ sea.amplitude  # at x = 0
    assert 4 * eta.std() == pytest.approx(hs, rel=0.03)
    from scipy.signal import welch

    f, S = welch(eta, fs=4.0, nperseg=2**14)
    assert 1 / f[np.argmax(S)] == pytest.approx(tp, rel=0.05)
    again = jonswap_waves(RHO, G, hs, tp, gamma=3.3, components=256, seed=7)
    other = jonswap_waves(RHO, G, hs, tp, gamma=3.3, components=256, seed=8)
    np.testing.assert_array_equal(again.phase, sea.phase)
    np.testing.assert_array_equal(again.omega, sea.omega)
    assert not np.allclose(other.phase, sea.phase)


@pytest.mark.parametrize("forces", ["points", "panels"])
@pytest.mark.parametrize(
    "integrator", ["euler", "splitting", "implicit", "rk4", pytest.param("rk45", marks=pytest.mark.slow)]
)  # rk45: 5-10 s
def test_zero_amplitude_is_still_water(forces, integrator):
    """The waves' general path (per-point surface, stretched pressure, water velocity, higher-order
    panel rule) with a = 0 reproduces still water to round-off."""
    base = with_overrides(
        load_scene("damped"), fluid__forces=forces, fluid__drag_coefficient=0.5, step__integrator=integrator, step__dt=0.01
    )
    still = Simulation(base, backend="numpy")
    flat = Simulation(with_overrides(base, waves__kind="regular", waves__height=0.0), backend="numpy")
    assert not flat.model.water.flat
    still.step(150)
    flat.step(150)
    a = still.state.as_vector()
    np.testing.assert_allclose(flat.state.as_vector(), a, rtol=0, atol=1e-11 * (1 + np.abs(a).max()))


def box_model(L=1.0, B=1.0, H=1.0, edge=0.05) -> Model:
    mesh = trimesh.creation.box(extents=(L, B, H))
    v, f = trimesh.remesh.subdivide_to_size(mesh.vertices, mesh.faces, max_edge=edge)
    body = make_mesh_body(trimesh.Trimesh(v, f), samples=len(f), density=900.0)
    return body


@pytest.mark.parametrize("direction", [0.0, 30.0])
def test_froude_krylov_force_on_a_fixed_box_is_linear_theory(direction):
    """A box L x B with draft d held still in a deep-water wave of tiny steepness: the force beyond the
    still-water buoyancy is F_z = rho g a e^(-kd) L B sinc(k_x L/2) sinc(k_y B/2) cos(omega t) and
    F_x = -2 rho g a B sinc(k_y B/2) sin(k_x L/2) (1 - e^(-kd))/k sin(omega t) (sinc u = sin u / u)."""
    L = B = 1.0
    d = 0.9
    a, T = 1e-6, 4.0
    body = box_model(L, B)
    fluid = FluidConfig(forces="panels")
    waves = regular_waves(RHO, G, 2 * a, T, direction_deg=direction)
    x, R = np.array([0.0, 0.0, 0.5 - d]), np.eye(3)
    still_model = Model(body, StillWater(RHO, G), fluid)
    still = np.concatenate(still_model.pose_loads(still_model.wetted(x, R)))
    model = Model(body, waves, fluid)
    k, w = waves.k[0], waves.omega[0]
    kx, ky = k * math.cos(math.radians(direction)), k * math.sin(math.radians(direction))

    def sinc(u):
        return 1.0 if u == 0 else math.sin(u) / u

    scale = RHO * G * a * L * B
    for t in np.linspace(0.0, T, 7):
        load = np.concatenate(model.pose_loads(model.wetted(x, R, t), t)) - still
        fz = RHO * G * a * math.exp(-k * d) * L * B * sinc(kx * L / 2) * sinc(ky * B / 2) * math.cos(w * t)
        fx = -2 * RHO * G * a * B * sinc(ky * B / 2) * math.sin(kx * L / 2) * (1 - math.exp(-k * d)) / k * math.sin(w * t)
        fy = -2 * RHO * G * a * L * sinc(kx * L / 2) * math.sin(ky * B / 2) * (1 - math.exp(-k * d)) / k * math.sin(w * t)
        np.testing.assert_allclose(load[:3], [fx, fy, fz], rtol=0, atol=1e-6 * scale)


def heave_amplitude(period: float, height: float = 0.2, cycles: int = 6) -> tuple[float, float]:
    """(simulated, linear prediction) heave amplitude of the floating ice cube in a regular wave: a
    least-squares fit of z(t) at the wave frequency and at the free heave frequency together (the waves at full
    height from the start: no ramp, whose growth the fit has no term for)."""
    scene = with_overrides(load_scene("rest"), fluid__forces="panels", waves__kind="regular", waves__height=height, waves__period=period,
                           step__dt=0.01, waves__ramp=0.0)  # fmt: skip
    sim = Simulation(scene)
    w = 2 * math.pi / period
    wn = math.sqrt(RHO * G * 1.0 / 900.0)
    k = float(wavenumber(w, G, math.inf))
    ts, zs = [], []
    for _ in range(round(cycles * period / 0.01) // 5):
        sim.step(5)
        ts.append(sim.state.t)
        zs.append(sim.state.x_world[2])
    t, z = np.array(ts), np.array(zs)
    A = np.column_stack([np.ones_like(t), np.cos(w * t), np.sin(w * t), np.cos(wn * t), np.sin(wn * t)])
    c = np.linalg.lstsq(A, z, rcond=None)[0]
    predicted = 0.5 * height * math.exp(-k * 0.9) * math.sin(k / 2) / (k / 2) / abs(1 - (w / wn) ** 2)
    return math.hypot(c[1], c[2]), predicted


def test_a_small_cube_follows_long_waves_at_the_linear_rao():
    simulated, predicted = heave_amplitude(period=2 * math.pi / math.sqrt(G * 2 * math.pi / 200.0))  # wavelength 200 m
    assert simulated == pytest.approx(predicted, rel=0.01)


def test_heave_response_grows_towards_resonance():
    wn = math.sqrt(RHO * G / 900.0)
    ratios = [0.5, 0.7, 0.85]
    amps = [heave_amplitude(2 * math.pi / (r * wn), height=0.02, cycles=12) for r in ratios]
    for (sim_amp, pred), r in zip(amps, ratios):
        assert sim_amp == pytest.approx(pred, rel=0.05), r
    assert amps[0][0] < amps[1][0] < amps[2][0]


@pytest.mark.parametrize("changes, message", [
    ({"waves__kind": "regular", "waves__height": -1.0}, "wave height must be >= 0"),
    ({"waves__kind": "regular", "waves__period": 0.0}, "wave period must be > 0"),
    ({"waves__kind": "regular", "waves__height": 10.0, "waves__period": 5.0}, "past the breaking limit"),
    ({"waves__kind": "jonswap", "waves__hs": 8.0, "waves__tp": 4.0}, "past the breaking limit"),
    ({"waves__kind": "tsunami"}, "unknown waves 'tsunami'"),
    ({"waves__kind": "regular", "waves__ramp": -1.0}, "wave ramp must be >= 0"),
])  # fmt: skip
def test_bad_wave_input_is_one_clear_error(changes, message):
    with pytest.raises(ConfigError, match=message):
        with_overrides(load_scene("rest"), **changes)


def test_panels_converge_under_refinement_and_points_converge_to_panels():
    """A tilted cube cut by a 10 m wave (steepness 0.05): the panel model's force and torque converge
    as the panels shrink (the surface between vertices is a plane: second order by construction;
    observed 3-4), and the samples converge to the finest panels at the midpoint rule's N^-2."""
    from scipy.spatial.transform import Rotation

    waves = regular_waves(RHO, G, 0.5, 2.5)
    R, x, t = Rotation.from_rotvec([0.3, -0.2, 0.4]).as_matrix(), np.array([0.2, 0.1, -0.3]), 0.7

    def load(body, forces):
        model = Model(body, waves, FluidConfig(forces=forces))
        return np.concatenate(model.pose_loads(model.wetted(x, R, t), t))

    from sim.bodies.body import make_box

    reference = load(box_model(edge=0.02), "panels")
    panels = [np.abs(load(box_model(edge=e), "panels") - reference).max() for e in (0.5, 0.25, 0.125, 0.0625)]
    assert np.polyfit(np.log([0.5, 0.25, 0.125, 0.0625]), np.log(panels), 1)[0] > 2.5
    assert panels[-1] < 1e-9 * RHO * G
    points = [np.abs(load(make_box((1.0, 1.0, 1.0), n, 900.0), "points") - reference).max() for n in (5, 10, 20, 40)]
    slopes = np.diff(np.log(points)) / np.log(2)
    assert np.all(slopes < -1.8) and points[-1] < 1e-5 * RHO * G


def test_the_ramp_grows_every_wave_quantity_by_a_half_cosine():
    """At time t the ramped sea is the full sea with every amplitude times r(t) = (1 - cos(pi t / T_r)) / 2 up to T_r, and
    the full sea after: elevation, pressure (stretched under the ramped surface) and flow (the current unramped); r and
    its slope are continuous at both ends. Unset, the ramp is 3.5 periods of the sea (regular: its period, JONSWAP: Tp),
    0 in still water; 0 is full height from the start."""
    full = jonswap_waves(RHO, G, 2.0, 8.0, components=16, seed=4, depth=30.0, spreading=4.0)
    full = replace(full, current=(0.3, -0.1))
    sea = replace(full, ramp=20.0)
    pts = np.random.default_rng(3).uniform([-20, -20, -6], [20, 20, 0.5], (50, 3))
    for t in (0.0, 3.0, 10.0, 19.9, 20.0, 31.0):
        r = 0.5 - 0.5 * math.cos(math.pi * min(t, 20.0) / 20.0)
        assert sea.ramped(t) == pytest.approx(r, abs=1e-15)
        scaled = replace(full, amplitude=r * full.amplitude)
        np.testing.assert_allclose(sea.elevation(pts[:, :2], t), scaled.elevation(pts[:, :2], t), rtol=0, atol=1e-12)
        (p, v), (p_scaled, v_scaled) = sea.field(pts, t), scaled.field(pts, t)
        np.testing.assert_allclose(p, p_scaled, rtol=0, atol=1e-9)
        np.testing.assert_allclose(v, v_scaled, rtol=0, atol=1e-12)
        np.testing.assert_allclose(sea.pressure(pts, t), p_scaled, rtol=0, atol=1e-9)
    h = 1e-6
    for end in (0.0, 20.0):  # value and slope continuous
        assert abs(ramp_factor(end + h, 20.0) - ramp_factor(end - h, 20.0)) < 1e-12
    assert ramp_factor(-1.0, 0.0) == ramp_factor(0.0, 0.0) == 1.0
    scenes = {"regular": {"waves__period": 6.0}, "jonswap": {"waves__tp": 9.0}}
    for kind, changes in scenes.items():
        sim = Simulation(with_overrides(load_scene("rest"), waves__kind=kind, **changes), backend="numpy")
        assert sim.model.water.ramp == pytest.approx(3.5 * next(iter(changes.values())))
    assert Simulation(with_overrides(load_scene("waves"), waves__ramp=0.0), backend="numpy").model.water.ramp == 0.0
    assert Simulation(with_overrides(load_scene("waves"), waves__ramp=4.0), backend="numpy").model.water.ramp == 4.0


def _sphere_at(tmp_path: Path, x0: float) -> Path:
    """The sphere preset as a scene file of its own, started at rest at x = x0 (its release height set to its rest)."""
    text = (ROOT / "assets/scenes/sphere.toml").read_text().replace("../meshes/sphere.stl", str(ROOT / "assets/meshes/sphere.stl"))
    path = tmp_path / f"sphere-{x0:g}.toml"
    path.write_text(text.replace("position = [0.0, 0.0, 0.1]", f"position = [{x0!r}, 0.0, 0.0]"))
    return path


@pytest.mark.slow
def test_the_ramp_starts_a_free_body_without_a_kick(tmp_path):
    """The sphere preset free in regular waves (T 2.5 s; 2 and 1 cm high) through the CLI, started at rest at x = 0 and
    half a wave down-wave (the wave's sign flipped there): the part of its period-mean surge that flips with the wave
    (first order: a start-up kick) leaves the ramp with no drift, under 1 % of the amplitude a per period (measured 0.002 %;
    without a ramp -570 %: 1.4 m in a minute), after settling once by at most a third of a while the waves rise; the part
    that does not flip grows four-fold when a doubles: second order, the mean force's drift."""
    T, dt = 2.5, 0.005
    half = 0.5 * wavelength(T)
    runs = {}
    procs = {}
    for height in (0.02, 0.01):
        for x0 in (0.0, half):
            out = tmp_path / f"{height}-{x0:g}.csv"
            procs[(height, x0)] = (out, subprocess.Popen([sys.executable, "-m", "sim", "run", "--scene", str(_sphere_at(tmp_path, x0)),
                                                          "--waves", "regular", "--wave-height", str(height), "--wave-period", str(T),
                                                          "--t-end", "25", "--every", "1", "--out", str(out)], cwd=ROOT,
                                                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True))  # fmt: skip
        for key in [k for k in procs if k[0] == height]:
            out, proc = procs[key]
            _, err = proc.communicate(timeout=600)
            assert proc.returncode == 0, err
            rows = np.genfromtxt(out, delimiter=",", names=True)
            runs[key] = period_means(rows["x"][1:] - key[1], round(T / dt))  # (the first row is t = 0)
    ramp = 3.5 * T
    even = {}
    for height in (0.02, 0.01):
        a = 0.5 * height
        odd = 0.5 * (runs[(height, 0.0)] - runs[(height, half)])
        even[height] = 0.5 * (runs[(height, 0.0)] + runs[(height, half)])
        drift = kick_drift(odd, T, ramp)  # m per period
        assert abs(drift) < 0.01 * a, (height, drift)
        assert np.abs(odd).max() < 0.33 * a
    assert even[0.02][-1] / even[0.01][-1] == pytest.approx(4.0, rel=0.05)
    assert even[0.02][-1] > 1e-3  # the mean force moves it (5 mm in 25 s at 2 cm)


def test_a_broad_sea_at_many_points_is_taken_in_blocks_with_the_same_values(monkeypatch):
    """Issue 59: 60 000 samples in 4096 components took 6 GB in the numpy reference's sea (points x components arrays
    at once; 290 MB now). Taken in blocks of at most seas.BLOCK points x components, each point's elevation, pressure
    and velocity are the unblocked ones to round-off, for points in any leading shape."""
    from sim.water import seas

    sea = seas.jonswap_waves(1025.0, 9.81, 1.5, 8.0, components=64, seed=3, depth=30.0)
    rng = np.random.default_rng(5)
    points = np.concatenate([rng.uniform(-20, 20, (7, 5, 2)), rng.uniform(-6, 0, (7, 5, 1))], axis=-1)
    whole = sea.elevation(points[..., :2], 4.2), sea.pressure(points, 4.2), *sea.field(points, 4.2)
    rows = []
    psi = seas.Waves._psi
    monkeypatch.setattr(seas.Waves, "_psi", lambda self, xy, t: rows.append(len(xy)) or psi(self, xy, t))
    monkeypatch.setattr(seas, "BLOCK", 64 * 4)  # four points a block: 9 blocks for 35 points
    blocked = sea.elevation(points[..., :2], 4.2), sea.pressure(points, 4.2), *sea.field(points, 4.2)
    for got, want in zip(blocked, whole):
        assert got.shape == want.shape
        np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-9)
    assert max(rows) == 4 and len(rows) == 3 * 9  # each of the three evaluations in nine blocks

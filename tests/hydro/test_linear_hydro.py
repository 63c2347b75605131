"""Linear hydrostatics and Froude-Krylov force (`[fluid] hydro = "linear"`, sim/hydro/linear_hydro.py): the loads are the
exact model's to first order about rest, the Froude-Krylov force is the BEM solve's, and a run is linear theory itself."""

import dataclasses
import subprocess
import sys

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from sim.hydro.forces import Model
from sim.hydro.linear_hydro import LinearLoads, moved, rotation_vector
from sim.scene.config import load_scene, with_overrides
from sim.system.frequency import response, steady_start
from sim.system.tree import build
from sim.water.seas import StillWater, regular_waves
from tests.system.test_rm3 import _shipped_only, kicked_float, time_domain  # noqa: F401  (the fixture: the shipped coefficients, no solve)


def rm3(**changes):
    return with_overrides(load_scene("rm3"), fluid__hydro="linear", **changes)


def test_rotation_vector_inverts_the_exponential_up_to_a_half_turn():
    rng = np.random.default_rng(4)
    for scale in (1e-9, 1e-3, 0.5, 2.0, 3.0, np.pi * (1 - 1e-9)):
        phi = rng.normal(size=3)
        phi *= scale / np.linalg.norm(phi)
        np.testing.assert_allclose(rotation_vector(Rotation.from_rotvec(phi).as_matrix()), phi, rtol=0, atol=1e-12)


def test_the_linear_loads_are_the_exact_ones_to_first_order_about_rest():
    """Moved by eps along any direction of pose space, the float's linear loads differ from the exact clipped ones by
    O(eps^2): the gap falls four-fold when eps halves."""
    system, _ = build(rm3(waves__kind="still"))
    loads = system.loads[1]
    m = loads.model
    still = Model(m.body, StillWater(m.water.rho, m.water.g), m.fluid)
    direction = np.array([0.3, -0.2, 1.0, 0.02, -0.03, 0.01])
    gaps = []
    for eps in (0.2, 0.1, 0.05):
        x, R = moved(loads.x0, loads.R0, eps * direction)
        exact = np.concatenate(still.pose_loads(still.wetted(x, R, 0.0)))
        linear, _ = loads(x, R, 0.0, np.zeros(6))
        gaps.append(np.abs(linear - exact).max())
        assert gaps[-1] < 0.01 * np.abs(loads.C @ (eps * direction)).max()  # the linear part is the load's bulk
    assert 3.5 < gaps[0] / gaps[1] < 4.5 and 3.5 < gaps[1] / gaps[2] < 4.5


def test_the_froude_krylov_force_is_the_boundary_element_solves():
    """The undisturbed wave's pressure over the wet surface at rest, per unit amplitude, against Capytaine's Froude-Krylov
    force of the same meshes at every solve frequency: forces within 2 % of each body's largest, moments within 2 % of
    that force times the body's radius (the solve's panel centroids against the clipped triangles' quadrature: 1 % on
    the float's heave, rho g A_wp at long waves; the spar's pitch moment is a small difference of large parts)."""
    system, _ = build(rm3())
    c = system.radiation.coefficients
    for i in range(len(c.omega)):
        for b, at_rest in enumerate(system.loads):
            m = at_rest.model
            waves = regular_waves(m.water.rho, m.water.g, 2.0, 2 * np.pi / float(c.omega[i]))
            ours, theirs = LinearLoads(Model(m.body, waves, m.fluid), at_rest.x0, at_rest.R0).X[0], c.froude_krylov[i, 0, 6 * b : 6 * b + 6]
            force = np.abs(theirs[:3]).max()
            assert force > 1e4 and np.abs(ours[:3] - theirs[:3]).max() < 0.02 * force, (c.omega[i], b, ours, theirs)
            assert np.abs(ours[3:] - theirs[3:]).max() < 0.02 * force * m.body.radius, (c.omega[i], b, ours, theirs)


@pytest.mark.parametrize("amplitude", [0.05, 1.0])
def test_a_linear_run_is_linear_theory_at_any_wave_height(amplitude):
    """rm3 with linear hydrostatics and Froude-Krylov force, started on the frequency domain's steady state in regular
    waves: six periods match its relative heave and take-off power within 0.1 % for 10 cm waves and for 2 m ones alike
    (the exact wet surface is linear theory only in small waves)."""
    system, _ = build(rm3())
    c = system.radiation.coefficients
    i = int(np.argmin(abs(c.omega - 2 * np.pi / 8.0)))
    w = float(c.omega[i])
    system, rest = build(rm3(waves__height=2 * amplitude, waves__period=2 * np.pi / w, waves__ramp=0.0))  # (started on the steady state)
    froude_krylov = np.concatenate([loads.X[0] for loads in system.loads]) / amplitude
    xi = response(system, rest, i, froude_krylov=froude_krylov)
    relative, power = time_domain(system, steady_start(system, rest, xi, w, amplitude), w, periods=6)
    slide = next(g for g in system.joints if g.name == "float")
    k, d = slide.coordinate, slide.dofs.start
    expected = 0.5 * slide.damping * w * w * abs(amplitude * xi[d]) ** 2
    assert abs(abs(relative[k]) / abs(amplitude * xi[d]) - 1) < 1e-3 and abs(power[k] / expected - 1) < 1e-3
    assert abs(np.angle(relative[k] / xi[d])) < 1e-3 and expected > 100.0


@pytest.mark.parametrize(
    "flags, message",
    [
        (["--scene", "drop", "--hydro", "linear"], "is for scenes of several bodies"),
        (["--scene", "rm3", "--hydro", "linear", "--drag-coefficient", "1.0"], "quadratic drag needs the instantaneous wet surface"),
        (["--scene", "rm3", "--hydro", "linearised"], "hydro"),
    ],
)
def test_a_linear_scene_it_cannot_run_is_a_one_line_error(flags, message):
    done = subprocess.run([sys.executable, "-m", "sim", "run", *flags, "--t-end", "0.1"], capture_output=True, text=True, timeout=120)
    assert done.returncode != 0 and message in done.stderr and "Traceback" not in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) <= 2


def test_run_rm3_with_linear_hydro_in_a_sea(tmp_path):
    """From the CLI: a 64-component sea with linear hydro runs and writes the take-off's power; the float's heave stays
    within the sea's own height."""
    out = tmp_path / "rm3.csv"
    done = subprocess.run([sys.executable, "-m", "sim", "run", "--scene", "rm3", "--hydro", "linear", "--waves", "jonswap", "--hs", "2.5",
                           "--tp", "8", "--wave-components", "64", "--dt", "0.01", "--t-end", "20", "--out", str(out)], capture_output=True,
                          text=True, timeout=300)  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    import csv

    rows = list(csv.DictReader(out.open()))
    z = np.array([float(r["float_z"]) for r in rows])
    assert len(rows) > 100 and np.isfinite(z).all() and np.ptp(z) < 2 * 2.5
    assert np.ptp(z) > 0.1  # it moves in the sea


def test_a_linear_system_on_slides_is_stepped_exactly():
    """rm3 with linear hydro from rest in its regular waves for 40 s, the first 28 s of them the waves' ramp: the exact
    stepper gives the same joint coordinates at dt = 0.4 s as at 0.0125 s and at 0.32 s (a step across the ramp's end,
    split there), to 1e-12 m, and Stormer-Verlet (the general scheme) converges to it at second order, the take-off's
    absorbed energy too."""
    from sim.system.linear import exact_linear

    system, s0 = build(rm3())
    exact = exact_linear(system, s0)
    assert exact is not None and exact.ramp == pytest.approx(28.0)
    coarse, fine, across = exact.advance(s0, 0.4, 100), exact.advance(s0, 0.0125, 3200), exact.advance(s0, 0.32, 125)
    assert abs(fine.t - 40.0) < 1e-9 and np.abs(coarse.theta - fine.theta).max() < 1e-12
    assert abs(across.t - 40.0) < 1e-9 and np.abs(across.theta - fine.theta).max() < 1e-12
    assert abs(across.absorbed.sum() / fine.absorbed.sum() - 1) < 1e-6  # Simpson's rule over the split step too
    assert np.ptp([coarse.theta[1], 0.0]) > 0.1  # the float moves
    gaps, energy = [], []
    for dt in (0.05, 0.025):
        s = s0
        for _ in range(round(40.0 / dt)):
            s = system.step(s, dt)
        gaps.append(np.abs(s.theta - fine.theta).max())
        energy.append(abs(s.absorbed.sum() - fine.absorbed.sum()))
    assert 3.6 < gaps[0] / gaps[1] < 4.4 and 3.6 < energy[0] / energy[1] < 4.4 and gaps[1] < 1e-4


@pytest.mark.parametrize("period", [8.0, 6.0])
def test_the_exact_stepper_keeps_the_frequency_domains_steady_state(period):
    """Started on the frequency-domain solution (system_frequency.py: its own stiffness, by differences of the exact
    loads, and the solve's A(omega), B(omega)), six periods of the exact stepper stay on it: relative heave and power
    within 0.3 % in 1 m waves (what is left is the radiation memory's fit of B(omega): Stormer-Verlet at 160 steps a
    period is off by as much, 2.4e-3 and 2.5e-3 at 6 s)."""
    system, _ = build(rm3())
    c = system.radiation.coefficients
    i = int(np.argmin(abs(c.omega - 2 * np.pi / period)))
    w, a = float(c.omega[i]), 0.5
    system, rest = build(rm3(waves__height=2 * a, waves__period=2 * np.pi / w, waves__ramp=0.0))  # (started on the steady state)
    from sim.system.linear import exact_linear

    exact = exact_linear(system, rest)
    xi = response(system, rest, i, froude_krylov=np.concatenate([loads.X[0] for loads in system.loads]) / a)
    start = steady_start(system, rest, xi, w, a)
    relative, power = time_domain(type("Exact", (), {"step": staticmethod(lambda s, dt: exact.advance(s, dt))})(), start, w, periods=6)
    slide = next(g for g in system.joints if g.name == "float")
    k, d = slide.coordinate, slide.dofs.start
    expected = 0.5 * slide.damping * w * w * abs(a * xi[d]) ** 2
    assert abs(relative[k] / (a * xi[d]) - 1) < 3e-3 and abs(power[k] / expected - 1) < 6e-3


def test_energy_closes_to_fourth_order_when_stepped_exactly():
    """The kicked float in still water, stepped exactly: the energies, the take-off's and the radiated waves' add up to the
    start's, the gap falling 16-fold when dt halves (Simpson's rule on the absorbed and radiated power: fourth order)."""
    from sim.simulation import Simulation

    errors = []
    for dt in (0.2, 0.1):
        run = Simulation(kicked_float(fluid__hydro="linear", step__dt=dt))
        assert run.exact is not None and any("stepped exactly" in note for note in run.notes)
        start = run.frame()
        run.step(round(30.0 / dt))
        end = run.frame()
        kinetic = start.E_kin
        assert end.E_pto > 0.1 * kinetic and run.state.E_rad > 0.01 * kinetic
        errors.append(abs(end.E_total + end.E_pto + run.state.E_rad - start.E_total))
    assert 12.0 < errors[0] / errors[1] < 20.0 and errors[1] < 1e-6 * kinetic  # fourth order: 2.0 J and 0.12 J of 1.9e5


def test_a_linear_system_that_turns_is_stepped_by_the_general_scheme():
    """rm3 with its spar on a planar joint (surge, heave, pitch) is not linear in its coordinates: Stormer-Verlet steps it."""
    from sim.simulation import Simulation

    base = rm3()
    spar = dataclasses.replace(
        base.bodies[0], constraint=dataclasses.replace(base.bodies[0].constraint, joint="planar", axis=(0.0, 1.0, 0.0))
    )
    run = Simulation(dataclasses.replace(base, bodies=(spar, *base.bodies[1:])))
    assert run.exact is None and not any("stepped exactly" in note for note in run.notes)
    run.step(20)
    assert run.state.is_finite() and abs(run.state.t - 20 * run.dt) < 1e-9


def test_the_linear_froude_krylov_force_acts_where_the_body_is():
    """A body's linear Froude-Krylov force moved by dx along the waves (at 30 degrees) is the one at rest turned by the
    phase k . dx: exactly, at every time; and it grows with the waves' ramp (half of it at the ramp's middle)."""
    system, _ = build(rm3(waves__direction=30.0))
    loads = system.loads[1]
    k = loads.k[0]
    assert k @ k == pytest.approx(loads.model.water.k[0] ** 2)
    ramp = loads.model.water.ramp
    for t in (0.3 * ramp, ramp + 1.7, ramp + 5.2):
        for dx in (np.array([7.0, -3.0, 0.4]), np.array([-11.0, 2.5, 0.0])):
            turned = (np.exp(1j * (k @ dx[:2] - loads.omega * t)) @ loads.X).real * loads.model.water.ramped(t)
            np.testing.assert_allclose(loads.excitation(t, loads.x0 + dx), turned, rtol=1e-12, atol=1e-9 * np.abs(loads.X).max())
    at = lambda t: loads.excitation(t, loads.x0)  # noqa: E731
    middle = 0.5 * ramp
    np.testing.assert_allclose(at(middle), 0.5 * (np.exp(-1j * loads.omega * middle) @ loads.X).real, rtol=1e-12, atol=1e-9)


def test_a_horizontal_slide_in_waves_is_stepped_by_the_general_scheme():
    """rm3 with its spar on a surge slide: the waves' phase at the spar changes as it slides, which the exact stepper's
    fixed-phase forcing cannot follow: Stormer-Verlet steps it (in still water the exact stepper still applies)."""
    from sim.simulation import Simulation

    base = rm3()
    spar = dataclasses.replace(base.bodies[0], constraint=dataclasses.replace(base.bodies[0].constraint, axis=(1.0, 0.0, 0.0)))
    surging = dataclasses.replace(base, bodies=(spar, *base.bodies[1:]))
    run = Simulation(surging)
    assert run.exact is None and not any("stepped exactly" in note for note in run.notes)
    run.step(5)
    assert run.state.is_finite()
    assert Simulation(with_overrides(surging, waves__kind="still")).exact is not None

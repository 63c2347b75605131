"""A uniform current is a property of the water, not a force term: the water and its waves move with it, and
damping and drag act on the body's velocity relative to it. Checked by Galilean invariance (a body carried
at the current's speed is the body at rest in water at rest, seen from a moving frame), by the drift of a
body released at rest, and by the kernels against the reference."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from sim import Simulation, load_scene, with_overrides
from tests.covering import cases, still
from tests.covering import waves as sea

ROOT = Path(__file__).resolve().parents[2]
U = np.array([0.6, -0.3, 0.0])


def carried(scene, current, backend):
    """The scene in a current, the body moving with it from the start."""
    return Simulation(with_overrides(scene, water__current=tuple(current[:2]), initial__velocity=tuple(current)), backend=backend)


SEAS = [{}, {"waves__kind": "regular", "waves__height": 0.4, "waves__period": 4.0, "waves__direction": 30.0}]


def carried_kernels(waves: dict, backend: str):
    """The moving body's kernels (in waves the current costs no code of its own: the storm preset's; numpy: none)."""
    return (
        still("implicit", "points")
        if backend == "numpy"
        else (sea("implicit", "points") if waves else still("implicit", "points", current=True))
    )


@pytest.mark.parametrize("waves, backend", cases([(w, b) for b in ("numpy", "numba") for w in SEAS], carried_kernels))
def test_a_body_carried_by_the_current_is_the_body_in_water_at_rest_seen_moving(waves, backend):
    """Galilean invariance: with damping and drag, every position shifted by U t and every velocity by U, to round-off."""
    scene = with_overrides(load_scene("damped"), fluid__drag_coefficient=0.8, initial__position=(0.0, 0.0, -0.2), **waves)
    moving, resting = carried(scene, U, backend), Simulation(scene, backend=backend)
    assert moving.compiled == resting.compiled == (backend == "numba")
    for _ in range(4):
        moving.step(50)
        resting.step(50)
        a, b = resting.state, moving.state
        scale = 1.0 + np.abs(a.as_vector()).max()
        np.testing.assert_allclose(b.x_world, a.x_world + U * a.t, rtol=0, atol=1e-10 * scale)
        np.testing.assert_allclose(b.u_world, a.u_world + U, rtol=0, atol=1e-10 * scale)
        np.testing.assert_allclose(b.q_world_body, a.q_world_body, rtol=0, atol=1e-10)
        np.testing.assert_allclose(b.L_world, a.L_world, rtol=0, atol=1e-9 * scale)
    assert np.abs(resting.state.u_world).max() > 1e-3, "the body moves: the check is not trivial"


@pytest.mark.parametrize("integrator, forces", cases([("implicit", "points"), ("implicit", "panels"), ("implicit", "cells"), ("splitting", "points")],
                                                     lambda integrator, forces: still(integrator, forces, current=True)))  # fmt: skip
def test_kernels_match_the_reference_in_a_current(integrator, forces):
    scene = with_overrides(load_scene("damped"), fluid__forces=forces, fluid__drag_coefficient=0.8, step__integrator=integrator,
                           water__current=(0.5, 0.2), initial__orientation=(0.96, 0.2, 0.1, 0.17))  # fmt: skip
    reference, compiled = Simulation(scene, backend="numpy"), Simulation(scene, backend="numba")
    assert compiled.compiled
    for _ in range(3):
        reference.step(40)
        compiled.step(40)
        a, b = reference.state.as_vector(), compiled.state.as_vector()
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-10 * (1 + np.abs(a).max()))
        for field in ("force_world", "torque_world"):
            np.testing.assert_allclose(getattr(compiled.frame(), field), getattr(reference.frame(), field), rtol=1e-10, atol=1e-8)


@pytest.mark.slow  # over 4 s (the marker's rule)
def test_a_floating_body_released_at_rest_drifts_with_the_current(tmp_path):
    """Through the CLI: the damped cube released at rest in a 0.5 m/s current ends up moving with it, at
    rest relative to the water (the only horizontal force is damping on the relative velocity)."""
    out = tmp_path / "drift.csv"
    done = subprocess.run([sys.executable, "-m", "sim", "run", "--scene", "damped", "--current", "0.5", "0.0", "--t-end", "40", "--every", "100",
                           "--out", str(out)], cwd=ROOT, capture_output=True, text=True, timeout=300)  # fmt: skip
    assert done.returncode == 0, done.stderr
    rows = np.genfromtxt(out, delimiter=",", names=True)
    assert rows["ux"][0] == 0.0 and rows["x"][0] == 0.0
    relative = np.hypot(rows["ux"] - 0.5, rows["uy"])  # the scene's initial spin stirs uy for a while: it dies away too
    assert relative[-1] < 2e-5 and relative[-1] < 1e-2 * relative[len(rows) // 4]
    assert np.all(np.diff(rows["x"]) > 0)  # carried downstream all along
    bad = subprocess.run([sys.executable, "-m", "sim", "run", "--scene", "damped", "--current", "0.5"], cwd=ROOT, capture_output=True, text=True,
                         timeout=120)  # fmt: skip
    assert bad.returncode != 0 and "Traceback" not in bad.stderr and len(bad.stderr.strip().splitlines()) == 1, bad.stderr


def test_a_current_with_radiation_is_refused_in_one_line():
    """The radiation memory (Cummins) assumes water at rest: a current with it is not modelled, so not run."""
    done = subprocess.run([sys.executable, "-m", "sim", "run", "--scene", "sphere", "--current", "0.5", "0"], cwd=ROOT, capture_output=True, text=True,
                          timeout=120)  # fmt: skip
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1 and "current with radiation" in done.stderr, done.stderr


def test_a_small_body_released_in_a_strong_current_runs_as_the_same_body_thrown_into_water_at_rest(tmp_path):
    """Issue 37: a 0.3 m cube released at rest in a 20 m/s current (the range's limit) was stopped as a divergence at
    t = 0.7 s: the blow-up check measured the energy the current gives it (1/2 M U^2, 4.9 kJ) against the cube's own
    scale (10.5 J at rest). Through the CLI it now runs, and is (Galilean invariance) the cube thrown at -U into water
    at rest, seen moving with the water: positions shifted by U t, velocities by U."""
    out = tmp_path / "strong.csv"
    done = subprocess.run([sys.executable, "-m", "sim", "run", "--scene", "damped", "--size", "0.3", "--current", "20", "0", "--t-end", "1.5",
                           "--every", "10", "--out", str(out)], cwd=ROOT, capture_output=True, text=True, timeout=300)  # fmt: skip
    assert done.returncode == 0 and "diverged" not in done.stderr, done.stderr
    rows = np.genfromtxt(out, delimiter=",", names=True)
    U = np.array([20.0, 0.0, 0.0])
    thrown = Simulation(with_overrides(load_scene("damped"), body__size=0.3, initial__velocity=tuple(-U)), backend="numpy")
    for row in rows[1:]:
        thrown.step(10)
        s = thrown.state
        assert row["t"] == pytest.approx(s.t, abs=1e-9)
        np.testing.assert_allclose([row["x"], row["y"], row["z"]], s.x_world + U * s.t, rtol=0, atol=1e-6)
        np.testing.assert_allclose([row["ux"], row["uy"], row["uz"]], s.u_world + U, rtol=0, atol=1e-6)
    assert rows["ux"][-1] > 0.9 * U[0]  # carried up to the current's speed

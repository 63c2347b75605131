"""Ensembles: each body advances exactly as it would alone; sweeps land on the analytic equilibria."""

import numpy as np
import pytest

from sim import ConfigError, Simulation, load_scene, with_overrides
from sim.commands import main
from sim.ensemble import Ensemble
from tests.covering import LINEAR, cases, still


@pytest.mark.parametrize("backend", ["numba", "numpy"])
def test_each_body_of_an_ensemble_moves_as_it_would_alone(backend):
    base = load_scene("damped")
    scenes = [with_overrides(base, body__density=rho, fluid__damping=d, initial__position=(0.0, 0.0, z))
              for rho, d, z in [(300.0, 50.0, 0.2), (900.0, 100.0, 0.0), (1500.0, 0.0, -0.3)]]  # fmt: skip
    ensemble = Ensemble(scenes, backend=backend)
    ensemble.step(150)
    for scene, state in zip(scenes, ensemble.states):
        alone = Simulation(scene, backend=backend)
        alone.step(150)
        a = alone.state.as_vector()  # (inertia scaled from the shared shape: round-off apart)
        np.testing.assert_allclose(state.as_vector(), a, rtol=0, atol=1e-13 * (1 + np.abs(a).max()))
        assert state.t == pytest.approx(alone.state.t, rel=1e-14)


@pytest.mark.parametrize(
    "integrator", cases([("splitting",), ("implicit",), ("rk4",)], lambda i: still(i, "points", LINEAR))
)  # the one alone without drag
def test_bodies_with_and_without_drag_share_one_ensemble(integrator):
    """Per-body term coefficients: a body whose drag coefficient is 0 moves exactly as alone (where
    the term is left out), next to bodies with drag."""
    base = with_overrides(load_scene("damped"), step__integrator=integrator)
    scenes = [with_overrides(base, fluid__drag_coefficient=cd) for cd in (0.0, 0.5, 2.0)]
    ensemble = Ensemble(scenes)
    ensemble.step(200)
    for scene, state in zip(scenes, ensemble.states):
        alone = Simulation(scene)
        alone.step(200)
        a = alone.state.as_vector()
        np.testing.assert_allclose(state.as_vector(), a, rtol=0, atol=1e-12 * (1 + np.abs(a).max()))
    assert not np.allclose(ensemble.states[0].as_vector(), ensemble.states[2].as_vector(), atol=1e-3)


def test_a_diverging_body_stops_alone():
    base = with_overrides(load_scene("damped"), step__integrator="euler", step__dt=0.01)
    ensemble = Ensemble([with_overrides(base, fluid__damping=d) for d in (100.0, 1e6, 50.0)])
    ensemble.step(300)
    assert [why is None for why in ensemble.diverged] == [True, False, True]
    assert "diverged at t =" in ensemble.diverged[1]
    assert all(s.is_finite() for s in ensemble.states)
    assert ensemble.states[0].t == pytest.approx(3.0) and ensemble.states[1].t < 3.0


def test_ensemble_refuses_bodies_of_different_shapes():
    base = load_scene("damped")
    with pytest.raises(ConfigError, match="must share shape"):
        Ensemble([base, with_overrides(base, body__points_per_edge=4)])


def test_density_sweep_settles_each_cube_at_its_archimedes_draft(tmp_path):
    """Upright cube of side 1 floats with its centre at z = 1/2 - rho_body / rho_water."""
    import pandas as pd

    densities = [300.0, 600.0, 900.0]
    code = main(["sweep", "--param", "density=" + ",".join(map(str, densities)), "--scene", "rest", "--t-end", "20", "--out", str(tmp_path),
                 "--history-every", "200"])  # fmt: skip
    assert code == 0
    rows = pd.read_parquet(tmp_path).sort_values("case")
    assert list(rows.density) == densities and set(rows.status) == {"end"}
    history = pd.read_parquet(tmp_path / "_history")
    for case, rho in enumerate(densities):
        # rest scene starts at z = -0.4 with no damping: it oscillates about its equilibrium,
        # so check the range of the history instead of the final point
        z = history[history.case == case].z.to_numpy()
        assert len(z) == 21
        assert z.min() <= 0.5 - rho / 1000 <= z.max()
    assert rows.t.to_numpy() == pytest.approx(20.0)
    assert rows.z.iloc[2] == pytest.approx(-0.4, abs=1e-9)  # the 900 one was at rest already


def test_sweep_bad_input_is_one_line(capsys, tmp_path):
    assert main(["sweep", "--param", "density=900,-5", "--scene", "rest", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "density must be >= 0.001" in err

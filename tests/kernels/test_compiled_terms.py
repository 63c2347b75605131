"""No term can go missing: every registered force term has its compiled twin, each one alone agrees with the
reference stage by stage, and a term without a twin sends its scene to the numpy reference with a note."""

from dataclasses import replace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import sim.hydro.forces
from sim import FluidConfig, Model, Simulation, StillWater, load_scene, with_overrides
from sim.bodies.body import make_box
from sim.hydro.forces import TERMS, Load, Term
from sim.kernels import COMPILED_TERMS, Spec, pack, sea_pack, specialised
from sim.kernels import Model as Packed
from sim.kernels.layout import Scratch
from sim.water.seas import regular_waves

POSES = list(zip(Rotation.random(4, random_state=3).as_quat(scalar_first=True), np.linspace(-0.3, 0.25, 4)))
TWISTS = np.random.default_rng(7).normal(size=(4, 6))
CASES = [("points", "still"), ("panels", "regular")]


def test_every_registered_term_is_compiled_in_registry_order():
    assert COMPILED_TERMS == tuple(term.name for term in TERMS)
    terms = specialised(Spec("implicit", "points", COMPILED_TERMS, False, False)).terms
    for term in TERMS:
        assert callable(getattr(terms, term.name)), f"kernels/terms.py has no {term.name}"


def alone(model: Model, name: str) -> Model:
    """The model with only the term `name` switched on."""
    term = next(t for t in TERMS if t.name == name)
    model.terms, model.pose_terms, model.twist_terms = (term,), () if term.twist else (term,), (term,) if term.twist else ()
    model.needs_wet, model.linear_in_twist = name != "gravity", term.linear
    return model


@pytest.mark.parametrize("forces, water", CASES)
@pytest.mark.parametrize("name", [term.name for term in TERMS])
def test_each_term_alone_matches_the_reference(name, forces, water):
    """The term's force, torque and linearisation (f, D), kernel against reference, with no other term on (in waves
    halfway up their ramp: 0.44 of their height at t = 2.3 s)."""
    waves = water != "still"
    sea_state = replace(regular_waves(1000.0, 9.81, 0.4, 5.0, 20.0), ramp=5.0) if waves else StillWater()
    model = alone(
        Model(
            make_box((1.0, 0.8, 0.6), 6, 400.0),
            sea_state,
            FluidConfig(forces=forces, damping=40.0, drag_coefficient=0.8, heave_damping=900.0),
        ),
        name,
    )
    kernels = specialised(Spec("implicit", forces, (name,), waves, False))
    forces_kernel = kernels.forces
    packed = Packed(model.body.packed, model.body.mass, model.body.inertia, pack(model)[1])
    s = Scratch(np.zeros(model.body.n_samples, dtype=bool), np.zeros(34), kernels.surface.workspace(model.body.packed))
    sea = sea_pack(model.water, model.body)
    t = 2.3 if waves else 0.0
    weight = model.body.mass * 9.81
    for (q, z), twist in zip(POSES, TWISTS):
        x, R = np.array([0.1, -0.2, z]), Rotation.from_quat(q, scalar_first=True).as_matrix()
        wet = model.wetted(x, R, t)
        F, T, D, is_wet = forces_kernel.pose_loads(x, R, t, packed, s, sea)
        Fv, Tv = F.copy(), T.copy()
        forces_kernel.twist_loads(x, R, twist[:3], twist[3:], packed, D, is_wet, s, Fv, Tv)
        F_ref, T_ref = model.loads(wet, twist[:3], twist[3:], t)
        assert np.abs(F_ref).max() + np.abs(T_ref).max() > 0.0, "the term acts at this pose"
        np.testing.assert_allclose(np.concatenate([Fv, Tv]), np.concatenate([F_ref, T_ref]), rtol=0, atol=1e-11 * weight)
        f, Dt = forces_kernel.linearised(x, R, twist[:3], twist[3:], packed, F, T, D, is_wet, s)
        f_ref, D_ref = model.linearised(wet, twist, t)
        np.testing.assert_allclose(f, f_ref, rtol=0, atol=1e-11 * weight)
        np.testing.assert_allclose(Dt, np.zeros((6, 6)) if D_ref is None else D_ref, rtol=0, atol=1e-11 * weight)


def test_a_term_without_a_compiled_twin_runs_on_numpy_and_says_so(monkeypatch):
    """A term registered in the reference but not compiled is not dropped: the scene runs on numpy, with a note."""

    def push(body, water, fluid, wet, twist, t) -> Load:
        return Load(np.array([3.0, 0.0, 0.0]), np.zeros(3))

    monkeypatch.setattr(sim.hydro.forces, "TERMS", TERMS + (Term("push", push, used=lambda fluid: True),))
    scene = with_overrides(load_scene("damped"), step__t_end=1.0)
    pushed = Simulation(scene, backend="numba")
    assert not pushed.compiled and any("push" in note and "numpy" in note for note in pushed.notes), pushed.notes
    pushed.step(100)
    monkeypatch.setattr(sim.hydro.forces, "TERMS", TERMS)
    plain = Simulation(scene, backend="numba")
    assert plain.compiled
    plain.step(100)
    # 3 N along x for 0.5 s on a 900 kg cube in damped water: it moves along x by up to the undamped a t^2 / 2
    shift = pushed.state.x_world[0] - plain.state.x_world[0]
    assert 2e-4 < shift < 0.5 * 3.0 / 900.0 * 0.5**2

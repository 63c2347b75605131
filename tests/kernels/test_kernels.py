"""The compiled kernels against the plain-numpy reference: the same trajectories to round-off."""

from dataclasses import replace

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from sim import FluidConfig, Model, Simulation, SimulationDiverged, State, StillWater, load_scene, make_integrator, with_overrides
from sim.bodies.body import make_box, make_mesh_body
from sim.kernels import NO_RADIATION, SCHEMES, Spec, pack, sea_pack, spec_of, specialised
from sim.kernels.layout import Model as Packed
from sim.kernels.layout import Scratch
from sim.water.seas import jonswap_waves, regular_waves
from tests.covering import EVERY, LINEAR, cases, still, terms_for

WATER_KIND = {"still": False, "regular": True, "jonswap": True, "spread": True}
"""Whether each of the stage tests' waters (WATERS below) is a sea, for the kernels' spec."""

CASES = [(scene, changes, integrator, forces) for scene, changes in [("damped", {}), ("spin", {}), ("drop", {"body__density": 300.0}), ("damped", {"fluid__damping": 1e6})]
         for integrator in ["euler", "splitting", "implicit", "rk4"] for forces in ["points", "cells", "panels"]
         if integrator == "implicit" or "fluid__damping" not in changes]  # explicit ones diverge there (tested below)  # fmt: skip
"""Still water, no drag: the implicit cases run by default (the presets' kernels and cells'), the others under -m exhaustive."""


@pytest.mark.parametrize(
    "scene, changes, integrator, forces", cases(CASES, lambda scene, changes, integrator, forces: still(integrator, forces, LINEAR))
)
def test_compiled_path_matches_numpy_reference(scene, changes, integrator, forces):
    config = with_overrides(load_scene(scene), step__integrator=integrator, fluid__forces=forces, **changes)
    reference, compiled = Simulation(config, backend="numpy"), Simulation(config, backend="numba")
    assert compiled.compiled and not reference.compiled
    for _ in range(5):  # several calls: state carried correctly between calls of many steps
        reference.step(40)
        compiled.step(40)
        a, b = reference.state.as_vector(), compiled.state.as_vector()
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-10 * (1 + np.abs(a).max()))
    assert compiled.state.t == pytest.approx(reference.state.t, rel=1e-14)


def test_compiled_path_stops_on_divergence_with_a_finite_state():
    config = with_overrides(load_scene("damped"), fluid__damping=1e6, step__integrator="euler", step__dt=0.01)
    sim = Simulation(config, backend="numba")
    with pytest.raises(SimulationDiverged, match="diverged at t = .*--integrator implicit"):
        sim.step(1000)
    assert sim.state.is_finite()


def test_adaptive_integrators_use_the_numpy_path():
    sim = Simulation(with_overrides(load_scene("rest"), step__integrator="dop853"), backend="numba")
    assert not sim.compiled
    sim.step(5)
    assert abs(sim.state.x_world[2] + 0.4) < 1e-9


@pytest.mark.parametrize("forces", ["points", "cells", "panels"])
@pytest.mark.parametrize(
    "scene, changes", [("damped", {}), ("spin", {"fluid__damping": 30.0}), ("drop", {"initial__position": (0.0, 0.0, 3.0)})]
)
def test_compiled_frame_matches_numpy_frame(scene, changes, forces):
    config = with_overrides(load_scene(scene), fluid__forces=forces, **changes)
    reference, compiled = Simulation(config, backend="numpy"), Simulation(config, backend="numba")
    for _ in range(4):
        a, b = reference.frame(), compiled.frame()
        for field in ("force_world", "torque_world", "omega_world"):
            np.testing.assert_allclose(getattr(b, field), getattr(a, field), rtol=1e-12, atol=1e-9)
        for field in ("E_kin", "E_grav", "E_hyd", "E_hyd_of_model", "E_total", "submerged_area", "submerged_volume"):
            assert getattr(b, field) == pytest.approx(getattr(a, field), rel=1e-12, abs=1e-9)
        np.testing.assert_array_equal(b.wet_index, a.wet_index)
        reference.step(25)
        compiled.reset(reference.state)  # the same state for both


# ---- stage by stage, on the cube and on an anisotropic mesh body, with every term on ------------------

BODIES = {
    "cube": lambda: make_box((1.0, 1.0, 1.0), 6, 900.0, "cube"),
    # a box given as a mesh, tilted in its file so its principal frame is not the file's: three different moments
    "mesh": lambda: make_mesh_body(
        trimesh.creation.box(extents=(1.0, 0.6, 0.3), transform=trimesh.transformations.rotation_matrix(0.4, [1, 2, 3])), 300, density=700.0
    ),  # fmt: skip
}
POSES = list(zip(Rotation.random(6, random_state=11).as_quat(scalar_first=True), np.linspace(-0.35, 0.3, 6)))
TWISTS = np.random.default_rng(2).normal(size=(6, 6))


WATERS = {
    "still": lambda: StillWater(),
    "regular": lambda: regular_waves(1000.0, 9.81, 0.5, 6.0, 30.0),  # the direct sum
    "jonswap": lambda: jonswap_waves(1000.0, 9.81, 3.0, 9.0, components=64, seed=1, direction_deg=20.0),  # the local expansion
    "spread": lambda: jonswap_waves(1000.0, 9.81, 3.0, 9.0, components=24, seed=2, spreading=8.0, depth=25.0),  # direct, finite depth
}
T_WAVES = 3.7
FORCES = ("points", "cells", "panels")
FORCES_WATERS = [(f, w) for f in FORCES for w in WATERS if f != "cells" or w == "still"]
"""cells has no compiled twin in waves (the simulation runs it on the numpy reference there)."""


def model_of(body_name: str, forces: str, damping: float = 40.0, drag_coefficient: float = 0.7, water: str = "still") -> Model:
    fluid = FluidConfig(forces=forces, damping=damping, drag_coefficient=drag_coefficient)
    return Model(BODIES[body_name](), WATERS[water](), fluid)


def kernels_of(model: Model, scheme: str = "implicit"):
    """The compiled kernels specialised for this model (and scheme)."""
    return specialised(spec_of(model, scheme))


WAVE_KERNELS = Spec("implicit", "points", ("gravity", "pressure", "damping"), True, False)


def close(a, b, scale=1.0, tol=1e-12):
    np.testing.assert_allclose(a, b, rtol=0, atol=tol * max(1.0, scale, np.abs(b).max()))


@pytest.mark.parametrize("body_name", BODIES)
@pytest.mark.parametrize("forces", FORCES)
def test_stage_wet_integrals(body_name, forces):
    """The kernel's running wet-set sums (points, carried from pose to pose) and closed-form clipped
    panels against the reference's quadrature nodes: area, z nu, (z r) x nu, r and r r^T integrals."""
    model = model_of(body_name, forces)
    k = kernels_of(model)
    flags, acc, ws = np.zeros(model.body.n_samples, dtype=bool), np.zeros(34), k.surface.workspace(model.body.packed)
    for q, z in POSES:
        x, R = np.array([0.05, -0.1, z]), Rotation.from_quat(q, scalar_first=True).as_matrix()
        wet = model.wetted(x, R)
        zn, zt, A, S, rr = k.wet.wet_integrals(x, R, model.body.packed, True, flags, acc, ws)
        wz = wet.weight * wet.point[:, 2]
        close(A, wet.submerged_area)
        close(zn, wz @ wet.normal)
        close(zt, (wz[:, None] * np.cross(wet.lever, wet.normal)).sum(axis=0))
        close(S, wet.weight @ wet.lever)
        close(rr, (wet.lever * wet.weight[:, None]).T @ wet.lever)
        if forces == "points":
            np.testing.assert_array_equal(np.flatnonzero(flags), wet.index)


@pytest.mark.parametrize("body_name", BODIES)
@pytest.mark.parametrize(
    "forces, water", cases(FORCES_WATERS, lambda forces, water: Spec("implicit", forces, EVERY, WATER_KIND[water], False), forces_only=True)
)
def test_stage_loads_and_linearisation(body_name, forces, water):
    """Every term's total force and torque at a pose, time and twist, and the implicit scheme's
    linearised loads (f, D), kernel against reference, in still water and in waves."""
    model = model_of(body_name, forces, water=water)
    terms, coef = pack(model)
    assert terms == 0b1111  # gravity, pressure, damping, drag
    k = kernels_of(model)
    s = Scratch(np.zeros(model.body.n_samples, dtype=bool), np.zeros(34), k.surface.workspace(model.body.packed))
    body = Packed(model.body.packed, model.body.mass, model.body.inertia, coef)
    sea = sea_pack(model.water, model.body)
    weight = model.body.mass * 9.81
    tol = 1e-10 if water == "jonswap" else 1e-12  # the expansion's truncation bound is 1e-13 of the amplitudes
    t = 0.0 if water == "still" else T_WAVES
    for (q, z), twist in zip(POSES, TWISTS):
        x, R = np.array([0.0, 0.2, z]), Rotation.from_quat(q, scalar_first=True).as_matrix()
        wet = model.wetted(x, R, t)
        u, w = twist[:3], twist[3:]
        F, T, D, is_wet = k.forces.pose_loads(x, R, t, body, s, sea)
        Fv, Tv = F.copy(), T.copy()
        k.forces.twist_loads(x, R, u, w, body, D, is_wet, s, Fv, Tv)
        F_ref, T_ref = model.loads(wet, u, w, t)
        close(Fv, F_ref, weight, tol)
        close(Tv, T_ref, weight, tol)
        f, Dt = k.forces.linearised(x, R, u, w, body, F, T, D, is_wet, s)
        f_ref, D_ref = model.linearised(wet, twist, t)
        close(f, f_ref, weight, tol)
        assert is_wet == (D_ref is not None)  # a wave trough can leave the body dry
        close(Dt, np.zeros((6, 6)) if D_ref is None else D_ref, weight, tol)


STEP_CASES = [(scheme, forces, water) for scheme in SCHEMES for forces, water in FORCES_WATERS
              if scheme == "implicit" or forces == "points" or (forces, water) == ("panels", "still")]  # fmt: skip
"""The implicit step with every force model in every water; the other schemes with points in every water and
panels in still water. Each scheme meets each water and drag, and each force model meets each water and drag,
here; each scheme meets each force model in the trajectories above and below (with drag for points and panels).
A specialisation compiles for half a minute on a cold cache: the full product would add six. By default each
scheme with points in still water, and the implicit one with each force model and points in waves (tests/covering.py)."""


@pytest.mark.parametrize("body_name", BODIES)
@pytest.mark.parametrize(
    "scheme, forces, water", cases(STEP_CASES, lambda scheme, forces, water: Spec(scheme, forces, EVERY, WATER_KIND[water], False))
)
def test_stage_one_step_of_each_scheme(body_name, forces, scheme, water):
    model = model_of(body_name, forces, water=water)
    _, coef = pack(model)
    sea = sea_pack(model.water, model.body)
    integrator = make_integrator(scheme)
    schemes = kernels_of(model, scheme).schemes
    t = 0.0 if water == "still" else T_WAVES
    for (q, z), twist in zip(POSES[:3], TWISTS):
        R = Rotation.from_quat(q, scalar_first=True).as_matrix()
        state = State(
            t, np.array([0.0, 0.0, z]), np.asarray(q, float), 0.5 * twist[:3], R @ (model.body.inertia * (R.T @ (0.5 * twist[3:])))
        )
        ref = integrator.step(model, state, 0.01).as_vector()
        y, done = schemes.advance(state.as_vector(), t, 1, 0.01, Packed(model.body.packed, model.body.mass, model.body.inertia, coef), sea,
                                  NO_RADIATION)  # fmt: skip
        assert done == 1
        close(y, ref, np.abs(ref).max(), 1e-10 if water == "jonswap" else 1e-12)


@pytest.mark.parametrize("body_name", BODIES)
@pytest.mark.parametrize(
    "forces, water", cases(FORCES_WATERS, lambda forces, water: Spec("implicit", forces, EVERY, WATER_KIND[water], False))
)
def test_stage_frame_with_every_term(body_name, forces, water):
    model = model_of(body_name, forces, water=water)
    _, coef = pack(model)
    observe_kernel = kernels_of(model).simulation.observe
    body = Packed(model.body.packed, model.body.mass, model.body.inertia, coef)
    sea = sea_pack(model.water, model.body)
    t = 0.0 if water == "still" else T_WAVES
    tol = 1e-10 if water == "jonswap" else 1e-12
    for (q, z), twist in zip(POSES, TWISTS):
        R = Rotation.from_quat(q, scalar_first=True).as_matrix()
        x = np.array([0.0, 0.0, z])
        wet = np.empty(model.body.n_samples, dtype=bool)
        F, T, e_hyd, a_sub, v_sub = observe_kernel(x, R, t, twist[:3], twist[3:], body, sea, wet)
        ref = model.wetted(x, R, t)
        F_ref, T_ref = model.loads(ref, twist[:3], twist[3:], t)
        close(F, F_ref, model.body.mass * 9.81, tol)
        close(T, T_ref, model.body.mass * 9.81, tol)
        assert e_hyd == pytest.approx(model.hydrostatic_energy(ref), rel=tol, abs=1e-9)
        assert (a_sub, v_sub) == pytest.approx((ref.submerged_area, ref.submerged_volume), rel=tol, abs=1e-12)
        heights = model.water.height_above_surface(x + model.body.r_body @ R.T, t)
        np.testing.assert_array_equal(
            np.flatnonzero(wet), ref.index if forces == "cells" else np.flatnonzero(heights < 0)
        )  # cells: any part wet


@pytest.mark.parametrize("integrator, forces", cases([(i, f) for f in ("points", "panels") for i in SCHEMES], lambda i, f: still(i, f)))
def test_compiled_path_matches_numpy_with_drag(integrator, forces):
    config = with_overrides(load_scene("damped"), step__integrator=integrator, fluid__forces=forces, fluid__drag_coefficient=1.5)
    reference, compiled = Simulation(config, backend="numpy"), Simulation(config, backend="numba")
    for _ in range(3):
        reference.step(40)
        compiled.step(40)
        a, b = reference.state.as_vector(), compiled.state.as_vector()
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-10 * (1 + np.abs(a).max()))


@pytest.mark.parametrize("integrator, forces", cases([(i, f) for f in ("points", "panels") for i in ("implicit", "splitting")],
                                                    lambda i, f: still(i, f)))  # fmt: skip
def test_drag_switched_on_and_off_keeps_the_kernels_and_their_path_follows(integrator, forces):
    """Issue 57: one specialisation serves a scene with drag and without (the waves and storm presets share theirs).
    The implicit and splitting steps choose their path at run time: drag off (the exact linear modes), on (relinearised,
    splitting's general flow), off again, the compiled run follows the numpy reference through every switch, on the
    same kernels."""
    assert Simulation(load_scene("waves"), backend="numpy").spec == Simulation(load_scene("storm"), backend="numpy").spec
    config = with_overrides(load_scene("damped"), step__integrator=integrator, fluid__forces=forces)
    reference, compiled = Simulation(config, backend="numpy"), Simulation(config, backend="numba")
    spec = compiled.spec
    for drag in (0.0, 2.0, 0.0):
        for run in (reference, compiled):
            run.update(fluid__drag_coefficient=drag)
            run.step(60)
        a, b = reference.state.as_vector(), compiled.state.as_vector()
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-10 * (1 + np.abs(a).max()), err_msg=f"drag {drag}")
        assert compiled.compiled and compiled.spec == spec


def test_fixed_step_integrator_without_a_kernel_falls_back_to_numpy_with_a_note(monkeypatch):
    """A new fixed-step scheme that has no compiled twin yet runs on the reference, and says so."""
    import sim.kernels

    monkeypatch.setattr(sim.kernels, "SCHEMES", {k: v for k, v in sim.kernels.SCHEMES.items() if k != "rk4"})
    config = with_overrides(load_scene("damped"), step__integrator="rk4")
    sim = Simulation(config, backend="numba")
    assert not sim.compiled and any("rk4" in note and "numpy" in note for note in sim.notes)
    reference = Simulation(config, backend="numpy")
    sim.step(20)
    reference.step(20)
    np.testing.assert_array_equal(sim.state.as_vector(), reference.state.as_vector())


# ---- waves: the compiled sea against the reference --------------------------------------------------


@pytest.mark.parametrize("scene, changes, forces", cases([(scene, changes, forces) for forces in ("points", "panels") for scene, changes in
                                                           [("waves", {}), ("storm", {}), ("storm", {"waves__spreading": 10.0, "waves__depth": 30.0, "waves__components": 16})]],
                                                          lambda scene, changes, forces: Spec("implicit", forces, EVERY, True, False)))  # fmt: skip
def test_compiled_path_matches_numpy_in_waves(scene, changes, forces):
    """Trajectories in a regular swell (direct sum), the storm (local expansion, with drag) and a
    short-crested finite-depth sea (direct sum), across the end of a short ramp: kernel and reference agree to round-off."""
    config = with_overrides(load_scene(scene), fluid__forces=forces, waves__ramp=0.15, **changes)
    reference, compiled = Simulation(config, backend="numpy"), Simulation(config, backend="numba")
    assert compiled.compiled
    for _ in range(3):
        reference.step(20)
        compiled.step(20)
        a, b = reference.state.as_vector(), compiled.state.as_vector()
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-10 * (1 + np.abs(a).max()))


@pytest.mark.parametrize("ramp", [0.0, 10.0])
def test_local_expansion_of_the_sea_matches_the_direct_sum(ramp):
    """Elevation, pressure and flow from the expansion about the body against every component summed,
    at points spread over the body's reach (its radius, and stretched depths down to its draft); without a ramp
    and a third of the way up one (the sea at 0.25 of its height)."""
    body = BODIES["cube"]()
    water = replace(jonswap_waves(1000.0, 9.81, 3.0, 9.0, components=64, seed=1, direction_deg=20.0), ramp=ramp)
    x = np.array([3.0, -2.0, -0.4])
    pts = x + np.random.default_rng(5).uniform(-1, 1, (400, 3)) * body.radius / np.sqrt(3)
    results = []
    prepare, elevations, fields = (getattr(specialised(WAVE_KERNELS).water, f) for f in ("prepare", "elevations", "fields"))
    for expand in (True, False):
        sea = sea_pack(water, body, expand)
        ex = prepare(sea, T_WAVES, x)
        assert (ex[0] >= 0) == expand  # the expansion's degree, -1: direct sum
        eta, out = np.empty(len(pts)), np.empty((len(pts), 4))
        elevations(sea, ex, pts, len(pts), eta)
        fields(sea, ex, pts, eta, len(pts), 1000.0, 9.81, True, out, True)
        results.append((eta, out))
    (eta, out), (eta_d, out_d) = results
    np.testing.assert_allclose(eta_d, water.elevation(pts[:, :2], T_WAVES), rtol=0, atol=1e-12)  # the direct sum is the reference's
    pressure, flow = water.field(pts, T_WAVES)
    np.testing.assert_allclose(out_d[:, 0], pressure, rtol=0, atol=1e-12 * 1000 * 9.81)
    np.testing.assert_allclose(out_d[:, 1:], flow, rtol=0, atol=1e-12)
    amplitude = water.amplitude.sum() * water.ramped(T_WAVES)
    assert np.abs(eta - eta_d).max() < 1e-12 * amplitude
    assert np.abs(out[:, 0] - out_d[:, 0]).max() < 1e-12 * 1000 * 9.81 * amplitude
    assert np.abs(out[:, 1:] - out_d[:, 1:]).max() < 1e-12 * (water.amplitude * water.omega).sum() * water.ramped(T_WAVES)
    assert water.ramped(T_WAVES) == (1.0 if not ramp else pytest.approx(0.5 - 0.5 * np.cos(np.pi * T_WAVES / ramp), rel=1e-15))


def test_a_body_large_against_the_waves_falls_back_to_the_direct_sum():
    """A 300 m barge in a sea whose short waves are 14 m long: no expansion degree meets the bound."""
    body = make_box((300.0, 60.0, 20.0), 2, 1.0e8)
    water = jonswap_waves(1000.0, 9.81, 3.0, 9.0, components=64, seed=1)
    prepare = specialised(WAVE_KERNELS).water.prepare
    assert prepare(sea_pack(water, body), 0.0, np.zeros(3))[0] == -1
    assert prepare(sea_pack(water, BODIES["cube"]()), 0.0, np.zeros(3))[0] > 0


# ---- radiation: the compiled Cummins terms against the reference ------------------------------------


RADIATION_CHANGES = [{"initial__omega": (0.3, -0.2, 0.1)}, {"fluid__drag_coefficient": 0.8, "fluid__damping": 30.0},
                     {"waves__kind": "regular", "waves__height": 0.3, "fluid__damping": 20.0, "waves__ramp": 0.2,
                      "initial__position": (1.3, -0.4, -0.3)}]  # fmt: skip
"""In waves: across the end of a short ramp, away from the origin (the diffraction force is phased where the body is)."""
RADIATION_CASES = [(integrator, ("points", "panels")[(i + j) % 2], changes) for i, integrator in enumerate(["euler", "splitting", "implicit", "rk4"])
                   for j, changes in enumerate(RADIATION_CHANGES)]  # fmt: skip
"""Every scheme with every change, and each of them, scheme or change, with both force models: every pair of
the three factors (the radiation code meets the scheme and the water, not the force model's quadrature), in 12
specialisations (each compiles for half a minute on a cold cache) instead of the 24 of the full product; by default
only the implicit one alone on panels (the sphere preset's kernels), the others under -m exhaustive."""


def radiation_spec(integrator: str, forces: str, changes: dict) -> Spec:
    return Spec(
        integrator, forces, terms_for(integrator, EVERY if "fluid__drag_coefficient" in changes else LINEAR), "waves__kind" in changes, True
    )


@pytest.mark.parametrize("integrator, forces, changes", cases(RADIATION_CASES, radiation_spec))
def test_compiled_radiation_matches_numpy(integrator, forces, changes):
    """Added mass in the kicks and the exact linear flow, the memory and E_rad, alone, with damping and
    drag (relinearised) and in waves (with the diffraction force): kernel and reference to round-off, memory states included."""
    config = with_overrides(load_scene("rest"), fluid__forces=forces, step__integrator=integrator, fluid__radiation="bem",
                            **{"initial__position": (0.0, 0.0, -0.3), **changes})  # fmt: skip
    reference, compiled = Simulation(config, backend="numpy"), Simulation(config, backend="numba")
    assert compiled.compiled and len(compiled.state.memory) > 20
    assert (compiled.model.radiation.diffraction is not None) == ("waves__kind" in changes)  # in waves: the diffraction force too
    for _ in range(3):
        reference.step(30)
        compiled.step(30)
        a, b = reference.state.as_vector(), compiled.state.as_vector()
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-10 * (1 + np.abs(a).max()))
    assert compiled.state.E_rad > 0
    fa, fb = reference.frame(), compiled.frame()
    np.testing.assert_allclose(fb.force_world, fa.force_world, rtol=1e-9, atol=1e-6)
    assert fb.E_kin == pytest.approx(fa.E_kin, rel=1e-9)


def test_compiled_radiation_with_a_turned_rest_pose(monkeypatch):
    """A cube at rest yawed 30 degrees: its coefficients in world axes couple surge and sway (they
    are the upright cube's, turned), the memory is fitted in those axes and the body frame is turned
    from them. Kernel and reference agree, and the heave is the unturned cube's."""
    import dataclasses

    import sim.hydro.bem as bem
    from sim.bodies.body import make_box

    cube = make_box((1.0, 1.0, 1.0), 10, 900.0)
    upright = bem.radiation_coefficients(cube.mesh_vertices + [0.0, 0.0, -0.4], cube.mesh_faces, progress=False, center=(0.0, 0.0, -0.4))
    a = np.radians(30.0)
    Rz = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
    T = np.kron(np.eye(2), Rz)
    turned = dataclasses.replace(upright, added_mass=T @ upright.added_mass @ T.T, damping=T @ upright.damping @ T.T,
                                 added_mass_inf=T @ upright.added_mass_inf @ T.T)  # fmt: skip
    monkeypatch.setattr(bem, "radiation_coefficients", lambda *args, **kw: turned)
    # panels: the sphere preset's kernels (tests/covering.py); the turn is in the radiation, not the force model
    base = with_overrides(load_scene("rest"), fluid__forces="panels", fluid__radiation="bem", step__integrator="implicit", fluid__damping=10.0,
                          initial__position=(0.0, 0.0, -0.35), initial__velocity=(0.2, 0.0, 0.0))  # fmt: skip
    yawed = with_overrides(base, initial__orientation=(np.cos(a / 2), 0.0, 0.0, np.sin(a / 2)))
    reference, compiled = Simulation(yawed, backend="numpy"), Simulation(yawed, backend="numba")
    assert any(
        e.row != e.col and {e.row, e.col} <= {0, 1, 3, 4} and e.row % 3 != e.col % 3 for e in compiled.model.radiation.memory.entries
    )
    for _ in range(3):
        reference.step(40)
        compiled.step(40)
        ra, rb = reference.state.as_vector(), compiled.state.as_vector()
        np.testing.assert_allclose(rb, ra, rtol=0, atol=1e-10 * (1 + np.abs(ra).max()))
    monkeypatch.setattr(bem, "radiation_coefficients", lambda *args, **kw: upright)
    straight = Simulation(
        with_overrides(base, initial__velocity=(0.2 * np.cos(-a), 0.2 * np.sin(-a), 0.0))
    )  # the same motion in its own axes
    straight.step(120)
    assert compiled.state.x_world[2] == pytest.approx(straight.state.x_world[2], abs=2e-4)
    assert np.linalg.norm(compiled.state.u_world) == pytest.approx(np.linalg.norm(straight.state.u_world), rel=0.02)


def test_inliner_with_shared_scope_copies_inlines_correctly():
    """jit.py's fix to numba's inliner (one memo for the blocks of one scope): a callee of many blocks inlined at
    several sites of a caller, itself inlined, still computes what Python does (no variable of one site leaks into another)."""
    from numba import njit

    from sim.kernels import jit

    assert jit.SCOPES_SHARED  # the numba pinned in pyproject.toml has the inliner the fix is for

    def branchy(a, n):
        total = 0.0
        for i in range(n):
            if a > i:
                total += a * i
            elif i % 2 == 0:
                total -= i
            else:
                total += 1.0
        return total

    inlined = njit(inline="always")(branchy)

    @njit(inline="always")
    def twice(a, n):
        return inlined(a, n) - 2.0 * inlined(a + 1.0, n + 1)

    @njit
    def caller(a, n):
        return twice(a, n) + twice(-a, 2 * n)

    assert inlined.targetoptions["inline"] == "always"
    python = branchy(3.5, 7) - 2.0 * branchy(4.5, 8) + branchy(-3.5, 14) - 2.0 * branchy(-2.5, 15)
    assert caller(3.5, 7) == python

"""The cells force model (each sample's cell clipped at the water line), the physical energy every
model reports, and the warning for the points model's bad band."""

import math

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from sim import FluidConfig, Model, Simulation, State, StillWater, load_scene, with_overrides
from sim.bodies.body import make_box, make_mesh_body
from sim.hydro.hydrostatics import hydrostatics
from sim.system.frame import CSV_COLUMNS, observe

RHO_G = 1000.0 * 9.81
POSES = list(zip(Rotation.random(8, random_state=5).as_quat(scalar_first=True), np.linspace(-0.4, 0.35, 8)))


def frame(body, forces: str, q, z, damping: float = 0.0):
    model = Model(body, StillWater(), FluidConfig(forces=forces, damping=damping))
    return observe(model, State(0.0, np.array([0.1, -0.2, z]), np.asarray(q, float), np.zeros(3), np.zeros(3)))


BODIES = {
    "cube N=3": lambda: make_box((1.0, 1.0, 1.0), 3, 500.0),
    "box N=7": lambda: make_box((1.2, 0.8, 0.5), 7, 200.0),
    "capsule": lambda: make_mesh_body(trimesh.creation.capsule(height=1.0, radius=0.3, count=[12, 12]), 400, density=500.0),
}


@pytest.mark.parametrize("name", BODIES)
def test_cells_pressure_force_and_volume_are_exact_at_any_pose(name):
    """Pressure is linear over each cell's planar wet part, so its integral there is exact: the cells
    model's buoyancy equals the exact (panels) one at random poses, horizontal part zero, where the
    points model is off by the cells the water line cuts."""
    body = BODIES[name]()
    worst_points = 0.0
    for q, z in POSES:
        exact, cells, points = frame(body, "panels", q, z), frame(body, "cells", q, z), frame(body, "points", q, z)
        np.testing.assert_allclose(cells.force_world, exact.force_world, rtol=0, atol=1e-10 * RHO_G)
        assert cells.submerged_volume == pytest.approx(exact.submerged_volume, abs=1e-13)
        worst_points = max(worst_points, np.abs(points.force_world - exact.force_world).max())
    assert worst_points > 1.0  # N: the points model's error the cells remove


def test_cells_torque_converges_to_the_exact_one_as_n_squared():
    """What remains of the cells model's error is the midpoint rule's on the torque: O(h^2)."""
    q = Rotation.from_rotvec([0.3, -0.2, 0.1]).as_quat(scalar_first=True)
    errors = []
    for n in (8, 16, 32):
        body = make_box((1.0, 1.0, 1.0), n, 500.0)
        errors.append(np.linalg.norm(frame(body, "cells", q, -0.05).torque_world - frame(body, "panels", q, -0.05).torque_world))
    slopes = np.diff(np.log(errors)) / np.log(2.0)
    assert np.all(slopes < -1.8), errors


def test_cells_wetting_is_continuous_where_points_jumps():
    """As a sample of the tilted cube crosses the water line, the points model's wet area (and so the
    damping force on a moving body) jumps by the sample's whole area; the cells model's grows by
    about (waterline length) x dz. Pressure itself is continuous in both (zero at the water line)."""
    body = make_box((1.0, 1.0, 1.0), 6, 500.0)
    q = Rotation.from_rotvec([0.2, 0.1, 0.0]).as_quat(scalar_first=True)
    R = Rotation.from_quat(q, scalar_first=True).as_matrix()
    k = int(np.argmax(body.n_body[:, 0]))  # a sample on a side face
    z_cross = -(body.r_body[k] @ R[2])  # the centre's height at which sample k sits on the water line
    dz = 1e-7

    def moving(forces, z):
        model = Model(body, StillWater(), FluidConfig(forces=forces, damping=100.0))
        x = np.array([0.1, -0.2, z])
        return observe(model, State(0.0, x, np.asarray(q, float), np.array([0.0, 0.0, -1.0]), np.zeros(3)))

    for forces, jump in (("points", body.area[k]), ("cells", 0.0)):
        below, above = moving(forces, z_cross - dz), moving(forces, z_cross + dz)
        area_step = below.submerged_area - above.submerged_area
        force_step = abs(below.force_world[2] - above.force_world[2])
        if forces == "points":
            assert area_step == pytest.approx(jump, rel=1e-9)
            assert force_step > 0.5 * 100.0 * jump  # d a |u|: the damping force jumps
        else:
            assert 0 <= area_step < 10 * 2 * dz  # the cube's waterline is under 10 m long
            assert force_step < 100.0 * 10 * 2 * dz + RHO_G * 2.0 * 2 * dz


def settle(density: float, n: int, forces: str, t_settle: float = 60.0, t_watch: float = 10.0):
    """The upright cube at its draft tilted 5 deg, d = 100: (min tilt, max tilt) in deg and sideways speed over the watch."""
    q = Rotation.from_rotvec([math.radians(5.0), 0.0, 0.0]).as_quat(scalar_first=True)
    scene = with_overrides(load_scene("rest"), body__density=density, body__points_per_edge=n, fluid__forces=forces, fluid__damping=100.0,
                           initial__position=(0.0, 0.0, 0.5 - density / 1000.0), initial__orientation=tuple(q), step__dt=0.01)  # fmt: skip
    sim = Simulation(scene)
    sim.step(round(t_settle / sim.dt))
    start, tilts = sim.state.x_world[:2].copy(), []
    for _ in range(round(t_watch / sim.dt / 10)):
        sim.step(10)
        tilts.append(math.degrees(math.acos(min(1.0, np.abs(sim.state.R_world_body[2]).max()))))
    return min(tilts), max(tilts), np.linalg.norm(sim.state.x_world[:2] - start) / t_watch


@pytest.mark.parametrize("density", [180.0, 215.0, 820.0])
def test_cells_bring_the_points_models_restless_cubes_to_rest_at_the_exact_pose(density):
    """Near the cube's stability transitions (GM = 0 at 211 and 789 kg/m^3) the points model at N = 10
    keeps rocking or drifting; the cells model comes to rest, at the exact (panels) tilt within the
    midpoint rule's error, which shrinks with N."""
    exact = settle(density, 10, "panels")
    assert exact[1] - exact[0] < 1e-3 and exact[2] < 1e-6
    lo, hi, speed = settle(density, 10, "cells")
    assert hi - lo < 1e-3 and speed < 1e-6
    assert abs(0.5 * (lo + hi) - exact[0]) < 0.5
    if density == 215.0:  # a tilted rest (9.04 deg): the error falls with N
        lo40, hi40, _ = settle(density, 40, "cells")
        assert abs(lo40 - exact[0]) < 0.05 * abs(lo - exact[0])


def test_every_model_reports_the_physical_hydrostatic_energy():
    """E_hyd is rho g V (-z_B) of the mesh clipped at the water line for every model (the hydrostatics
    module's independent closed forms); E_hyd_model is each model's own quadrature, the same for panels."""
    body = make_box((1.0, 1.0, 1.0), 5, 500.0)
    for q, z in POSES[:4]:
        R = Rotation.from_quat(q, scalar_first=True).as_matrix()
        h = hydrostatics(body, np.array([0.1, -0.2, z]), R)
        expected = RHO_G * h.volume * -h.buoyancy_centre[2]
        frames = {f: frame(body, f, q, z) for f in ("points", "cells", "panels")}
        for f, fr in frames.items():
            assert fr.E_hyd == pytest.approx(expected, rel=1e-12), f
        assert frames["panels"].E_hyd_of_model == frames["panels"].E_hyd
        assert abs(frames["points"].E_hyd_of_model - expected) > 1e-4 * expected
    assert CSV_COLUMNS[CSV_COLUMNS.index("E_rad") + 1] == "E_hyd_model"


def test_the_points_model_warns_in_its_bad_band_only():
    def warned(density, forces="points", n=10):
        sim = Simulation(with_overrides(load_scene("rest"), body__density=density, fluid__forces=forces, body__points_per_edge=n))
        return any("points model may keep" in w for w in sim.warnings())

    assert warned(180.0) and warned(215.0) and warned(820.0)
    assert not warned(900.0) and not warned(500.0)  # the rest preset, and the corner-up band
    assert not warned(180.0, "cells") and not warned(180.0, "panels")


def test_cells_in_waves_run_on_the_numpy_reference_with_a_note():
    sim = Simulation(with_overrides(load_scene("waves"), fluid__forces="cells"), backend="numba")
    assert not sim.compiled and any("cells" in note for note in sim.notes)
    sim.step(20)
    assert sim.state.is_finite() and sim.frame().submerged_volume > 0


def rested(mesh, **changes):
    """A Simulation of `mesh` (default force model for a mesh unless changed) placed at its rest height, at rest."""
    import dataclasses

    from sim.hydro.hydrostatics import at_rest

    sim = Simulation(with_overrides(load_scene("rest"), body__density=500.0, fluid__damping=0.0, **changes), mesh=mesh)
    sim.body_state = dataclasses.replace(sim.body_state, x_world=np.array([0.0, 0.0, at_rest(sim.body, sim.params)[0]]))
    return sim


@pytest.mark.parametrize("mesh", [trimesh.creation.box(extents=(1.0, 0.6, 0.3)), trimesh.creation.capsule(height=1.0, radius=0.3)],
                         ids=["box", "capsule"])  # fmt: skip
def test_a_symmetric_mesh_at_rest_feels_no_yaw_torque_and_stays_still(mesh):
    """A mesh body runs on panels unless asked otherwise: at rest it feels no torque and does not turn
    about the vertical (undamped, 10 s); on points the samples' midpoint rule gives a chiral triangulation a yaw torque,
    which falls as 1/samples (the cause, kept measurable)."""
    sim = rested(mesh)
    weight = sim.body.mass * 9.81
    assert sim.params.forces == "panels"
    assert np.abs(sim.frame().torque_world).max() < 1e-12 * weight
    sim.step(round(10.0 / sim.dt))
    assert abs(sim.state.L_world[2]) < 1e-9 * weight  # no yaw (the capsule standing on end may roll over: that is physics)
    if len(mesh.faces) > 12:  # the capsule, whose triangulation has a handedness (the box's halves alike: no yaw)
        yaw = [rested(mesh, fluid__forces="points", body__shape="mesh", body__mesh="x", body__samples=n) for n in (1, 4 * len(mesh.faces))]
        torque = [abs(sim.frame().torque_world[2]) for sim in yaw]
        assert torque[0] > 1e-3 * weight  # the cause, kept measurable
        ratio = yaw[1].body.n_samples / yaw[0].body.n_samples
        assert torque[0] / torque[1] > ratio  # the midpoint rule's error shrinks as the triangles are split


def test_mesh_samples_are_at_least_the_count_asked_and_keep_the_symmetry():
    """Edges longer than a threshold are halved, all alike: at least the count asked, at most about
    twice it, and a mirror-symmetric mesh keeps symmetric samples (their area-weighted centroid stays
    at the mesh's centre)."""
    from sim.bodies.body import make_mesh_body

    box = trimesh.creation.box(extents=(1.0, 0.6, 0.3))
    for n in (20, 600, 1500):
        body = make_mesh_body(box, n, density=500.0)
        assert n <= body.n_samples <= 2.2 * n
        mirrored = body.r_body * np.array([-1.0, 1.0, 1.0])  # the samples' set is its own mirror image
        assert np.abs(np.sort(mirrored, axis=0) - np.sort(body.r_body, axis=0)).max() < 1e-12
    many = trimesh.creation.icosphere(4)  # 5120 triangles: one sample each, more than asked
    assert make_mesh_body(many, 600, density=500.0).n_samples == len(many.faces)

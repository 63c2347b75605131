"""The exact panel model: Archimedes and the centre of buoyancy to round-off at any pose,
exactly conservative forces, and agreement with the sampled model as N grows."""

import numpy as np
import pytest
from scipy.spatial import ConvexHull
from scipy.spatial.transform import Rotation

from sim import Simulation, load_scene, with_overrides
from sim.bodies.rotation import quat_to_matrix, rotate_world
from sim.bodies.surface import wet_panels
from sim.hydro.forces import hydrostatic_energy


def clipped_hull(vertices_world: np.ndarray, edges) -> tuple[float, np.ndarray]:
    """Volume and centroid of a convex body's part below z = 0, independently of the panel code:
    the hull of its submerged vertices and of its edges' crossings of the water plane."""
    pts = [v for v in vertices_world if v[2] < 0]
    for a, b in edges:
        za, zb = vertices_world[a][2], vertices_world[b][2]
        if (za < 0) != (zb < 0):
            pts.append(vertices_world[a] + (vertices_world[b] - vertices_world[a]) * za / (za - zb))
    pts = np.array(pts)
    hull = ConvexHull(pts)
    inner = pts.mean(axis=0)
    vols, cents = [], []
    for simplex in hull.simplices:  # tetrahedra from an interior point
        tet = np.vstack([pts[simplex], inner])
        vols.append(abs(np.linalg.det(tet[:3] - tet[3])) / 6)
        cents.append(tet.mean(axis=0))
    return hull.volume, np.average(cents, axis=0, weights=vols)


POSES = [
    (q, z) for q, z in zip(Rotation.random(12, random_state=7).as_quat(scalar_first=True), np.linspace(-0.45, 0.45, 12))
]  # always cut by the water line


@pytest.mark.parametrize("q, zc", POSES)
def test_archimedes_and_centre_of_buoyancy_to_round_off(q, zc):
    scene = with_overrides(load_scene("rest"), fluid__forces="panels", initial__position=(0.1, -0.2, zc), initial__orientation=tuple(q))
    sim = Simulation(scene)
    body, frame = sim.body, sim.frame()
    x = sim.state.x_world
    verts = x + body.mesh_vertices @ sim.state.R_world_body.T
    edges = {tuple(sorted(e)) for e in body.mesh_faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)}
    volume, centroid = clipped_hull(verts, edges)
    buoyancy = frame.force_world + np.array([0.0, 0.0, body.mass * 9.81])
    rg = 1000 * 9.81
    np.testing.assert_allclose(buoyancy, [0.0, 0.0, rg * volume], atol=1e-11 * rg)
    assert frame.submerged_volume == pytest.approx(volume, rel=1e-12)
    # the torque is that of the buoyancy acting through the centre of buoyancy
    np.testing.assert_allclose(frame.torque_world, np.cross(centroid - x, buoyancy), atol=1e-10 * rg)
    # and the hydrostatic energy is rho g V times the depth of that centre
    assert frame.E_hyd == pytest.approx(-rg * volume * centroid[2], rel=1e-10)


@pytest.mark.parametrize("forces, tolerance", [("panels", 2e-7), ("points", None)])
def test_panel_forces_are_exactly_conservative(forces, tolerance):
    """Force and torque equal minus the gradient of the potential E_grav + E_hyd (central
    differences): exactly for panels; the sampled model is only conservative up to its quadrature."""
    scene = with_overrides(load_scene("rest"), fluid__forces=forces, body__points_per_edge=6)
    sim = Simulation(scene)
    params, body = sim.params, sim.body
    x0 = np.array([0.0, 0.0, -0.3])
    q0 = Rotation.from_rotvec([0.3, -0.5, 0.2]).as_quat(scalar_first=True)
    model = sim.model

    def potential(x, q):
        R = quat_to_matrix(q)
        wet = model.wetted(x, R)
        return body.mass * params.g * x[2] + hydrostatic_energy(model.water, wet)

    R0 = quat_to_matrix(q0)
    force, torque = model.pose_loads(model.wetted(x0, R0))
    h = 1e-6
    grad_x = [(potential(x0 + h * e, q0) - potential(x0 - h * e, q0)) / (2 * h) for e in np.eye(3)]
    grad_rot = [(potential(x0, rotate_world(q0, h * e)) - potential(x0, rotate_world(q0, -h * e))) / (2 * h) for e in np.eye(3)]
    scale = body.mass * params.g
    mismatch = max(np.abs(force + grad_x).max(), np.abs(torque + grad_rot).max()) / scale
    if tolerance is not None:
        assert mismatch < tolerance
    else:
        assert mismatch > 1e-4  # the points' kinked sum is not a gradient: the test can tell


def test_fully_submerged_damping_matrix_is_the_shell_integral():
    """Deep under water the whole cube is wet: D = d [A Id, 0; 0, J] with A = 6 s^2 and
    J = integral of (|r|^2 Id - r r^T) dA = (5/3) s^4 Id for the unit cube shell."""
    scene = with_overrides(load_scene("rest"), fluid__forces="panels", fluid__damping=2.0, initial__position=(0.0, 0.0, -3.0),
                           initial__orientation=tuple(Rotation.from_rotvec([0.4, 0.1, -0.7]).as_quat(scalar_first=True)))  # fmt: skip
    sim = Simulation(scene)
    wet = wet_panels(sim.body, sim.model.water, sim.state.x_world, sim.state.R_world_body, 0.0)
    D = sim.model.damping_matrix(wet)
    expected = 2.0 * np.diag([6.0, 6.0, 6.0, 5 / 3, 5 / 3, 5 / 3])
    np.testing.assert_allclose(D, expected, atol=1e-13)


def test_rest_scene_with_panels_stays_put():
    sim = Simulation(with_overrides(load_scene("rest"), fluid__forces="panels"))
    sim.step(1000)
    assert abs(sim.state.x_world[2] + 0.4) < 1e-9
    assert np.linalg.norm(sim.frame().force_world) < 1e-9 * sim.body.mass * 9.81


@pytest.mark.exhaustive  # the splitting's kernels on panels without drag are not the default run's (tests/covering.py)
@pytest.mark.xdist_group("kernels-splitting_panels_t7_still")
def test_panel_energy_is_conserved_to_the_integrator_order():
    """Exact conservative forces: with d = 0 the splitting's energy error has no model drift left,
    and it falls ~4x when dt halves, through the water line and while tumbling."""
    errors = []
    for dt in (0.01, 0.005):
        scene = with_overrides(
            load_scene("spin"), fluid__forces="panels", step__integrator="splitting", step__dt=dt, initial__omega=(-2.0, 2.0, 0.5)
        )
        sim = Simulation(scene)
        e0 = sim.frame().E_total
        worst = 0.0
        for _ in range(round(20 / dt) // 10):
            sim.step(10)
            worst = max(worst, abs(sim.frame().E_total - e0))
        errors.append(worst / e0)
    assert errors[0] / errors[1] == pytest.approx(4.0, rel=0.25)
    assert errors[1] < 1e-4


def test_sampled_model_converges_to_the_panel_model():
    """At a tilted pose, the samples' buoyancy and torque approach the exact ones as N grows."""
    q = tuple(Rotation.from_rotvec([0.5, 0.2, 0.0]).as_quat(scalar_first=True))
    base = with_overrides(load_scene("rest"), initial__position=(0.0, 0.0, -0.2), initial__orientation=q)
    exact = Simulation(with_overrides(base, fluid__forces="panels")).frame()
    errors = []
    for n in (5, 10, 20, 40):
        f = Simulation(with_overrides(base, body__points_per_edge=n)).frame()
        errors.append(np.linalg.norm(np.r_[f.force_world - exact.force_world, f.torque_world - exact.torque_world]))
    assert all(b < a for a, b in zip(errors, errors[1:]))
    assert errors[-1] < 2e-3 * 1000 * 9.81


def test_panels_use_the_exact_shell_inertia_and_no_longer_depend_on_n():
    """The panel model's body has the mesh shell's exact inertia ((5/18) M s^2 for the cube, whatever N),
    so its trajectories are the same for every N; the points model keeps the samples' (the report's)."""
    from sim.bodies.body import make_box, shell_inertia

    for n in (1, 4, 10):
        cube = make_box((1.3, 1.3, 1.3), n, 900.0, exact=True)
        np.testing.assert_allclose(cube.inertia, 5 / 18 * 900.0 * 1.3**2, rtol=1e-14)
        assert make_box((1.0, 1.0, 1.0), n, 900.0).inertia[0] == pytest.approx(5 / 18 * 900.0 * (1 - 2 / (5 * n * n)), rel=1e-12)
    # a thin square plate seen as a shell: two faces of area a^2 dominate, I about its normal -> M a^2 / 6
    plate = make_box((1.0, 1.0, 1e-6), 2, 1.0, exact=True)
    assert plate.inertia.max() == pytest.approx(1 / 6, rel=1e-5)
    assert np.allclose(shell_inertia(plate.mesh_vertices, plate.mesh_faces, 1.0), np.diag(plate.inertia), atol=1e-12)
    ends = []
    for n in (3, 10):
        sim = Simulation(with_overrides(load_scene("spin"), fluid__forces="panels", body__points_per_edge=n))
        sim.step(1000)
        ends.append(np.concatenate([sim.state.x_world, sim.state.L_world, sim.state.q_world_body]))
    np.testing.assert_array_equal(ends[0], ends[1])
    sim = Simulation(load_scene("spin"))
    assert not sim.body.exact_inertia
    sim.update(fluid__forces="panels")  # a live switch rebuilds the body with the exact inertia
    assert sim.body.exact_inertia and sim.body.inertia[0] == pytest.approx(250.0, rel=1e-14)

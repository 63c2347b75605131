"""Bodies: sample geometry, mass properties, meshes, and refusal of bad shapes."""

import numpy as np
import pytest
import trimesh

from sim.bodies.body import make_box, make_mesh_body
from sim.scene.config import BodyConfig, ConfigError, SceneConfig, validate


@pytest.mark.parametrize("n", [1, 3, 10])
def test_cube_samples_cover_the_surface(n):
    body = make_box((2.0, 2.0, 2.0), n, mass=5.0)
    assert body.n_samples == 6 * n * n
    assert body.area.sum() == pytest.approx(6 * 4.0, rel=1e-14)  # cell centres: no area lost at edges
    assert body.sample_mass.sum() == pytest.approx(5.0, rel=1e-14)
    np.testing.assert_allclose(np.linalg.norm(body.n_body, axis=1), 1.0, rtol=1e-15)
    # every sample lies on its face: |r . n| = s/2, and strictly inside the face (no edge points)
    np.testing.assert_allclose(np.einsum("ki,ki->k", body.r_body, body.n_body), 1.0, rtol=1e-14)
    assert np.abs(body.r_body).max() == pytest.approx(1.0)
    tangential = np.abs(body.r_body - body.n_body * 1.0)
    assert tangential.max() <= 1.0 - 1.0 / n + 1e-12
    np.testing.assert_allclose(body.area @ body.r_body, 0.0, atol=1e-14)  # centre of mass at origin


def test_cube_inertia_tends_to_thin_plate_value():
    """I -> (5/18) M s^2 Id with error shrinking like N^-2 (midpoint rule)."""
    s, M = 1.5, 7.0
    exact = 5.0 / 18.0 * M * s**2
    errors = []
    for n in (2, 4, 8, 16, 32):
        body = make_box((s, s, s), n, M)
        np.testing.assert_allclose(body.inertia, body.inertia[0], rtol=1e-13)  # isotropic
        # exact for cell centres: sum of c_i^2 over N centres of [-1/2, 1/2] is (N^2 - 1) / (12 N)
        assert body.inertia[0] == pytest.approx(exact * (1 - 2 / (5 * n * n)), rel=1e-13)
        errors.append(abs(body.inertia[0] - exact) / exact)
    assert errors[-1] < 1e-3
    slopes = np.diff(np.log(errors)) / np.log(2)
    np.testing.assert_allclose(slopes, -2.0, atol=0.05)


def test_mesh_body_matches_the_box_it_meshes():
    mesh = trimesh.creation.box(extents=(1.0, 0.6, 0.3))
    body = make_mesh_body(mesh, samples=2000, density=700.0)
    assert body.n_samples >= 2000
    assert body.volume == pytest.approx(0.18, rel=1e-12)
    assert body.mass == pytest.approx(700 * 0.18, rel=1e-12)
    assert body.area.sum() == pytest.approx(mesh.area, rel=1e-12)
    # outward normals: the surface integral of r . n equals 3 V for a closed surface
    assert body.area @ np.einsum("ki,ki->k", body.r_body, body.n_body) == pytest.approx(3 * 0.18, rel=1e-12)
    box = make_box((1.0, 0.6, 0.3), 20, 700 * 0.18)
    np.testing.assert_allclose(np.sort(body.inertia), np.sort(box.inertia), rtol=2e-3)


def test_mesh_body_is_put_in_its_principal_frame():
    rot = trimesh.transformations.rotation_matrix(0.7, [1.0, 2.0, 0.5])
    mesh = trimesh.creation.box(extents=(1.0, 0.6, 0.3), transform=rot)
    body = make_mesh_body(mesh, samples=500, mass=1.0)
    m = body.sample_mass
    r = body.r_body
    tensor = (m @ np.einsum("ki,ki->k", r, r)) * np.eye(3) - (r * m[:, None]).T @ r
    np.testing.assert_allclose(tensor, np.diag(body.inertia), atol=1e-12)


def test_non_watertight_mesh_is_refused():
    mesh = trimesh.creation.box()
    open_mesh = trimesh.Trimesh(mesh.vertices, mesh.faces[:-2])
    with pytest.raises(ConfigError, match="not watertight"):
        make_mesh_body(open_mesh, samples=100, mass=1.0)


def test_missing_mesh_file_is_refused(tmp_path):
    with pytest.raises(ConfigError, match="mesh file not found"):
        make_mesh_body(str(tmp_path / "nope.stl"), samples=100, mass=1.0)


@pytest.mark.parametrize(
    "body, message",
    [
        (BodyConfig(points_per_edge=0), "points per edge must be >= 1"),
        (BodyConfig(size=0.0), "cube size must be >= 0.001"),
        (BodyConfig(size=-1.0), "cube size must be >= 0.001"),
        (BodyConfig(mass=0.0), "mass must be >= 1e-06"),
        (BodyConfig(mass=-2.0), "mass must be >= 1e-06"),
        (BodyConfig(density=float("nan")), "density must be finite"),
        (BodyConfig(shape="box", extents=(1.0, 0.0, 1.0)), "box extents must be >= 0.001"),
        (BodyConfig(shape="sphere"), "body shape must be"),
    ],
)
def test_bad_bodies_are_refused(body, message):
    with pytest.raises(ConfigError, match=message):
        validate(SceneConfig(body=body))

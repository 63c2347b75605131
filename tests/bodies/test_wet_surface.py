"""The exact wet surface at the field's scale: rm3 (a 20 m float, a spar with a 30 m plate) in an irregular sea, its
triangles taken a part at a time with the water's series about each part's centre (kernels/water.py: clusters),
against the direct sum over components, which is the numpy reference's definition."""

import numpy as np
import pytest

from sim.bodies.clusters import LEAF, bisection_tree
from sim.kernels import sea_pack
from sim.kernels import water as kw
from sim.scene.config import load_scene, with_overrides
from sim.simulation import Simulation
from sim.system.body_loads import BodyLoads


@pytest.fixture(autouse=True)
def _shipped_only(monkeypatch, tmp_path):
    """rm3's coefficients come from the shipped file: no user cache, no solve."""
    import sim.hydro.bem as bem

    monkeypatch.setenv("FLOATSIM_BEM_CACHE", str(tmp_path))
    monkeypatch.setattr(bem, "solve_parts", lambda *a, **k: pytest.fail("the shipped rm3 coefficients were not found"))


def rm3_sea(**changes):
    """rm3 in a 64-component JONSWAP sea (Hs 2.5 m, Tp 8 s, long-crested, deep)."""
    return with_overrides(
        load_scene("rm3"), **{"waves__kind": "jonswap", "waves__hs": 2.5, "waves__tp": 8.0, "waves__components": 64, **changes}
    )


def rotation(v):
    from scipy.spatial.transform import Rotation

    return Rotation.from_rotvec(v).as_matrix()


def test_the_tree_nests_compact_parts_of_every_triangle():
    """Each node's items are its children's, its sphere holds their vertices, leaves hold at most LEAF items, and the
    order is a permutation: every triangle in exactly one leaf."""
    items = np.random.default_rng(0).normal(size=(300, 3, 3)) * [10.0, 3.0, 1.0]
    order, spans, spheres = bisection_tree(items)
    assert sorted(order) == list(range(300))
    for (start, end, left, right), (cx, cy, cz, radius) in zip(spans, spheres):
        pts = items[order[start:end]].reshape(-1, 3)
        assert np.linalg.norm(pts - [cx, cy, cz], axis=1).max() <= radius * (1 + 1e-12)
        if left < 0:
            assert right < 0 and end - start <= LEAF
        else:
            assert (spans[left, 0], spans[left, 1], spans[right, 0], spans[right, 1]) == (start, spans[right, 0], spans[left, 1], end)
            assert 0 < spans[left, 1] - start < end - start


@pytest.mark.parametrize("sea", [{}, {"waves__spreading": 8.0, "waves__components": 1024}], ids=["long-crested", "short-crested"])
@pytest.mark.parametrize("body_index", [0, 1], ids=["spar", "float"])
def test_each_part_s_series_matches_the_direct_sum_on_rm3(body_index, sea):
    """Over a random sea and random poses, the elevation, pressure and flow from each part's series at points anywhere in
    the part's sphere (above the water too, where the pressure is clamped as the reference's) equal the direct sum
    (water.Waves, the reference) within 1e-10 of the sea's scale (rho g sum a, sum a omega): the bound is 1e-13.
    Every part of rm3 has a series (no fallback to the direct sum), and the parts dropped lie above the water. In a
    short-crested sea of 1024 components (kernels/directional.py) the parts whose series pays take it, the others the
    direct sum."""
    scene = rm3_sea(waves__direction=30.0, waves__seed=int(7 + body_index), **sea)
    run = Simulation(scene, backend="numpy")
    loads = run.system.loads[body_index]
    water, body = loads.model.water, loads.model.body
    sea = sea_pack(water, body)
    order, spans, spheres = body.face_tree
    rng = np.random.default_rng(body_index)
    rest = np.array([0.0, 0.0, scene.bodies[body_index].initial.position[2]])
    worst = np.zeros(3)
    for trial in range(3):
        x, R, t = rest + rng.normal(0, [2.0, 2.0, 0.5]), rotation(rng.normal(0, 0.08, 3)), 30.0 + 17.0 * trial
        cut = kw.clusters(sea, t, x, R, spans, spheres, True)
        assert (cut[2] <= kw.PMAX).all() and ((cut[2] >= 0).all() if not sea else (cut[2] >= 0).any())
        covered = np.zeros(len(order), dtype=bool)
        for c, nd in enumerate(cut[0]):
            ex = kw.cluster_ex(cut, c)
            covered[order[spans[nd, 0] : spans[nd, 1]]] = True
            centre, radius = x + R @ spheres[nd, :3], spheres[nd, 3]
            u = rng.normal(size=(200, 3))
            pts = centre + u / np.linalg.norm(u, axis=1, keepdims=True) * radius * rng.uniform(0, 1, (200, 1)) ** (1 / 3)
            eta, out = np.empty(len(pts)), np.empty((len(pts), 4))
            kw.fields(sea, ex, pts, eta, len(pts), water.rho, water.g, True, out, False)
            pressure, flow = water.field(pts, t)
            worst = np.maximum(worst, [np.abs(eta - water.elevation(pts[:, :2], t)).max() / water.amplitude.sum(),
                                       np.abs(out[:, 0] - pressure).max() / (water.rho * water.g * water.amplitude.sum()),
                                       np.abs(out[:, 1:] - flow).max() / (water.amplitude * water.omega).sum()])  # fmt: skip
        dropped = body.mesh_vertices[body.mesh_faces[~covered]].reshape(-1, 3) @ R.T + x
        assert (dropped[:, 2] > water.elevation(dropped[:, :2], t)).all()
    assert (worst < 1e-10).all(), worst


@pytest.mark.parametrize("spreading, components, series", [(10.0, 4096, True), (10.0, 64, False), (0.0, 64, True)])
def test_a_short_crested_sea_s_series_matches_the_direct_sum(spreading, components, series):
    """The ice cube's single series in a short-crested sea: 4096 components from many directions take it (within 1e-12
    of the sea's scale of the direct sum: elevation, pressure, flow), 64 do not (their direct sum costs less than a
    series of about P^3 / 6 terms a point), a long-crested sea does."""
    from dataclasses import replace

    from sim.bodies.body import make_box
    from sim.water.seas import jonswap_waves

    water = replace(jonswap_waves(1000.0, 9.81, 3.0, 9.0, components=components, seed=1, spreading=spreading, direction_deg=20.0), ramp=0.0)
    body = make_box((1.0, 1.0, 1.0), 10, 900.0)
    x, t = np.array([3.0, -2.0, -0.4]), 37.0
    pts = x + np.random.default_rng(5).uniform(-1, 1, (300, 3)) * body.radius / np.sqrt(3)
    sea = sea_pack(water, body)
    ex = kw.prepare(sea, t, x)
    assert (ex[0] >= 0) == series and ex[10] == (spreading > 0)
    eta, out = np.empty(len(pts)), np.empty((len(pts), 4))
    kw.fields(sea, ex, pts, eta, len(pts), water.rho, water.g, True, out, False)
    pressure, flow = water.field(pts, t)
    assert np.abs(eta - water.elevation(pts[:, :2], t)).max() < 1e-12 * water.amplitude.sum()
    assert np.abs(out[:, 0] - pressure).max() < 1e-12 * water.rho * water.g * water.amplitude.sum()
    assert np.abs(out[:, 1:] - flow).max() < 1e-12 * (water.amplitude * water.omega).sum()


def test_rm3_loads_from_the_parts_series_match_the_reference():
    """Each rm3 body's compiled loads (the parts' series) against the numpy reference (the direct sum) at random poses
    across the wave surface: force and torque within 1e-10 of their scale; and so do the loads on the direct sum."""
    run = Simulation(rm3_sea(waves__direction=-20.0), backend="numpy")
    rng = np.random.default_rng(3)
    for index, loads in enumerate(run.system.loads):
        series, direct, reference = BodyLoads(loads.model), BodyLoads(loads.model), BodyLoads(loads.model)
        series.use_kernels(True)
        direct.use_kernels(True, expand=False)
        rest = np.array([0.0, 0.0, run.scene.bodies[index].initial.position[2]])
        for trial in range(3):
            x, R, t, nu = rest + rng.normal(0, [3.0, 3.0, 0.6]), rotation(rng.normal(0, 0.1, 3)), 40.0 + 9.0 * trial, np.zeros(6)
            f_ref, _ = reference(x, R, t, nu)
            scale = np.abs(f_ref).max()
            for loads_of in (series, direct):
                f, _ = loads_of(x, R, t, nu)
                np.testing.assert_allclose(f, f_ref, rtol=0, atol=1e-10 * scale)


@pytest.mark.slow  # 100 s of rm3 on the direct sum: about 20 s
def test_rm3_trajectory_on_the_parts_series_follows_the_direct_sum_for_100_s():
    """rm3 (its exact wet surface) stepped 100 s in the irregular sea on the parts' series and on the direct sum, both
    compiled: the same trajectory to 1e-8 (m, m/s, J)."""
    ends = []
    for expand in (True, False):
        run = Simulation(rm3_sea(), backend="numpy")
        run.use_backend("numba")
        run.system.use_kernels(True, expand=expand)
        run.step(int(round(100.0 / run.dt)))
        ends.append(run)
    a, b = ends
    assert np.abs(a.state.theta - a.start.theta).max() > 0.1  # it moved
    np.testing.assert_allclose(a.state.theta, b.state.theta, rtol=0, atol=1e-8)
    np.testing.assert_allclose(a.state.v, b.state.v, rtol=0, atol=1e-8)
    np.testing.assert_allclose(a.state.absorbed, b.state.absorbed, rtol=0, atol=1e-8 * max(1.0, np.abs(b.state.absorbed).max()))

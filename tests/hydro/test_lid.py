"""The lids the BEM solves get against irregular frequencies (sim/hydro/lid.py): the whole section of every hull just under
the water line, whatever its outline (issue 38: Capytaine's generate_lid as called covered 2.52 of a cylinder's 3.14 m2,
110 of the rm3 float's 233 m2 and nothing of the spar). Read from the bodies the solve is handed, the solve stopped
before it starts."""

import numpy as np
import pytest
import trimesh

from sim.hydro import bem
from sim.hydro.hydrostatics import hydrostatics


class Handed(Exception):
    """The solve stopped here: the problems it was handed."""


def handed_body(monkeypatch, tmp_path, solve):
    """The Capytaine body (hull and lid) `solve()` hands the solver, with no stored solve to read."""
    cpt = pytest.importorskip("capytaine")

    def stop(self, problems, **kw):
        raise Handed(problems)

    monkeypatch.setattr(cpt.BEMSolver, "solve_all", stop)
    monkeypatch.setattr(bem, "in_child", lambda solve_now: solve_now())  # here, so that the problems handed come back
    monkeypatch.setattr(cpt.BEMSolver, "__init__", lambda self, *a, **kw: None)  # (no Green function tabulated: 45 s on a fresh machine)
    monkeypatch.setattr(bem, "SHIPPED", tmp_path / "none")
    monkeypatch.setenv(bem.CACHE_ENV, str(tmp_path / "cache"))
    with pytest.raises(Handed) as e:
        solve()
    return e.value.args[0][0].body


def faces(mesh) -> tuple[np.ndarray, np.ndarray]:
    """(triangles (f, 3, 3), areas (f,)) of a Capytaine mesh (its quads split)."""
    v, q = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    T = np.concatenate([v[q[:, [0, 1, 2]]], v[q[:, [0, 2, 3]]]])
    area = 0.5 * np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)
    return T[area > 0], area[area > 0]


def check_lid(lid, z: float, area: float, panel: float) -> None:
    T, a = faces(lid)
    assert np.allclose(T[..., 2], z)  # flat, at the lid's depth
    assert a.sum() == pytest.approx(area, rel=2e-3)  # the whole section (the hull's outline, to the merged points)
    normal = np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])[:, 2]
    assert (normal < 0).all()  # facing down, as Capytaine takes it
    edges = np.linalg.norm(T - np.roll(T, 1, axis=1), axis=2)
    assert edges.max() < 1.6 * panel  # panels about the hull's
    assert (a > 1e-3 * panel**2).all()  # no slivers


def test_a_cylinders_lid_covers_its_whole_section(monkeypatch, tmp_path):
    """A vertical cylinder (r 1 m, 64-gon, draft 1 m): the lid covers the polygon's area, just under the water line."""
    m = trimesh.creation.cylinder(radius=1.0, height=2.0, sections=64)
    body = handed_body(monkeypatch, tmp_path, lambda: bem.radiation_coefficients(m.vertices, m.faces, omega=[1.0, 2.0, 3.0],
                                                                                 panel=0.2, progress=False))  # fmt: skip
    polygon = 0.5 * 64 * np.sin(2 * np.pi / 64)  # r = 1
    check_lid(body.lid_mesh, -bem.LID_DEPTH * 1.0, polygon, 0.2)


def test_rm3s_lids_cover_the_float_annulus_and_the_spar(monkeypatch, tmp_path):
    """rm3 as its scene builds it: the float's lid is its annulus (its waterplane, about 233 m2, the hole where the spar
    passes left open) and the spar's its column; together the two bodies' waterplane areas, from floatsim's hydrostatics."""
    from sim.scene.config import load_scene, with_overrides
    from sim.system.tree import build

    scene = with_overrides(load_scene("rm3"), waves__kind="still")
    body = handed_body(monkeypatch, tmp_path, lambda: build(scene))
    system, state = build(with_overrides(scene, fluid__radiation="none"))
    pose = system.pose(state)
    planes = [hydrostatics(m.model.body, x, R).waterplane_area for m, x, R in zip(system.members, pose.x, pose.R)]
    lids = [b.lid_mesh for b in body.bodies]
    assert all(lid is not None for lid in lids)
    draft = [float(-np.min(b.mesh.vertices[:, 2])) for b in body.bodies]
    for lid, plane, d in zip(lids, planes, draft):
        T, _ = faces(lid)
        check_lid(lid, float(T[0, 0, 2]), plane, 1.6 * float(np.median(np.linalg.norm(T - np.roll(T, 1, axis=1), axis=2))))
        assert float(T[0, 0, 2]) == pytest.approx(-bem.LID_DEPTH * d)
    assert sum(planes) == pytest.approx(233.0 + np.pi * 3.0**2, rel=0.05)


@pytest.mark.parametrize("scene", ["sphere", "point-absorber", "moored-buoy"])
def test_every_one_body_preset_with_radiation_gets_a_whole_lid(monkeypatch, tmp_path, scene):
    """The sphere (two triangles' cuts of one edge lie a sliver's width apart where the wet mesh dropped a sliver), the
    cube free and moored: each lid covers its hull's section at its depth (floatsim's hydrostatics, the body raised so
    that plane is the water line), at 1 % of the draft under the water line."""
    from sim import Simulation
    from sim.bodies.body import make_body
    from sim.bodies.rotation import quat_to_matrix
    from sim.hydro.equilibrium import scene_rest
    from sim.scene.config import load_scene

    config = load_scene(scene)
    body = handed_body(monkeypatch, tmp_path, lambda: Simulation(config, backend="numpy"))
    T, _ = faces(body.lid_mesh)
    z = float(T[0, 0, 2])
    b = make_body(config.body, config.base_dir, True)
    R = quat_to_matrix(b.q_input_body)
    draft = -float(np.asarray(body.mesh.vertices)[:, 2].min())  # the solve's (a moored one's rest is rounded)
    assert z == pytest.approx(-bem.LID_DEPTH * draft, rel=1e-6)
    rest = -draft - float((b.mesh_vertices @ R.T)[:, 2].min())
    assert rest == pytest.approx(scene_rest(b, config, R)[2], abs=1e-3 * b.radius)
    section = hydrostatics(b, np.array([0.0, 0.0, rest - z]), R).waterplane_area
    check_lid(body.lid_mesh, z, section, 1.6 * float(np.median(np.linalg.norm(T - np.roll(T, 1, axis=1), axis=2))))

"""A mesh file that cannot be a floating body is refused with one line saying why, on the command line
(exit 2, before any run) and by load_mesh (issue 23, items 3 and 11): a surface folded onto itself (no
volume), a body a nanometre across ("too small", not "not watertight"), two overlapping boxes in one file
(not their summed volume), and files declaring more faces than allowed (refused before parsing)."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest
import trimesh

from sim.bodies.body import MAX_TRIANGLES, load_mesh, make_mesh_body
from sim.errors import ConfigError

DEGENERATE_OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 2\n"


def two_boxes() -> trimesh.Trimesh:
    return trimesh.util.concatenate([trimesh.creation.box(extents=(1.0, 1.0, 1.0)),
                                     trimesh.creation.box(extents=(1.0, 1.0, 1.0)).apply_translation((0.5, 0.0, 0.0))])  # fmt: skip


@pytest.fixture
def files(tmp_path):
    (tmp_path / "degenerate.obj").write_text(DEGENERATE_OBJ)
    trimesh.creation.box(extents=(1e-9,) * 3).export(tmp_path / "speck.stl")
    two_boxes().export(tmp_path / "two.obj")
    return tmp_path


@pytest.mark.parametrize("name, reason", [("degenerate.obj", "encloses no volume"), ("speck.stl", "too small"),
                                          ("two.obj", "2 separate closed surfaces")])  # fmt: skip
def test_the_cli_refuses_a_mesh_that_cannot_float_in_one_line(files, name, reason):
    run = subprocess.run([sys.executable, "-m", "sim", "run", "--mesh", str(files / name), "--t-end", "0.1"], capture_output=True,
                         text=True, timeout=120, env={**os.environ, "PYTHONWARNINGS": "ignore"})  # fmt: skip
    assert run.returncode == 2, run.stderr
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and reason in lines[0] and name in lines[0] and "Traceback" not in run.stderr


def test_load_mesh_says_what_is_wrong(files):
    with pytest.raises(ConfigError, match="encloses no volume"):
        load_mesh(str(files / "degenerate.obj"))
    with pytest.raises(ConfigError, match="too small: 1e-09 m across"):
        load_mesh(str(files / "speck.stl"))
    with pytest.raises(ConfigError, match="single closed surface"):
        load_mesh(str(files / "two.obj"))
    with pytest.raises(ConfigError, match="single closed surface"):
        make_mesh_body(two_boxes(), 600, density=500.0)  # a mesh object, not a file: the same check
    with pytest.raises(ConfigError, match="not watertight"):  # still told apart from the ones above
        box = trimesh.creation.box()
        load_mesh(trimesh.Trimesh(box.vertices, box.faces[:-1]).export(file_type="stl"), "open.stl")
    with pytest.raises(ConfigError, match="is too small"):
        make_mesh_body(str(files / "speck.stl"), 600, density=500.0)
    # one closed box still loads, in every unit that makes it plausible
    assert load_mesh(trimesh.creation.box(extents=(800.0, 600.0, 500.0)).export(file_type="stl"), "b.stl", "mm").volume == pytest.approx(
        0.24
    )


def test_a_name_with_control_characters_is_shown_without_them():
    with pytest.raises(ConfigError) as refused:
        load_mesh(b"not a mesh", "bo\x00at\x1b[2J\n.stl")
    assert refused.value.args[0].startswith("'bo?at?[2J?.stl'") and str(refused.value).isprintable()


@pytest.mark.parametrize("kind", ["stl", "stl_ascii", "obj", "ply"])
def test_too_many_faces_are_counted_before_parsing(kind, monkeypatch):
    """The count comes from the header (binary STL, PLY) or the face lines (OBJ, ASCII STL): trimesh never sees the file."""
    sphere = trimesh.creation.icosphere(subdivisions=7)  # 327 680 triangles
    if kind == "stl_ascii":  # written tersely (trimesh's own ASCII would be 98 MB, refused by its size)
        facet = b"facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n"
        content = b"solid s\n" + facet * len(sphere.faces) + b"endsolid s\n"
    else:
        content = sphere.export(file_type=kind)
        content = content.encode() if isinstance(content, str) else content
    monkeypatch.setattr(trimesh, "load", lambda *a, **k: pytest.fail("parsed"))
    with pytest.raises(ConfigError, match=f"has {len(sphere.faces):,} faces, more than a mesh of {MAX_TRIANGLES:,}"):
        load_mesh(content, f"sphere.{kind[:3]}")


def test_a_body_with_no_volume_mass_or_inertia_is_refused():
    """make_mesh_body's checks hold for mesh objects too (no file checks on the way): a body never has a
    density of 0/0 or a moment of inertia of 0 or nan."""
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    flat = trimesh.Trimesh(v, [[0, 1, 2], [0, 2, 1]], process=False)
    with pytest.raises(ConfigError, match="encloses no volume"):
        make_mesh_body(flat, 100, density=500.0)
    for mass in (0.0, float("nan")):
        with pytest.raises(ConfigError, match="gives no usable body"):
            make_mesh_body(trimesh.creation.box(), 100, mass=mass)

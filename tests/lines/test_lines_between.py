"""Mooring lines on several bodies ([moorings] attach): a line between two bodies, anchors shared by several lines, buoys
on lines (the absorber-pair preset), checked at rest against the elastic catenary, and the one-line refusals."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from sim.bodies.rotation import quat_to_matrix
from sim.lines.catenary import fairlead_tension

ROOT = Path(__file__).resolve().parents[2]
W = (1.0 - 1000.0 * np.pi * 0.02**2 / 4) * 9.81
"""The preset's line in water, N/m."""
EA = 1.0e5
START = {"a_float": np.array([-4.0, 0.0, 0.0]), "b_float": np.array([4.0, 0.0, 0.0])}
FAIRLEADS = [("a_float", (-3.5, 0.0, -0.3)), ("a_float", (-4.0, 0.5, -0.3)), ("a_float", (-4.0, -0.5, -0.3)), ("a_float", (-4.5, 0.0, -0.3)),
             ("b_float", (3.5, 0.0, -0.3)), ("b_float", (4.0, 0.5, -0.3)), ("b_float", (4.0, -0.5, -0.3)), ("b_float", (4.5, 0.0, -0.3))]  # fmt: skip
"""The Coupled points of assets/moorings/absorber_pair.txt, in its order, and the body each is on."""


@pytest.mark.slow
def test_the_absorber_pairs_lines_settle_on_their_elastic_catenaries(tmp_path):
    """absorber-pair in still water, run to rest (60 s): the two floats held between their shared anchors, their outer
    anchors and the line between them. Each fairlead's pull (MoorDyn's net force on the line's end node) is the elastic catenary's
    for where the bodies came to rest within 1 %: the four lines to the two shared anchors (measured 0.6 %) and the line
    between the floats, fully suspended, T = sqrt(H^2 + (w L / 2)^2) with 2 (H / w) asinh(w L / 2H) + H L / EA its span
    (measured 0.2 %). The two floats mirror each other."""
    out = tmp_path / "rest.csv"
    done = subprocess.run([sys.executable, "-m", "sim", "run", "--scene", "absorber-pair", "--waves", "still", "--t-end", "60", "--every",
                           "500", "--out", str(out)], cwd=ROOT, capture_output=True, text=True, timeout=900)  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    last = np.genfromtxt(out, delimiter=",", names=True)[-1]

    def world(i: int) -> np.ndarray:
        name, r = FAIRLEADS[i]
        x = np.array([last[f"{name}_{c}"] for c in "xyz"])
        R = quat_to_matrix(np.array([last[f"{name}_{c}"] for c in ("qw", "qx", "qy", "qz")]))
        return x + R @ (np.asarray(r) - START[name])

    for i, anchor in ((1, (0.0, 20.0, -10.0)), (2, (0.0, -20.0, -10.0)), (5, (0.0, 20.0, -10.0)), (6, (0.0, -20.0, -10.0))):
        gap = world(i) - np.asarray(anchor)
        expected = fairlead_tension(float(np.hypot(*gap[:2])), float(gap[2]), 24.0, W, EA)
        assert last[f"T_fair_{i + 1}"] == pytest.approx(expected, rel=0.01), i
    span, L = float(np.linalg.norm((world(4) - world(0))[:2])), 7.5
    H = brentq(lambda H: 2 * H / W * np.arcsinh(W * L / (2 * H)) + H * L / EA - span, 1e-6, 1e6)
    for i in (0, 4):
        assert last[f"T_fair_{i + 1}"] == pytest.approx(np.hypot(H, W * L / 2), rel=0.01)
    assert last["a_float_x"] == pytest.approx(-last["b_float_x"], abs=1e-6)  # mirrored
    assert np.hypot(last["a_float_ux"], last["a_float_uy"]) < 1e-3  # at rest


@pytest.mark.parametrize(
    "attach, message",
    [
        ("a_float a_float", "names 2 bodies; the mooring file has 8 Coupled points"),
        ("a_float nobody a_float a_float b_float b_float b_float b_float", "nobody is not one of the [[bodies]]"),
    ],
)
def test_attachments_it_cannot_follow_are_one_line(tmp_path, attach, message):
    text = (ROOT / "assets" / "scenes" / "absorber-pair.toml").read_text().replace("../moorings/", str(ROOT / "assets" / "moorings") + "/")
    text = text.replace('attach = "a_float a_float a_float a_float b_float b_float b_float b_float"', f'attach = "{attach}"')
    scene = tmp_path / "pair.toml"
    scene.write_text(text)
    done = subprocess.run([sys.executable, "-m", "sim", "run", "--scene", str(scene), "--t-end", "0.1"], cwd=ROOT, capture_output=True,
                          text=True, timeout=300)  # fmt: skip
    assert done.returncode == 2 and message in done.stderr and len(done.stderr.strip().splitlines()) == 1, done.stderr


def test_one_body_scenes_refuse_attachments_in_one_line():
    done = subprocess.run([sys.executable, "-m", "sim", "run", "--scene", "moored-buoy", "--t-end", "0.1"], cwd=ROOT, capture_output=True,
                          text=True, timeout=300, input="")  # fmt: skip
    assert done.returncode == 0, done.stderr  # (as shipped: no attach)
    from sim.errors import ConfigError
    from sim.scene.config import load_scene, with_overrides

    with pytest.raises(ConfigError, match="it is for scenes of \\[\\[bodies\\]\\]"):
        with_overrides(load_scene("moored-buoy"), moorings__attach="body")

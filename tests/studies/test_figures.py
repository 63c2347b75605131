"""`studies.seed_figures` (`python -m studies figures`) on its quick setting: every figure the page promises is
written, one section per figure group of the source report, and the physics facts the page states hold."""

from __future__ import annotations

import json
import re
import struct

import numpy as np
import pytest

from studies.seed_figures import ASSETS, PAGE, FiguresArgs, figures, fmt, report_grid

SECTIONS = ("Figures 1-2", "Figure 3", "Figures 4-5", "Figure 6", "Density", "Figures 7-9")
PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    out = tmp_path_factory.mktemp("figures")
    with np.errstate(all="raise", under="ignore"):  # as conftest does for each test
        assert figures(FiguresArgs(out_dir=str(out), quick=True, progress=False)) == 0
    text = (out / PAGE).read_text()
    numbers = json.loads((out / ASSETS / "numbers.json").read_text())
    return out, text, numbers


def test_every_promised_figure_is_a_real_png(page):
    import matplotlib.image

    out, text, _ = page
    links = re.findall(r"!\[[^\]]*\]\(([^)\s]+)\)", text)
    assert len(links) >= 8
    assert len(set(links)) == len(links)
    for link in links:
        assert link.startswith(f"{ASSETS}/") and link.endswith(".png"), link  # relative, next to the page
        data = (out / link).read_bytes()
        assert data[:8] == PNG, link
        width, height = struct.unpack(">II", data[16:24])
        assert width >= 300 and height >= 250 and len(data) > 10_000, link
        pixels = matplotlib.image.imread(out / link)[..., :3]
        assert pixels.std() > 0.05, f"{link} looks blank"
    assert sorted(p.name for p in (out / ASSETS).glob("*.png")) == sorted(link.split("/")[1] for link in links)


def test_says_how_to_regenerate(page):
    _, text, _ = page
    assert "python -m studies figures" in text


def test_one_section_per_figure_group_with_settings_and_comparison(page):
    _, text, _ = page
    headings = re.findall(r"^## (.+)$", text, re.MULTILINE)
    assert len(headings) == len(SECTIONS)
    for prefix, heading in zip(SECTIONS, headings):
        assert heading.startswith(prefix), (prefix, heading)
    for section in text.split("\n## ")[1:]:
        for part in ("**Settings.**", "**The report.**", "**floatsim.**", "**Where and why they differ.**"):
            if section.startswith("Figures 7-9") and part == "**Where and why they differ.**":
                part = "**Why face up"
            assert part in section, (section[:30], part)


@pytest.mark.parametrize("n", [3, 4, 5, 10, 17])
def test_report_grid_loses_its_edge_strips(n):
    s = 1.7
    r, normals, area, kept = report_grid(s, n)
    assert kept.sum() == 6 * (n - 2) ** 2
    assert np.all(np.abs(r[kept]).max(axis=1) == pytest.approx(s / 2))  # on the surface
    assert np.all(np.abs(r[kept] * normals[kept]).sum(axis=1) == pytest.approx(s / 2))  # normal along its face's axis
    assert 6 * s**2 - area.sum() == pytest.approx(6 * s**2 * (1 - ((n - 2) / n) ** 2), rel=1e-12)


def test_the_physics_the_page_states(page):
    _, text, nums = page
    # Figures 1-2: the report's grid loses 6 s^2 (1 - ((N-2)/N)^2) of area and the same fraction of buoyancy; ours loses neither.
    assert nums["grid_area_deficit_N10"] == pytest.approx(6 * (1 - 0.8**2), rel=1e-12)
    assert f"the deficit is {fmt(nums['grid_area_deficit_N10'], 4)} m^2" in text
    grid = nums["grid"]["10"]
    assert grid["report"]["buoyancy_ratio"] == pytest.approx(0.64, rel=1e-12)
    assert grid["ours"]["buoyancy_ratio"] == pytest.approx(1.0, abs=1e-12)
    assert grid["ours"]["waterplane_ratio"] == pytest.approx(1 - 1 / 10**2, rel=1e-12)  # midpoint rule
    # Figures 3 and 6: released at rest with no velocity, the cube stays put.
    assert nums["rest"]["max_dz"] < 1e-12
    assert nums["force_at_rest"]["max_F_rel"] < 1e-9
    assert f"{fmt(nums['force_at_rest']['max_F_rel'])} of the weight" in text
    # Figures 4-5: |L| changes by the torque's integral; euler's error against implicit is first order; torque-free keeps |L|.
    spin = nums["spin"]
    assert spin["torque_integral_rel"] < 1e-3
    assert 1.6 < spin["euler_dev_ratio"] < 2.5
    assert spin["free_rel_dev"] < 1e-12
    implicit = spin["runs"]["spin_implicit"]
    assert (implicit["max"] - implicit["min"]) / spin["L0"] > 0.05  # a real change, not round-off
    # Density: the sinking cube accelerates at -(1 - rho/rho_b) g once under.
    sinking = nums["densities"]["runs"]["1100"]
    assert sinking["accel_end"] == pytest.approx(sinking["accel_exact"], rel=1e-9)
    # Figures 7-9: GM = s/10.8 - 0.05 s, sampled with the midpoint rule's (1 - 1/N^2) on I_wp; yaw is neutral.
    damped = nums["damped"]
    assert damped["GM"] == pytest.approx(1 / 10.8 - 0.05, rel=1e-12)
    assert damped["GM_sampled"] == pytest.approx((1 - 1 / 10**2) / 10.8 - 0.05, rel=1e-6)
    assert damped["yaw_torque_rel"] < 1e-12

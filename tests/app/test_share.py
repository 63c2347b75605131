"""Issue 12 without a browser: what a recording holds (every pose exactly, the CSV beside it, the size
of a minute), the video's frames, the markers against the exact hydrostatics, mesh files refused with a
reason, and setup links that round-trip."""

from __future__ import annotations

import base64
import dataclasses
import re

import numpy as np
import pytest
import trimesh

from app.drawn.scene import SceneView
from app.live.share import link_query, parse_link
from app.live.upload import check_upload
from app.recording.replay import FixedLayers, private_server, replay_html
from app.recording.take import Take, shot_of
from sim import ConfigError, FluidConfig, Model, Simulation, StillWater, load_scene, with_overrides
from sim.bodies.rotation import matrix_to_quat, quat_to_matrix
from sim.hydro.forces import pressure
from sim.scene.gauges import Gauge
from sim.system.frame import CSV_COLUMNS


def recording_messages(html: str) -> tuple[float, list]:
    """(duration, [(time, message dict)]) of the recording inside a replay page."""
    import msgspec
    import zstandard

    raw = base64.b64decode(re.search(r'window.__VISER_EMBED_DATA__="([^"]+)"', html).group(1))
    inner = zstandard.ZstdDecompressor().decompress(raw[8:], max_output_size=int.from_bytes(raw[:8], "little"))
    n = int.from_bytes(inner[:8], "little")
    doc = msgspec.msgpack.decode(inner[8 : 8 + n])
    return doc["durationSeconds"], doc["messages"]


def pose_at(messages, time: float) -> tuple[np.ndarray, np.ndarray]:
    """The body's pose the replay shows at `time`: the last position and orientation sent by then."""
    position = orientation = None
    for t, m in messages:
        if t > time + 1e-9:
            break
        if m.get("name") == "/world/body" and m["type"] == "SetPositionMessage":
            position = np.array(m["position"])
        if m.get("name") == "/world/body" and m["type"] == "SetOrientationMessage":
            orientation = np.array(m["wxyz"])
    return position, orientation


def record(scene: str, seconds: float, every: int = 7, **changes) -> tuple[Take, Simulation]:
    sim = Simulation(with_overrides(load_scene(scene), **changes))
    take = Take()
    take.add(shot_of(sim))
    while sim.state.t < seconds - 1e-9:
        sim.step(every)
        take.add(shot_of(sim))
    return take, sim


def test_replay_shows_every_recorded_pose_exactly_as_the_csv():
    take, _ = record("drop", 3.0)
    html = replay_html(take)
    duration, messages = recording_messages(html)
    rows = np.loadtxt(take.csv().splitlines()[1:], delimiter=",")
    assert rows.shape == (len(take), len(CSV_COLUMNS)) and duration >= take.duration
    t0 = rows[0, 0]
    for row in rows[[0, 1, len(rows) // 3, len(rows) // 2, -1]]:
        position, wxyz = pose_at(messages, row[0] - t0)  # the replay's clock starts at the first row
        np.testing.assert_allclose(position, row[1:4], atol=1e-6)
        np.testing.assert_allclose(wxyz, row[4:8], atol=1e-6)
    # at rest, viser's own filter would drop moves under 1e-5: the replay still sends every one
    assert sum(m["type"] == "SetPositionMessage" and m["name"] == "/world/body" for _, m in messages) == len(take) + 1


def test_a_replay_in_waves_follows_the_body_and_carries_the_shaded_sea():
    """A recording of `waves` moves the world under the camera as the live view does by default (the body, drawn
    shifted by the world's frame, stays near the origin while it rides the swell) and holds the sea's shades (the swell
    at full height from the start: its ramp would take 21 s)."""
    from app.drawn.scene import ROOT

    take, _ = record("waves", 6.0, waves__ramp=0.0)
    duration, messages = recording_messages(replay_html(take))
    assert any(str(m.get("name", "")).startswith(f"{ROOT}/waves/sea") for _, m in messages)
    shift, seen, drift = np.zeros(3), [], []
    for t, m in messages:
        if m.get("name") == ROOT and m["type"] == "SetPositionMessage":
            shift = np.array(m["position"])
        if m.get("name") == f"{ROOT}/body" and m["type"] == "SetPositionMessage" and t > 2.0:
            seen.append(np.array(m["position"]) + shift)
            drift.append(np.array(m["position"]))
    seen, drift = np.array(seen), np.array(drift)
    assert np.ptp(drift[:, 2]) > 0.1  # it rides the 0.5 m swell
    assert np.abs(seen).max() < 0.5 * np.abs(drift).max()  # shown near the origin the camera looks at


@pytest.mark.slow
@pytest.mark.parametrize("scene", ["damped", "storm"])
def test_a_minute_of_replay_fits_in_one_and_a_half_megabytes(scene):
    take, _ = record(scene, 60.0)
    html = replay_html(take)
    assert len(html.encode()) <= 1.5e6, len(html) / 1e6
    assert "initialCameraPosition" in html  # opens on the live viewer's view


def test_take_clock_never_runs_backwards_and_skips_paused_repeats():
    take, sim = record("drop", 0.2)
    n = len(take)
    assert take.add(shot_of(sim)) and len(take) == n  # same time (paused): not kept
    sim.reset()
    sim.step(1)
    take.add(shot_of(sim))
    assert np.all(np.diff(take.times) > 0) and take.at(take.duration).frame.t == take[len(take) - 1].frame.t
    assert take.at(0.0).frame.t == take[0].frame.t and take.at(take.times[3] - 1e-6).frame.t == take[2].frame.t
    np.testing.assert_array_equal(take[len(take) - 1].frame.wet_index, shot_of(sim).frame.wet_index)  # packed and unpacked


def panel_buoyancy_centre(body, x, R):
    """Horizontal point of the panel model's buoyancy line of action and the displaced volume."""
    water, fluid = StillWater(1000.0, 9.81), FluidConfig(forces="panels")
    load = pressure(body, water, fluid, Model(body, water, fluid).wetted(x, R), np.zeros(6), 0.0)
    return x[:2] + np.array([-load.torque[1], load.torque[0]]) / load.force[2], load.force[2] / (1000.0 * 9.81)


def test_markers_sit_at_the_exact_centre_of_buoyancy_and_metacentre():
    sim = Simulation(load_scene("rest"))  # the cube at rest face up, density ratio r = 0.9
    r, s = 0.9, 1.0
    with private_server() as server:
        view = SceneView(server, FixedLayers.of(), sim.body, replay=True)
        view.show(shot_of(sim), now=0.0)
        np.testing.assert_allclose(view.markers.b.position, [0.0, 0.0, -r * s / 2], atol=1e-9)
        gm = s / (12 * r) - s * (1 - r) / 2
        np.testing.assert_allclose(view.markers.m.position[2] - sim.state.x_world[2], gm, atol=1e-9)
        # a tilted pose: B on the panel model's line of action of buoyancy, M above it by I / V
        R = quat_to_matrix(np.array([0.95, 0.2, -0.15, 0.1]) / np.linalg.norm([0.95, 0.2, -0.15, 0.1]))
        x = np.array([0.2, 0.1, -0.05])
        sim.reset(sim.body_state.__class__(0.5, x, matrix_to_quat(R), np.zeros(3), np.zeros(3)))
        view.show(shot_of(sim), now=1.0)
        line, volume = panel_buoyancy_centre(sim.body, x, R)
        np.testing.assert_allclose(view.markers.b.position[:2], line, atol=1e-9)
        h = view.markers.latest
        assert h.volume == pytest.approx(volume, rel=1e-10)
        np.testing.assert_allclose(view.markers.m.position, h.buoyancy_centre + [0, 0, h.bm[0]], atol=1e-12)
        assert view.hull.line.visible  # the waterline: on the hull (body frame), on z = 0 in the world
        np.testing.assert_allclose((np.asarray(view.hull.line.points, float).reshape(-1, 3) @ R.T + x)[:, 2], 0.0, atol=1e-6)


@pytest.mark.slow
def test_exported_video_has_the_requested_frames_and_size(tmp_path):
    from conftest import _require

    from app.recording.browser import missing

    _require(missing() is None, missing() or "")
    import av

    from app.recording.video import render_video

    take, _ = record("drop", 1.0)
    n = render_video(take, tmp_path / "run.mp4", fps=7.5, size="640x360")  # a rate that is not a whole number
    with av.open(str(tmp_path / "run.mp4")) as video:
        frames = list(video.decode(video=0))
    assert n == 8 == len(frames)  # 0, 2/15, ..., 14/15 s
    assert (frames[0].width, frames[0].height) == (640, 360)
    first, last = (f.to_ndarray(format="rgb24").astype(float) for f in (frames[0], frames[-1]))
    assert first.std() > 10 and np.abs(first - last).mean() > 0.5  # a picture, and the cube fell between them


def stl(mesh: trimesh.Trimesh) -> bytes:
    return mesh.export(file_type="stl")


@pytest.mark.parametrize(
    "name, content, unit, reason",
    [
        ("notes.stl", b"these are not triangles", "m", "not a mesh"),
        ("open.stl", stl(trimesh.Trimesh(*(lambda b: (b.vertices, b.faces[:-2]))(trimesh.creation.box()))), "m", "not watertight"),
        ("ship.stl", stl(trimesh.creation.box(extents=(1000.0, 150.0, 60.0))), "m", "millimetres"),
        ("big.stl", stl(trimesh.creation.icosphere(subdivisions=7)), "m", "200,000"),
        ("cube.step", b"ISO-10303-21;", "m", "must be .stl, .obj, .ply"),
        ("empty.stl", b"", "m", "empty"),
    ],
    ids=["not-a-mesh", "open", "ship-in-mm", "too-large", "wrong-format", "empty"],
)
def test_a_bad_mesh_file_is_refused_with_its_reason(name, content, unit, reason):
    with pytest.raises(ConfigError, match=re.escape(reason)):
        check_upload(name, content, unit)


@pytest.mark.parametrize("kind", ["stl", "obj", "ply"])
def test_closed_meshes_load_in_each_format_and_unit(kind):
    box = trimesh.creation.box(extents=(800.0, 600.0, 500.0))  # millimetres
    content = box.export(file_type=kind)
    content = content.encode() if isinstance(content, str) else content
    check_upload(f"box.{kind}", content, "mm")
    from sim.bodies.body import load_mesh

    assert load_mesh(content, f"box.{kind}", "mm").volume == pytest.approx(0.24, rel=1e-9)


def test_links_carry_the_preset_and_what_differs_from_it():
    from app.live.loop import SimLoop

    loop = SimLoop(load_scene("drop"), "drop", scene_options=("drop", "rest"))
    for name, value in parse_link("?scene=drop&density=500&damping=40&integrator=rk4", loop.scene_options)[0]:
        loop._apply(name, value)
    query = link_query(loop.settings)
    assert query.startswith("?scene=drop") and "density=500" in query and "damping=40" in query and "integrator=rk4" in query
    assert "dt=" not in query  # unchanged from the preset
    commands, problems = parse_link(query + "&fixedDpr=0.5&bogus=1&dt=abc&scene=nowhere", ("drop",))
    assert commands[0] == ("scene", "drop") and ("density", 500.0) in commands
    assert problems == ["'scene' given more than once (the first kept)", "unknown parameter 'bogus'", "dt = 'abc' is not a number"]


def test_a_link_carries_each_body_s_own_parameters_by_name():
    """rm3 with the float made lighter and given drag: the link names them float.density and float.drag_coefficient, a
    fresh viewer opening it runs the same bodies (the spar untouched) and writes the same link; a body's parameter
    without a body, or of a body the scene lacks, is refused."""
    from app.live.loop import SimLoop

    def fresh() -> SimLoop:
        return SimLoop(load_scene("rm3"), "rm3", scene_options=("rm3",), kernels=False)

    loop = fresh()
    for name, value in (("focus", "float"), ("density", 700.0), ("drag_coefficient", 1.5), ("focus", "spar")):
        loop._apply(name, value)
    query = link_query(loop.settings)
    assert query == "?scene=rm3&float.density=700&float.drag_coefficient=1.5"
    commands, problems = parse_link(query, ("rm3",))
    assert not problems and commands[1:] == [("focus", "float"), ("density", 700.0), ("focus", "float"), ("drag_coefficient", 1.5)]
    opened = fresh()
    for name, value in commands[1:]:
        opened._apply(name, value)
    assert opened.settings.config.bodies == loop.settings.config.bodies and link_query(opened.settings) == query
    assert opened.settings.config.bodies[0] == load_scene("rm3").bodies[0]  # the spar as shipped
    _, problems = parse_link("?scene=rm3&density=700&buoy.density=700&float.rho=1", ("rm3",))
    assert problems == ["'density': a body's own parameter is BODY.density, BODY one of the scene's bodies (spar, float)",
                        "'buoy.density': a body's own parameter is BODY.density, BODY one of the scene's bodies (spar, float)",
                        "unknown parameter 'float.rho'"]  # fmt: skip


def test_links_compare_the_value_in_effect_not_the_one_written():
    """The sphere's diffraction switch is unset: off in still water, on in waves (radiation from the BEM). A link
    names it only where the run's switch differs from what the link's own scene would have in effect, and a
    fresh viewer opening the link runs as the first one did."""
    from app.live.loop import SimLoop

    def opened(query: str) -> SimLoop:
        fresh = SimLoop(load_scene("sphere"), "sphere", scene_options=("sphere",), kernels=False)
        commands, problems = parse_link(query, ("sphere",))
        assert not problems
        for name, value in commands[1:]:
            fresh._apply(name, value)
        return fresh

    loop = SimLoop(load_scene("sphere"), "sphere", scene_options=("sphere",), kernels=False)
    assert link_query(loop.settings) == "?scene=sphere"  # (its N: the mesh's, from its samples)
    loop._apply("kind", "regular")
    assert link_query(loop.settings) == "?scene=sphere&kind=regular"  # waves with a BEM: diffraction on, as unset
    assert opened(link_query(loop.settings)).sim.model.radiation.diffraction is not None
    loop._apply("diffraction", False)
    query = link_query(loop.settings)
    assert query == "?scene=sphere&kind=regular&diffraction=false" and loop.sim.model.radiation.diffraction is None
    assert opened(query).sim.model.radiation.diffraction is None


def test_viewer_takes_a_mesh_from_the_command_line_and_floats_it(tmp_path):
    from app.args import ViewArgs
    from app.main import start

    path = tmp_path / "crate.ply"
    trimesh.creation.box(extents=(800.0, 600.0, 500.0)).export(path)
    app = start(ViewArgs(scene="damped", port=0, mesh=str(path), mesh_unit="mm"), kernels=False)
    try:
        snap = app.sync()
        assert snap.body.volume == pytest.approx(0.24, rel=1e-9) and snap.settings.config.body.mesh_unit == "mm"
        # it starts a quarter of its height (0.5 m, upright as in the file) above its rest height
        from sim.hydro.hydrostatics import at_rest

        z_rest = at_rest(snap.body, snap.params, quat_to_matrix(snap.body.q_input_body))[0]
        assert "draft 0.45" in snap.notice and snap.frame.t < 1.0
        assert app.loop.sim.scene.initial.position[2] == pytest.approx(z_rest + 0.125, abs=1e-9)
    finally:
        app.stop()


def test_the_gauges_stand_on_the_sea_with_their_elevation_written_beside():
    """The waves preset with two gauges: a marker at each, at (x, y, eta) of the sea at the frame's time, labelled with
    its name and elevation to the centimetre; hidden with the water (the layer off), shown again with it."""
    scene = load_scene("waves")
    scene = dataclasses.replace(scene, gauges=(Gauge("near", 0.0, 0.0), Gauge("far", 12.0, -3.0)))
    sim = Simulation(scene, backend="numpy")
    sim.step(4000)  # 20 s: the sea is up
    layers = FixedLayers.of()
    with private_server() as server:
        view = SceneView(server, layers, sim.body, waves=True, replay=True)
        view.show(shot_of(sim), now=0.0)
        t = sim.frame().t
        heights = []
        for name, x, y in (("near", 0.0, 0.0), ("far", 12.0, -3.0)):
            eta = float(sim.water.elevation(np.array([x, y]), t))
            sphere, label, text = view.gauges.nodes[name]
            np.testing.assert_allclose(sphere.position, [x, y, eta], atol=1e-12)
            assert text == f"{name}: {eta:+.2f} m" and sphere.visible
            heights.append(eta)
        assert max(map(abs, heights)) > 0.02 and abs(heights[0] - heights[1]) > 0.005  # a sea up, and not the same there
        layers.water.value = False
        view.show(shot_of(sim), now=1.0)
        assert not any(sphere.visible for sphere, _, _ in view.gauges.nodes.values())

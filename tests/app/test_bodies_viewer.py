"""The viewer on a scene of several bodies (the rm3 preset), through viser's real websocket protocol: the one viewer of
every scene (app/main.py, app/live/loop.py) draws every body where the run has it, the joints' axes, the take-offs' numbers;
Pause, Step, Reset and Speed from the page; the chosen body's density and take-off from the page; a mesh for a chosen body."""

import asyncio
import contextlib
import io
import subprocess
import sys

import numpy as np
import pytest

from app.tools.page import Page
from tests.viewer import wait_for


@contextlib.contextmanager
def viewer(kernels: bool = False, scene: str = "rm3"):
    from app.args import ViewArgs
    from app.main import start

    with contextlib.redirect_stdout(io.StringIO()):
        app = start(ViewArgs(scene=scene, port=0), kernels=kernels, publish_hz=20.0)
    try:
        yield app
    finally:
        app.stop()


def test_every_body_is_drawn_where_the_run_has_it_and_the_controls_drive_it():
    with viewer() as app:

        async def watch():
            async with Page.open(app.port) as page:
                await page.read(1.5, until=lambda p: "Pause" in p.controls)
                await page.camera()
                await page.read(0.5)  # viser runs a page's callbacks once its camera message is in
                await page.update("Pause", True)
                for _ in range(50):  # (a loaded machine may take a while)
                    await page.read(0.2)
                    if app.sync().settings.paused:
                        break
                snap = app.sync()
                await page.read(1.0)  # what the paused run drew last has arrived
                return page, snap

        page, snap = asyncio.run(watch())
        assert snap.settings.paused and snap.frame.t > 0
        frame = snap.run
        for body in frame.bodies:  # each body's frame node is where the run has it (viser sends float32)
            node = page.nodes[f"/world/bodies/{body.name}"]
            np.testing.assert_allclose(node["position"], body.x_world, atol=1e-4)
            np.testing.assert_allclose(node.get("wxyz", (1.0, 0.0, 0.0, 0.0)), body.q_world_body, atol=1e-6)  # (unsent while unturned)
        spar, floater = (b.x_world for b in frame.bodies)
        assert abs(floater[2] - spar[2] - 17.9743 - frame.joints[1][1]) < 1e-9  # the float slides on the spar: its stroke
        assert "/world/bodies/spar/mesh" in page.nodes and "/world/bodies/float/mesh" in page.nodes and "/world/joint" in page.nodes
        assert len(page.nodes["/world/joint"]["points"]) == 2  # both slides
        text = page.text("Joint float")
        assert f"t = **{frame.t:.2f} s**" in text and "paused" in text and "take-off" in text and "Joint spar: stroke" in text
        t_paused = app.sync().frame.t
        assert app.sync().frame.t == t_paused  # paused: the run stands still

        async def drive():
            async with Page.open(app.port) as page:
                await page.read(1.5, until=lambda p: "Pause" in p.controls)
                await page.camera()
                await page.read(0.5)
                assert page.value("Pause") is True  # a new page is shown the run's own state
                await page.send({"type": "GuiUpdateMessage", "uuid": page.control("Step")["uuid"], "updates": {"value": True}})
                await page.read(0.5)
                stepped = app.sync().frame.t
                await page.send({"type": "GuiUpdateMessage", "uuid": page.control("Reset")["uuid"], "updates": {"value": True}})
                await page.read(0.5)
                reset = app.sync()
                await page.update("Speed", 1000.0)
                await page.update("Pause", False)
                await page.read(0.5)
                return stepped, reset

        epoch = app.sync().epoch
        stepped, reset = asyncio.run(drive())
        assert stepped == pytest.approx(app.loop.sim.dt)  # the first page of a viewer restarts the run (as for one body): then one step
        assert reset.frame.t == 0.0 and reset.epoch == epoch + 2  # that restart, and Reset
        snap = wait_for(
            app, lambda s: "Speed: 1000 is outside" in s.notice and s.frame.t > 0.5, what="the clamped speed and the run going on"
        )
        assert snap.settings.speed == 100.0 and app.controls.speed.value == 100.0  # every page shows the speed the run uses


def test_the_run_moves_to_the_compiled_loads_without_a_jump():
    """With the bodies' kernels on disk the loop loads them on a thread and moves to them between two steps: the
    run goes on from the same state (its time never goes back), now compiled."""
    from sim.compiling import warm_up
    from sim.kernels import SYSTEM_STEP
    from sim.scene.config import load_scene
    from sim.simulation import Simulation

    specs = Simulation(load_scene("rm3"), backend="numpy").specs
    assert SYSTEM_STEP in specs  # the step of several bodies compiles and loads as the bodies' loads do
    for spec in specs:
        warm_up(spec)
    with viewer(kernels=True) as app:
        times = []
        snap = wait_for(app, lambda s: times.append(s.frame.t) or app.loop.sim.compiled, what="the compiled loads")
        assert times == sorted(times) and snap.engine == ""
        later = wait_for(app, lambda s: s.frame.t > snap.frame.t + 1.0, what="the run going on")
        assert app.loop.sim.compiled and np.isfinite(later.run.E_total)


def test_one_body_flags_are_one_line_errors():
    flag = ["--mesh", "assets/meshes/rm3_float.stl"]
    done = subprocess.run([sys.executable, "-m", "app", "--scene", "rm3", *flag], capture_output=True, text=True, timeout=60, check=False)
    assert done.returncode == 2 and "choose one under Body in the viewer" in done.stderr and "Traceback" not in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1


def test_the_mooring_lines_of_a_body_among_several_are_drawn(tmp_path):
    """A moored [[bodies]] scene (tests/system/test_system.py's pontoon): the lines' node and the pull in the numbers."""
    pytest.importorskip("moordyn")
    import textwrap

    from tests.system.test_system import MOORED

    (tmp_path / "moored.toml").write_text(textwrap.dedent(MOORED))
    with viewer(scene=str(tmp_path / "moored.toml")) as app:

        async def watch():
            async with Page.open(app.port) as page:
                await page.read(2.0, until=lambda p: "/world/moorings" in p.nodes and p.text("Mooring: 3 lines pull"))
                return page

        page = asyncio.run(watch())
        snap = app.sync()
        assert "/world/moorings" in page.nodes and len(snap.run.lines) == 3
        assert "largest fairlead tension" in page.text("Mooring: 3 lines pull")


def embedded_messages(html: str) -> list:
    """The messages of a replay page's recording (viser's serialised scene, inline), binary buffers left out."""
    import base64
    import re

    import msgspec
    import zstandard

    raw = base64.b64decode(re.search(r'window.__VISER_EMBED_DATA__="([^"]+)"', html).group(1))
    inner = zstandard.ZstdDecompressor().decompress(raw[8:], max_output_size=int.from_bytes(raw[:8], "little"))
    n = int.from_bytes(inner[:8], "little")
    return msgspec.msgpack.decode(inner[8 : 8 + n])["messages"]


def test_a_recording_of_several_bodies_replays_every_pose_and_writes_the_run_csv(tmp_path, monkeypatch):
    """Record and Stop from the page's buttons: the take's CSV has the run's columns and each recorded snapshot's
    row; its replay page moves every body through every recorded pose (the float's last one exactly, float32)."""
    from tests.app.test_recordings import record_takes

    monkeypatch.chdir(tmp_path)
    with viewer() as app:
        record_takes(app, 1, seconds=1.0)
        take, files = app.recorder.last, app.recorder.files
        header = files["csv"].read_text().splitlines()[0].split(",")
        assert header == app.loop.sim.columns()
        data = np.loadtxt(files["csv"], delimiter=",", skiprows=1)
        assert len(data) == len(take) > 10 and np.all(np.diff(data[:, 0]) > 0)
        np.testing.assert_allclose(data[:, header.index("float_z")], [shot.run.bodies[1].x_world[2] for shot in take.shots], atol=1e-9)
        moves = [
            m[1] for m in embedded_messages(files["html"].read_text()) if m[1].get("name") == "/world/bodies/float" and "position" in m[1]
        ]
        assert len(moves) >= len(take)  # every pose, none skipped as too close to the last
        np.testing.assert_allclose(moves[-1]["position"], take[len(take) - 1].run.bodies[1].x_world, atol=1e-4)


def test_the_chosen_body_s_controls_change_that_body_alone_from_the_page():
    """Body -> float from a page, then its Density, Take-off damping and Drag C_d from the page: the run's float has them
    (its mass density x volume, its take-off's damper absorbing, its own drag), the spar keeps its own; choosing the spar
    again shows its values."""
    with viewer() as app:
        spar = app.sync().settings.config.bodies[0]

        async def drive():
            async with Page.open(app.port) as page:
                await page.read(1.5, until=lambda p: "Pause" in p.controls)
                await page.camera()
                await page.read(0.5)
                await page.update("Body", "float")
                await page.read(0.5)
                await page.update("Density", 700.0)
                await page.update("PTO damping", 2.0e6)
                await page.update("Drag C_d", 1.5)
                await page.read(1.0)

        asyncio.run(drive())
        snap = wait_for(app, lambda s: s.settings.config.bodies[1].constraint.pto_damping == 2.0e6, what="the float's take-off")
        (float_,) = (m for m in app.loop.sim.system.members if m.name == "float")
        assert snap.settings.focus == "float" and snap.settings.density == pytest.approx(700.0)
        assert float_.body.mass == pytest.approx(700.0 * float_.body.volume)
        assert snap.settings.config.bodies[0] == spar  # the spar untouched
        drag = {m.name: m.model.fluid.drag_coefficient for m in app.loop.sim.system.members}
        assert drag == {"float": 1.5, "spar": 0.0}  # a term's parameter is the chosen body's own too
        assert next(g for g in app.loop.sim.system.joints if g.name == "float").damping == 2.0e6
        absorbed = wait_for(app, lambda s: s.run.joints[1][4] > 0.0, what="the float's take-off absorbing").run.joints[1][4]
        assert absorbed > 0.0
        app.controls.focus.value = "spar"
        snap = wait_for(app, lambda s: s.settings.focus == "spar", what="the spar chosen")
        assert app.controls.density.value == pytest.approx(snap.settings.density) and snap.settings.density != pytest.approx(700.0)
        assert app.controls.drag_coefficient.value == 0.0  # the spar's drag, the scene's


def test_a_mesh_loaded_for_the_chosen_body_takes_its_place_on_its_joint():
    """An upload while the float is chosen: the float's body is the mesh (its panels), on the float's slide; the spar keeps
    its own mesh; radiation is off for it, said in the note."""
    import trimesh
    from test_upload_guard import stl, upload

    with viewer() as app:
        app.loop.post("focus", "float")
        spar = app.sync().parts[0].body
        ring = trimesh.creation.annulus(r_min=4.0, r_max=10.0, height=4.0)
        upload(app, "ring.stl", stl(ring))
        snap = wait_for(app, lambda s: "Loaded ring" in s.notice, what="the ring as the float")
        assert snap.parts[1].body.volume == pytest.approx(ring.volume, rel=1e-6) and snap.parts[1].name == "float"  # (float32 STL)
        assert "Loaded ring" in snap.notice and "in the place of float" in snap.notice and "Radiation is off" in snap.notice
        assert snap.parts[0].body.n_samples == spar.n_samples and snap.settings.config.fluid.radiation == "none"
        assert snap.settings.config.bodies[1].constraint.joint == "prismatic" and snap.settings.focus == "float"
        later = wait_for(app, lambda s: s.frame.t > snap.frame.t + 0.5, what="the run going on")
        assert np.isfinite(later.run.E_total) and not later.settings.paused


def test_the_stability_readout_of_a_joined_body_says_it_is_the_free_bodys():
    """rm3's spar alone would roll over (GM < 0 as a free body); joined to the float through the slide it floats upright.
    The page says which GM it shows, and what holds the body, rather than an alarm for a stable system."""
    with viewer() as app:

        async def watch():
            async with Page.open(app.port) as page:
                await page.read(3.0, until=lambda p: p.text("GM ="))
                return page

        page = asyncio.run(watch())
        snap = app.sync()
        text = page.text("GM =")
        gm = snap.hydrostatics.gm[0]
        assert f"GM = **{gm:+.3f} m**" in text and "the bodies it is joined to" in text, text
        assert ("would roll over" in text) == (gm < 0) and "rolls over: a heel grows" not in text, text


def test_the_take_off_damping_is_a_number_box_stepped_to_the_bodys_scale():
    """rm3's float takes off 1.2 MN s/m: a slider 3 rem wide showed it as 120000, pinned at a range made for a 1 m cube.
    The page gets a number box holding the value whole, stepping by a hundredth of its size; choosing the spar (no
    damper) steps it as the smallest."""
    with viewer() as app:

        async def drive():
            async with Page.open(app.port) as page:
                await page.read(1.5, until=lambda p: "PTO damping" in p.controls)
                await page.camera()
                await page.read(0.5)
                await page.update("Body", "float")
                await page.read(5.0, until=lambda p: p.value("PTO damping") == 1.2e6)
                float_ = dict(page.control("PTO damping"))
                await page.update("Body", "spar")
                await page.read(5.0, until=lambda p: p.value("PTO damping") == 0.0)
                return float_, dict(page.control("PTO damping"))

        float_, spar = asyncio.run(drive())
    assert float_["kind"] == "GuiNumberMessage" and float_["value"] == 1.2e6 and float_["step"] == 1e4, float_
    assert spar["value"] == 0.0 and spar["step"] == 10.0, spar

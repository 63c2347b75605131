"""A recorded run as one self-contained HTML page that replays offline (play, pause, seek): the
viewer's own scene, staged on a private viser server and captured by viser's scene serializer.

The timeline is the take clock (simulated seconds from the first shot): a seek to time s shows the
pose of the last shot taken at or before s, exactly as in the run's CSV.
"""

from __future__ import annotations

import contextlib
import io
from dataclasses import dataclass

import viser

from app.drawn.scene import SceneView
from app.recording.take import Take


@dataclass
class Layer:
    value: bool = True


@dataclass
class FixedLayers:
    """What a replay or a video shows (the live viewer's Layers, without checkboxes)."""

    mesh: Layer
    points: Layer
    water: Layer
    forces: Layer
    markers: Layer
    axes: Layer

    @classmethod
    def of(cls, points: bool = True, markers: bool = True) -> FixedLayers:
        return cls(Layer(True), Layer(points), Layer(True), Layer(True), Layer(markers), Layer(False))


@contextlib.contextmanager
def private_server():
    """A viser server on a free local port, silent, stopped on exit."""
    with contextlib.redirect_stdout(io.StringIO()):  # viser's banner
        server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        yield server
    finally:
        with contextlib.redirect_stdout(io.StringIO()):
            server.stop()


def stage(server: viser.ViserServer, take: Take, layers: FixedLayers | None = None) -> SceneView:
    """The take's scene at its first shot, on `server` (every body of a scene of several)."""
    first = take[0]
    view = SceneView(server, layers or FixedLayers.of(), first.body, waves=not first.water.flat, replay=True, parts=first.parts)
    view.show(first, now=0.0)
    return view


def replay_html(take: Take, layers: FixedLayers | None = None) -> str:
    """The take as a self-contained HTML page (viser's client plus the recording inline)."""
    if not len(take):
        raise ValueError("nothing recorded")
    with private_server() as server:
        view = stage(server, take, layers)
        recording = server.get_scene_serializer()
        previous = 0.0
        for time, shot in zip(take.times, take.shots):
            recording.insert_sleep(time - previous)
            view.show(shot, now=time)
            previous = time
        recording.insert_sleep(1.0 / 30.0)  # the last pose stays on screen for a frame
        camera = server.initial_camera
        return with_camera(recording.as_html(), camera.position, camera.look_at)


def with_camera(html: str, position, look_at) -> str:
    """Open the page on the live viewer's view: a recording does not carry the initial camera, but
    viser's client reads one from the URL (z up, world coordinates), which this writes in first."""
    vec = lambda v: ",".join(f"{float(c):.4g}" for c in v)  # noqa: E731
    query = f"initialCameraPosition={vec(position)}&initialCameraLookAt={vec(look_at)}&initialCameraUp=0,0,1"
    script = ("<script>if(!location.search.includes('initialCamera'))history.replaceState(null,'',location.pathname+"
              f"(location.search?location.search+'&':'?')+'{query}'+location.hash);</script>")  # fmt: skip
    head = html.index("<head>") + len("<head>")
    return html[:head] + script + html[head:]

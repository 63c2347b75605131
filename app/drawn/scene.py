"""The 3D scene: water, the body's frame with its mesh and samples as children, force arrows; `show` streams a snapshot.

ARCHITECTURE rule 7: the mesh and the sample points live in the body frame and are sent once per
body; each frame moves only the `/body` pose. Sample colours (wet or dry) go out only while the
points are shown, at most `COLOUR_HZ` times a second, and only when the wet set changed.
"""

from __future__ import annotations

import time

import numpy as np
import viser

import sim
from app.drawn.camera import Follower
from app.drawn.gauges import GaugesView
from app.drawn.hull import HULL_HZ, HullView
from app.drawn.markers import MarkersView
from app.drawn.tension import THICKNESS, TensionLegend, TensionScale, segment_colours
from app.drawn.water import LINED_OPACITY, REPLAY_HZ, WAVE_OPACITY, WaterView
from app.live.controls import Layers
from app.live.loop import Part, Snapshot

ROOT = "/world"
"""Every node of the scene hangs from this frame: following the body moves it, never the pages' cameras (drawn/camera.py)."""
REPLAY_FOLLOW_HZ = 10.0
"""A recording's world moves at most this often a simulated second (it stays small)."""
COLOUR_HZ = 5.0
ARROW_HZ = 10.0
LINES_HZ = 15.0
JOINT_COLOUR = (240, 120, 20)
WET = np.array([30, 110, 230], np.uint8)
DRY = np.array([245, 150, 40], np.uint8)


BODY_COLOURS = ((215, 235, 250), (250, 215, 160), (200, 240, 200), (240, 200, 230))
"""Each body's mesh colour, in the scene's order (one body: the first)."""


class BodyNodes:
    """One body's nodes: its frame with its mesh and samples as children, its waterline and wet part, its force
    arrows and its B and M markers. `node` names its frame under the world root: `body` for the one body of a scene,
    `bodies/NAME` for each of several."""

    def __init__(self, server: viser.ViserServer, layers: Layers, body: sim.Body, node: str, colour, replay: bool):
        self.server, self.layers, self.node, self.colour, self.replay = server, layers, node, colour, replay
        scene = server.scene
        marks = f"{ROOT}" if node == "body" else f"{ROOT}/marks/{node.rsplit('/', 1)[-1]}"
        self.markers = MarkersView(server, body.radius, root=marks)
        self.frame = scene.add_frame(
            f"{ROOT}/{node}", axes_length=0.8 * body.radius, axes_radius=0.012 * body.radius, show_axes=layers.axes.value
        )
        arrows = f"{ROOT}/forces" if node == "body" else f"{ROOT}/forces/{node.rsplit('/', 1)[-1]}"
        self.arrows = scene.add_arrows(arrows, np.zeros((2, 2, 3)), np.array([[220, 40, 40], [40, 170, 70]]), shaft_radius=0.02,
                                       head_radius=0.05)  # fmt: skip
        self.body: sim.Body | None = None
        self.hull: HullView | None = None
        """The waterline and the wet part (made for each body and sea)."""
        self.mesh = self.points = None
        self._wet: np.ndarray | None = None  # wet set last sent
        self._colour_time = self._arrow_time = -np.inf
        self.colour_updates = 0
        self.set_body(body)

    def set_body(self, body: sim.Body) -> None:
        """(Re)send the body's geometry; only when the body itself changes (scene, points per edge, a loaded mesh)."""
        self.body = body
        scene = self.server.scene
        self.mesh = scene.add_mesh_simple(f"{ROOT}/{self.node}/mesh", body.mesh_vertices, body.mesh_faces, color=self.colour, flat_shading=True,
                                          visible=self.layers.mesh.value)  # fmt: skip
        # Lift the points a little off the faces so the opaque mesh does not hide half of each one.
        lifted = body.r_body + 0.01 * body.radius * body.n_body
        size = 0.3 * np.sqrt(body.area.mean())  # a third of the sample spacing
        self.points = scene.add_point_cloud(
            f"{ROOT}/{self.node}/points", lifted, np.tile(DRY, (body.n_samples, 1)), point_size=float(size), precision="float32",
            point_shape="circle", visible=self.layers.points.value,
        )  # fmt: skip
        self._wet = None
        self._colour_time = -np.inf
        self.hull = None

    def remove(self) -> None:
        for node in (self.frame, self.arrows, self.markers.b, self.markers.m):
            node.remove()

    def show(self, part, water, params, now: float, due: bool) -> None:
        """The body at its part's pose (snapshot.Part), with its throttled colours, arrows, markers and waterline."""
        if part.body is not self.body:
            self.set_body(part.body)
        layers, frame = self.layers, part.frame
        for node, box in ((self.mesh, layers.mesh), (self.points, layers.points), (self.arrows, layers.forces)):
            if node.visible != box.value:
                node.visible = box.value
        if self.frame.show_axes != layers.axes.value:
            self.frame.show_axes = layers.axes.value
        if self.replay:  # viser skips a pose within 1e-5 of the last one sent: a replay keeps every pose exactly
            self.frame._impl.position[:] = np.nan
            self.frame._impl.wxyz[:] = np.nan
        self.frame.position = frame.x_world
        self.frame.wxyz = frame.q_world_body
        self.markers.show(part, now, layers.markers.value)
        if layers.points.value and now - self._colour_time >= 1.0 / COLOUR_HZ:
            self._send_colours(frame.wet_index, now)
        if layers.forces.value and now - self._arrow_time >= 1.0 / ARROW_HZ:
            self._send_arrows(part, params, now)
        if self.hull is None or not self.hull.fits(part.body, water):
            self.hull = HullView(self.server, part.body, water, root=ROOT, hz=REPLAY_HZ if self.replay else HULL_HZ, node=self.node)
        self.hull.show(
            frame, water, layers.markers.value, layers.mesh.value and not self.replay, now, due=due
        )  # with the sea: the same instant

    def _send_colours(self, wet_index: np.ndarray, now: float) -> None:
        if self._wet is not None and np.array_equal(self._wet, wet_index):
            return
        colours = np.tile(DRY, (self.body.n_samples, 1))
        colours[wet_index] = WET
        self.points.colors = colours
        self._wet, self._colour_time = wet_index.copy(), now
        self.colour_updates += 1

    def _send_arrows(self, part, params, now: float) -> None:
        """Net force at the centre of mass (1 m per body weight) and torque (1 m per weight x radius)."""
        frame, body = part.frame, part.body
        weight = body.mass * (params.g or 9.81)  # without gravity keep the scale of an ordinary weight
        x = frame.x_world
        ends = np.array([[x, x + frame.force_world / weight], [x, x + frame.torque_world / (weight * body.radius)]])
        if np.isfinite(ends).all():
            self.arrows.points = ends
        self._arrow_time = now


class SceneView:
    """Scene nodes of one viewer: the water, every body (BodyNodes), the joints' axes, the mooring lines; `show` runs on
    the simulation thread only."""

    def __init__(self, server: viser.ViserServer, layers: Layers, body: sim.Body, waves: bool = False, replay: bool = False,
                 parts: tuple = ()):  # fmt: skip
        """`parts`: every body of a scene of several (snapshot.Part), else the one `body`. replay=True: for a recording
        (app/recording/replay.py): every pose exactly, a lighter wave surface, and the throttles counted in the time passed to
        `show` (simulated) rather than wall time."""
        self.server, self.layers, self.replay = server, layers, replay
        self.follower = Follower(REPLAY_FOLLOW_HZ) if replay and waves else None
        """A replay in waves follows the body as the live view does by default (the live view's own: drawn/camera.py)."""
        self.root = server.scene.add_frame(ROOT, show_axes=False)
        radius = max(p.body.radius for p in parts) if parts else body.radius
        self._sized_for = radius
        size = max(8.0, 8.0 * radius)
        self.water = WaterView(server, size, lighter=replay, root=ROOT)
        view = size / 8 * (2.5 if waves else 1.0)  # a sea needs a wider view than a calm pond
        server.initial_camera.position = (2.6 * view, -3.4 * view, 1.9 * view)
        server.initial_camera.look_at = (0.0, 0.0, -0.3)
        if len(parts) > 1:  # several bodies: the view takes in their whole height (rm3's spar reaches 35 m down)
            extent = max(max(float(np.ptp(p.body.mesh_vertices, axis=0).max()) for p in parts), 2.0)
            server.initial_camera.position = (1.6 * extent, -2.2 * extent, 0.9 * extent)
            server.initial_camera.look_at = (0.0, 0.0, -0.25 * extent)
        self.bodies: list[BodyNodes] = []
        self._names: tuple = ()
        self._colour_time = self._arrow_time = self._lines_time = -np.inf
        self.lines = None
        """The mooring lines' node (made for the first scene that has lines), coloured by tension (app/drawn/tension.py)."""
        self.tension = TensionScale()
        self.legend = None if replay else TensionLegend(server)
        """The lines' colour bar in the panel (a recording keeps no panel)."""
        self.joint = None
        self._joint_of = None  # the joints' axes the node shows
        self.gauges = GaugesView(server, radius, root=ROOT)
        self._place(parts or (Part("body", body, None),))

    def _place(self, parts) -> None:
        """Nodes for these bodies (their names decide: a scene of other bodies replaces them all)."""
        names = tuple(p.name for p in parts)
        if names == self._names:
            return
        for nodes in self.bodies:
            nodes.remove()
        radius = max(p.body.radius for p in parts)
        if not 0.5 < radius / self._sized_for < 2.0:  # another size of body: the water to its scale
            self._sized_for = radius
            self.water = WaterView(self.server, max(8.0, 8.0 * radius), lighter=self.replay, root=ROOT)
        one = len(parts) == 1
        self.bodies = [BodyNodes(self.server, self.layers, p.body, "body" if one else f"bodies/{p.name}", BODY_COLOURS[k % len(BODY_COLOURS)],
                                 self.replay) for k, p in enumerate(parts)]  # fmt: skip
        self._names = names

    def __getattr__(self, key: str):
        """The first body's nodes by name (mesh, points, hull, markers, arrows, frame, body, colour_updates): the one body's."""
        if key in ("mesh", "points", "hull", "markers", "arrows", "frame", "body", "colour_updates") and self.__dict__.get("bodies"):
            return getattr(self.bodies[0], key)
        raise AttributeError(key)

    def set_body(self, body: sim.Body) -> None:
        self._place((Part("body", body, None),))
        self.bodies[0].set_body(body)

    def show(self, snap: Snapshot, now: float | None = None) -> None:
        """Every body at its pose, plus throttled colours, arrows, markers and waves; `now` is the clock the throttles count
        in (default: wall time). The water is centred on the chosen body (snap.frame)."""
        parts = snap.parts or (Part("body", snap.body, snap.frame),)
        self._place(parts)
        now = time.monotonic() if now is None else now
        frame, run = snap.frame, snap.run
        with self.server.atomic():
            sent = self.water.show(snap.water, frame.t, frame.x_world, self.layers.water.value, now)
            for nodes, part in zip(self.bodies, parts):
                nodes.show(part, snap.water, snap.params, now, sent)
            self._show_lines(run.lines, run.line_tensions, frame.t, now, frame.x_world)
            self._show_joint(run.joint_axes)
            self.gauges.show(run.gauges, now, self.layers.water.value)
            if self.follower is not None:
                self.follower.step(self.root, frame.x_world, now)

    def _show_joint(self, axes: list) -> None:
        """The joints' axes (a slide's or a hinge's: point and direction, world frame), 4 body radii long; sent when they
        change, hidden without one."""
        key = tuple((tuple(p), tuple(a)) for p, a in axes)
        if key == self._joint_of:
            return
        self._joint_of = key
        if not axes:
            if self.joint is not None:
                self.joint.visible = False
            return
        reach = 2.0 * self._sized_for
        segments = np.array(
            [[p - reach * a, p + reach * a] for p, a in ((np.asarray(p, float), np.asarray(a, float)) for p, a in axes)], np.float32
        )
        self.joint = self.server.scene.add_line_segments(f"{ROOT}/joint", segments, JOINT_COLOUR, thickness=0.04)

    def _show_lines(self, lines: tuple, tensions: tuple, t: float, now: float, centre: np.ndarray) -> None:
        """The mooring lines as segments between their nodes, coloured by the tension there, at most LINES_HZ times a
        second (none: hidden, with their legend); the seabed under them, around `centre`."""
        self.water.opacity = LINED_OPACITY if lines else WAVE_OPACITY
        if not lines or not self.layers.water.value:
            self.water.show_seabed(None, np.zeros(2))
        if not lines:
            if self.lines is not None and self.lines.visible:
                self.lines.visible = False
            if self.legend is not None:
                self.legend.show(None)
            return
        if now - self._lines_time < 1.0 / LINES_HZ:
            return
        self.tension.take(tensions, t)
        segments = np.concatenate([np.stack([p[:-1], p[1:]], axis=1) for p in lines]).astype(np.float32)
        if self.layers.water.value:  # the anchors lie on the seabed: the lines' lowest node
            self.water.show_seabed(float(segments[..., 2].min()) - 0.05, centre)
        colours = segment_colours(tensions, self.tension.low, self.tension.high)
        if self.lines is None or len(self.lines.points) != len(segments):
            self.lines = self.server.scene.add_line_segments(
                f"{ROOT}/moorings", segments, colours, thickness=THICKNESS, thickness_units="screen"
            )
        else:
            self.lines.points = segments
            if not np.array_equal(self.lines.colors, colours):
                self.lines.colors = colours
            self.lines.visible = True
        if self.legend is not None:
            self.legend.show(self.tension)
        self._lines_time = now

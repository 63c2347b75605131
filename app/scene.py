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

from .camera import Follower
from .controls import Layers
from .hull import HULL_HZ, HullView
from .loop import Snapshot
from .markers import MarkersView
from .tension import THICKNESS, TensionLegend, TensionScale, segment_colours
from .water import LINED_OPACITY, REPLAY_HZ, WAVE_OPACITY, WaterView

ROOT = "/world"
"""Every node of the scene hangs from this frame: following the body moves it, never the pages' cameras (camera.py)."""
REPLAY_FOLLOW_HZ = 10.0
"""A recording's world moves at most this often a simulated second (it stays small)."""
COLOUR_HZ = 5.0
ARROW_HZ = 10.0
LINES_HZ = 15.0
JOINT_COLOUR = (240, 120, 20)
WET = np.array([30, 110, 230], np.uint8)
DRY = np.array([245, 150, 40], np.uint8)


class SceneView:
    """Scene nodes of one viewer; `show` runs on the simulation thread only."""

    def __init__(self, server: viser.ViserServer, layers: Layers, body: sim.Body, waves: bool = False, replay: bool = False):
        """replay=True: for a recording (app/replay.py): every pose exactly, a lighter wave surface, and
        the throttles counted in the time passed to `show` (simulated) rather than wall time."""
        self.server, self.layers, self.replay = server, layers, replay
        self.follower = Follower(REPLAY_FOLLOW_HZ) if replay and waves else None
        """A replay in waves follows the body as the live view does by default (the live view's own: camera.py)."""
        scene = server.scene
        self.root = scene.add_frame(ROOT, show_axes=False)
        self._sized_for = body.radius
        size = max(8.0, 8.0 * body.radius)
        self.water = WaterView(server, size, lighter=replay, root=ROOT)
        self.markers = MarkersView(server, body.radius, root=ROOT)
        self.frame = scene.add_frame(
            f"{ROOT}/body", axes_length=0.8 * body.radius, axes_radius=0.012 * body.radius, show_axes=layers.axes.value
        )
        self.arrows = scene.add_arrows(
            f"{ROOT}/forces", np.zeros((2, 2, 3)), np.array([[220, 40, 40], [40, 170, 70]]), shaft_radius=0.02, head_radius=0.05
        )
        view = size / 8 * (2.5 if waves else 1.0)  # a sea needs a wider view than a calm pond
        server.initial_camera.position = (2.6 * view, -3.4 * view, 1.9 * view)
        server.initial_camera.look_at = (0.0, 0.0, -0.3)
        self.body: sim.Body | None = None
        self.hull: HullView | None = None
        """The waterline and the wet part (made for each body and sea)."""
        self.mesh = self.points = None
        self._wet: np.ndarray | None = None  # wet set last sent
        self._colour_time = self._arrow_time = self._lines_time = -np.inf
        self.colour_updates = 0
        self.lines = None
        """The mooring lines' node (made for the first scene that has lines), coloured by tension (app/tension.py)."""
        self.tension = TensionScale()
        self.legend = None if replay else TensionLegend(server)
        """The lines' colour bar in the panel (a recording keeps no panel)."""
        self.joint = None
        self._joint_of = None  # the [constraint] table the joint's node shows
        self.set_body(body)

    def set_body(self, body: sim.Body) -> None:
        """(Re)send the body's geometry; only when the body itself changes (scene, points per edge, a loaded mesh)."""
        self.body = body
        scene = self.server.scene
        if not 0.5 < body.radius / self._sized_for < 2.0:  # another size of body: water, frame and markers to its scale
            self._sized_for = body.radius
            self.water = WaterView(self.server, max(8.0, 8.0 * body.radius), lighter=self.replay, root=ROOT)
            self.markers = MarkersView(self.server, body.radius, root=ROOT)
            self.frame = scene.add_frame(
                f"{ROOT}/body", axes_length=0.8 * body.radius, axes_radius=0.012 * body.radius, show_axes=self.layers.axes.value
            )
        self.mesh = scene.add_mesh_simple(
            f"{ROOT}/body/mesh",
            body.mesh_vertices,
            body.mesh_faces,
            color=(215, 235, 250),
            flat_shading=True,
            visible=self.layers.mesh.value,
        )
        # Lift the points a little off the faces so the opaque mesh does not hide half of each one.
        lifted = body.r_body + 0.01 * body.radius * body.n_body
        size = 0.3 * np.sqrt(body.area.mean())  # a third of the sample spacing
        self.points = scene.add_point_cloud(
            f"{ROOT}/body/points", lifted, np.tile(DRY, (body.n_samples, 1)), point_size=float(size), precision="float32",
            point_shape="circle", visible=self.layers.points.value,
        )  # fmt: skip
        self._wet = None
        self._colour_time = -np.inf
        self.hull = None

    def show(self, snap: Snapshot, now: float | None = None) -> None:
        """Move the body to the snapshot's pose, plus throttled colours, arrows, markers and waves;
        `now` is the clock the throttles count in (default: wall time)."""
        if snap.body is not self.body:
            self.set_body(snap.body)
        layers = self.layers
        now = time.monotonic() if now is None else now
        for node, box in ((self.mesh, layers.mesh), (self.points, layers.points), (self.arrows, layers.forces)):
            if node.visible != box.value:
                node.visible = box.value
        if self.frame.show_axes != layers.axes.value:
            self.frame.show_axes = layers.axes.value
        frame = snap.frame
        with self.server.atomic():
            if self.replay:  # viser skips a pose within 1e-5 of the last one sent: a replay keeps every pose exactly
                self.frame._impl.position[:] = np.nan
                self.frame._impl.wxyz[:] = np.nan
            self.frame.position = frame.x_world
            self.frame.wxyz = frame.q_world_body
            self.markers.show(snap, now, layers.markers.value)
            if layers.points.value and now - self._colour_time >= 1.0 / COLOUR_HZ:
                self._send_colours(frame.wet_index, now)
            if layers.forces.value and now - self._arrow_time >= 1.0 / ARROW_HZ:
                self._send_arrows(snap, now)
            sent = self.water.show(snap.water, frame.t, frame.x_world, layers.water.value, now)
            if self.hull is None or not self.hull.fits(snap.body, snap.water):
                self.hull = HullView(self.server, snap.body, snap.water, root=ROOT, hz=REPLAY_HZ if self.replay else HULL_HZ)
            self.hull.show(
                snap, layers.markers.value, layers.mesh.value and not self.replay, now, due=sent
            )  # with the sea: the same instant
            self._show_lines(frame.lines, frame.line_tensions, frame.t, now)
            self._show_joint(frame.joint_axis)
            if self.follower is not None:
                self.follower.step(self.root, frame.x_world, now)

    def _show_joint(self, axis) -> None:
        """A slide's or a hinge's axis (frame.joint_axis), 4 body radii long; sent when it changes, hidden without one."""
        key = None if axis is None else (tuple(axis[0]), tuple(axis[1]))
        if key == self._joint_of:
            return
        self._joint_of = key
        if axis is None:
            if self.joint is not None:
                self.joint.visible = False
            return
        point, direction = (np.asarray(a, float) for a in axis)
        reach = 2.0 * self._sized_for
        segment = np.array([[point - reach * direction, point + reach * direction]], np.float32)
        self.joint = self.server.scene.add_line_segments(f"{ROOT}/joint", segment, JOINT_COLOUR, thickness=0.04)

    def _show_lines(self, lines: tuple, tensions: tuple, t: float, now: float) -> None:
        """The mooring lines as segments between their nodes, coloured by the tension there, at most LINES_HZ times a
        second (none: hidden, with their legend)."""
        self.water.opacity = LINED_OPACITY if lines else WAVE_OPACITY
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

    def _send_colours(self, wet_index: np.ndarray, now: float) -> None:
        if self._wet is not None and np.array_equal(self._wet, wet_index):
            return
        colours = np.tile(DRY, (self.body.n_samples, 1))
        colours[wet_index] = WET
        self.points.colors = colours
        self._wet, self._colour_time = wet_index.copy(), now
        self.colour_updates += 1

    def _send_arrows(self, snap: Snapshot, now: float) -> None:
        """Net force at the centre of mass (1 m per body weight) and torque (1 m per weight x radius)."""
        frame, body = snap.frame, snap.body
        weight = body.mass * (snap.params.g or 9.81)  # without gravity keep the scale of an ordinary weight
        x = frame.x_world
        ends = np.array([[x, x + frame.force_world / weight], [x, x + frame.torque_world / (weight * body.radius)]])
        if np.isfinite(ends).all():
            self.arrows.points = ends
        self._arrow_time = now

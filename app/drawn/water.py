"""The water in the 3D scene: a calm translucent sheet in still water; in waves an animated surface whose
heights come from the simulation's own `Water`, shaded by height and slope, sent at most `WAVE_HZ` times a
second and only while shown (ARCHITECTURE rule 7: stream only what changed and is visible).

viser's simple meshes take one colour each, so the sea is drawn as `BANDS` meshes, one per shade: each
update sorts the surface's triangles into them by height and by how squarely they face the light. A fine
patch around the body (cells of `WAVE_PATCH * size / CELLS`) sits in a coarse ring of the same surface
reaching `FAR` patch widths out, which fades into the sky's colour (fog) at the horizon.
"""

from __future__ import annotations

import time

import numpy as np
import viser

WAVE_HZ = 10.0
CELLS = 48
"""Grid cells per side of the fine patch around the body."""
REPLAY_CELLS, REPLAY_HZ = 20, 5.0
"""A recording's sea: the fine patch alone, 441 vertices in one mid-shade, smooth-lit mesh whose triangles are sent
once, 5 times a simulated second (sending colours and triangles each time: a minute of storm would no longer fit
in 1.5 MB)."""
RING_CELLS = 4
"""Cells of the coarse ring along each side of the fine patch (CELLS and REPLAY_CELLS are multiples of it);
outside it they grow geometrically to the horizon."""
FAR = 16.0
"""The ring reaches this many patch half-widths from the body (waves of storms are 100 m and more long)."""
WATER_COLOUR, WATER_OPACITY = (25, 95, 175), 0.6
"""Calm sheet: deep enough a blue to read as water, translucent enough that the submerged part shows under it."""
WAVE_OPACITY = 0.85
LINED_OPACITY = 0.3
"""A sea over mooring lines: see-through enough for their tension colours (at 0.85 they showed 15 % of them, at 0.55
they read grey), over the SEABED's dark floor, which keeps it reading as deep water rather than as the pale sky."""
SEABED_COLOUR = (14, 42, 70)
"""The floor drawn under a sea over mooring lines, at their lowest node (their anchors lie on it)."""
TROUGH, CREST = np.array([4, 30, 80]), np.array([125, 185, 230])
"""The sea's darkest and lightest shades (deep troughs facing away from the light, crests facing it)."""
SKY = (222, 232, 242)
"""The background and the fog the far water fades into."""
LIGHT = np.array([0.45, -0.55, 0.70]) / np.linalg.norm([0.45, -0.55, 0.70])
"""Where the shading's light comes from: behind the default camera, above."""
HEIGHT_SCALE = 2.0
"""m: the height that lightens a crest by 0.35 of the way from trough to crest, in every scene (it was twice each sea's
own standard deviation, which drew 10 cm waves with a storm's range of shades)."""
SLOPE_GAIN = 4.0
"""Shade per unit of slope facing the light (a slope of 0.1 toward it: 0.4 of the way from trough to crest)."""
INNER = 0.4
"""The share of the fine patch's half-width that shows the whole surface (beyond it, a blend to what the ring shows)."""
WAVE_PATCH = 3.0
"""The fine patch spans this many times the scene's base size."""


def grid_faces(n: int) -> np.ndarray:
    """Two triangles per cell of an (n + 1) x (n + 1) vertex grid, counter-clockwise seen from above."""
    return _cell_faces(n, n, np.ones((n, n), bool))


def _cell_faces(nx: int, ny: int, keep: np.ndarray) -> np.ndarray:
    """Two counter-clockwise triangles per kept cell of an (nx + 1) x (ny + 1) vertex grid (x index major)."""
    i, j = np.nonzero(keep)
    a = i * (ny + 1) + j
    b, c, d = a + ny + 1, a + 1, a + ny + 2
    return np.concatenate([np.stack([a, b, d], axis=1), np.stack([a, d, c], axis=1)]).astype(np.uint32)


class SeaGrid:
    """The sea's mesh around the origin: a fine square patch of `cells` per side and half-width `half`, in a
    coarse ring of the same surface out to `far * half` whose cells grow outward. The ring's cells along the
    patch are fans onto the patch's own edge vertices, so the two share every vertex of their seam: no
    T-junction, and no crack for the sky to show through."""

    def __init__(self, half: float, cells: int, far: float = FAR, blend: bool = True):
        self.fine = np.linspace(-half, half, cells + 1)
        per = cells // RING_CELLS  # patch cells per ring cell along the seam
        step, out = self.fine[per] - self.fine[0], [half]
        while out[-1] < far * half:  # cells growing by a quarter each: a few dozen vertices to the horizon
            step *= 1.25
            out.append(out[-1] + step)
        outer = np.array(out[1:])
        self.ring = np.concatenate([-outer[::-1], self.fine[::per], outer])
        gap = np.diff(self.ring)
        self.ring_side = np.maximum(np.r_[gap, gap[-1]], np.r_[gap[0], gap])
        """Each ring coordinate's wider neighbouring cell: what the ring can show there."""
        n, m, nf = len(self.ring) - 1, len(outer), (cells + 1) ** 2
        centre = 0.5 * (self.ring[:-1] + self.ring[1:])
        inside = np.abs(centre) < half
        beside = np.zeros(n, bool)
        beside[[m - 1, m + RING_CELLS]] = True
        along = (inside[:, None] | beside[:, None]) & (inside[None, :] | beside[None, :])
        along &= ~(beside[:, None] & beside[None, :])  # the patch's cells and the ring's beside its sides (the fans'), not its corners
        fine = lambda i, j: i * (cells + 1) + j  # noqa: E731
        ring = lambda i, j: nf + i * (n + 1) + j  # noqa: E731
        fans = []
        for k in range(RING_CELLS):  # the ring's cells beside the patch's four sides
            edge = range(k * per, (k + 1) * per + 1)
            for (o0, o1), inner in (
                ((ring(m - 1, m + k), ring(m - 1, m + k + 1)), [fine(0, e) for e in edge]),
                ((ring(m + RING_CELLS + 1, m + k), ring(m + RING_CELLS + 1, m + k + 1)), [fine(cells, e) for e in edge]),
                ((ring(m + k, m - 1), ring(m + k + 1, m - 1)), [fine(e, 0) for e in edge]),
                ((ring(m + k, m + RING_CELLS + 1), ring(m + k + 1, m + RING_CELLS + 1)), [fine(e, cells) for e in edge]),
            ):
                mid = per // 2
                fans += [(o0 if e < mid else o1, inner[e], inner[e + 1]) for e in range(per)] + [(o0, inner[mid], o1)]
        faces = np.concatenate([_cell_faces(n, n, ~along) + nf, np.array(fans, np.int64), grid_faces(cells)])
        # (the ring first: the page draws a translucent mesh's triangles in order, the patch near the camera last)
        same = np.arange(nf + (n + 1) ** 2)  # the ring's vertices on the patch's edge are the patch's own (its corners')
        for a in range(RING_CELLS + 1):
            for b in range(RING_CELLS + 1):
                same[ring(m + a, m + b)] = fine(a * per, b * per)
        self.faces = _upward(same[faces].astype(np.uint32), self.xy(np.zeros(2)))
        self.seam = np.full(len(self.fine), self.fine[per] - self.fine[0])
        """The ring's cells beside the patch, for each patch coordinate: what the patch's edge shows, as the ring does."""
        s = np.clip((1.0 - np.hypot.outer(self.fine, self.fine) / half) / (1.0 - INNER), 0.0, 1.0)
        self.inner = s * s * (3.0 - 2.0 * s) if blend else None
        """(n, n) the weight of the whole surface in the patch: 1 within INNER of its half-width from its centre, falling
        smoothly (a circle: no corner for the eye) to 0 at its half-width, where the patch shows what the ring shows (a
        wave too short for the ring, drawn to the patch's edge, met the ring's flat water in facets that the shading lit
        as sharp-edged wedges); None (`blend` False): the whole surface to the edge, for a recording's patch drawn alone."""

    def xy(self, origin: np.ndarray) -> np.ndarray:
        """(v, 2) the vertices' horizontal positions, the grid centred on `origin`."""
        grids = [np.meshgrid(c + origin[0], c + origin[1], indexing="ij") for c in (self.fine, self.ring)]
        return np.concatenate([np.column_stack([gx.ravel(), gy.ravel()]) for gx, gy in grids])

    def heights(self, water, t: float, origin: np.ndarray) -> np.ndarray:
        """(v,) the surface's heights at the vertices (Waves.elevation_on_grid: the ring leaves out what it cannot show, and
        the patch fades from the whole surface to that towards its edge)."""
        xs, ys = self.fine + origin[0], self.fine + origin[1]
        whole = water.elevation_on_grid(xs, ys, t)
        if self.inner is not None:
            whole = water.elevation_on_grid(xs, ys, t, self.seam, self.seam) * (1.0 - self.inner) + self.inner * whole
        fine = whole.ravel()
        ring = water.elevation_on_grid(self.ring + origin[0], self.ring + origin[1], t, self.ring_side, self.ring_side).ravel()
        return np.concatenate([fine, ring])


def _upward(faces: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """The triangles turned counter-clockwise seen from above (their normals up: vertex_normals reads them)."""
    a, b, c = (xy[faces[:, k]] for k in range(3))
    turn = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    faces = faces.copy()
    faces[turn < 0] = faces[turn < 0][:, [0, 2, 1]]
    return faces


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(v, 3) unit normals at the vertices: the area-weighted mean of their triangles' (all facing up)."""
    P = vertices[faces].astype(float)
    n = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])  # twice the area, along the normal
    out = np.column_stack([np.bincount(faces.ravel(), np.repeat(n[:, k], 3), len(vertices)) for k in range(3)])
    return out / np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-30)


def shade(vertices: np.ndarray, faces: np.ndarray, scale: float = HEIGHT_SCALE) -> np.ndarray:
    """(v,) each vertex's shade, 0 (TROUGH) .. 1 (CREST): lighter the more squarely the surface there faces LIGHT (its
    true slope) and the higher it lies (height over `scale`, the same in every scene). A sea's contrast is its own:
    10 cm waves 2.2 s long (slopes of 0.04) read as ripples, a storm's 3 m sea (slopes of 0.2) as a storm. Continuous:
    the page interpolates it across each triangle."""
    n = vertex_normals(vertices, faces)
    height = vertices[:, 2] / scale
    return np.clip(0.5 + 0.35 * np.clip(height, -1.0, 1.0) + SLOPE_GAIN * (n @ LIGHT - LIGHT[2]), 0.0, 1.0)


def shade_colours(value: np.ndarray) -> np.ndarray:
    """(v, 3) sRGB colours 0..255 of the shades (0 .. 1)."""
    return TROUGH + (CREST - TROUGH) * value[:, None]


def linear(srgb: np.ndarray) -> np.ndarray:
    """sRGB 0..255 to linear 0..1 (glTF's vertex colours are linear: the page converts them back)."""
    c = np.asarray(srgb, float) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def sea_glb(vertices: np.ndarray, colours: np.ndarray, faces: np.ndarray, opacity: float = WAVE_OPACITY) -> bytes:
    """A GLB of one mesh: float32 positions, float32 linear RGB vertex colours (no 8-bit steps in the dark troughs),
    16-bit triangles when they fit; an unlit, double-sided, blended material (KHR_materials_unlit: the page shows the
    colours as they are, fogged)."""
    import json
    import struct

    index = np.uint16 if len(vertices) < 65536 else np.uint32
    blobs = [np.ascontiguousarray(vertices, np.float32).tobytes(), np.ascontiguousarray(colours, np.float32).tobytes(),
             np.ascontiguousarray(faces, index).tobytes()]  # fmt: skip
    views, binary = [], b""
    for blob, target in zip(blobs, (34962, 34962, 34963)):
        views.append({"buffer": 0, "byteOffset": len(binary), "byteLength": len(blob), "target": target})
        binary += blob + b"\0" * (-len(blob) % 4)
    v = np.asarray(vertices, np.float32)
    doc = {
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_materials_unlit"],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "COLOR_0": 1}, "indices": 2, "material": 0, "mode": 4}]}],
        "materials": [
            {
                "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, opacity], "metallicFactor": 0.0, "roughnessFactor": 1.0},
                "alphaMode": "BLEND",
                "doubleSided": True,
                "extensions": {"KHR_materials_unlit": {}},
            }
        ],
        "buffers": [{"byteLength": len(binary)}],
        "bufferViews": views,
        "accessors": [
            {
                "bufferView": 0,
                "componentType": 5126,
                "count": len(v),
                "type": "VEC3",
                "min": v.min(axis=0).tolist(),
                "max": v.max(axis=0).tolist(),
            },
            {"bufferView": 1, "componentType": 5126, "count": len(v), "type": "VEC3"},
            {"bufferView": 2, "componentType": 5123 if index is np.uint16 else 5125, "count": faces.size, "type": "SCALAR"},
        ],
    }
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    chunks = struct.pack("<II", len(text), 0x4E4F534A) + text + struct.pack("<II", len(binary), 0x004E4942) + binary
    return struct.pack("<III", 0x46546C67, 2, 12 + len(chunks)) + chunks


class WaterView:
    """Scene nodes for the water; `show` runs on the simulation thread only."""

    def __init__(self, server: viser.ViserServer, size: float, lighter: bool = False, root: str = ""):
        """lighter=True: a coarser surface sent less often (recordings: the file stays small); `root`: the frame
        the nodes hang from."""
        self.server, self.root = server, root
        self.size = WAVE_PATCH * size
        self.cells, self.hz = (REPLAY_CELLS, REPLAY_HZ) if lighter else (CELLS, WAVE_HZ)
        half = 0.5 * self.size
        reach = (1.0 if lighter else FAR) * half  # calm water: one translucent sheet the submerged part shows through (no floor-like grid)
        sheet = np.array([[-reach, -reach, 0.0], [reach, -reach, 0.0], [reach, reach, 0.0], [-reach, reach, 0.0]], dtype=np.float32)
        self.calm = server.scene.add_mesh_simple(
            f"{root}/water", sheet, np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32), color=WATER_COLOUR, opacity=WATER_OPACITY,
            side="double", cast_shadow=False, receive_shadow=False,
        )  # fmt: skip
        self.lighter = lighter
        self.reach = reach
        self.seabed = None
        """The floor under a sea over mooring lines (`show_seabed`), made when first asked."""
        self.grid = SeaGrid(half, self.cells, blend=not lighter)  # (a recording draws the patch alone: no ring to meet)
        self.surface = server.scene.add_frame(f"{root}/waves", show_axes=False, visible=False)
        """The sea's node: its children are the surfaces (hidden with it)."""
        flat = np.column_stack([self.grid.xy(np.zeros(2)), np.zeros(len(self.grid.xy(np.zeros(2))))])
        if lighter:  # one mesh of fixed triangles in one mid shade, smooth-lit, only its vertices sent
            patch = flat[: (self.cells + 1) ** 2].astype(np.float32)
            self.replay_mesh = server.scene.add_mesh_simple(
                f"{root}/waves/sea", patch, grid_faces(self.cells), color=tuple(int(c) for c in shade_colours(np.array([0.5]))[0]),
                opacity=WAVE_OPACITY, side="double", cast_shadow=False, receive_shadow=False, visible=False,
            )  # fmt: skip
            self.seas = []
        else:  # two nodes: the next surface goes into the hidden one, shown at the next publish (sea_glb)
            blank = sea_glb(flat, np.tile(linear(shade_colours(np.array([0.5]))), (len(flat), 1)), self.grid.faces)
            self.seas = [
                server.scene.add_glb(f"{root}/waves/sea{k}", blank, cast_shadow=False, receive_shadow=False, visible=False)
                for k in range(2)
            ]
        self._front, self._pending = 1, False
        self.opacity = WAVE_OPACITY
        """The sea's opacity from its next surface on (LINED_OPACITY while the scene shows lines under it)."""
        self.vertices = flat.astype(np.float32)
        """(v, 3) the surface last sent (the fine patch's (cells + 1)^2 first, x major, then the ring's), m."""
        self.colours = np.zeros((len(flat), 3))
        """(v, 3) its vertices' sRGB colours, 0..255 (a recording's: none)."""
        if not lighter:  # the far water fades into the sky at the horizon (a recording's sea is the patch alone)
            server.scene.configure_fog(3.0 * half, 0.9 * reach, color=SKY)
            server.scene.set_background_image(np.full((2, 2, 3), SKY, np.uint8), format="png")
        self._sent = -np.inf
        self.sent_time = 0.0
        """Simulated time of the surface last sent."""
        self.updates = 0
        """How many wave surfaces were sent (tests check the throttle and the still-water silence)."""

    def show_seabed(self, depth: float | None, centre: np.ndarray) -> None:
        """The seabed at z = depth (< 0) under the sea around `centre`, opaque; None: none (a scene without lines)."""
        if depth is None:
            if self.seabed is not None and self.seabed.visible:
                self.seabed.visible = False
            return
        if self.seabed is None:
            r = self.reach
            floor = np.array([[-r, -r, 0.0], [r, -r, 0.0], [r, r, 0.0], [-r, r, 0.0]], dtype=np.float32)
            self.seabed = self.server.scene.add_mesh_simple(
                f"{self.root}/seabed", floor, np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32), color=SEABED_COLOUR,
                side="double", cast_shadow=False, receive_shadow=False,
            )  # fmt: skip
        where = (float(centre[0]), float(centre[1]), float(depth))
        if not np.allclose(self.seabed.position, where, atol=0.5):
            self.seabed.position = where
        if not self.seabed.visible:
            self.seabed.visible = True

    def show(self, water, t: float, centre: np.ndarray, visible: bool, now: float | None = None) -> bool:
        """The flat sheet for still water; otherwise the surface around `centre` (x, y) at time t, throttled.
        Whether a surface went out."""
        still = water.flat
        if self.calm.visible != (visible and still):
            self.calm.visible = visible and still
        if self.surface.visible != (visible and not still):
            self.surface.visible = visible and not still
        if self._pending:  # the surface sent at the last update has been parsed by now: show it, hide the other
            back, front = self.seas[self._front ^ 1], self.seas[self._front]
            back.visible, self._front, self._pending = True, self._front ^ 1, False
            if front.visible:
                front.visible = False
        now = time.monotonic() if now is None else now
        if still or not visible or now - self._sent < 1.0 / self.hz:
            return False
        cell = self.size / self.cells
        origin = np.round(np.asarray(centre[:2]) / cell) * cell  # follow the body in whole cells
        vertices = np.column_stack([self.grid.xy(origin), self.grid.heights(water, t, origin)]).astype(np.float32)
        self.vertices = vertices
        if self.lighter:
            node = self.replay_mesh
            node.vertices = vertices[: (self.cells + 1) ** 2]
            if not node.visible:
                node.visible = True
        else:
            self.colours = shade_colours(shade(vertices, self.grid.faces))
            self.seas[self._front ^ 1].glb_data = sea_glb(vertices, linear(self.colours), self.grid.faces, self.opacity)
            self._pending = True
        self._sent, self.sent_time = now, t
        self.updates += 1
        return True

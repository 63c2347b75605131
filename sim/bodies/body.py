"""Rigid bodies as surface samples: a cell-centred box or cube, or any watertight trimesh mesh."""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from sim.bodies.clusters import bisection_tree
from sim.bodies.rotation import matrix_to_quat
from sim.errors import ConfigError

if TYPE_CHECKING:
    from sim.scene.config import BodyConfig, SceneConfig


@dataclass(frozen=True, eq=False)
class Body:
    """Static description of a body. The body frame has its origin at the centre of mass and
    its axes along the principal axes of inertia (for a cube or box: the edges)."""

    r_body: np.ndarray
    """(n, 3) sample positions, body frame, m."""
    n_body: np.ndarray
    """(n, 3) outward unit normals, body frame."""
    area: np.ndarray
    """(n,) sample areas, m^2."""
    mass: float
    """Total mass M, kg (spread over the samples in proportion to their area)."""
    inertia: np.ndarray
    """(3,) principal moments of inertia, kg m^2 (the body-frame tensor is diag(inertia)): of the samples,
    or with `exact_inertia` of the mesh's triangles as a uniform shell."""
    volume: float
    """Enclosed volume, m^3."""
    radius: float
    """Largest distance of a sample from the centre of mass, m."""
    mesh_vertices: np.ndarray
    """(v, 3) display mesh vertices, body frame, m."""
    mesh_faces: np.ndarray
    """(f, 3) display mesh triangles (vertex indices)."""
    q_input_body: np.ndarray
    """(4,) rotation from the principal frame to the frame the shape was given in (w, x, y, z)."""
    cells: np.ndarray | None = None
    """(n, 4, 3) each sample's own patch of the surface (the cell its area stands for), as a planar convex
    polygon, body frame, m: a box face's rectangle, or a mesh sample's triangle (last corner repeated).
    The `cells` force model clips these at the water line."""
    name: str = "body"
    exact_inertia: bool = False
    """Whether `inertia` is the mesh shell's exact one (the panels model) rather than the samples' (the report's)."""

    @property
    def sample_mass(self) -> np.ndarray:
        """(n,) sample masses m_k = M a_k / A, kg."""
        return self.mass * self.area / self.area.sum()

    @property
    def n_samples(self) -> int:
        """How many surface samples (the panels model: mesh triangles) the body has."""
        return len(self.area)

    @cached_property
    def face_normals(self) -> np.ndarray:
        """(f, 3) outward unit normals of the display mesh's triangles, body frame."""
        v = self.mesh_vertices[self.mesh_faces]
        n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
        return n / np.linalg.norm(n, axis=1, keepdims=True)

    @cached_property
    def packed(self) -> tuple:
        """The arrays the compiled kernels take: samples (r, n, area) and mesh (vertices, faces, normals)."""
        c = np.ascontiguousarray
        return (c(self.r_body), c(self.n_body), c(self.area), c(self.mesh_vertices, dtype=float),
                c(self.mesh_faces, dtype=np.int64), c(self.face_normals), self.sample_moments, self.cell_corners, self.cell_reach,
                *self.face_tree)  # fmt: skip

    @cached_property
    def face_tree(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The mesh's triangles as a tree of nested compact parts (clusters.bisection_tree): order, spans, spheres."""

        return bisection_tree(self.mesh_vertices[self.mesh_faces])

    @cached_property
    def cell_corners(self) -> np.ndarray:
        """(n, 4, 3) `cells`; a body made from bare samples has none: each cell is then its sample alone."""
        cells = self.cells if self.cells is not None else np.repeat(self.r_body[:, None], 4, axis=1)
        return np.ascontiguousarray(cells, dtype=float)

    @cached_property
    def cell_reach(self) -> np.ndarray:
        """(n,) how far each cell's corners lie from its sample, m: a sample farther than this from the
        water line has its whole cell on one side of it."""
        return np.ascontiguousarray(np.linalg.norm(self.cell_corners - self.r_body[:, None], axis=2).max(axis=1))

    @cached_property
    def sample_moments(self) -> np.ndarray:
        """(n, 34) per-sample constants whose sums over the wet samples give every water-force
        integral (z = x_z + R[2].r is linear in r): a; a r; a r r^T (xx xy xz yy yz zz); a n;
        a n r^T (row-major); a c; a c r^T, with c = r x n. Body frame."""
        a, r, n = self.area[:, None], self.r_body, self.n_body
        c = np.cross(r, n)
        rr = r[:, [0, 0, 0, 1, 1, 2]] * r[:, [0, 1, 2, 1, 2, 2]]
        n_r = (n[:, :, None] * r[:, None, :]).reshape(-1, 9)
        c_r = (c[:, :, None] * r[:, None, :]).reshape(-1, 9)
        return np.ascontiguousarray(np.hstack([a, a * r, a * rr, a * n, a * n_r, a * c, a * c_r]))


def box_samples(extents, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Cell-centre samples of a box surface: n x n cells per face (midpoint rule); with their cells."""
    ext = np.asarray(extents, dtype=float)
    c = (np.arange(n) + 0.5) / n - 0.5  # cell centres on [-1/2, 1/2]
    a, b = np.meshgrid(c, c, indexing="ij")
    pos, nor, area, cells = [], [], [], []
    for axis in range(3):
        j, k = (axis + 1) % 3, (axis + 2) % 3
        for sign in (1.0, -1.0):
            p = np.zeros((n * n, 3))
            p[:, axis] = sign * ext[axis] / 2
            p[:, j] = a.ravel() * ext[j]
            p[:, k] = b.ravel() * ext[k]
            normal = np.zeros(3)
            normal[axis] = sign
            pos.append(p)
            nor.append(np.tile(normal, (n * n, 1)))
            area.append(np.full(n * n, ext[j] * ext[k] / n**2))
            half_j, half_k = np.zeros(3), np.zeros(3)
            half_j[j], half_k[k] = ext[j] / (2 * n), ext[k] / (2 * n)
            corners = np.array([-half_j - half_k, half_j - half_k, half_j + half_k, -half_j + half_k])
            cells.append(p[:, None, :] + corners[None])
    return np.concatenate(pos), np.concatenate(nor), np.concatenate(area), np.concatenate(cells)


def _mass_from(cfg: BodyConfig, volume: float) -> float:
    return float(cfg.mass) if cfg.mass is not None else float(cfg.density) * volume


def shell_inertia(verts: np.ndarray, faces: np.ndarray, mass: float) -> np.ndarray:
    """(3, 3) inertia tensor about the origin of the mesh's triangles as a shell of uniform surface
    density and total mass `mass`, exact: over a triangle, the integral of r r^T dA is
    A/12 (sum of v_i v_i^T + s s^T), s = v_0 + v_1 + v_2."""
    T = verts[faces]
    A = 0.5 * np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)
    s = T.sum(axis=1)
    S = (np.einsum("k,kvi,kvj->ij", A, T, T) + np.einsum("k,ki,kj->ij", A, s, s)) / 12.0
    S *= mass / A.sum()
    return np.trace(S) * np.eye(3) - S


def _assemble(r, nrm, area, cells, mass, volume, verts, faces, name, exact: bool = False, centre_of_mass=None, moments=None) -> Body:
    """Shift to the centre of mass and rotate to principal axes; compute inertia (the samples', or
    with `exact` the mesh shell's; both share the centre of mass: the area centroid, which the
    samples' midpoint rule gets exactly). A given `centre_of_mass` (the shape's own frame) and principal
    `moments` (about it, along the shape's axes) replace the shell's: a ballasted body as its designer gives it."""
    w = area / area.sum()
    com = w @ r if centre_of_mass is None else np.asarray(centre_of_mass, float)
    r = r - com
    cells = cells - com
    verts = verts - com
    m = mass * w
    if moments is not None:
        inertia = np.diag(check_moments(moments, name))
    elif exact:
        inertia = shell_inertia(verts, faces, mass)
    else:
        inertia = np.einsum("k,k->", m, np.einsum("ki,ki->k", r, r)) * np.eye(3) - (r * m[:, None]).T @ r
    off = np.abs(inertia - np.diag(np.diag(inertia))).max()
    lam = np.linalg.eigvalsh(inertia)
    if moments is not None or off <= 1e-12 * np.abs(inertia).max() or np.ptp(lam) <= 1e-6 * lam.max():  # keep the given axes
        moments, axes = np.diag(inertia).copy(), np.eye(3)
    else:
        moments, axes = np.linalg.eigh(inertia)
        if np.linalg.det(axes) < 0:
            axes[:, 2] *= -1

    return Body(
        r_body=np.ascontiguousarray(r @ axes),
        n_body=np.ascontiguousarray(nrm @ axes),
        area=area,
        mass=mass,
        inertia=moments,
        volume=float(volume),
        radius=float(np.sqrt(np.einsum("ki,ki->k", r, r).max())),
        mesh_vertices=np.ascontiguousarray(verts @ axes),
        mesh_faces=faces,
        q_input_body=matrix_to_quat(axes),
        cells=np.ascontiguousarray(cells @ axes),
        name=name,
        exact_inertia=exact,
    )


def check_moments(moments, name: str) -> np.ndarray:
    """Principal moments of inertia a rigid body can have (each at most the sum of the other two), else one ConfigError line."""
    m = np.asarray(moments, float)
    if m.shape != (3,) or not np.all(np.isfinite(m)) or np.any(m <= 0) or np.any(2 * m > m.sum() * (1 + 1e-9)):
        raise ConfigError(f"'{name}': moments of inertia {tuple(float(v) for v in m.ravel())} are not a rigid body's "
                          "(each must be positive and at most the sum of the other two)")  # fmt: skip
    return m


def make_box(extents, points_per_edge: int, mass: float, name: str = "box", exact: bool = False, centre_of_mass=None,
             moments=None) -> Body:  # fmt: skip
    import trimesh

    r, nrm, area, cells = box_samples(extents, points_per_edge)
    display = trimesh.creation.box(extents=extents)
    return _assemble(r, nrm, area, cells, mass, np.prod(extents), display.vertices, display.faces, name, exact, centre_of_mass, moments)


MESH_FORMATS = ("stl", "obj", "ply")
MAX_TRIANGLES = 200_000
"""Larger meshes are refused: their samples would not keep real time, nor fit a browser."""
MAX_VERTICES = 3 * MAX_TRIANGLES
"""More vertices than a mesh of MAX_TRIANGLES triangles can use: refused before parsing, like the triangles."""
MAX_MESH_BYTES = 50_000_000
"""A larger file is refused before it is read (a 200 000-triangle binary STL is 10 MB, an ASCII one about 50 MB)."""
SIZE_RANGE = (1e-3, 500.0)
"""Plausible extents of a floating body, m: outside, the file is most likely in another unit."""
MIN_FILL = 1e-6
"""Least enclosed volume, as a fraction of the cube on the mesh's largest extent: below it the surface
folds onto itself (two faces back to back enclose nothing) and no density or buoyancy can be had."""
UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254, "ft": 0.3048}


def printable(name: str, limit: int = 80) -> str:
    """A file name fit to show and to build a file name from: control characters (a NUL byte, a
    newline, an escape) become '?', at most `limit` characters."""
    import unicodedata

    text = "".join("?" if unicodedata.category(c).startswith("C") else c for c in str(name))
    return text[:limit] or "mesh"


def _declared_counts(data: bytes, kind: str) -> tuple[int, int]:
    """(triangles, vertices) a mesh file declares, read cheaply before any parser allocates for them:
    a binary STL's header count; an ASCII STL's 'vertex' words (three a facet); an OBJ's 'f' and 'v' lines (a polygon
    line is at least one triangle); a PLY header's `element face N` and `element vertex N`. -1: unknown."""
    if kind == "stl":  # binary exactly when its length is what its header's count makes it (as trimesh reads it)
        if len(data) >= 84 and len(data) == 84 + 50 * int.from_bytes(data[80:84], "little"):
            return int.from_bytes(data[80:84], "little"), 0
        return data.count(b"vertex") // 3, 0  # three corners a facet
    if kind == "obj":

        def lines(tag: bytes) -> int:
            return sum(data.count(b"\n" + tag + sep) + data.startswith(tag + sep) for sep in (b" ", b"\t"))

        return lines(b"f"), lines(b"v")
    if kind == "ply":
        header = data[: data.find(b"end_header")] if b"end_header" in data[:65536] else b""
        counts = dict(re.findall(rb"element\s+(face|vertex)\s+(\d+)", header))
        return int(counts.get(b"face", -1)), int(counts.get(b"vertex", -1))
    return -1, -1


def _read(source, name: str, file_type: str | None) -> tuple[bytes, str]:
    """The file's bytes and its format, refused when of another format or too large to read."""
    if isinstance(source, (bytes, bytearray)):
        kind, data = (file_type or Path(name).suffix.lstrip(".")).lower(), bytes(source)
    else:
        path = Path(source)
        if not path.is_file():
            raise ConfigError(f"mesh file not found: {printable(str(source), 200)}")
        kind = path.suffix.lstrip(".").lower()
        if kind in MESH_FORMATS and path.stat().st_size > MAX_MESH_BYTES:
            raise ConfigError(
                f"'{name}' is {path.stat().st_size / 1e6:.0f} MB, more than {MAX_MESH_BYTES / 1e6:.0f} MB: simplify it first (e.g. in Blender)"
            )
        data = path.read_bytes() if kind in MESH_FORMATS else b""
    if kind not in MESH_FORMATS:
        raise ConfigError(f"'{name}': mesh files must be {', '.join(f'.{f}' for f in MESH_FORMATS)}, got '.{printable(kind, 12)}'")
    if len(data) > MAX_MESH_BYTES:
        raise ConfigError(
            f"'{name}' is {len(data) / 1e6:.0f} MB, more than {MAX_MESH_BYTES / 1e6:.0f} MB: simplify it first (e.g. in Blender)"
        )
    return data, kind


def load_mesh(source, name: str = "mesh", unit: str = "m", file_type: str | None = None):
    """A closed triangle mesh from a path or bytes (STL, OBJ or PLY), scaled from `unit` to metres,
    checked: readable, at most MAX_TRIANGLES (counted before parsing where the format says), finite,
    of a plausible size, watertight, one piece, enclosing a volume. ConfigError with one line saying
    what is wrong otherwise."""
    import io

    import trimesh

    name = printable(name)
    if unit not in UNITS:
        raise ConfigError(f"mesh unit must be one of {', '.join(UNITS)}, got {printable(unit, 20)!r}")
    data, kind = _read(source, name, file_type)
    triangles, vertices = _declared_counts(data, kind)
    if triangles > MAX_TRIANGLES or vertices > MAX_VERTICES:
        what = f"{triangles:,} faces" if triangles > MAX_TRIANGLES else f"{vertices:,} vertices"
        raise ConfigError(
            f"'{name}' has {what}, more than a mesh of {MAX_TRIANGLES:,} triangles needs: simplify it first (e.g. in Blender)"
        )
    try:
        mesh = trimesh.load(io.BytesIO(data), file_type=kind, force="mesh", process=False)
    except Exception as e:  # noqa: BLE001 -- trimesh raises many types for unreadable files
        why = printable(f"{type(e).__name__}: {str(e)[:80]}", 120)
        raise ConfigError(f"'{name}' is not a mesh: not readable as {kind.upper()} ({why})") from None
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise ConfigError(f"'{name}' holds no triangles: not a mesh")
    if len(mesh.faces) > MAX_TRIANGLES:
        raise ConfigError(f"'{name}' has {len(mesh.faces):,} triangles, more than {MAX_TRIANGLES:,}: simplify it first (e.g. in Blender)")
    if not np.isfinite(mesh.vertices[mesh.referenced_vertices]).all():
        raise ConfigError(f"'{name}' has vertices with coordinates that are not finite numbers (nan or inf)")
    _check_size(mesh, name, unit)
    mesh.process()  # merges the corners triangles share (an STL repeats them): needed to tell closed from open
    check_closed(mesh, name)
    mesh.apply_scale(UNITS[unit])
    return mesh


def _check_size(mesh, name: str, unit: str) -> None:
    """Before merging vertices (which would fuse a tiny body into a point): a size in metres within SIZE_RANGE."""
    size = float(mesh.extents.max()) * UNITS[unit]
    lo, hi = SIZE_RANGE
    if size < lo:
        hint = "in another unit? give a larger one" if unit != "ft" else "really this small?"
        raise ConfigError(f"'{name}' is too small: {size:.4g} m across in {unit}, less than {lo:g} m: is the file {hint}")
    if size > hi:
        raise ConfigError(f"'{name}' is {size:.4g} m across in {unit}, more than {hi:g} m: is the file in millimetres? give the unit mm")


def check_closed(mesh, name: str) -> None:
    """ConfigError unless the mesh is one closed surface that encloses a volume."""
    import trimesh

    if not mesh.is_watertight:
        raise ConfigError(f"'{name}' is not watertight (it has holes or open edges): a floating body needs a closed surface")
    pieces = len(trimesh.graph.connected_components(mesh.face_adjacency, nodes=np.arange(len(mesh.faces)), min_len=1))
    if pieces > 1:
        raise ConfigError(f"'{name}' is {pieces} separate closed surfaces, not one: a floating body must be a single closed surface "
                          "(join overlapping parts into one, e.g. a boolean union in Blender)")  # fmt: skip
    with np.errstate(all="ignore"):  # trimesh divides by the volume for the centre of mass: 0/0 when there is none
        volume, size = abs(float(mesh.volume)), float(mesh.extents.max())
    if not volume > MIN_FILL * size**3:  # nan too
        raise ConfigError(f"'{name}' encloses no volume (its faces lie back to back, or nearly): a floating body needs a solid inside")


def check_body(body: Body) -> Body:
    """ConfigError unless the body has a positive volume and mass and finite, positive moments of inertia
    (anything else gives a density or an angular velocity of 0/0 once it runs)."""
    numbers = np.concatenate([[body.volume, body.mass, body.radius], body.inertia])
    if not (np.isfinite(numbers).all() and body.volume > 0 and body.mass > 0 and body.radius > 0 and (body.inertia > 0).all()):
        raise ConfigError(f"mesh '{body.name}' gives no usable body (volume {body.volume:.3g} m^3, mass {body.mass:.3g} kg, "
                          f"moments of inertia {', '.join(f'{i:.3g}' for i in body.inertia)} kg m^2): it needs a solid, closed surface")  # fmt: skip
    return body


def make_mesh_body(mesh, samples: int, mass: float | None = None, density: float | None = None, name: str = "mesh", unit: str = "m",
                   exact: bool = False, centre_of_mass=None, moments=None) -> Body:  # fmt: skip
    """Samples at triangle centroids after subdividing to at least `samples` triangles (one per
    triangle when the mesh already has more); the count used is `Body.n_samples`. ConfigError (one
    line) for a mesh that is not one closed surface enclosing a volume, or that gives no usable body."""
    import trimesh

    name = printable(name)
    if not isinstance(mesh, trimesh.Trimesh):
        mesh = load_mesh(mesh, Path(mesh).name, unit)
    else:
        check_closed(mesh, name)
    if mesh.volume < 0:
        mesh = mesh.copy()
        mesh.invert()
    verts, faces = np.asarray(mesh.vertices, float), np.asarray(mesh.faces)
    # the longest edge allowed shrinks until there are enough triangles: the first count past the target.
    # Every edge longer than it is halved, so mirror-image triangles split alike and the samples keep
    # the mesh's symmetry (splitting only some equal triangles to hit the count exactly would break it)
    edge = float(mesh.edges_unique_length.max()) * 1.0001
    while True:
        v, f = trimesh.remesh.subdivide_to_size(verts, faces, max_edge=edge)
        if len(f) >= samples:
            break
        edge *= 0.95
    tri = v[f]
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area = 0.5 * np.linalg.norm(cross, axis=1)
    keep = area > 0
    normals = cross[keep] / (2 * area[keep, None])
    volume = float(mesh.volume)
    total = float(mass) if mass is not None else float(density) * volume
    if not (np.isfinite(total) and total > 0):  # before the principal axes, which a nan would stop with LinAlgError
        raise ConfigError(f"mesh '{name}' gives no usable body: mass {total:.3g} kg (it needs a positive mass or density)")
    cells = tri[keep][:, [0, 1, 2, 2]]  # each sample's own triangle, as a polygon of four corners
    return check_body(_assemble(tri.mean(axis=1)[keep], normals, area[keep], cells, total, volume, verts, faces, name, exact, centre_of_mass,
                                moments))  # fmt: skip


def make_body(cfg: BodyConfig, base_dir: str = ".", exact_inertia: bool = False) -> Body:
    """The body a scene's config describes; `exact_inertia`: the mesh shell's (for the panels model)."""
    given = (cfg.centre_of_mass, cfg.inertia)
    if cfg.shape == "cube":
        s = float(cfg.size)
        return make_box((s, s, s), int(cfg.points_per_edge), _mass_from(cfg, s**3), "cube", exact_inertia, *given)
    if cfg.shape == "box":
        ext = tuple(float(e) for e in cfg.extents)
        return make_box(ext, int(cfg.points_per_edge), _mass_from(cfg, float(np.prod(ext))), "box", exact_inertia, *given)
    path = Path(cfg.mesh)
    if not path.is_absolute() and not path.is_file():
        path = Path(base_dir) / path
    return make_mesh_body(str(path), int(cfg.samples), cfg.mass, cfg.density, path.stem, cfg.mesh_unit, exact_inertia, *given)


def with_mass(body: Body, mass: float, given_inertia=None) -> Body:
    """The same geometry with another total mass (inertia scales with it, unless the scene gives it: [body] inertia)."""
    inertia = body.inertia * (mass / body.mass) if given_inertia is None else np.asarray(given_inertia, float)
    return dataclasses.replace(body, mass=float(mass), inertia=inertia)


def body_mass(scene: SceneConfig, volume: float) -> float:
    b = scene.body
    return float(b.mass) if b.mass is not None else float(b.density) * volume


def exact_inertia(scene: SceneConfig) -> bool:
    """The panels model integrates the mesh exactly: its body takes the mesh shell's exact inertia too.
    The points model keeps the samples' (the source report's model)."""
    return scene.fluid.forces == "panels"

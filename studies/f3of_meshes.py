"""The F3OF meshes (assets/meshes/f3of_base.stl, f3of_flap.stl): a floating three-body oscillating flap platform.

Dimensions measured from SEA-Stack's Meshmagick panel meshes (commit 4d1eae6453f0cd775ab3184d579ce7d943dbfda7,
data/demos/run_seastack/f3of/assets/geometry/base.obj and flap.obj, MIT licence; hinges at x = +-12.5 m, z = -9 m
from its model files). Those are open, wetted-only panel meshes (the faces where base and flap touch are left
out), so here each body is rebuilt from primitives as one closed surface (manifold3d booleans). Base frame: origin
at its centre of mass, 9 m below the water line.

    part                 centre (base frame)            size
    4 corner columns     x, y = +-12.5                  octagons r 1.5 m (circumscribed), z -3 .. 9 (water line)
    4 corner boxes       x, y = +-12.5                  3 x 3 x 2 m (z -1 .. 1), with a 2 m wide stub
                                                        to y = +-10.5 (where the flap starts)
    6 node boxes         x = +-4; y = 0, +-12.5          2 x 2 x 2 m
    2 end nodes          x = +-12.5, y = 0               2 x 2 x 2 m (between the flap's two halves)
    pontoons, along x    y = 0, +-12.5; z = 0            octagons r 1 m, node to node
    pontoons, along y    x = +-4; z = 0                  octagons r 1 m, node to node
    flap (each of 2)     its hinge at x = +-12.5, z = 0  two plates 2 m thick, y +-1 .. +-10.5, from the hinge axis
                                                        to the water line 9 m above it, on a half cylinder r 1 m
                                                        about the hinge

The flap's frame (flap.obj's) has its origin at its centre of mass, 3.5 m above the hinge: plates z -3.5 .. 5.5,
bottom z -4.5. The base has no pontoon along the hinges: the flap's half cylinders take its place.

Choices: cylinders have SECTIONS sides (the OBJ's octagons), with a ring of vertices every LONGEST at most, and the
flap's outline points that far apart: panels the BEM solve takes as they are (its subdivision at an eighth of the
platform, 3.5 m, would cut long thin triangles into sixteen; 2786 panels with the lids, about 5 s a frequency).
What pierces the surface (columns, flap) goes FREEBOARD above it, closed. The flap's two halves are joined by a
BRIDGE above the water (the gap under it is the end node's), so it is one piece. Where base and flap would touch (the
end node between the flap's halves, the stubs at its ends) the base stops CLEARANCE short: a BEM solve cannot take
coincident panels of two bodies (the OBJs leave those faces out; touching, the solve here gave NaN, and 0.15 m apart
a negative added mass). Submerged volumes 658.9 and 368.9 m^3 (OBJ 672.9 and 368.9), water planes 25.456 and 38.0 m^2 (both the OBJ's).

Frames: f3of_base.stl in the world frame at rest (base.obj + (0, 0, -9): water line z = 0); f3of_flap.stl in the
flap's own frame (flap.obj's: origin at its centre of mass, water line z = 5.5, hinge axis along y at z = -3.5);
place it at (+-12.5, 0, -5.5). Run: python -m studies.f3of_meshes (writes the two files, prints their measures).
"""

from pathlib import Path

import numpy as np

MESHES = Path(__file__).resolve().parent.parent / "assets" / "meshes"
FREEBOARD = 2.0  # m above the water line for what pierces it
BRIDGE = 1.0  # m: thickness of the flap's top bridge, under its top (FREEBOARD - BRIDGE above the water)
SECTIONS = 8
CLEARANCE = 0.5  # m between base and flap where they would touch (a BEM solve cannot take coincident panels of two bodies)
LONGEST = 3.5  # m: the longest edge (a panel no longer than the solve's, so its subdivision does not multiply thin triangles)
BASE_Z = -9.0  # the base's centre of mass (world z), 9 m below the water line
FLAP_WATER = 5.5  # the water line in the flap's frame


def equal_area(r_octagon: float) -> float:
    """The radius of a SECTIONS-gon with the area of an octagon of circumscribed radius `r_octagon`."""
    return r_octagon * np.sqrt(8 * np.sin(np.pi / 4) / (SECTIONS * np.sin(2 * np.pi / SECTIONS)))


def box(lo, hi):
    """The box between corners lo and hi."""
    import trimesh

    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return trimesh.creation.box(extents=hi - lo, transform=trimesh.transformations.translation_matrix((lo + hi) / 2))


def stations(a: float, b: float, step: float = LONGEST) -> np.ndarray:
    """Points from a to b no more than `step` apart, evenly spaced."""
    return np.linspace(a, b, max(1, int(np.ceil(abs(b - a) / step))) + 1)


def ring_mesh(rings: list[np.ndarray]):
    """A closed tube through rings of points (each (n, 3), the same n, in order), its two ends capped by fans from
    their centres."""
    import trimesh

    n, m = len(rings[0]), len(rings)
    V = np.vstack([*rings, rings[0].mean(axis=0), rings[-1].mean(axis=0)])
    k = np.arange(n)
    F = []
    for i in range(m - 1):
        a, b = i * n, (i + 1) * n
        F += [np.column_stack([a + k, a + (k + 1) % n, b + (k + 1) % n]), np.column_stack([a + k, b + (k + 1) % n, b + k])]
    F += [
        np.column_stack([np.full(n, m * n), (k + 1) % n, k]),
        np.column_stack([np.full(n, m * n + 1), (m - 1) * n + k, (m - 1) * n + (k + 1) % n]),
    ]
    return tidy(trimesh.Trimesh(V, np.vstack(F), process=False))


def cylinder(a, b, r: float):
    """A SECTIONS-gon prism of radius r from point a to point b, with a ring of vertices every LONGEST at most."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    axis = (b - a) / np.linalg.norm(b - a)
    u = np.cross(axis, [0.0, 0.0, 1.0] if abs(axis[2]) < 0.9 else [1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    w = np.cross(axis, u)
    phi = 2 * np.pi * (np.arange(SECTIONS) + 0.5) / SECTIONS
    section = r * (np.cos(phi)[:, None] * u + np.sin(phi)[:, None] * w)
    return ring_mesh([a + s * (b - a) + section for s in stations(0.0, 1.0, LONGEST / np.linalg.norm(b - a))])


def union(parts):
    import trimesh

    return tidy(trimesh.boolean.union(parts, engine="manifold"))


def tidy(mesh):
    """The mesh with duplicate vertices merged, degenerate faces dropped, outward normals."""
    mesh.merge_vertices()
    mesh.update_faces(mesh.nondegenerate_faces())
    mesh.remove_unreferenced_vertices()
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def base():
    """The base, in its own frame (origin at its centre of mass)."""
    top, r_col, r_pon = 9.0 + FREEBOARD, equal_area(1.5), equal_area(1.0)
    parts = []
    for sx in (-1, 1):
        c = 1.0 - CLEARANCE
        parts.append(box((12.5 * sx - 1, -c, -1), (12.5 * sx + 1, c, 1)))  # end node, clear of the flap's two halves
        parts.append(cylinder((4 * sx, -12.5, 0), (4 * sx, 12.5, 0), r_pon))  # pontoon along y
        for y in (-12.5, 0, 12.5):
            parts.append(box((4 * sx - 1, y - 1, -1), (4 * sx + 1, y + 1, 1)))  # node box
        for sy in (-1, 1):
            x, y = 12.5 * sx, 12.5 * sy
            parts.append(cylinder((x, y, -3), (x, y, top), r_col))  # column
            parts.append(box((x - 1.5, y - 1.5, -1), (x + 1.5, y + 1.5, 1)))  # corner box
            y0, y1 = sorted(((10.5 + CLEARANCE) * sy, 11.25 * sy))  # the stub, 0.25 m into the box, clear of the flap
            parts.append(box((x - 1, y0, -1), (x + 1, y1, 1)))
    for y in (-12.5, 0, 12.5):
        parts.append(cylinder((-12.5, y, 0), (12.5, y, 0), r_pon))  # pontoon along x
    return split_long_edges(union(parts))


def split_long_edges(mesh, longest: float = LONGEST):
    """The mesh with its longest edge halved (both triangles beside it split in two) until none is longer than
    `longest`: the surface unchanged, still closed, long thin triangles cut across only."""
    import trimesh

    V, F = [*np.asarray(mesh.vertices, float)], np.asarray(mesh.faces).copy()
    while True:
        E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
        P = np.asarray(V)
        length = np.linalg.norm(P[E[:, 0]] - P[E[:, 1]], axis=1)
        k = int(np.argmax(length))
        if length[k] <= longest:
            return tidy(trimesh.Trimesh(np.asarray(V), F, process=False))
        a, b = E[k]
        V.append(0.5 * (P[a] + P[b]))
        m, new = len(V) - 1, []
        for face in F:
            i = [j for j in range(3) if {face[j], face[(j + 1) % 3]} == {a, b}]
            if not i:
                new.append(face)
                continue
            p, q, r = face[i[0]], face[(i[0] + 1) % 3], face[(i[0] + 2) % 3]
            new += [(p, m, r), (m, q, r)]
        F = np.asarray(new)


def flap_profile() -> np.ndarray:
    """The flap's cross-section (x, z), anticlockwise seen from -y: the plate on a half cylinder about the hinge."""
    arc = np.linspace(np.pi, 2 * np.pi, SECTIONS // 2 + 1)
    top = FLAP_WATER + FREEBOARD
    return densified(np.vstack([np.column_stack([np.cos(arc), -3.5 + np.sin(arc)]), [(1.0, top), (-1.0, top)]]))


def prism(profile: np.ndarray, y0: float, y1: float):
    """A closed prism of a convex (x, z) profile from y0 to y1, a ring every LONGEST at most (caps fanned from the
    profile's centroid)."""
    ring = np.column_stack([profile[:, 0], np.zeros(len(profile)), profile[:, 1]])
    return ring_mesh([ring + (0.0, y, 0.0) for y in stations(y0, y1)])


def densified(profile: np.ndarray) -> np.ndarray:
    """The closed outline with points no more than LONGEST apart along each side."""
    out = []
    for p, q in zip(profile, np.roll(profile, -1, axis=0)):
        out += [p + s * (q - p) for s in stations(0.0, 1.0, LONGEST / max(np.linalg.norm(q - p), 1e-12))[:-1]]
    return np.asarray(out)


def flap():
    """The flap, in its own frame: one prism 21 m wide less the 2 m gap over the end node, under the bridge."""
    import trimesh

    gap = box((-2, -1, -5), (2, 1, FLAP_WATER + FREEBOARD - BRIDGE))
    return split_long_edges(tidy(trimesh.boolean.difference([prism(flap_profile(), -10.5, 10.5), gap], engine="manifold")))


def report(name: str, mesh, water: float) -> None:
    """Print the mesh's measures; `water`: the water line's z in the mesh's frame."""
    from sim.bodies.surface import clip_triangles

    T = np.asarray(mesh.vertices)[mesh.faces] - (0, 0, water)
    W, _ = clip_triangles(T, T[:, :, 2])
    cross = np.cross(W[:, 1] - W[:, 0], W[:, 2] - W[:, 0])
    submerged = np.einsum("ki,ki->", W.mean(axis=1), cross) / 6  # the lid at z = 0 adds nothing
    waterplane = -cross[:, 2].sum() / 2
    lo, hi = np.round(mesh.bounds, 3)
    print(
        f"{name}: {len(mesh.faces)} triangles, volume {mesh.volume:.3f} m^3, submerged {submerged:.3f} m^3, "
        f"water plane {waterplane:.3f} m^2, area {mesh.area:.3f} m^2, bounds {lo.tolist()} .. {hi.tolist()}, "
        f"watertight {mesh.is_watertight}, winding consistent {mesh.is_winding_consistent}, bodies {mesh.body_count}"
    )


def main() -> None:
    base_mesh = base()
    base_mesh.apply_translation((0.0, 0.0, BASE_Z))
    for name, mesh, water in (("f3of_base", base_mesh, 0.0), ("f3of_flap", flap(), FLAP_WATER)):
        mesh.export(MESHES / f"{name}.stl")
        report(name, mesh, water)


if __name__ == "__main__":
    main()

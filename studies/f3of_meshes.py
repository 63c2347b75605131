"""The F3OF meshes (assets/meshes/f3of_base.stl, f3of_flap.stl): a floating three-body oscillating flap platform.

Dimensions measured from SEA-Stack's Meshmagick panel meshes (commit 4d1eae6453f0cd775ab3184d579ce7d943dbfda7,
data/demos/run_seastack/f3of/assets/geometry/base.obj and flap.obj, MIT licence). Those are open, wetted-only
panel meshes (the faces where base and flap touch are left out), so here each body is rebuilt from primitives
as one closed surface (manifold3d booleans). Base frame: origin at its centre of mass, 9 m below the water line.

    part                 centre (base frame)            size
    4 corner columns     x, y = +-12.5                  octagons r 1.5 m (circumscribed), z -3 .. 9 (water line)
    4 corner boxes       x, y = +-12.5                  3 x 3 x 2 m (z -1 .. 1), a 2 m wide, 0.5 m stub (y +-10.5 .. +-11) towards the flap
    6 node boxes         x = +-4; y = 0, +-12.5          2 x 2 x 2 m
    2 end nodes          x = +-12.5, y = 0               2 x 2 x 2 m (between the flap's two halves)
    pontoons, along x    y = 0, +-12.5; z = 0            octagons r 1 m, node to node
    pontoons, along y    x = +-4; z = 0                  octagons r 1 m, node to node
    flap (each of 2)     its hinge at x = +-12.5, z = 0  two plates 2 m thick, y +-1 .. +-10.5, from the hinge axis to 9 m
                                                        above it (the water line), on a half cylinder r 1 m about the hinge

The flap's frame (flap.obj's) has its origin at its centre of mass, 3.5 m above the hinge: plates z -3.5 .. 5.5,
bottom z -4.5. The base has no pontoon along the hinges: the flap's half cylinders take its place.

Choices: cylinders have SECTIONS sides; the base's have the radius that keeps the octagon's cross-section
area (0.954 of it), so volume and water-plane area are the OBJ's; the flap's half cylinder keeps r = 1 m (flush
with the plate), 0.7 % more volume. What pierces the surface (columns, flap) goes FREEBOARD above it, closed.
The flap's two halves are joined by a BRIDGE above the water (the gap under it is the end node's), so it is one
piece. Submerged volumes 672.9 and 371.5 m^3 (OBJ 672.9 and 368.9), water planes 25.456 and 38.0 m^2 (both the OBJ's).

Frames: f3of_base.stl in the world frame at rest (base.obj + (0, 0, -9): water line z = 0); f3of_flap.stl in the
flap's own frame (flap.obj's: origin at its centre of mass, water line z = 5.5, hinge axis y at z = -3.5); place
it at (+-12.5, 0, -5.5). Run: python -m studies.f3of_meshes (writes the two files, prints their measures).
"""

from pathlib import Path

import numpy as np

MESHES = Path(__file__).resolve().parent.parent / "assets" / "meshes"
FREEBOARD = 2.0  # m above the water line for what pierces it
BRIDGE = 1.0  # m: thickness of the flap's top bridge, under its top (FREEBOARD - BRIDGE above the water)
SECTIONS = 24
BASE_Z = -9.0  # the base's centre of mass (world z), 9 m below the water line
FLAP_WATER = 5.5  # the water line in the flap's frame


def equal_area(r_octagon: float) -> float:
    """The radius of a SECTIONS-gon with the area of an octagon of circumscribed radius `r_octagon`."""
    return r_octagon * np.sqrt(8 * np.sin(np.pi / 4) / (SECTIONS * np.sin(2 * np.pi / SECTIONS)))


def box(lo, hi):
    import trimesh

    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return trimesh.creation.box(extents=hi - lo, transform=trimesh.transformations.translation_matrix((lo + hi) / 2))


def cylinder(a, b, r: float):
    """A SECTIONS-gon prism of radius r from point a to point b."""
    import trimesh

    return trimesh.creation.cylinder(radius=r, segment=np.array([a, b], float), sections=SECTIONS)


def union(parts):
    import trimesh

    mesh = trimesh.boolean.union(parts, engine="manifold")
    return tidy(mesh)


def tidy(mesh):
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
        parts.append(box((12.5 * sx - 1, -1, -1), (12.5 * sx + 1, 1, 1)))  # end node
        parts.append(cylinder((4 * sx, -12.5, 0), (4 * sx, 12.5, 0), r_pon))  # pontoon along y
        for y in (-12.5, 0, 12.5):
            parts.append(box((4 * sx - 1, y - 1, -1), (4 * sx + 1, y + 1, 1)))  # node box
        for sy in (-1, 1):
            x, y = 12.5 * sx, 12.5 * sy
            parts.append(cylinder((x, y, -3), (x, y, top), r_col))  # column
            parts.append(box((x - 1.5, y - 1.5, -1), (x + 1.5, y + 1.5, 1)))  # corner box
            parts.append(box((x - 1, min(10.5 * sy, y), -1), (x + 1, max(10.5 * sy, y), 1)))  # its stub
    for y in (-12.5, 0, 12.5):
        parts.append(cylinder((-12.5, y, 0), (12.5, y, 0), r_pon))  # pontoon along x
    return union(parts)


def flap_profile() -> np.ndarray:
    """The flap's cross-section (x, z), anticlockwise seen from -y: the plate on a half cylinder about the hinge."""
    arc = np.linspace(np.pi, 2 * np.pi, SECTIONS // 2 + 1)
    top = FLAP_WATER + FREEBOARD
    return np.vstack([np.column_stack([np.cos(arc), -3.5 + np.sin(arc)]), [(1.0, top), (-1.0, top)]])


def prism(profile: np.ndarray, y0: float, y1: float):
    """A closed prism of a convex (x, z) profile from y0 to y1 (caps fanned from the profile's centroid)."""
    import trimesh

    n = len(profile)
    centre = profile.mean(axis=0)
    ring = [np.column_stack([profile[:, 0], np.full(n, y), profile[:, 1]]) for y in (y0, y1)]
    ends = [(centre[0], y, centre[1]) for y in (y0, y1)]
    vertices = np.vstack([ring[0], ring[1], ends])
    k = np.arange(n)
    faces = np.vstack(
        [
            np.column_stack([k, (k + 1) % n, n + (k + 1) % n]),
            np.column_stack([k, n + (k + 1) % n, n + k]),
            np.column_stack([np.full(n, 2 * n), (k + 1) % n, k]),
            np.column_stack([np.full(n, 2 * n + 1), n + k, n + (k + 1) % n]),
        ]
    )
    return tidy(trimesh.Trimesh(vertices, faces, process=False))


def flap():
    """The flap, in its own frame: one prism 21 m wide less the 2 m gap over the end node, under the bridge."""
    import trimesh

    gap = box((-2, -1, -5), (2, 1, FLAP_WATER + FREEBOARD - BRIDGE))
    return tidy(trimesh.boolean.difference([prism(flap_profile(), -10.5, 10.5), gap], engine="manifold"))


def report(name: str, mesh, water: float) -> None:
    """Print the mesh's measures; `water`: the water line's z in the mesh's frame."""
    from sim.surface import clip_triangles

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
    import trimesh

    meshes = {"f3of_base": (base(), BASE_Z), "f3of_flap": (flap(), 0.0)}
    meshes["f3of_base"][0].apply_transform(trimesh.transformations.translation_matrix((0, 0, BASE_Z)))
    for name, (mesh, _) in meshes.items():
        mesh.export(MESHES / f"{name}.stl")
        report(name, mesh, 0.0 if name == "f3of_base" else FLAP_WATER)


if __name__ == "__main__":
    main()

"""The `rm3` preset's meshes (assets/meshes/rm3_float.stl, rm3_spar.stl): an RM3-like two-body point absorber.

WEC-Sim's RM3 (Reference Model 3, Neary et al. 2014): a float 20 m across around a spar 6 m across that ends in a
heave plate 30 m across; both at hydrostatic equilibrium (WEC-Sim's mass = 'equilibrium'): float 727.01 t,
spar and plate 878.30 t. Here, as surfaces of revolution (24 sections, points every 3 m along the outline): the float an annulus 20 m across with a
10 m hole (a 2 m gap around the spar; the water in it sloshes, with the
float's heave added mass negative near 1.39 rad/s: the preset's bem_min_period keeps the solve below that), 3.1 m draft and 1.7 m freeboard (its area centroid, the centre of mass here, at z = -0.7 m: WEC-Sim's
-0.72 m); the spar 6 m across from 6 m above the water to 21 m below it, on a plate 30 m across and 3 m thick
(RM3's is thin; Capytaine's constant panels, 3.75 m here, cannot resolve a plate much thinner than they are:
a 0.4 m plate broke the reciprocity of the bodies' coupling damping by 12 % and its passivity by 15 %, a 3 m one by 6 %
and 0). Displacements 722 t and 2683 t (RM3: 727 t and 878 t; the spar's added mass, about 9000 t, is the plate's). Run: python -m studies.rm3_meshes (writes the two files, prints the masses).
"""

from pathlib import Path

import numpy as np

MESHES = Path(__file__).resolve().parent.parent / "assets" / "meshes"


def revolved(profile, sections: int = 24):
    """A closed surface of revolution about z of an (r, z) profile."""
    import trimesh

    mesh = trimesh.creation.revolve(np.asarray(profile, float), sections=sections)
    mesh.merge_vertices()
    mesh.update_faces(mesh.nondegenerate_faces())
    mesh.remove_unreferenced_vertices()
    if mesh.volume < 0:
        mesh.invert()
    assert mesh.is_watertight
    return mesh


def _outline(corners, step: float = 3.0) -> np.ndarray:
    """The profile's corners with points every `step` metres between them (panels of even size, not long fans)."""
    points = [np.asarray(corners[0], float)]
    for a, b in zip(corners[:-1], corners[1:]):
        a, b = np.asarray(a, float), np.asarray(b, float)
        n = max(1, int(np.ceil(np.linalg.norm(b - a) / step)))
        points += [a + (b - a) * k / n for k in range(1, n + 1)]
    return np.array(points)


def main() -> None:
    from sim.hydro.bem import wet_mesh

    parts = {
        "rm3_float": revolved(_outline([(5.0, -3.1), (10.0, -3.1), (10.0, 1.7), (5.0, 1.7), (5.0, -3.1)])),
        "rm3_spar": revolved(_outline([(0.0, -24.0), (15.0, -24.0), (15.0, -21.0), (3.0, -21.0), (3.0, 6.0), (0.0, 6.0)])),
    }
    for name, mesh in parts.items():
        mesh.export(MESHES / f"{name}.stl")
        T = np.asarray(mesh.vertices)[mesh.faces]
        area = 0.5 * np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)
        centroid = (area[:, None] * T.mean(axis=1)).sum(axis=0) / area.sum()
        wv, wf = wet_mesh(mesh.vertices, mesh.faces, 100.0)
        W = wv[wf]
        displaced = -float(np.einsum("ki,ki->k", W.mean(axis=1), np.cross(W[:, 1] - W[:, 0], W[:, 2] - W[:, 0]))[:, None].sum()) / 6
        print(
            f"{name}: {len(mesh.faces)} triangles, centre of mass (area centroid) z = {centroid[2]:.4f} m, displaced {abs(displaced):.3f} m^3"
        )


if __name__ == "__main__":
    main()

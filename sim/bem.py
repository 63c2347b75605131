"""Added mass and radiation damping of a floating body from the boundary-element solver Capytaine.

Linear potential flow about the rest pose: the body's mesh, refined to panels of a chosen size and
clipped at the still water line of its equilibrium, radiates in each of its six rigid-body modes
(surge, sway, heave, roll, pitch, yaw about the centre of mass, axes of the world at rest). For each
frequency omega Capytaine gives the 6x6 added mass A(omega) and radiation damping B(omega), and for
omega -> infinity A_inf. A lid on the water plane inside the body removes the irregular frequencies.

Solving takes seconds to a minute, so results are kept on disk, keyed by everything they depend on
(the clipped mesh, rho, g, depth and the frequency grid): first in the shipped `assets/coefficients/`,
then in the user's cache. Capytaine is an optional extra (`pip install -e ".[bem]"`); the shipped
files let the presets run without it.
"""

from __future__ import annotations

import hashlib
import math
import os
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import ConfigError

DOFS = ("Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw")
SHIPPED = Path(__file__).resolve().parent.parent / "assets" / "coefficients"


@dataclass(frozen=True, eq=False)
class Coefficients:
    """Radiation coefficients of one body at rest, world axes at the centre of mass, SI units."""

    omega: np.ndarray
    """(n,) frequencies, rad/s, increasing."""
    added_mass: np.ndarray
    """(n, 6, 6) A(omega): kg, kg m, kg m^2."""
    damping: np.ndarray
    """(n, 6, 6) B(omega): kg/s, kg m/s, kg m^2/s."""
    added_mass_inf: np.ndarray
    """(6, 6) A at infinite frequency."""
    rho: float
    depth: float
    """Water depth, m (inf: deep water)."""
    panels: int
    """How many panels the wet surface had."""

    def save(self, path: Path) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(".tmp.npz")
        np.savez_compressed(tmp, omega=self.omega, added_mass=self.added_mass, damping=self.damping, added_mass_inf=self.added_mass_inf,
                            rho=self.rho, depth=self.depth, panels=self.panels)  # fmt: skip
        os.replace(tmp, path)  # never a half-written cache file

    @classmethod
    def load(cls, path: Path) -> Coefficients:
        with np.load(path) as f:
            return cls(f["omega"], f["added_mass"], f["damping"], f["added_mass_inf"], float(f["rho"]), float(f["depth"]), int(f["panels"]))


def default_frequencies(length: float, g: float = 9.81, n: int = 60) -> np.ndarray:
    """A grid for the radiation kernel of a body of size `length`, uniform in omega: from where its
    waves are 100 times longer than it to where they are half as long (the default panels, length/8,
    still resolve them four times; the damping of heave and of the rotations has died out there)."""
    lo, hi = math.sqrt(2 * math.pi * g / (100 * length)), math.sqrt(2 * math.pi * g / (0.5 * length))
    return np.linspace(lo, hi, n)


def wet_mesh(vertices: np.ndarray, faces: np.ndarray, panel: float) -> tuple[np.ndarray, np.ndarray]:
    """The part of a closed triangle mesh (world frame, at rest) under z = 0, refined so that no edge
    is longer than `panel` (trimesh's subdivision, then floatsim's own exact clipping at the water line)."""
    import trimesh

    from .surface import clip_triangles

    v, f = trimesh.remesh.subdivide_to_size(np.asarray(vertices, float), np.asarray(faces), max_edge=panel)
    T, _ = clip_triangles(v[f], v[f][:, :, 2])
    area = 0.5 * np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)
    T = T[area > 1e-6 * panel * panel]  # slivers where a vertex sits on the water line
    return T.reshape(-1, 3), np.arange(3 * len(T)).reshape(-1, 3)


def cache_key(vertices: np.ndarray, faces: np.ndarray, rho: float, g: float, depth: float, omega: np.ndarray) -> str:
    h = hashlib.sha256()
    for a in (np.round(np.asarray(vertices, float), 9), np.asarray(faces, np.int64), np.array([rho, g, depth]), np.asarray(omega, float)):
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()[:20]


def user_cache() -> Path:
    root = os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache")
    return Path(root) / "floatsim" / "bem"


def radiation_coefficients(vertices: np.ndarray, faces: np.ndarray, rho: float = 1000.0, g: float = 9.81, depth: float = math.inf,
                           omega: np.ndarray | None = None, panel: float | None = None, progress: bool = True) -> Coefficients:  # fmt: skip
    """A(omega), B(omega), A_inf of the closed mesh (world frame, at rest, centre of mass at the
    origin) floating in water of density rho: from the shipped files or the user's cache when they
    hold this case, else solved by Capytaine (and cached)."""
    vertices = np.asarray(vertices, float)
    size = float(np.ptp(vertices, axis=0).max())
    panel = panel or size / 8
    wv, wf = wet_mesh(vertices, faces, panel)
    omega = default_frequencies(size, g) if omega is None else np.asarray(omega, float)
    key = cache_key(wv, wf, rho, g, depth, omega)
    for folder in (SHIPPED, user_cache()):
        path = folder / f"{key}.npz"
        if path.exists():
            try:
                return Coefficients.load(path)
            except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile):  # damaged: solve again (and rewrite it)
                continue
    result = solve(wv, wf, rho, g, depth, omega, progress)
    result.save(user_cache() / f"{key}.npz")
    return result


def solve(vertices: np.ndarray, faces: np.ndarray, rho: float, g: float, depth: float, omega: np.ndarray, progress: bool = True) -> Coefficients:
    """Capytaine on the wet mesh (vertices and triangles under z = 0): radiation in the six rigid
    modes about the origin at every omega and at infinity, with a lid against irregular frequencies."""
    try:
        import capytaine as cpt
    except ImportError:
        raise ConfigError("radiation = 'bem' needs the boundary-element solver Capytaine for this body: pip install -e \".[bem]\"") from None
    import logging

    logging.getLogger("capytaine").setLevel(logging.ERROR)  # its resolution warnings concern the top of the grid, where B has died out
    mesh = cpt.Mesh(vertices, faces)
    lid = mesh.generate_lid(z=-0.01 * float(np.ptp(vertices[:, 2])))  # just below the water line, as Capytaine advises
    body = cpt.FloatingBody(mesh=mesh, lid_mesh=lid, dofs=cpt.rigid_body_dofs(rotation_center=(0.0, 0.0, 0.0)), center_of_mass=(0.0, 0.0, 0.0))
    solver = cpt.BEMSolver()
    water = {"rho": rho, "g": g, "water_depth": depth}
    freqs = [*omega, math.inf]
    problems = [cpt.RadiationProblem(body=body, radiating_dof=dof, omega=w, **water) for w in freqs for dof in DOFS]
    results = solver.solve_all(problems, progress_bar=progress)
    A = np.zeros((len(freqs), 6, 6))
    B = np.zeros((len(freqs), 6, 6))
    for r in results:
        i, j = freqs.index(r.omega), DOFS.index(r.radiating_dof)
        for k, name in enumerate(DOFS):
            A[i, k, j] = r.added_masses[name]
            B[i, k, j] = r.radiation_dampings[name]
    return Coefficients(np.asarray(omega, float), A[:-1], B[:-1], A[-1], float(rho), float(depth), int(mesh.nb_faces))

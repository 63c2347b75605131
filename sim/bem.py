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
import sys
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import ConfigError

DOFS = ("Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw")
SHIPPED = Path(__file__).resolve().parent.parent / "assets" / "coefficients"
CACHE_ENV = "FLOATSIM_BEM_CACHE"
"""A folder to cache solved coefficients in, instead of $XDG_CACHE_HOME/floatsim/bem (~/.cache/floatsim/bem)."""
UNREADABLE = (OSError, ValueError, KeyError, EOFError, TypeError, AttributeError, zipfile.BadZipFile)


class MissingSolver(ConfigError):
    """Capytaine is not installed."""


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
        """Written to a new temporary file beside it (mkstemp: O_EXCL, so never through a link someone placed),
        then renamed over it: never a half-written cache file."""
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=".tmp.npz")
        try:
            with os.fdopen(fd, "wb") as f:
                np.savez_compressed(f, omega=self.omega, added_mass=self.added_mass, damping=self.damping, added_mass_inf=self.added_mass_inf,
                                    rho=self.rho, depth=self.depth, panels=self.panels)  # fmt: skip
            os.replace(tmp, path)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise

    @classmethod
    def load(cls, path: Path) -> Coefficients:
        """The coefficients in `path`, checked (ValueError saying what is wrong with the file)."""
        try:
            with np.load(path) as f:
                c = cls(f["omega"], f["added_mass"], f["damping"], f["added_mass_inf"], float(f["rho"]), float(f["depth"]), int(f["panels"]))
        except UNREADABLE as e:
            raise ValueError(f"not a coefficients file ({type(e).__name__})") from None
        check(c)
        return c


def check(c: Coefficients) -> None:
    """ValueError unless `c` can be used: shapes that agree with the frequency grid (6x6 per frequency), finite
    real numbers, frequencies positive and increasing, added mass with a positive diagonal (translations
    strictly; rotations down to -1e-4 of the largest diagonal entry, a sphere's numerical noise), and damping
    symmetric (to 10 % of each frequency's largest entry) and positive semi-definite (to 2 %): passive, the
    body only gives energy to the waves. The shipped files pass with room to spare (3 % and 0.2 % at worst)."""
    w, A, B, Ainf = (np.asarray(a) for a in (c.omega, c.added_mass, c.damping, c.added_mass_inf))
    if w.ndim != 1 or len(w) < 3:
        raise ValueError(f"{w.size} frequencies, need at least 3")
    n = len(w)
    if A.shape != (n, 6, 6) or B.shape != (n, 6, 6) or Ainf.shape != (6, 6):
        raise ValueError(f"added mass {A.shape}, damping {B.shape}, A_inf {Ainf.shape}: need ({n}, 6, 6) for {n} frequencies and (6, 6)")
    if not all(np.isrealobj(a) and a.dtype.kind in "fiu" for a in (w, A, B, Ainf)):
        raise ValueError("not arrays of real numbers")
    if not all(np.isfinite(a).all() for a in (w, A, B, Ainf)) or not (math.isfinite(c.rho) and c.rho > 0 and c.depth > 0):
        raise ValueError("numbers that are not finite (or rho, depth not positive)")
    if w[0] <= 0 or np.any(np.diff(w) <= 0):
        raise ValueError("frequencies not positive and increasing")
    diag = np.concatenate([np.diagonal(A, axis1=1, axis2=2), np.diag(Ainf)[None]])
    if diag[:, :3].min() <= 0 or diag[:, 3:].min() < -1e-4 * diag.max():
        raise ValueError(f"added mass with a diagonal entry <= 0 ({diag.min():.3g})")
    scale = np.abs(B).max(axis=(1, 2))
    if np.any(np.abs(B - B.transpose(0, 2, 1)).max(axis=(1, 2)) > 0.1 * scale):
        raise ValueError("damping matrices not symmetric")
    if np.any(np.linalg.eigvalsh(0.5 * (B + B.transpose(0, 2, 1))).min(axis=1) < -0.02 * scale):
        raise ValueError("damping not positive semi-definite (the body would draw energy from the waves)")


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
    if os.environ.get(CACHE_ENV):
        return Path(os.environ[CACHE_ENV])
    root = os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache")
    return Path(root) / "floatsim" / "bem"


def note(text: str) -> None:
    print(f"floatsim: {text}", file=sys.stderr, flush=True)


def radiation_coefficients(vertices: np.ndarray, faces: np.ndarray, rho: float = 1000.0, g: float = 9.81, depth: float = math.inf,
                           omega: np.ndarray | None = None, panel: float | None = None, progress: bool = True) -> Coefficients:  # fmt: skip
    """A(omega), B(omega), A_inf of the closed mesh (world frame, at rest, centre of mass at the
    origin) floating in water of density rho: from the shipped files or the user's cache when they
    hold this case, else solved by Capytaine (and cached). A file that fails `check` counts as absent, with a note."""
    vertices = np.asarray(vertices, float)
    size = float(np.ptp(vertices, axis=0).max())
    panel = panel or size / 8
    wv, wf = wet_mesh(vertices, faces, panel)
    omega = default_frequencies(size, g) if omega is None else np.asarray(omega, float)
    key = cache_key(wv, wf, rho, g, depth, omega)
    cached = user_cache() / f"{key}.npz"
    bad = []
    for path in (SHIPPED / f"{key}.npz", cached):
        if path.exists():
            try:
                return Coefficients.load(path)
            except ValueError as e:
                bad.append(f"{path} is not usable ({e})")
    try:
        if bad:
            import capytaine  # noqa: F401  (said before a solve of minutes starts, or instead of it)

            note(f"note: {bad[0]}: solving again")
        result = solve(wv, wf, rho, g, depth, omega, progress)
    except (ImportError, MissingSolver):
        raise MissingSolver(f"radiation = 'bem': {bad[0]} and solving again needs Capytaine: pip install -e \".[bem]\"" if bad else
                            f"radiation = 'bem' needs the boundary-element solver Capytaine for this body (or its coefficients in {cached}): "
                            'pip install -e ".[bem]"') from None  # fmt: skip
    keep(result, cached)
    return result


def keep(result: Coefficients, path: Path) -> None:
    """Cache a fresh solve; one that fails the check, or a cache that cannot be written, costs a warning, not the run."""
    try:
        check(result)
    except ValueError as e:
        note(f"warning: Capytaine's coefficients for this body fail the check ({e}): used for this run, not cached")
        return
    try:
        result.save(path)
    except OSError as e:
        note(f"warning: cannot cache the radiation coefficients in {path.parent} ({e.strerror or e}): this run goes on, the next one solves again")


def solve(vertices: np.ndarray, faces: np.ndarray, rho: float, g: float, depth: float, omega: np.ndarray, progress: bool = True) -> Coefficients:
    """Capytaine on the wet mesh (vertices and triangles under z = 0): radiation in the six rigid
    modes about the origin at every omega and at infinity, with a lid against irregular frequencies."""
    try:
        import capytaine as cpt
    except ImportError:
        raise MissingSolver("radiation = 'bem' needs the boundary-element solver Capytaine for this body: pip install -e \".[bem]\"") from None
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

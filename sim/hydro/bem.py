"""Added mass and radiation damping of a floating body from the boundary-element solver Capytaine.

Linear potential flow about the rest pose: the body's mesh, refined to panels of a chosen size and
clipped at the still water line of its equilibrium, radiates in each of its six rigid-body modes
(surge, sway, heave, roll, pitch, yaw about the centre of mass, axes of the world at rest). For each
frequency omega Capytaine gives the 6x6 added mass A(omega) and radiation damping B(omega), and for
omega -> infinity A_inf. A lid on the water plane inside the body removes the irregular frequencies.
Asked for, the same solve gives the wave excitation of the body held at rest: for an incident wave
of unit amplitude heading beta (elevation Re{e^(i (k (x cos beta + y sin beta) - omega t))}), the
complex Froude-Krylov force (the undisturbed wave's pressure) and diffraction force (the scattered
wave's), 6 dofs, on a grid of headings around the circle; and the far field of each wave the body
sends out (its Kochin function, for the mean drift force: sim/hydro/drift.py).

Solving takes seconds to a minute, so results are kept on disk, keyed by everything they depend on
(the clipped mesh, rho, g, depth and the frequency grid): first in the shipped `assets/coefficients/`,
then in the user's cache. Capytaine is an optional extra (`pip install -e ".[bem]"`); the shipped
files let the presets run without it.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import math
import os
import sys
import tempfile
import threading
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sim import limits
from sim.bodies.surface import clip_triangles
from sim.errors import ConfigError
from sim.forked import in_child
from sim.hydro.lid import make_lid

DOFS = ("Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw")
SHIPPED = Path(__file__).resolve().parents[2] / "assets" / "coefficients"
CACHE_ENV = "FLOATSIM_BEM_CACHE"
"""A folder to cache solved coefficients in, instead of $XDG_CACHE_HOME/floatsim/bem (~/.cache/floatsim/bem)."""
UNREADABLE = (OSError, ValueError, KeyError, EOFError, TypeError, AttributeError, zipfile.BadZipFile)


class MissingSolver(ConfigError):
    """Capytaine is not installed."""


_thread = threading.local()


@contextlib.contextmanager
def no_solves(why: str):
    """On this thread, inside this block, a case absent from the shipped files and the cache is refused (a ConfigError
    saying `why`) instead of solved: a live viewer's simulation thread must not stop for the minute a solve takes."""
    _thread.no_solve = why
    try:
        yield
    finally:
        _thread.no_solve = None


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
    center: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))
    """(3,) the point the rotations are about (the centre of mass at rest), world frame, m; several bodies: (k, 3),
    one per body (their dofs follow one another: 6 per body, the matrices 6k x 6k)."""
    headings: np.ndarray | None = None
    """(m,) wave headings beta of the excitation, rad, increasing in [0, 2 pi); None: not solved."""
    diffraction: np.ndarray | None = None
    """(n, m, 6) complex diffraction force per unit wave amplitude: N/m, N m/m (time factor e^(-i omega t))."""
    froude_krylov: np.ndarray | None = None
    """(n, m, 6) complex Froude-Krylov force per unit wave amplitude, likewise."""
    kochin_diffraction: np.ndarray | None = None
    """(n, m, KOCHIN_ANGLES) complex: the Kochin function H(theta) of the wave scattered by the body held still in each
    unit wave (Capytaine's: (1/4 pi) of the sources times e^(k z - i k (x cos theta + y sin theta)) over the hull and
    lid, about the world's origin), at theta = 2 pi j / KOCHIN_ANGLES. None: not solved."""
    kochin_radiation: np.ndarray | None = None
    """(n, 6k, KOCHIN_ANGLES) complex: likewise of the wave each dof radiates moving at unit velocity amplitude
    (Capytaine's radiation problem: the body's motion per unit wave, times these, adds its share)."""
    mean_drift: np.ndarray | None = None
    """(n, m, 3) real: the mean drift (F_x, F_y, M_z about the world's origin) per unit wave amplitude squared, N/m²
    and N m/m², read from a file (WAMIT's .8 or .9: its bodies moving as its run had them), at omega and headings; None:
    from the far field (drift.mean_drift). Not kept in the cache's files."""

    @property
    def has_excitation(self) -> bool:
        return self.headings is not None

    @property
    def has_far_field(self) -> bool:
        return self.kochin_diffraction is not None

    def save(self, path: Path) -> None:
        """Written to a new temporary file beside it (mkstemp: O_EXCL, so never through a link someone placed),
        then renamed over it: never a half-written cache file. Its sha256 goes beside it (KEY.sha256, as
        `sha256sum` writes it), checked when the cache is read (`verify_digest`)."""
        excitation = (
            {"headings": self.headings, "diffraction": self.diffraction, "froude_krylov": self.froude_krylov} if self.has_excitation else {}
        )
        if self.has_far_field:  # single precision: 1e-7 is far below the solve's own error, and halves the shipped files
            excitation |= {name: getattr(self, name).astype(np.complex64) for name in FAR_FIELD}

        def arrays(f) -> None:
            np.savez_compressed(f, omega=self.omega, added_mass=self.added_mass, damping=self.damping, added_mass_inf=self.added_mass_inf,
                                rho=self.rho, depth=self.depth, panels=self.panels, center=self.center, **excitation)  # fmt: skip

        digest = _replace(path, ".tmp.npz", arrays)
        _replace(digest_path(path), ".tmp", lambda f: f.write(f"{digest}  {path.name}\n".encode()))

    @classmethod
    def load(cls, path: Path) -> Coefficients:
        """The coefficients in `path`, checked (ValueError saying what is wrong with the file)."""
        try:
            with np.load(path) as f:
                extra = {key: f[key] for key in ("center", "headings", "diffraction", "froude_krylov") if key in f.files}
                extra |= {key: f[key].astype(complex) for key in FAR_FIELD if key in f.files}
                c = cls(
                    f["omega"],
                    f["added_mass"],
                    f["damping"],
                    f["added_mass_inf"],
                    float(f["rho"]),
                    float(f["depth"]),
                    int(f["panels"]),
                    **extra,
                )
        except UNREADABLE as e:
            raise ValueError(f"not a coefficients file ({type(e).__name__})") from None
        check(c)
        return c


def _replace(path: Path, suffix: str, write) -> str:
    """`write(file)` into a new temporary beside `path` (mkstemp: O_EXCL, never through a link), renamed over `path`
    once whole; the sha256 of what was written."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=suffix)
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
        digest = file_sha256(Path(tmp))
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return digest


def file_sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def digest_path(path: Path) -> Path:
    """Where a cached file's sha256 is recorded: beside it, under its key (KEY.sha256)."""
    return path.with_suffix(".sha256")


def verify_digest(path: Path) -> None:
    """ValueError unless `path` (a cached file) has the sha256 recorded beside it when it was written: plausible
    numbers edited since (a damping 100 times too large passes `check`) are refused all the same."""
    record = digest_path(path)
    try:
        recorded = record.read_text().split()[0]
    except (OSError, UnicodeDecodeError, IndexError):
        raise ValueError(f"no sha256 recorded beside it in {record.name}: cached by an older floatsim, or the record was lost") from None
    try:
        found = file_sha256(path)
    except OSError as e:
        raise ValueError(f"cannot read it ({e.strerror})") from None
    if found != recorded:
        raise ValueError(f"its content changed since it was cached: its sha256 is not the one recorded in {record.name}")


def check(c: Coefficients) -> None:
    """ValueError unless `c` can be used: shapes that agree with the frequency grid (6x6 per frequency), finite
    real numbers, frequencies positive and increasing, added mass with a positive diagonal (translations
    strictly; rotations down to -1e-4 of the largest diagonal entry, a sphere's numerical noise), and damping
    symmetric (to 10 % of each frequency's largest entry) and positive semi-definite (to 2 %): passive, the
    body only gives energy to the waves. The shipped files pass with room to spare (3 % and 0.2 % at worst)."""
    w, A, B, Ainf = (np.asarray(a) for a in (c.omega, c.added_mass, c.damping, c.added_mass_inf))
    if w.ndim != 1 or len(w) < 3:
        raise ValueError(f"{w.size} frequencies, need at least 3")
    n, d = len(w), (A.shape[1] if A.ndim == 3 else 0)
    if d < 6 or d % 6 or A.shape != (n, d, d) or B.shape != (n, d, d) or Ainf.shape != (d, d):
        raise ValueError(f"added mass {A.shape}, damping {B.shape}, A_inf {Ainf.shape}: need ({n}, 6k, 6k) for {n} frequencies and (6k, 6k), "
                         "k bodies")  # fmt: skip
    if not all(np.isrealobj(a) and a.dtype.kind in "fiu" for a in (w, A, B, Ainf)):
        raise ValueError("not arrays of real numbers")
    if not all(np.isfinite(a).all() for a in (w, A, B, Ainf)) or not (math.isfinite(c.rho) and c.rho > 0 and c.depth > 0):
        raise ValueError("numbers that are not finite (or rho, depth not positive)")
    if w[0] <= 0 or np.any(np.diff(w) <= 0):
        raise ValueError("frequencies not positive and increasing")
    diag = np.concatenate([np.diagonal(A, axis1=1, axis2=2), np.diag(Ainf)[None]]).reshape(n + 1, d // 6, 6)
    if diag[..., :3].min() <= 0 or diag[..., 3:].min() < -1e-4 * diag.max():
        raise ValueError(f"added mass with a diagonal entry <= 0 ({diag.min():.3g})")
    scale = np.abs(B).max(axis=(1, 2))
    if np.any(np.abs(B - B.transpose(0, 2, 1)).max(axis=(1, 2)) > 0.1 * scale):
        raise ValueError("damping matrices not symmetric")
    if np.any(np.linalg.eigvalsh(0.5 * (B + B.transpose(0, 2, 1))).min(axis=1) < -0.02 * scale):
        raise ValueError("damping not positive semi-definite (the body would draw energy from the waves)")
    if np.shape(c.center) not in ((3,), (d // 6, 3)) or not np.isfinite(c.center).all():
        raise ValueError("the centre of rotation is not three finite numbers (per body)")
    if c.headings is not None:
        beta = np.asarray(c.headings)
        if beta.ndim != 1 or not len(beta) or np.any(np.diff(beta) <= 0) or beta[0] < 0 or beta[-1] >= 2 * math.pi:
            raise ValueError("wave headings not increasing in [0, 2 pi)")
        for name in ("diffraction", "froude_krylov"):
            X = np.asarray(getattr(c, name))
            if X.shape != (n, len(beta), d) or X.dtype.kind != "c" or not np.isfinite(X).all():
                raise ValueError(f"{name} force {X.shape}: need finite complex numbers, ({n}, {len(beta)}, {d})")
    if c.kochin_diffraction is not None:
        for name, rows in zip(FAR_FIELD, (len(c.headings) if c.headings is not None else -1, d)):
            H = np.asarray(getattr(c, name))
            if H.shape != (n, rows, KOCHIN_ANGLES) or H.dtype.kind != "c" or not np.isfinite(H).all():
                raise ValueError(f"{name} {np.shape(H)}: need finite complex numbers, ({n}, {rows}, {KOCHIN_ANGLES})")


def passive(A: np.ndarray, B: np.ndarray, length: float) -> tuple[np.ndarray, np.ndarray, float]:
    """(A, B, change): the added mass made symmetric, the damping the nearest symmetric positive semi-definite matrix
    (rotations scaled by the bodies' size, so units weigh alike), and the largest change of B relative to each
    frequency's largest entry. The physical ones are both; coaxial bodies' damping is singular (they radiate the
    same wave pattern), so the solve's small errors break it."""
    d = B.shape[1]
    S = np.diag(np.tile([1.0, 1.0, 1.0, 1.0 / length, 1.0 / length, 1.0 / length], d // 6))
    Bs = S @ (0.5 * (B + B.transpose(0, 2, 1))) @ S
    lam, V = np.linalg.eigh(Bs)
    Si = np.linalg.inv(S)
    fixed = Si @ ((V * np.maximum(lam, 0.0)[:, None, :]) @ V.transpose(0, 2, 1)) @ Si
    change = float((np.abs(fixed - B).max(axis=(1, 2)) / np.maximum(np.abs(B).max(axis=(1, 2)), 1e-300)).max())
    return 0.5 * (A + A.transpose(0, 2, 1)), fixed, change


def default_frequencies(
    length: float, g: float = 9.81, n: int = 60, min_period: float | None = None, lowest: float | None = None
) -> np.ndarray:
    """A grid for the radiation kernel of a body of size `length`, uniform in omega: from where its
    waves are 100 times longer than it to where they are half as long (the default panels, length/8,
    still resolve them four times; the damping of heave and of the rotations has died out there), or
    up to the period `min_period`; down past `lowest` where that is lower (a moored body's slow natural frequency), the
    n points' spacing kept."""
    lo, hi = math.sqrt(2 * math.pi * g / (100 * length)), math.sqrt(2 * math.pi * g / (0.5 * length))
    hi = hi if min_period is None else 2 * math.pi / min_period
    if lowest is not None and 0.0 < lowest < lo:  # as many more points below, at the same spacing (the fit keeps its detail)
        step = (hi - lo) / (n - 1)
        more = min(math.ceil((lo - lowest) / step), math.ceil(lo / step) - 1)  # (never down to zero or below it)
        lo, n = lo - more * (hi - lo) / (n - 1), n + more  # (as the shipped grids were computed, to the last bit)
    return np.linspace(lo, hi, n)


HEADINGS = np.radians(np.arange(0.0, 360.0, 15.0))
"""Wave headings the excitation is solved for (15 degrees apart, interpolated between)."""
KOCHIN_ANGLES = 72
"""Directions the far field is taken at, 5 degrees apart (every heading among them): the drift's integrals over them
are the periodic trapezoid rule, exact for the angular modes under 36 a body of k r up to about 30 sends out."""
FAR_FIELD = ("kochin_diffraction", "kochin_radiation")


LID_DEPTH = 0.01
"""The lid's depth under the water line, as a share of the body's draft (just below it, as Capytaine's examples place it)."""


def panel_size(vertices: np.ndarray, faces: np.ndarray) -> float:
    """The wet mesh's typical panel: its median edge length."""
    T = np.asarray(vertices, float)[np.asarray(faces)]
    return float(np.median(np.linalg.norm(T - np.roll(T, 1, axis=1), axis=2)))


def wet_mesh(vertices: np.ndarray, faces: np.ndarray, panel: float) -> tuple[np.ndarray, np.ndarray]:
    """The part of a closed triangle mesh (world frame, at rest) under z = 0, refined so that no edge
    is longer than `panel` (trimesh's subdivision, then floatsim's own exact clipping at the water line)."""
    import trimesh

    v, f = trimesh.remesh.subdivide_to_size(np.asarray(vertices, float), np.asarray(faces), max_edge=panel)
    T, _ = clip_triangles(v[f], v[f][:, :, 2])
    area = 0.5 * np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)
    T = T[area > 1e-6 * panel * panel]  # slivers where a vertex sits on the water line
    return T.reshape(-1, 3), np.arange(3 * len(T)).reshape(-1, 3)


SOLVER_VERSION = b"lid from the exact section, damping passive for one body too (issue 38)"
"""Part of every solve's key: solves made before these changed are solved again, never read."""


def cache_key(
    vertices: np.ndarray, faces: np.ndarray, rho: float, g: float, depth: float, omega: np.ndarray, center=(0.0, 0.0, 0.0)
) -> str:
    """The solve's inputs hashed, with SOLVER_VERSION (a centre at the origin adds nothing)."""
    h = hashlib.sha256(SOLVER_VERSION)
    center = np.round(np.asarray(center, float), 9) + 0.0  # + 0.0: -0.0 becomes 0.0 (a vertex on the water line may come out either)
    for a in (np.round(np.asarray(vertices, float), 9) + 0.0, np.asarray(faces, np.int64), np.array([rho, g, depth]), np.asarray(omega, float),
              *([center] if center.any() else [])):  # fmt: skip
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
                           omega: np.ndarray | None = None, panel: float | None = None, progress: bool = True, center=(0.0, 0.0, 0.0),
                           excitation: bool = False, far_field: bool = False) -> Coefficients:  # fmt: skip
    """A(omega), B(omega), A_inf of the closed mesh (world frame, at rest) floating in water of density rho,
    rotations about `center` (its centre of mass), and with `excitation` the wave excitation forces too:
    from the shipped files or the user's cache when they hold this case, else solved by Capytaine (and
    cached). A file that fails `check` counts as absent, with a note; one without the excitation asked for is solved again.
    `far_field`: the Kochin functions too (the mean drift force), which come with every excitation solved since issue 42."""
    vertices = np.asarray(vertices, float)
    size = float(np.ptp(vertices, axis=0).max())
    wv, wf = wet_mesh(vertices, faces, panel or size / 8)
    omega = default_frequencies(size, g) if omega is None else np.asarray(omega, float)
    key = cache_key(wv, wf, rho, g, depth, omega, center)
    needs = "far field" if far_field else "excitation" if excitation else ""
    solve_now = lambda: solve(wv, wf, rho, g, depth, omega, progress, center, HEADINGS if needs else None)  # noqa: E731
    return _stored_or_solved(key, needs, solve_now, len(wf), len(omega))


def bodies_coefficients(parts: list, rho: float = 1000.0, g: float = 9.81, depth: float = math.inf, omega: np.ndarray | None = None,
                        panel: float | None = None, progress: bool = True, excitation: bool = False,
                        far_field: bool = False) -> Coefficients:  # fmt: skip
    """The same for several bodies solved together (their waves act on one another): `parts` = [(vertices,
    faces, center)] at rest, world frame; the matrices are 6k x 6k, body after body."""
    if len(parts) == 1:
        return radiation_coefficients(*parts[0][:2], rho, g, depth, omega, panel, progress, parts[0][2], excitation, far_field)
    size = max(float(np.ptp(np.asarray(v, float), axis=0).max()) for v, _, _ in parts)
    wet = [(*wet_mesh(np.asarray(v, float), f, panel or size / 8), np.asarray(c, float)) for v, f, c in parts]
    omega = default_frequencies(size, g) if omega is None else np.asarray(omega, float)
    h = hashlib.sha256(b"bodies")
    for wv, wf, c in wet:
        h.update(cache_key(wv, wf, rho, g, depth, omega, c).encode())
    needs = "far field" if far_field else "excitation" if excitation else ""
    solve_now = lambda: solve_parts(wet, rho, g, depth, omega, progress, HEADINGS if needs else None)  # noqa: E731
    return _stored_or_solved(h.hexdigest()[:20], needs, solve_now, sum(len(f) for _, f, _ in wet), len(omega), len(wet))


def _has(c: Coefficients, needs: str) -> bool:
    return {"": True, "excitation": c.has_excitation, "far field": c.has_far_field}[needs]


def _stored_or_solved(key: str, needs: str, solve_now, panels: int, frequencies: int, bodies: int = 1) -> Coefficients:
    """The shipped file or the user's cached one for `key` (the cached one only with the sha256 recorded beside
    it) holding what `needs` names ("", "excitation", "far field"), else `solve_now()` (kept in the cache), announced
    with its estimate from its `panels` (wet, in all, over `bodies` bodies) and `frequencies`, or refused when its
    matrices would not fit the memory."""
    cached = user_cache() / f"{key}.npz"
    bad, partial = [], None
    for path in (SHIPPED / f"{key}.npz", cached):
        if path.exists():
            try:
                if path == cached:
                    verify_digest(path)
                found = Coefficients.load(path)
            except ValueError as e:
                bad.append(f"{path} is not usable ({e})")
                continue
            if _has(found, needs):
                return found
            partial = partial or found
    wanted = "the mean drift force (the far field)" if needs == "far field" else "the wave excitation (diffraction)"
    what = wanted if partial is not None else "radiation = 'bem'"
    if getattr(_thread, "no_solve", None):
        raise ConfigError(f"it needs a boundary-element solve of the body as it now floats, {_thread.no_solve}")
    try:
        import_capytaine()  # before a solve of minutes starts, or instead of it
        if bad or partial is not None:
            note(f"note: {bad[0]}: solving again" if bad else f"note: the stored solve for this body lacks {wanted}: solving again with it")
        check_panels(panels, bodies)
        note(f"note: {solve_estimate(panels, frequencies)}; kept in {cached.parent} for the next run; Ctrl-C stops it")
        result = in_child(solve_now)  # (a child: Ctrl-C stops a solve of minutes in Capytaine's compiled code at once)
    except (ImportError, MissingSolver):
        if partial is not None:
            raise MissingSolver(f'{what} for this body needs Capytaine (the stored solve lacks it): pip install -e ".[bem]"') from None
        raise MissingSolver(f"{what}: {bad[0]} and solving again needs Capytaine: pip install -e \".[bem]\"" if bad else
                            f"{what} needs the boundary-element solver Capytaine for this body (or its coefficients in {cached}): "
                            'pip install -e ".[bem]"') from None  # fmt: skip
    keep(result, cached)
    return result


CAPYTAINE_CACHE = ("CAPYTAINE_CACHE_DIR", "XDG_CACHE_HOME")
"""Where Capytaine makes its cache folder as it is imported, in the order it looks (else ~/.cache)."""


def import_capytaine():
    """Capytaine, imported (ImportError when it is not installed). It makes its cache folder as it loads: a
    variable pointing where no folder can be made is a one-line ConfigError naming it, not a traceback."""
    try:
        import capytaine
    except OSError as e:
        raise ConfigError(cache_home_error(e)) from None
    return capytaine


def cache_home_error(e: OSError) -> str:
    why = f"{e.strerror or e} at {e.filename}" if e.filename else (e.strerror or str(e))
    name = next((n for n in CAPYTAINE_CACHE if os.environ.get(n, "").strip()), None)
    if name is None:
        return f"Capytaine cannot make its cache folder under ~/.cache ({why}): set XDG_CACHE_HOME to a folder it can write"
    value = os.environ[name]
    problem = "is a file, not a folder" if os.path.isfile(value) else f"cannot hold Capytaine's cache folder ({why})"
    return f"{name}={value} {problem}: Capytaine keeps its cache under it; set {name} to a folder (or unset it)"


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
        note(
            f"warning: cannot cache the radiation coefficients in {path.parent} ({e.strerror or e}): this run goes on, the next one solves again"
        )


def solve(vertices: np.ndarray, faces: np.ndarray, rho: float, g: float, depth: float, omega: np.ndarray, progress: bool = True,
          center=(0.0, 0.0, 0.0), headings: np.ndarray | None = None) -> Coefficients:  # fmt: skip
    """Capytaine on one wet mesh (vertices and triangles under z = 0): `solve_parts` of one body."""
    return solve_parts([(vertices, faces, np.asarray(center, float))], rho, g, depth, omega, progress, headings)


def solve_parts(parts: list, rho: float, g: float, depth: float, omega: np.ndarray, progress: bool = True,
                headings: np.ndarray | None = None) -> Coefficients:  # fmt: skip
    """Capytaine on the wet meshes [(vertices, faces, center)] together: radiation in each body's six rigid
    modes about its centre at every omega and at infinity, with a lid against irregular frequencies; with
    `headings`, the diffraction problem (the bodies held still) and the Froude-Krylov force for each."""
    try:
        cpt = import_capytaine()
    except ImportError:
        raise MissingSolver(
            "radiation = 'bem' needs the boundary-element solver Capytaine for this body: pip install -e \".[bem]\""
        ) from None
    import logging

    from capytaine.bem.airy_waves import froude_krylov_force
    from capytaine.post_pro.kochin import compute_kochin

    logging.getLogger("capytaine").setLevel(logging.ERROR)  # its resolution warnings concern the top of the grid, where B has died out
    bodies, centers, panels = [], [], 0
    for k, (vertices, faces, center) in enumerate(parts):
        center = tuple(float(c) for c in center)
        mesh = cpt.Mesh(vertices, faces)
        lv, lf = make_lid(vertices, faces, panel_size(vertices, faces), -LID_DEPTH * float(np.ptp(vertices[:, 2])))
        lid = cpt.Mesh(lv, lf) if len(lf) else None
        bodies.append(cpt.FloatingBody(mesh=mesh, lid_mesh=lid, dofs=cpt.rigid_body_dofs(rotation_center=center), center_of_mass=center,
                                       name=f"b{k}"))  # fmt: skip
        centers.append(center)
        panels += int(mesh.nb_faces)
    body = bodies[0] if len(bodies) == 1 else bodies[0].join_bodies(*bodies[1:])
    names = list(DOFS) if len(bodies) == 1 else [f"b{k}__{d}" for k in range(len(bodies)) for d in DOFS]
    n = len(names)
    solver = cpt.BEMSolver()
    water = {"rho": rho, "g": g, "water_depth": depth}
    freqs = [*omega, math.inf]
    betas = [] if headings is None else [float(b) for b in headings]
    problems = [cpt.RadiationProblem(body=body, radiating_dof=dof, omega=w, **water) for w in freqs for dof in names]
    problems += [cpt.DiffractionProblem(body=body, wave_direction=b, omega=w, **water) for w in omega for b in betas]
    results = solver.solve_all(problems, progress_bar=progress)
    A = np.zeros((len(freqs), n, n))
    B = np.zeros((len(freqs), n, n))
    Xd = np.zeros((len(omega), len(betas), n), complex)
    Xfk = np.zeros_like(Xd)
    Hd = np.zeros((len(omega), len(betas), KOCHIN_ANGLES), complex)
    Hr = np.zeros((len(omega), n, KOCHIN_ANGLES), complex)
    theta = 2 * math.pi * np.arange(KOCHIN_ANGLES) / KOCHIN_ANGLES
    for r in results:
        i = freqs.index(r.omega)
        if isinstance(r.problem, cpt.DiffractionProblem):
            j = betas.index(r.problem.wave_direction)
            fk = froude_krylov_force(r.problem)
            Xd[i, j] = [r.forces[name] for name in names]
            Xfk[i, j] = [fk[name] for name in names]
            Hd[i, j] = compute_kochin(r, theta)
            continue
        j = names.index(r.radiating_dof)
        for k, name in enumerate(names):
            A[i, k, j] = r.added_masses[name]
            B[i, k, j] = r.radiation_dampings[name]
        if headings is not None and math.isfinite(r.omega):
            Hr[i, j] = compute_kochin(r, theta)
    excitation = {} if headings is None else {"headings": np.asarray(betas), "diffraction": Xd, "froude_krylov": Xfk,
                                               "kochin_diffraction": Hd, "kochin_radiation": Hr}  # fmt: skip
    center = np.asarray(centers[0] if len(centers) == 1 else centers, float)
    A, B, change = passive(A, B, max(float(np.ptp(v, axis=0).max()) for v, _, _ in parts))
    if change > 0.01:
        note(f"note: the radiation damping made symmetric and passive (the solve breaks both a little, most in couplings such as "
             f"an axisymmetric body's rank-one surge-pitch block): entries changed by up to {100 * change:.1f} % of each frequency's largest")  # fmt: skip
    return Coefficients(np.asarray(omega, float), A[:-1], B[:-1], A[-1], float(rho), float(depth), panels, center, **excitation)


SOLVE_SECONDS_PER_PANEL2 = 1.0e-6
"""Capytaine's solve, seconds per (wet panel)^2 and frequency (infinity counted; radiation and diffraction together).
Measured (AMD EPYC, one core, the cube at draft 0.4 m, `solve_parts`): 1280 panels 1.4-1.6 s a frequency, 4864 panels
23-26 s (so about panels^2.1)."""
SOLVE_START_SECONDS = 15.0
"""A solve's start: importing Capytaine and tabulating its Green function, once in the child each solve runs in."""
BYTES_PER_PANEL_PAIR = 32.0
"""Capytaine's two dense complex matrices (the single- and double-layer influence), bytes per pair of panels."""


def solve_estimate(panels: int, frequencies: int) -> str:
    """What a solve of `panels` wet panels at `frequencies` frequencies (and infinity) will cost, in a phrase."""
    seconds = SOLVE_START_SECONDS + SOLVE_SECONDS_PER_PANEL2 * float(panels) ** 2 * (frequencies + 1)
    return (f"a boundary-element solve (Capytaine) of {panels:,} wet panels at {frequencies + 1} frequencies: about "
            f"{limits.duration(seconds)} and {limits.size(BYTES_PER_PANEL_PAIR * float(panels) ** 2)} of memory")  # fmt: skip


def check_panels(panels: int, bodies: int) -> None:
    """Refuse a joint BEM solve of `panels` wet panels over `bodies` bodies whose dense matrices would pass the memory share
    (limits.MEMORY_SHARE of what is available now), with the numbers and what to change."""
    need = BYTES_PER_PANEL_PAIR * float(panels) ** 2
    room = limits.MEMORY_SHARE * limits.available_bytes()
    if need > room:
        what, fewer = (
            ("the body", "a coarser mesh")
            if bodies == 1
            else (f"{bodies} bodies together", "fewer devices ([farm] rows, columns), coarser meshes")
        )
        raise ConfigError(f"the BEM solve of {what} has {panels} wet panels: its matrices take about {need / 1e9:.3g} GB, "
                          f"over the {room / 1e9:.3g} GB this machine can give it; use {fewer}, or radiation = \"none\"")  # fmt: skip

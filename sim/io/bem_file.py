"""A scene's bodies' coefficients from a file (`[fluid] bem_file`) instead of a Capytaine solve.

The file is WAMIT's output (`.out`, read by sim/io/wamit.py) or its numeric files (`.1`, `.3`, `.hst`:
sim/io/wamit_numeric.py), a BEMIO `.h5` (sim/io/bemio_h5.py), a NEMOH run (sim/io/nemoh.py), a Capytaine dataset
(sim/io/capytaine_nc.py) or floatsim's own coefficients file (`.npz`, as `bem.Coefficients.save` writes it), told
apart by content. Each is taken to the scene's bodies:

- its bodies are the scene's [[bodies]] by where they are: each entry takes the file's body whose centre of mass is
  nearest its own at the start, one each (one-line error when the counts differ or two entries want one body);
- its matrices and forces are about each body's centre of mass, and ride with it (as WEC-Sim takes them): a body may
  start a little below the pose it was solved at (a mooring's pull), not elsewhere in the horizontal (the waves'
  phases are the file's). WAMIT's, about each body's origin XBODY, are first moved to its centre of gravity XBODY +
  (Xg, Yg, Zg) as the file gives it (a rigid shift: A -> T^T A T, X -> T^T X with T = [[I, -[d]x], [0, I]], d the old
  point less the new, per body);
- WAMIT's damping is made symmetric and positive semi-definite (reciprocal and passive, as Capytaine's is here:
  bem.passive), its added mass symmetric; a note says by how much they changed;
- WAMIT's excitation is the whole linear wave force; floatsim adds the incident wave's part itself (exactly, or
  linearly about rest), so the file's is split: the Froude-Krylov force of the scene's own wet surfaces at rest
  (linear_hydro.LinearLoads' integration, per unit wave at each frequency and heading) and the rest, the
  diffraction force. The bodies' wet surfaces must be the ones the file was solved for: the split checks this
  where it can (the heave force of the longest waves: `split_excitation`).
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from sim.errors import ConfigError
from sim.hydro.bem import Coefficients, note, passive
from sim.hydro.forces import Model
from sim.hydro.hydrostatics import hydrostatics
from sim.hydro.linear_hydro import LinearLoads
from sim.io.bemio_h5 import is_bemio, read_bemio
from sim.io.capytaine_nc import read_capytaine
from sim.io.nemoh import is_nemoh, read_nemoh
from sim.io.wamit import read_out
from sim.io.wamit_drift import DRIFT, read_drift
from sim.io.wamit_numeric import Assumed, beside, columns_of, read_numeric, stiffness
from sim.water.records import record_path
from sim.water.seas import Waves, wavenumber

HORIZONTAL_SLACK = 0.01
"""m: a body must start this near, horizontally, the file's centre of mass (the excitation's phases are the file's)."""


def bem_file_path(name: str, base_dir: str) -> Path:
    """The file a scene names: relative to the scene file, else to the working directory."""

    path = record_path(name, base_dir)
    if not path.is_file():
        raise ConfigError(f"[fluid] bem_file {name!r}: no such file (beside the scene or from the working directory)")
    return path


def kind_of(path: Path) -> str:
    """What `path` holds, told by its content (not its name): "npz" (floatsim's coefficients), "bemio" (a BEMIO .h5
    file: HDF5 with its simulation_parameters group), "nemoh" (a NEMOH run's Nemoh.cal or Tecplot results), "netcdf" (a Capytaine dataset, netCDF3 or 4), "out" (WAMIT's output: its header's words), "numeric" (one of WAMIT's numeric files: rows of
    3, 4, 5 or 7 numbers) or, else, "out" (whose reader says what is wrong)."""
    with open(path, "rb") as f:
        head = f.read(65536)
    if head[:2] == b"PK":
        return "npz"
    if is_bemio(head):
        return "bemio"
    if is_nemoh(head):
        return "nemoh"
    if head[:3] == b"CDF" or head[:4] == b"\x89HDF":
        return "netcdf"
    if any(word in head for word in (b"Gravity:", b"Wave period", b"POTEN run date")):
        return "out"
    return "numeric" if columns_of(path) in (3, 4, 5, 7) else "out"


def from_file(path: Path, models: list, starts: list, fluid, water=None, drift: bool = False) -> Coefficients:
    """The coefficients in `path` for the bodies `models` (forces.Model) starting at `starts` (their poses), with the
    excitation of the sea `water` (None: radiation only); with `drift`, the mean drift too (a one-line ConfigError,
    before any other work, when the file has none)."""
    kind = kind_of(path)
    if kind == "npz":
        try:
            c = Coefficients.load(path)
        except ValueError as e:
            raise ConfigError(f"[fluid] bem_file {str(path)!r}: {e}") from None
    elif kind == "netcdf":
        c = _from_dataset(path, models, starts, fluid)
    elif kind == "bemio":
        c = _from_dataset(path, models, starts, fluid, read_bemio)
    elif kind == "nemoh":
        c = _from_dataset(path, models, starts, fluid, read_nemoh)
    else:
        c = _from_wamit(path, kind, models, starts, fluid, water, drift)
    if drift and c.mean_drift is None and not c.has_far_field:
        raise ConfigError(no_drift(path))
    bodies = c.added_mass.shape[1] // 6
    if bodies != len(models):
        raise ConfigError(f"[fluid] bem_file {str(path)!r} holds {bodies} bodies, the scene {len(models)}: one per [[bodies]] entry")
    _check_rho(path, c.rho, fluid)
    if water is not None:
        _check_sea(path, c, water)
    c = matched(c, np.array([s.x_world for s in starts]), path)
    centers = np.atleast_2d(c.center).reshape(-1, 3)
    for b, s in enumerate(starts):
        if np.hypot(*(centers[b, :2] - s.x_world[:2])) > HORIZONTAL_SLACK:
            raise ConfigError(f"body {b + 1} starts at x, y = ({s.x_world[0]:g}, {s.x_world[1]:g}) m, the bem_file has its centre of "
                              f"mass at ({centers[b, 0]:g}, {centers[b, 1]:g}): place it where the file does")  # fmt: skip
    if kind != "npz" and c.has_excitation:
        c = split_excitation(c, models, starts, fluid, path, either_time=kind == "bemio")
    return c


def no_drift(path: Path) -> str:
    return f"[fluid] bem_file {str(path)!r} holds no mean drift: WAMIT's .8 or .9 beside its .1 gives it (or leave [waves] drift off)"


def _from_wamit(path: Path, kind: str, models: list, starts: list, fluid, water, drift: bool = False) -> Coefficients:
    """A WAMIT run's coefficients (its `.out`, or its numeric `.1` and `.3`), made reciprocal and passive and moved to
    the bodies' centres of gravity; the numeric files' hydrostatics checked against the scene's bodies."""
    if kind == "out":
        run = read_out(path, fluid.rho)
    else:
        assumed = Assumed(fluid.g, water.depth if water is not None else math.inf, np.array([s.x_world for s in starts]))
        run, has_out = read_numeric(path, fluid.rho, assumed)
        if not has_out:
            note(f"note: {path.name} read without its .out: taken about the world's origin with ULEN = 1, the scene's g and depth "
                 "(put the run's .out beside it to have them checked)")  # fmt: skip
        _check_stiffness(beside(path, ".hst"), stiffness(path, run, fluid.rho), run.gravity_centers, models, starts, fluid)
    _check_g(path, run.g, fluid)
    not_yet = np.zeros_like(run.excitation)  # (split_excitation)
    table = drift_table(path, run, fluid) if kind == "numeric" and drift else None
    if drift and table is None:
        raise ConfigError(no_drift(path))  # before the passivity's note
    c = Coefficients(run.omega, run.added_mass, run.damping, run.added_mass_inf, fluid.rho, run.depth, run.panels, run.centers, run.headings,
                     run.excitation, not_yet, mean_drift=table)  # fmt: skip
    return moved(_passive(path, c, models), run.gravity_centers)


def drift_table(path: Path, run, fluid) -> np.ndarray | None:
    """(n, m, 3) the mean drift of the WAMIT run whose numeric files `path` names, from its `.8` (momentum conservation)
    or else its `.9` (pressure integration) beside it, at the run's frequencies and headings, the yaw moment about the
    world's origin; None when neither is there. Several bodies': their total (what floatsim applies to their tree), from
    the `.9`, each body's force and yaw about its own origin (a `.8`'s momentum flux is the bodies' together, about a point
    no public file here lets us check: refused in one line)."""
    bodies = run.added_mass.shape[1] // 6
    kinds = DRIFT if bodies == 1 else DRIFT[1:]
    found = next((beside(path, s) for s in kinds if beside(path, s).is_file()), None)
    if found is None:
        if bodies > 1 and beside(path, ".8").is_file():
            raise ConfigError(f"[fluid] bem_file {str(path)!r}: several bodies' drift is read from WAMIT's .9 (pressure integration, "
                              "each body's), not its .8 (their total by momentum conservation): put the run's .9 beside it")  # fmt: skip
        return None
    periods, headings, D = read_drift(found, fluid.rho, run.g, run.length, bodies)
    beta = np.mod(np.radians(headings), 2 * math.pi)
    if len(beta) != len(run.headings) or not np.allclose(np.sort(beta), np.sort(np.mod(run.headings, 2 * math.pi)), atol=1e-6):
        raise ConfigError(f"[fluid] bem_file {str(path)!r}: {found.name}'s headings ({', '.join(f'{h:g}' for h in headings)} degrees) "
                          "are not the excitation's")  # fmt: skip
    D = D[:, np.argsort(beta)][:, np.argsort(np.argsort(np.mod(run.headings, 2 * math.pi)))]
    origins = np.atleast_2d(run.centers)[:, :2]  # each body's moment about its origin -> the world's
    D[..., 2] += origins[:, 0] * D[..., 1] - origins[:, 1] * D[..., 0]
    total = D.sum(axis=2)
    omega = 2 * math.pi / periods[::-1]
    return np.stack([[np.interp(run.omega, omega, total[::-1, m, i]) for i in range(3)] for m in range(len(beta))], -1).transpose(1, 2, 0)


def _from_dataset(path: Path, models: list, starts: list, fluid, read=read_capytaine) -> Coefficients:
    """A Capytaine dataset's coefficients (sim/io/capytaine_nc.py; or a NEMOH run's, sim/io/nemoh.py, or a BEMIO file's,
    sim/io/bemio_h5.py, which read to the same: `read`), made reciprocal and passive and moved to the bodies' centres
    of mass; its hydrostatic stiffness, when it has one, checked against the scene's bodies."""
    c, gravity, g, C = read(path)
    _check_rho(path, c.rho, fluid)  # (before the stiffness, which holds rho)
    _check_g(path, g, fluid)
    if C is not None:
        _check_stiffness(path, C, gravity, models, starts, fluid)
    return moved(_passive(path, c, models), gravity)


def _check_rho(path: Path, rho: float, fluid) -> None:
    if abs(rho - fluid.rho) > 1e-9 * fluid.rho:
        raise ConfigError(f"[fluid] bem_file {str(path)!r} is for water of density {rho:g} kg/m^3, the scene has {fluid.rho:g}")


def _check_g(path: Path, g: float, fluid) -> None:
    if abs(g - fluid.g) > 1e-6 * fluid.g:
        raise ConfigError(f"[fluid] bem_file {str(path)!r} was solved with g = {g:g} m/s^2, the scene has {fluid.g:g}")


def _passive(path: Path, c: Coefficients, models: list) -> Coefficients:
    """`c` with its damping symmetric and positive semi-definite and its added mass symmetric (bem.passive), as a
    Capytaine solve's is here, and a note when that changed it by more than 1 %."""
    size = max(float(np.ptp(m.body.mesh_vertices, axis=0).max()) for m in models)
    A, B, _ = passive(np.concatenate([c.added_mass, c.added_mass_inf[None]]), np.concatenate([c.damping, c.damping[-1:]]), size)
    change = float(np.abs(B[:-1] - c.damping).max() / max(np.abs(c.damping).max(), 1e-300))  # (not per frequency: a long wave's
    if change > 0.01:  # damping is round-off small, and its round-off is all a per-frequency measure would see)
        note(f"note: {path.name}'s radiation damping made symmetric and passive, as a Capytaine solve's is: entries changed by up "
             f"to {100 * change:.1f} % of its largest")  # fmt: skip
    return replace(c, added_mass=A[:-1], damping=B[:-1], added_mass_inf=A[-1])


WATERPLANE_SLACK = 0.05
"""A WAMIT run's heave stiffness (`.hst`) and the scene body's rho g times its waterplane may differ by this fraction."""


def _check_stiffness(path: Path, C: np.ndarray | None, centers: np.ndarray, models: list, starts: list, fluid) -> None:
    """One line unless each body's heave stiffness in the file `path` (a WAMIT `.hst`, a Capytaine dataset's) is the
    scene's body's at rest (rho g times its waterplane): another body, draft or length scale otherwise. Each scene body
    is compared with the file's body nearest its start (`centers`, (k, 3): as `matched` takes them)."""
    if C is None or C.shape[0] != 6 * len(models):
        return
    centers = np.atleast_2d(centers).reshape(-1, 3)
    for model, s in zip(models, starts):
        b = int(np.linalg.norm(centers - s.x_world, axis=1).argmin())
        h = hydrostatics(model.body, s.x_world, s.R_world_body)
        if h is None:
            continue
        own, file = fluid.rho * fluid.g * h.waterplane_area, C[6 * b + 2, 6 * b + 2]
        if abs(file - own) > WATERPLANE_SLACK * max(abs(own), 1e-30):
            raise ConfigError(f"[fluid] bem_file {str(path)!r}: body {b + 1}'s heave stiffness is {file:.4g} N/m, "
                              f"the scene's body at rest has {own:.4g} N/m (rho g times a waterplane of {h.waterplane_area:.4g} m^2): "
                              "another body, draft or length scale")  # fmt: skip


def _check_sea(path: Path, c: Coefficients, water) -> None:
    """One line unless the file can excite the scene's bodies in its sea: excitation at the sea's depth, and at its
    headings where the file has only one; a file of several is interpolated between neighbouring headings, but not
    across a gap wider than HEADING_GAP (a file of 0 to 180 degrees, as WAMIT users solve a symmetric body, says nothing
    of waves from 270)."""
    if not c.has_excitation:
        raise ConfigError(f"[fluid] bem_file {str(path)!r} has no wave excitation: the scene's waves need it")
    if not (c.depth == water.depth or abs(c.depth - water.depth) <= 1e-6 * water.depth):
        raise ConfigError(f"[fluid] bem_file {str(path)!r} was solved for water {c.depth:g} m deep, the scene's waves are "
                          f"{water.depth:g} m deep ([waves] depth)")  # fmt: skip
    if len(c.headings) == 1:
        off = np.abs(np.angle(np.exp(1j * (np.asarray(water.direction) - c.headings[0])))).max(initial=0.0)
        if off > 1e-6:
            raise ConfigError(f"[fluid] bem_file {str(path)!r} has the excitation of waves travelling at {math.degrees(c.headings[0]):g} "
                              f"degrees only: set [waves] direction = {math.degrees(c.headings[0]):g} (and no spreading)")  # fmt: skip
    h = np.sort(np.mod(c.headings, 2 * math.pi))
    ends = np.append(h[1:], h[0] + 2 * math.pi)
    for start, end in zip(h, ends):
        if len(h) > 1 and end - start > HEADING_GAP:
            inside = np.mod(_main_directions(water) - start, 2 * math.pi)
            if np.any((inside > 1e-6) & (inside < end - start - 1e-6)):
                raise ConfigError(f"[fluid] bem_file {str(path)!r} has no headings between {math.degrees(start):g} and "
                                  f"{math.degrees(end) % 360:g} degrees, and the scene's waves travel there ([waves] direction, "
                                  "spreading): solve the file at headings around the sea's")  # fmt: skip


HEADING_GAP = math.pi / 2
"""rad: a file's excitation is interpolated between headings at most this far apart (wider: no heading there)."""
MAIN_ENERGY = 0.99
"""The share of a sea's energy whose directions a file's headings must cover (a spread sea's faint tails may not)."""


def _main_directions(water) -> np.ndarray:
    """The directions of the sea's components that carry MAIN_ENERGY of its energy, the largest first."""
    direction = np.atleast_1d(np.asarray(water.direction, float))
    energy = np.atleast_1d(np.asarray(water.amplitude, float)) ** 2 * np.ones_like(direction)
    order = np.argsort(energy)[::-1]
    share = np.cumsum(energy[order]) / max(energy.sum(), 1e-300)
    return direction[order[: int(np.searchsorted(share, MAIN_ENERGY)) + 1]]


def matched(c: Coefficients, starts: np.ndarray, path: Path) -> Coefficients:
    """`c` with its bodies in the scene's order: each the file's body nearest the scene body's start ((k, 3))."""
    centers = np.atleast_2d(c.center).reshape(-1, 3)
    nearest = np.linalg.norm(starts[:, None, :] - centers[None, :, :], axis=2).argmin(axis=1)
    if len(set(nearest.tolist())) != len(nearest):
        raise ConfigError(f"[fluid] bem_file {str(path)!r}: two [[bodies]] start nearest the same body of the file; start each "
                          "body where the file has it")  # fmt: skip
    if np.array_equal(nearest, np.arange(len(nearest))):
        return c
    dofs = (6 * nearest[:, None] + np.arange(6)).ravel()
    square = lambda M: M[..., dofs, :][..., dofs]  # noqa: E731
    X = {} if not c.has_excitation else {"diffraction": c.diffraction[..., dofs], "froude_krylov": c.froude_krylov[..., dofs]}
    return replace(c, added_mass=square(c.added_mass), damping=square(c.damping), added_mass_inf=square(c.added_mass_inf),
                   center=centers[nearest], **X)  # fmt: skip


def _shift(d: np.ndarray) -> np.ndarray:
    """(6, 6) T: a body's twist about the new point to its twist about the old one, d = old - new."""
    T = np.eye(6)
    T[:3, 3:] = -np.array([[0.0, -d[2], d[1]], [d[2], 0.0, -d[0]], [-d[1], d[0], 0.0]])
    return T


def moved(c: Coefficients, centers: np.ndarray) -> Coefficients:
    """`c` about `centers` ((k, 3), world) instead of its own reference points."""
    old = np.atleast_2d(c.center).reshape(-1, 3)
    d = old - centers
    if not np.any(d):
        return c
    T = np.zeros((6 * len(d), 6 * len(d)))
    for b, offset in enumerate(d):
        T[6 * b : 6 * b + 6, 6 * b : 6 * b + 6] = _shift(offset)
    turn = lambda M: T.T @ M @ T  # noqa: E731
    X = {} if not c.has_excitation else {"diffraction": c.diffraction @ T, "froude_krylov": c.froude_krylov @ T}
    return replace(c, added_mass=turn(c.added_mass), damping=turn(c.damping), added_mass_inf=turn(c.added_mass_inf),
                   center=centers.copy() if len(centers) > 1 else centers[0].copy(), **X)  # fmt: skip


def froude_krylov(c: Coefficients, models: list, starts: list, fluid) -> np.ndarray:
    """(n, m, 6k) the incident wave's linear force on each body's wet surface at rest, per unit wave of each of the
    solve's frequencies and headings (phase zero at the origin), about the bodies' centres of mass, as floatsim
    integrates it (linear_hydro.LinearLoads)."""

    n, m = len(c.omega), len(c.headings)
    omega = np.repeat(c.omega, m)
    waves = Waves(fluid.rho, fluid.g, np.ones(n * m), omega, wavenumber(omega, fluid.g, c.depth), np.tile(c.headings, n),
                  np.zeros(n * m), c.depth)  # fmt: skip
    forces = [LinearLoads(Model(model.body, waves, fluid), s.x_world, s.R_world_body).X for model, s in zip(models, starts)]
    return np.concatenate([f.reshape(n, m, 6) for f in forces], axis=2)


LONG_WAVE_SLACK = 0.05
"""The heave force of the file's longest waves and that of the scene's wet surfaces may differ by this fraction of
the larger part: more, and the bodies are not the ones solved for (a mesh at another draft, another body order)."""


def split_excitation(c: Coefficients, models: list, starts: list, fluid, path: Path, either_time: bool = False) -> Coefficients:
    """`c` whose `diffraction` holds the whole excitation, split into the scene's Froude-Krylov force and the rest.
    Checked in the file's longest waves, where the rest is the body's added mass times the water's acceleration
    (Taylor's long-wave limit: sum over the bodies c of -omega^2 A_3c e^(k z_c) per unit amplitude in heave, z_c
    their centres of mass's depths); and its time factor told there too (`flipped_time`): the other one is refused,
    or, with `either_time` (a BEMIO file, whose writers differ), taken with a note."""
    fk = froude_krylov(c, models, starts, fluid)
    total = c.diffraction
    if flipped_time(total[0], fk[0]):
        if not either_time:
            raise ConfigError(f"[fluid] bem_file {str(path)!r}: its long-wave horizontal force leads the waves' acceleration by half a "
                              "cycle: its excitation has the other time factor (its phases conjugated)")  # fmt: skip
        note(f"note: {path.name}'s excitation phases are for the time factor e^(-i omega t) (Capytaine's), not BEMIO's e^(i omega t): "
             "its long-wave horizontal force says so; taken as such")  # fmt: skip
        total = np.conj(total)
    w, k = c.omega[0], c.omega[0] ** 2 / fluid.g
    heaves = 6 * np.arange(len(starts)) + 2
    accelerations = -(w**2) * np.exp(k * np.minimum([float(s.x_world[2]) for s in starts], 0.0))
    for b in range(len(starts)):
        j = 6 * b + 2
        scattered = float(c.added_mass[0, j, heaves] @ accelerations)
        expected, found = fk[0, 0, j].real + scattered, total[0, 0, j]
        if abs(found - expected) > LONG_WAVE_SLACK * max(abs(fk[0, 0, j]), abs(scattered), 1e-30):
            raise ConfigError(f"body {b + 1}'s heave force in the bem_file's longest waves ({2 * math.pi / w:.4g} s) is {abs(found):.4g} N/m, "
                              f"its mesh at rest gives {abs(expected):.4g} N/m (Froude-Krylov and added mass): the mesh or its pose "
                              "is not the one the file was solved for")  # fmt: skip
    return replace(c, diffraction=total - fk, froude_krylov=fk)


def flipped_time(total: np.ndarray, fk: np.ndarray) -> bool:
    """Whether a file's excitation in its longest waves ((m, 6k) per heading) has the other time factor than floatsim's:
    there the horizontal forces are the water's acceleration times the body's mass and added mass, in phase with
    the Froude-Krylov force (a quarter cycle from the elevation); the other time factor puts them half a cycle off."""
    horizontal = np.concatenate([np.arange(b, total.shape[-1], 6) for b in (0, 1)])
    agree = float(np.sum(total[:, horizontal].imag * fk[:, horizontal].imag))
    size = float(np.sum(np.abs(total[:, horizontal].imag * fk[:, horizontal].imag)))
    return size > 0 and agree < -0.5 * size

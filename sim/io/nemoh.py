"""Radiation and excitation coefficients from a NEMOH run (v2 and v3's Tecplot results), as WEC-Sim's `readNEMOH`
takes them: name the run's `Nemoh.cal` (or one of its `Results/*.tec`).

What is read, all dimensional (SI, per metre of wave):

- `Nemoh.cal`: RHO, G, DEPTH (0: deep water), each body's degrees of freedom (type 1 a translation along an axis,
  type 2 a rotation about an axis through a point) and the headings (where a zone's title lacks its own: NEMOH
  prints them in 7 characters, so -100 degrees and below come out as *******). Each body must have
  floatsim's six: translations along x, y, z and rotations about x, y, z through one point, the point its
  coefficients are about;
- `Results/RadiationCoefficients.tec`: a zone per body and degree of freedom moved, each row omega and (A, B) for each
  force of every body;
- `Results/ExcitationForce.tec`: a zone per heading, each row omega and (|X|, arg X in radians) for each force.
  NEMOH's time factor is floatsim's, e^(-i omega t) (WEC-Sim negates its phases to WAMIT's); the check on the
  long-wave horizontal force confirms it (sim/io/bem_file.flipped_time);
- `Mesh/KH.dat` (`KH_0.dat`, `KH_1.dat`, ... for several bodies; `mesh/` and `results/` in NEMOH's own lower case
  serve as well as WEC-Sim's `Mesh/` and `Results/`): the hydrostatic stiffness, to check the bodies;
  `Mesh/Hydrostatics.dat` (`Hydrostatics_0.dat`, ...): each body's centre of gravity (XG, YG, ZG).

NEMOH v2 does not give the added mass at infinite frequency. It is made as WEC-Sim's BEMIO makes it (radiationIRF.m),
from Ogilvie's relation A(inf) = A(w) + (1/w) int_0^T K(t) sin(w t) dt with K(t) = (2/pi) int B(w) cos(w t) dw over
the file's frequencies, but taken as the median over the upper half of the frequencies (BEMIO takes the mean over all,
where the 1/w of the longest waves magnifies the truncation). On WEC-Sim's ellipsoid it meets WAMIT's A(inf) of the
same body within 0.3 % in heave and 1.1 % in pitch; NEMOH's surge added mass is 3.5 % above WAMIT's at every high
frequency, and so is its A(inf).
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from sim.errors import ConfigError
from sim.hydro.bem import Coefficients
from sim.hydro.impulse_response import frequency_response, impulse_response

ZONE = re.compile(r'Zone\s+t="([^"]*)"\s*,\s*I\s*=\s*(\d+)', re.IGNORECASE)
NUMBER = re.compile(r"^[-+]?(\d+\.?\d*|\.\d+)([eEdD][-+]?\d+)?$")
IRF_SECONDS, IRF_SAMPLES = 100.0, 2001
"""The radiation impulse response's span for A(inf), as BEMIO's default (100 s), and its samples. The span is cut to
pi / dw where the frequencies are dw apart: a sum over them repeats itself after 2 pi / dw."""


def is_nemoh(head: bytes) -> bool:
    """Whether a file's first bytes are a NEMOH run's `Nemoh.cal` or one of its Tecplot results."""
    return b"--- Environment" in head or (b"VARIABLES" in head and b"Zone t=" in head)


def _numbers(line: str) -> list[float]:
    """The leading numbers of a Nemoh.cal line (its comment after them)."""
    out = []
    for word in line.replace("\t", " ").split():
        if not NUMBER.match(word):
            break
        out.append(float(word.replace("D", "E").replace("d", "e")))
    return out


def _cal(path: Path) -> dict:
    """The environment, each body's dofs and the load cases of `Nemoh.cal`."""
    where = f"[fluid] bem_file {str(path)!r}"
    lines = [line for line in path.read_text(errors="replace").splitlines() if line.strip() and not line.lstrip().startswith("---")]
    it = iter(lines)
    try:
        rho, g, depth = (_numbers(next(it))[0] for _ in range(3))
        next(it)  # the wave measurement point
        bodies = []
        for _ in range(int(_numbers(next(it))[0])):
            next(it), next(it)  # the mesh file, its points and panels
            dofs = [_numbers(next(it))[:7] for _ in range(int(_numbers(next(it))[0]))]
            for _ in range(int(_numbers(next(it))[0])):
                next(it)  # the generalised forces
            for _ in range(int(_numbers(next(it))[0])):
                next(it)  # lines of additional information
            bodies.append(dofs)
        next(it)  # the frequencies
        count, first, last = _numbers(next(it))[-3:]
    except (StopIteration, IndexError, ValueError):
        raise ConfigError(f"{where}: not a Nemoh.cal floatsim can read (its environment, bodies and load cases)") from None
    headings = np.linspace(first, last, int(count)) if count > 1 else np.array([first])
    return {"rho": rho, "g": g, "depth": math.inf if depth <= 0 else depth, "bodies": bodies, "headings": headings}


def _reference_point(dofs: list[list[float]], where: str, body: int) -> np.ndarray:
    """The point a body's rotations are about: one line unless its dofs are x, y, z translations and rotations."""
    axes = np.eye(3)
    want = [(1, axes[k]) for k in range(3)] + [(2, axes[k]) for k in range(3)]
    if any(len(d) < 7 for d in dofs):
        raise ConfigError(f"{where}: body {body}'s degrees of freedom need 7 numbers each (type, axis, point)")
    got = [(int(d[0]), np.array(d[1:4])) for d in dofs]
    if len(got) != 6 or any(t != wt or not np.allclose(a, wa) for (t, a), (wt, wa) in zip(got, want)):
        raise ConfigError(f"{where}: body {body}'s degrees of freedom are not surge, sway, heave, roll, pitch and yaw in that order "
                          "(floatsim takes rigid bodies' six)")  # fmt: skip
    points = np.array([d[4:7] for d in dofs[3:]])
    if not np.allclose(points, points[0]):
        raise ConfigError(f"{where}: body {body}'s rotations are about different points")
    return points[0]


def _zones(path: Path, columns: int) -> list[tuple[str, np.ndarray]]:
    """Each zone's title and its rows ((I, columns) floats; rows may wrap over lines)."""
    if not path.is_file():
        raise ConfigError(f"[fluid] bem_file: {str(path)!r} is missing (NEMOH's Results/ beside its Nemoh.cal)")
    text = path.read_text(errors="replace")
    heads = list(ZONE.finditer(text))
    zones = []
    for n, head in enumerate(heads):
        end = heads[n + 1].start() if n + 1 < len(heads) else len(text)
        body = text[head.end() : end].split("\n", 1)[-1]
        words = [w for w in body.split() if NUMBER.match(w)]
        count = int(head.group(2))
        if len(words) != count * columns:
            raise ConfigError(f"[fluid] bem_file: {str(path)!r}'s zone {head.group(1)!r} has {len(words)} numbers, {count} rows of "
                              f"{columns} are {count * columns} (a cut file, or another run's bodies?)")  # fmt: skip
        zones.append((head.group(1), np.array([w.replace("D", "E").replace("d", "e") for w in words], float).reshape(count, columns)))
    if not zones:
        raise ConfigError(f"[fluid] bem_file: {str(path)!r} has no zones (not NEMOH's Tecplot results)")
    return zones


def added_mass_at_infinity(omega: np.ndarray, A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """(d, d) A(inf) from A(w) and B(w) ((n, d, d)) by Ogilvie's relation, the median over the upper half of the
    frequencies (the module's docstring)."""
    t = np.linspace(0.0, min(IRF_SECONDS, math.pi / np.diff(omega).max()), IRF_SAMPLES)  # (two frequencies at least: read_nemoh)
    upper = omega >= np.median(omega)
    memory, _ = frequency_response(impulse_response(omega, B, t), t, omega[upper], np.zeros(A.shape[1:]))  # -(1/w) int K sin
    return np.median(A[upper] - memory, axis=0)


def _files(path: Path) -> Path:
    """The run's Nemoh.cal from the file a scene names (it, or one of its Results/*.tec)."""
    if path.suffix.lower() == ".tec":
        path = path.parent.parent / "Nemoh.cal"
    if not path.is_file():
        raise ConfigError(f"[fluid] bem_file: {str(path)!r} is missing (a NEMOH run is named by its Nemoh.cal)")
    return path


def _folder(run: Path, name: str) -> Path:
    """The run's `name` folder as WEC-Sim spells it (Mesh, Results) or as NEMOH writes it (mesh, results)."""
    return next((run / n for n in (name, name.lower()) if (run / n).is_dir()), run / name)


def _beside(folder: Path, stem: str, body: int, bodies: int) -> Path:
    return _folder(folder, "Mesh") / (f"{stem}.dat" if bodies == 1 else f"{stem}_{body}.dat")


def _gravity_center(path: Path, fallback: np.ndarray) -> np.ndarray:
    """XG, YG, ZG of a Hydrostatics.dat ("XF = ... - XG = ..." lines), or `fallback` without one."""
    if not path.is_file():
        return fallback
    found = dict(re.findall(r"([XYZ]G)\s*=\s*([-+0-9.eEdD]+)", path.read_text(errors="replace")))
    try:
        return np.array([float(str(found.get(k, v)).replace("D", "E").replace("d", "e")) for k, v in zip(("XG", "YG", "ZG"), fallback)])
    except ValueError:
        raise ConfigError(f"[fluid] bem_file: {str(path)!r}: its XG, YG, ZG are not numbers") from None


def read_nemoh(path: Path) -> tuple[Coefficients, np.ndarray, float, np.ndarray | None]:
    """(the coefficients about each body's reference point with the whole excitation in `diffraction`, each body's
    centre of gravity ((k, 3): the reference points where the run has no Hydrostatics.dat), g, the hydrostatic
    stiffness or None)."""
    cal_path = _files(path)
    where = f"[fluid] bem_file {str(cal_path)!r}"
    cal = _cal(cal_path)
    k = len(cal["bodies"])
    points = np.array([_reference_point(d, where, b + 1) for b, d in enumerate(cal["bodies"])])
    results = _folder(cal_path.parent, "Results")
    d = 6 * k
    radiation = _zones(results / "RadiationCoefficients.tec", 1 + 2 * d)
    if len(radiation) != d:
        raise ConfigError(f"{where}: RadiationCoefficients.tec has {len(radiation)} zones, {k} bodies' six modes need {d}")
    omega = radiation[0][1][:, 0]
    if len(omega) < 2:
        raise ConfigError(f"{where}: one frequency; floatsim's radiation needs the damping over a range of them")
    A, B = np.zeros((len(omega), d, d)), np.zeros((len(omega), d, d))
    for moved, (_, table) in enumerate(radiation):  # rows: the forces on every mode; the zone: the mode moved
        if table.shape[0] != len(omega) or not np.allclose(table[:, 0], omega):
            raise ConfigError(f"{where}: RadiationCoefficients.tec's zones are not at the same frequencies")
        A[:, :, moved], B[:, :, moved] = table[:, 1::2], table[:, 2::2]
    excitation = _zones(results / "ExcitationForce.tec", 1 + 2 * d)
    titled = [re.search(r"beta\s*=\s*([-+0-9.eE]+)", title) for title, _ in excitation]
    headings = np.array([float(m.group(1)) for m in titled]) if all(titled) else cal["headings"]
    if len(headings) != len(excitation):
        raise ConfigError(f"{where}: ExcitationForce.tec has {len(excitation)} headings, Nemoh.cal {len(headings)}")
    if any(table.shape[0] != len(omega) or not np.allclose(table[:, 0], omega) for _, table in excitation):
        raise ConfigError(f"{where}: ExcitationForce.tec's frequencies are not RadiationCoefficients.tec's")
    X = np.stack([table[:, 1::2] * np.exp(1j * table[:, 2::2]) for _, table in excitation], axis=1)  # (n, m, d)
    order = np.argsort(omega)
    omega, A, B, X = omega[order], A[order], B[order], X[order]
    turn = np.mod(np.radians(headings), 2 * math.pi)
    X = X[:, np.argsort(turn)]
    stiffness = [_beside(cal_path.parent, "KH", b, k) for b in range(k)]
    C = None
    if all(p.is_file() for p in stiffness):
        C = np.zeros((d, d))
        for b, p in enumerate(stiffness):
            try:
                C[6 * b : 6 * b + 6, 6 * b : 6 * b + 6] = np.loadtxt(p).reshape(6, 6)
            except ValueError:
                raise ConfigError(f"[fluid] bem_file: {str(p)!r} is not a 6 x 6 stiffness matrix") from None
    gravity = np.array([_gravity_center(_beside(cal_path.parent, "Hydrostatics", b, k), points[b]) for b in range(k)])
    c = Coefficients(omega, A, B, added_mass_at_infinity(omega, A, B), cal["rho"], cal["depth"], 0, points[0] if k == 1 else points,
                     np.sort(turn), X, np.zeros_like(X))  # fmt: skip
    return c, gravity, cal["g"], C

"""Mooring lines on MoorDyn: lumped-mass lines with seabed contact, coupled to the body every step.

MoorDyn (Hall & Goupee 2015, `moordyn` on PyPI, the optional extra `.[moorings]`) integrates the lines;
floatsim gives it the fairleads' positions and velocities and takes back the lines' pull on them. The
fairleads are MoorDyn "coupled" points; the body's load is their forces' sum and moment about its
centre of mass.

Coupling, per step of the body from t to t + dt: MoorDyn advances the lines over the step with each
fairlead moving at its velocity at t (its own sub-steps), which predicts the pull at t + dt; the body
feels the mean of the pull at t and that prediction, held over its step (the trapezoidal rule on an
explicit predictor: second order in dt where the fairleads move smoothly, the way WEC-Sim and OpenFAST
couple MoorDyn too). The lines' own state lives in MoorDyn; a run can go forward only.

Lines are declared in the scene's [moorings] table, a symmetric spread of identical lines (anchors on the
seabed around the body's starting position, fairleads on the body), or by a MoorDyn v2 input file whose
"Coupled" points are the fairleads (their positions in the file: world, at the body's starting pose).
"""

from __future__ import annotations

import contextlib
import ctypes
import math
import os
import re
import sys
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sim.bodies.rotation import quat_to_matrix, skew
from sim.errors import ConfigError, SimulationDiverged
from sim.forked import ChildDied, in_child
from sim.lines.catenary import catenary
from sim.lines.line_energy import LineEnergy, read_spec
from sim.lines.moordyn_input import check_input, coupled_bodies_as_points

LINE_DRAG = (1.2, 1.0, 0.2, 0.0)
"""Cd, Ca normal, Cd, Ca axial of the spread's line type: MoorDyn's usual values for a chain-like line."""
REACH = 1.1
"""A line may span at most this times its unstretched length (a 10 % stretch) at the start."""
SEABED_STIFFNESS = 3.0e6
"""Seabed stiffness, Pa/m: MoorDyn's usual value (a node sinks 0.3 mm per kPa of its weight on the seabed)."""
RELAX_SECONDS = 200.0
"""MoorDyn's start-up (Init) relaxes the lines towards their rest shape for at most this long (TmaxIC), in its own steps;
it stops sooner once the fairleads' pull settles (0.2 s wall for moored-buoy, 0.5 s for rm3-moored)."""
CROSSINGS = 0.46
"""MoorDyn's step dtM at most this fraction of an axial wave's crossing of a segment, (L/N) sqrt(w/EA): MoorDyn's CFL
(its `CFL` option: dtM over the segment's natural period 2 pi (L/N) sqrt(w/EA), Line::cfl2dt) of 0.073. Its default
time scheme RK2 with its critically damped segments (BA = -1, as its docs advise) ran at 0.50 crossings and diverged at
0.55 on both presets' lines (the 1 kg/m line and the 100 kg/m chain, their fairleads driven harder than their scenes
drive them), where a free line's axial modes alone would allow 1.0: 0.46 keeps 8 % under the longest that ran. MoorDyn's
default CFL 0.5 (pi crossings) diverges on these lines. The presets: moored-buoy 5 steps of 2.0 ms over its 0.01 s step
(0.45 crossings), rm3-moored 19 of 2.6 ms over 0.05 s."""
SEABED_RATE = 1.0
"""dtM at most this over the seabed contact's angular frequency, sqrt(k d / m): half of RK2's bound (2) for a
critically damped contact (MoorDyn's CFL leaves the seabed out)."""
NS_PER_SEGMENT_STEP = 300.0
"""Wall time of one segment over one MoorDyn step, ns: measured 140-230 ns in its start-up's steps and 260-320 ns in a
run's (RK2, with the coupling's calls) on this machine (2 cores, under load); the larger, so an estimate is an upper bound."""
START_SECONDS = 120.0
"""The most MoorDyn's start-up may take at its longest (RELAX_SECONDS of relaxation): lines that need more are refused
before the run. The presets' estimates: 3.5 s (moored-buoy), 2.5 s (rm3-moored)."""
SURFACE = 0.0
"""The still water's height, m: MoorDyn's water reaches it (a line above it is treated as submerged all the same)."""


def moordyn():
    """The moordyn module, or a one-line ConfigError saying how to get it."""
    try:
        import moordyn as md
    except ImportError:
        raise ConfigError("mooring lines need MoorDyn: pip install -e '.[moorings]' (or pip install moordyn)") from None
    return md


def _moment(levers: np.ndarray, forces: np.ndarray) -> np.ndarray:
    """sum_i levers_i x forces_i of (k, 3) arrays: the antisymmetric part of levers^T forces (one small
    product; np.cross and column stacks cost 20 to 80 us here, a fifth of a moored step)."""
    S = levers.T @ forces
    return np.array([S[1, 2] - S[2, 1], S[2, 0] - S[0, 2], S[0, 1] - S[1, 0]])


_NULL: list = []  # /dev/null's descriptor and the C library (for fflush), opened once


@contextlib.contextmanager
def _quiet():
    """MoorDyn prints its progress ("t = ...") to the C stdout at every step: send that to /dev/null (the CSV may be on stdout)."""
    if not _NULL:
        _NULL.extend([os.open(os.devnull, os.O_WRONLY), ctypes.CDLL(None)])
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        os.dup2(_NULL[0], 1)
        yield
    finally:
        _NULL[1].fflush(None)
        os.dup2(saved, 1)
        os.close(saved)


@dataclass(frozen=True)
class LineSet:
    """Identical lines as the [moorings] table gives them: a symmetric spread of `lines`, or one line per
    anchor given (with its fairlead)."""

    lines: int
    first_heading: float
    anchor_radius: float
    anchor_depth: float
    fairlead_radius: float
    fairlead_height: float
    line_length: float
    line_mass: float
    line_diameter: float
    line_stiffness: float
    segments: int
    anchors: tuple = ()
    fairleads: tuple = ()

    def count(self) -> int:
        return len(self.anchors) or self.lines

    def headings(self) -> np.ndarray:
        return np.radians(self.first_heading) + 2 * math.pi * np.arange(self.lines) / self.lines

    def ends(self, x0: np.ndarray, R0: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """(anchor, fairlead) of each line, world frame, for a body at x0 with orientation R0 (input frame to
        world): the points given, or the spread's (anchors about the world's z axis on the seabed)."""
        if self.anchors:
            return [(np.array(a, float), x0 + R0 @ np.array(f, float)) for a, f in zip(self.anchors, self.fairleads)]
        out = []
        for a in self.headings():
            c, s = math.cos(a), math.sin(a)
            anchor = np.array([self.anchor_radius * c, self.anchor_radius * s, -self.anchor_depth])
            out.append((anchor, x0 + R0 @ np.array([self.fairlead_radius * c, self.fairlead_radius * s, self.fairlead_height])))
        return out

    def weight_in_water(self, rho: float, g: float) -> float:
        """w, N/m: the line's weight less its buoyancy."""
        return (self.line_mass - rho * math.pi * self.line_diameter**2 / 4) * g

    def seabed_damping(self) -> float:
        """Pa s/m: a node on the seabed critically damped, 2 sqrt(k_bed m) per node (MoorDyn's usual 3e5 suits
        a heavy chain; on a light line it would be the stiffest rate of all)."""
        return 2 * math.sqrt(SEABED_STIFFNESS * self.line_mass / self.line_diameter)

    def limits(self, rho: float) -> dict[str, float]:
        """The longest MoorDyn steps its scheme (RK2) stays stable with, s: CROSSINGS of an axial wave's crossing of a
        segment (MoorDyn's CFL rule: the mass that moves along the line is its own, CaAx = 0) and SEABED_RATE over the
        seabed contact's angular frequency."""
        along = self.line_mass + LINE_DRAG[3] * rho * math.pi * self.line_diameter**2 / 4
        return {
            "axial": CROSSINGS * (self.line_length / self.segments) / math.sqrt(self.line_stiffness / along),
            "seabed": SEABED_RATE * math.sqrt(self.line_mass / (SEABED_STIFFNESS * self.line_diameter)),
        }

    def sub_step(self, rho: float, dt: float | None = None) -> float:
        """MoorDyn's time step (its dtM): the shorter of the two limits; with the body's step dt, that step cut into the
        fewest whole sub-steps within them (MoorDyn's Step takes dtM steps and then the remainder)."""
        longest = min(self.limits(rho).values())
        return longest if dt is None else dt / math.ceil(dt / longest - 1e-9)

    def input_file(self, x0: np.ndarray, R0: np.ndarray, rho: float, g: float, dt: float | None = None) -> str:
        """The MoorDyn v2 input file of the spread: anchors about the world's z axis, fairleads on a body at x0
        with orientation R0 (input frame to world); dt, the body's step, sets MoorDyn's (sub_step)."""
        rows = self.ends(x0, R0)
        for i, (anchor, fair) in enumerate(rows):
            if anchor[2] < -self.anchor_depth * (1 + 1e-9):
                raise ConfigError(
                    f"mooring anchor {i + 1} is {-anchor[2]:g} m deep, below the seabed at anchor_depth = {self.anchor_depth:g} m"
                )
            reach = float(np.linalg.norm(fair - anchor))
            if reach > REACH * self.line_length:
                raise ConfigError(f"the mooring lines cannot reach: line {i + 1}'s anchor is {reach:.4g} m from its fairlead, the line "
                                  f"{self.line_length:g} m long (at most {REACH - 1:.0%} stretch); make [moorings] line_length longer or "
                                  "anchor_radius shorter")  # fmt: skip
        points = "\n".join(f"{2 * i + 1} Fixed {a[0]:.9g} {a[1]:.9g} {a[2]:.9g} 0 0 0 0\n{2 * i + 2} Coupled {f[0]:.9g} {f[1]:.9g} {f[2]:.9g} 0 0 0 0"
                           for i, (a, f) in enumerate(rows))  # fmt: skip
        lines = "\n".join(f"{i + 1} line {2 * i + 1} {2 * i + 2} {self.line_length:.9g} {self.segments} -" for i in range(len(rows)))
        cd, ca, cd_ax, ca_ax = LINE_DRAG
        return f"""--------------------- MoorDyn Input File ------------------------------------
floatsim: {len(rows)} lines
----------------------- LINE TYPES ------------------------------------------
TypeName Diam Mass/m EA BA/-zeta EI Cd Ca CdAx CaAx
(name) (m) (kg/m) (N) (N-s/-) (N-m^2) (-) (-) (-) (-)
line {self.line_diameter:.9g} {self.line_mass:.9g} {self.line_stiffness:.9g} -1.0 0 {cd} {ca} {cd_ax} {ca_ax}
---------------------- POINTS --------------------------------
ID Attachment X Y Z Mass Volume CdA Ca
(#) (-) (m) (m) (m) (kg) (m^3) (m^2) (-)
{points}
---------------------- LINES --------------------------------------
ID LineType AttachA AttachB UnstrLen NumSegs Outputs
(#) (name) (#) (#) (m) (-) (-)
{lines}
---------------------- OPTIONS -----------------------------------------
{_dtm(self.sub_step(rho, dt))} dtM
RK2 tScheme
{SEABED_STIFFNESS:g} kbot
{self.seabed_damping():.6g} cbot
{self.anchor_depth:.9g} WtrDpth
{rho:.9g} WtrDnsty
{g:.9g} g
1.0 dtIC
200.0 TmaxIC
4.0 CdScaleIC
0.0005 threshIC
------------------------- need this line --------------------------------------
"""


def _dtm(step: float) -> str:
    """dtM as written: a hair over the sub-step, so that MoorDyn's Step over the body's step takes exactly the whole
    sub-steps (exactly dt / n, its remainder after n of them could be a rounding's worth: one more step)."""
    return f"{step * (1 + 1e-7):.9g}"


def _silenced(text: str) -> tuple[str, bool]:
    """The input with MoorDyn's per-step progress ("t = ...", on the C stdout) and output files switched off (disableOutput
    in its OPTIONS; the outputs would go to a folder removed at the end), and whether that could be done (a file without
    an OPTIONS section: its steps are silenced one by one instead, 7 us each)."""
    header = re.search(r"(?im)^-+\s*options\b.*$", text)
    if header is None:
        return text, False
    return f"{text[: header.end()]}\n1 disableOutput{text[header.end() :]}", True


def start_seconds(dt: float, segments: int, relax: float = RELAX_SECONDS) -> float:
    """The longest MoorDyn's start-up can take, s: every step of its relaxation, over every segment."""
    return relax / dt * segments * NS_PER_SEGMENT_STEP * 1e-9


def _duration(seconds: float) -> str:
    if seconds < 600:
        return f"{seconds:.3g} s"
    return f"{seconds / 60:.0f} min" if seconds < 5400 else f"{seconds / 3600:.2g} h"


def _two_digits(x: float, up: bool) -> str:
    """x to two significant digits, rounded up or down (a suggested value must itself pass)."""
    unit = 10.0 ** (math.floor(math.log10(x)) - 1)
    return f"{(math.ceil if up else math.floor)(x / unit * (1 - 1e-12 if up else 1 + 1e-12)) * unit:.2g}"


def check_start(lines: LineSet, rho: float, dt: float | None = None) -> None:
    """Refuse lines whose MoorDyn step (sub_step, within the body's step dt) would make its start-up longer than
    START_SECONDS (and the run as slow), before MoorDyn is called: one line with the step they need, the time it would
    take and what to change."""
    limits, segments = lines.limits(rho), lines.count() * lines.segments
    step = lines.sub_step(rho, dt if dt is not None and dt > 0 else None)
    seconds = start_seconds(step, segments)
    if seconds <= START_SECONDS:
        return
    floor = step * seconds / START_SECONDS  # the shortest step the budget allows with these segments
    if dt is not None and dt > 0:  # in whole sub-steps of the body's step, longer than the floor itself (at the budget's edge)
        floor = dt / max(1, math.ceil(dt / floor) - 1)
    if limits["axial"] <= limits["seabed"]:
        why = f"{CROSSINGS:g} of an axial wave's {limits['axial'] / CROSSINGS:.3g} s crossing of a {lines.line_length / lines.segments:.3g} m segment"
    else:
        why = f"{SEABED_RATE:g} over the seabed contact's angular frequency, {limits['seabed']:.3g} s for this line_mass and line_diameter"
    if limits["axial"] <= limits["seabed"] and limits["seabed"] >= floor:  # the stiffness alone can bring the step up
        stiffness = lines.line_stiffness * (limits["axial"] / floor) ** 2
        change = f"lower [moorings] line_stiffness to {_two_digits(stiffness, up=False)} N or less, or use fewer segments"
    else:  # both limits grow as sqrt(line_mass)
        heavier = _two_digits(lines.line_mass * (floor / min(limits.values())) ** 2, up=True)
        change = f"use a heavier [moorings] line_mass ({heavier} kg/m or more) or a thinner line_diameter"
    raise ConfigError(f"the mooring lines need MoorDyn steps of {step:.3g} s ({why}): MoorDyn's start-up could take up to {_duration(seconds)} "
                      f"({RELAX_SECONDS:g} s of relaxation, {RELAX_SECONDS / step:.2g} steps of {segments} segments) and every simulated second "
                      f"of the run {_duration(seconds / RELAX_SECONDS)}, "
                      f"over the {START_SECONDS:g} s allowed for the start-up (steps of {floor:.2g} s or longer); {change}")  # fmt: skip


MOORDYN_RELAX = 120.0
"""MoorDyn v2's TmaxIC where its input file gives none, s."""


def _option(options: str, names: tuple[str, ...], default: float) -> float:
    """An option's value from a MoorDyn file's OPTIONS section ("value name" lines, names in any case; the last one given)."""
    found = re.findall(rf"(?im)^\s*(\S+)\s+({'|'.join(names)})\b", options)
    try:
        return float(found[-1][0]) if found else default
    except ValueError:
        return default


def _settle(md, system, x, v) -> int:
    """MoorDyn's Init (the lines' rest shape, its relaxation: up to START_SECONDS) in a forked child, whose state this
    process then loads: a C call cannot be interrupted, a child can be ended (Ctrl-C stops it at once). MoorDyn's status.
    The scene's validation has already refused lines whose start-up would pass its budget (`check_start`)."""
    if not hasattr(os, "fork") or threading.current_thread() is not threading.main_thread():
        # in this process: where there is no fork, and off the main thread (the viewer's simulation thread), where no
        # Ctrl-C arrives and a fork would copy a process whose other threads may hold locks the child needs
        with _quiet():
            return md.Init(system, x, v)
    status, state = _init_in_child(md, system, x, v)
    if status == 0:
        with _quiet():
            md.Init_NoIC(system, x, v)  # set up as Init does, without the relaxation; then the child's state, to the bit
        md.Deserialize(system, state)
    return status


def _init_in_child(md, system, x, v) -> tuple[int, bytes]:
    """MoorDyn's Init on the child's copy of the system: its status, and its state where it succeeded."""

    def init() -> tuple[int, bytes]:
        status = md.Init(system, x, v)
        return status, (md.Serialize(system) if status == 0 else b"")

    try:
        return in_child(init, quiet=True)  # MoorDyn's progress ("t = ...") is not the parent's stdout
    except ChildDied as e:
        raise ConfigError(f"MoorDyn stopped while finding the lines' rest shape ({e})") from None


def lines_of(section) -> LineSet | None:
    """The [moorings] table's lines (None when it declares none: no spread, no anchors)."""
    if not section.lines and not section.anchors:
        return None
    return LineSet(**{f: getattr(section, f) for f in LineSet.__dataclass_fields__})


def _link_named_files(text: str, source: Path | None, into: Path) -> None:
    """Link into MoorDyn's folder each file of `source` the input names (MoorDyn reads a curve beside its input)."""
    if source is None:
        return
    for token in set(text.split()):
        found = Path(source) / token
        if "/" not in token and token not in ("lines.txt", ".", "..") and found.is_file():
            (into / token).symlink_to(found.resolve())


def line_file(scene) -> Path:
    """The scene's MoorDyn file ([moorings] line_file), found beside the scene file or from the working directory."""
    given = Path(scene.moorings.line_file)
    path = next((p for p in (Path(scene.base_dir) / given, given) if p.is_file()), None)
    if path is None:
        raise ConfigError(f"mooring file not found: {scene.moorings.line_file}")
    return path


def check_lines(scene, x0: np.ndarray, R0: np.ndarray) -> None:
    """The lines' own checks with the body at x0, R0 (input frame to world): a file that is there, anchors on the seabed
    that the lines reach. A ConfigError for the first that fails; cheap, so made before any solve that needs the lines."""
    if scene.moorings.line_file:
        path = line_file(scene)
        try:
            text = path.read_text()
        except (OSError, UnicodeDecodeError) as e:
            raise ConfigError(f"mooring file {scene.moorings.line_file}: cannot be read ({e})") from None
        check_input(text, f"mooring file {scene.moorings.line_file}")
    elif (spread := lines_of(scene.moorings)) is not None:
        spread.input_file(np.asarray(x0, float), R0, scene.fluid.rho, scene.fluid.g)


class Moorings:
    """The scene's mooring lines in MoorDyn, coupled to one body. `load` is the wrench to hold over the
    next step; `advance` moves the lines over it. Close it (or use `with`) to free MoorDyn."""

    def __init__(self, text: str, x0: np.ndarray, R0: np.ndarray, u0: np.ndarray, omega0: np.ndarray, t0: float = 0.0,
                 at: np.ndarray | None = None, start: tuple | None = None, bodies: list | None = None, owner=None,
                 folder: Path | None = None):  # fmt: skip
        """`text`: a MoorDyn v2 input file's content; the body at x0, R0 (body to world) moving at u0, omega0. `at`: the
        lines settle with the body's centre of mass there instead (the fairleads still those of x0: a file's are where
        the body starts), as the rest pose's stiffness asks. `start`: ((k, 3) positions, (k, 3) velocities) of the
        coupled points to settle from instead (the lines alone, lines/lines_alone.py). `bodies`: several bodies' (x, R, u, omega) at
        the start, and `owner`: the body of each Coupled point (indices into `bodies`, or 'nearest': the body whose centre
        starts nearest it); x0, R0, u0, omega0 are then the first body's. `folder`: where the file came from, for the
        files it names (a nonlinear stiffness's curve)."""
        md = moordyn()
        self._md = md
        self._folder = tempfile.TemporaryDirectory(prefix="floatsim-moordyn-")  # MoorDyn reads a file and writes its outputs beside it
        path = Path(self._folder.name) / "lines.txt"
        _link_named_files(text, folder, path.parent)
        text, self._silent = _silenced(coupled_bodies_as_points(text))
        path.write_text(text)
        with _quiet():
            self._system = md.Create(str(path))
        if self._system is None:
            raise ConfigError("MoorDyn could not read the mooring input (see its messages above)")
        md.SetVerbosity(self._system, md.LEVEL_ERR)
        points = [md.GetPoint(self._system, i + 1) for i in range(md.GetNumberPoints(self._system))]
        self._fairleads = [p for p in points if md.GetPointType(p) == md.POINT_TYPE_COUPLED]
        if not self._fairleads or md.NCoupledDOF(self._system) != 3 * len(self._fairleads):
            self.close()
            raise ConfigError("the mooring input must couple the body through 'Coupled' points (its fairleads) and nothing else")
        world = np.array([md.GetPointPos(p) for p in self._fairleads], float)
        self.bodies = [(np.asarray(x0, float), np.asarray(R0, float), u0, omega0)] if bodies is None else list(bodies)
        try:
            self.owner = self._owners(world, owner)
        except ConfigError:
            self.close()
            raise
        """(k,) the body each fairlead is on (0 for one body)."""
        self.r_body = np.array([(w - self.bodies[b][0]) @ self.bodies[b][1] for w, b in zip(world, self.owner)]).reshape(-1, 3)
        """(k, 3) the fairleads in their body's frame, m."""
        self._lines = [md.GetLine(self._system, i + 1) for i in range(md.GetNumberLines(self._system))]
        try:
            self._check_input(text, [p for p in points if md.GetPointType(p) == md.POINT_TYPE_FIXED])
        except ConfigError:
            self.close()
            raise
        x0 = x0 if at is None else np.asarray(at, float)
        if start is not None:
            x, v = np.ravel(start[0]), np.ravel(start[1])
        elif bodies is not None:
            x, v = self._many_kinematics(self.bodies)
        else:
            x, v = self._kinematics(x0, self.r_body @ R0.T, u0, omega0)
        status = _settle(md, self._system, x, v)
        if status:
            self.close()
            raise ConfigError(f"MoorDyn could not find the lines' rest shape (error {status})")
        md.SetVerbosity(self._system, md.LEVEL_NONE)  # a step's failure is said in one line below, not in MoorDyn's two
        try:  # the wrapper's own call, without moordyn.Step's copies of the arrays into lists
            from cmoordyn import step
        except ImportError:
            step = md.Step
        self._step = step
        self.t = float(t0)
        self.seconds = 0.0
        """Wall time spent in MoorDyn's steps so far, s (the benchmark's split)."""
        self._text = text
        self.energy = None
        """line_energy.LineEnergy once `track_energy` is called: the lines' stored energy read from MoorDyn's nodes."""
        self.work_in = self.dissipated = 0.0
        """Work the fairleads have done on the lines and energy the lines have dissipated since `track_energy`, J."""
        self._forces = np.array([md.GetPointForce(p) for p in self._fairleads], float)  # at t, on the fairleads
        self.loads = self._wrenches(self._forces, [b[1] for b in self.bodies])
        """(bodies, 6) the lines' force and moment about each body's centre of mass, world frame, N and N m."""
        self.load = self.loads[0]
        """(6,) the lines' force and moment about the centre of mass on the (first) body, world frame, N and N m."""

    def track_energy(self) -> None:
        """Count, from now on, the work the fairleads do on the lines (`work_in`) and the energy the lines dissipate
        (`dissipated`; `energy_now`): a few hundred MoorDyn calls a step, so only when asked."""

        self.energy = LineEnergy(self._md, self._system, self._lines, read_spec(self._text))
        self.work_in = self.dissipated = 0.0
        self._power, self._reached = self.energy.dissipation(), None

    def _owners(self, world: np.ndarray, owner) -> np.ndarray:
        """The body of each Coupled point: all the first's, the ones given, or each the nearest's."""
        k = len(world)
        if owner is None:
            return np.zeros(k, int)
        if isinstance(owner, str) and owner == "nearest":
            centres = np.array([b[0] for b in self.bodies])
            return np.argmin(np.linalg.norm(world[:, None, :] - centres[None, :, :], axis=2), axis=1)
        owner = np.asarray(owner, int)
        if len(owner) != k:
            raise ConfigError(f"[moorings] attach names {len(owner)} bodies; the mooring file has {k} Coupled points (one body each, in "
                              "the file's order)")  # fmt: skip
        return owner

    def _many_kinematics(self, bodies: list) -> tuple[np.ndarray, np.ndarray]:
        """The fairleads' positions and velocities, flat, from each body's (x, R, u, omega)."""
        pos, vel = np.empty((len(self.owner), 3)), np.empty((len(self.owner), 3))
        for b, (x, R, u, omega) in enumerate(bodies):
            mine = self.owner == b
            lever = self.r_body[mine] @ np.asarray(R).T
            pos[mine], vel[mine] = x + lever, u + np.cross(omega, lever)
        return pos.ravel(), vel.ravel()

    def _wrenches(self, forces: np.ndarray, Rs: list) -> np.ndarray:
        """(bodies, 6) each body's share of the fairleads' forces, about its centre of mass."""
        out = np.zeros((len(Rs), 6))
        for b, R in enumerate(Rs):
            mine = self.owner == b
            if mine.any():
                out[b] = np.concatenate([forces[mine].sum(axis=0), _moment(self.r_body[mine] @ np.asarray(R).T, forces[mine])])
        return out

    def advance_bodies(self, bodies: list, dt: float) -> np.ndarray:
        """Move the lines from self.t over dt with every fairlead on its body, each body's (x, R, u, omega) at self.t; return
        each body's wrench to hold over the step (bodies, 6): the mean of the pull at both ends (as `advance`)."""
        Rs = [b[1] for b in bodies]
        now = self._wrenches(self._forces, Rs)
        self.pull(*self._many_kinematics(bodies), dt)
        self.loads = self._wrenches(self._forces, Rs)
        self.load = self.loads[0]
        return 0.5 * (now + self.loads)

    def _check_input(self, text: str, anchors: list) -> None:
        """What scene validation checks of a spread, for a MoorDyn file: anchors in the water, and a start-up within
        START_SECONDS at the file's dtM and TmaxIC (a file without dtM lets MoorDyn pick its step: not checked)."""
        md = self._md
        for i, p in enumerate(anchors):
            z = md.GetPointPos(p)[2]
            if z > SURFACE:
                raise ConfigError(f"mooring anchor (Fixed point) {i + 1} is {z:g} m above the water: MoorDyn would take its line as submerged; "
                                  "put it at or below z = 0")  # fmt: skip
        options = re.split(r"(?im)^-+\s*options\b.*$", text)[-1]
        dt, relax = _option(options, ("dtm", "dt"), math.inf), _option(options, ("tmaxic", "ictmax"), MOORDYN_RELAX)
        segments = sum(md.GetLineN(line) for line in self._lines)
        if math.isfinite(dt) and (seconds := start_seconds(dt, segments, relax)) > START_SECONDS:
            raise ConfigError(f"the mooring input's MoorDyn step dtM = {dt:g} s over {segments} segments: its start-up could take "
                              f"{_duration(seconds)} ({relax:g} s of relaxation, TmaxIC), over the {START_SECONDS:g} s allowed; "
                              "raise dtM or lower TmaxIC in the mooring file, or use fewer segments")  # fmt: skip

    @classmethod
    def of_scene(cls, scene, x0, R0, u0, omega0, at=None) -> Moorings | None:
        """The scene's lines with the body at x0, R0 moving at u0, omega0 (`at`: settled with it there, a file's
        fairleads still those at x0)."""
        m = scene.moorings
        if m.line_file:
            path = line_file(scene)
            return cls(path.read_text(), x0, R0, u0, omega0, at=at, folder=path.parent).counting(m.energy)
        spread = lines_of(m)
        if spread is None:
            return None
        q = np.asarray(scene.initial.orientation, float)

        text = spread.input_file(
            np.asarray(x0, float), quat_to_matrix(q / np.linalg.norm(q)), scene.fluid.rho, scene.fluid.g, scene.step.dt
        )
        return cls(text, x0, R0, u0, omega0, at=at).counting(m.energy)

    def counting(self, energy: bool) -> Moorings:
        """Self, its energy tracked if `energy` ([moorings] energy); closed if it cannot be."""
        if energy:
            try:
                self.track_energy()
            except ConfigError:
                self.close()
                raise
        return self

    def energy_now(self) -> tuple[float, float] | tuple:
        """(E_lines, D_lines): the energy the lines store now and have dissipated, J; () when not counted."""
        if self.energy is None:
            return ()
        stored = self.energy.stored()
        return (float(sum(stored.values())), self.dissipated)

    def _kinematics(self, x, lever, u, omega) -> tuple[np.ndarray, np.ndarray]:
        """The fairleads' positions and velocities, flat, from the body's pose and twist and their (k, 3) world levers."""
        return (x + lever).ravel(), (u + lever @ skew(omega).T).ravel()  # u + omega x lever, row by row

    def _wrench(self, forces: np.ndarray, R: np.ndarray) -> np.ndarray:
        return np.concatenate([forces.sum(axis=0), _moment(self.r_body @ R.T, forces)])

    def pull(self, pos: np.ndarray, vel: np.ndarray, dt: float) -> np.ndarray:
        """Move the lines from self.t over dt with the fairleads at pos and moving at vel (flat, (3 k,), world); return
        their pull at t + dt, (k, 3), now self's. The per-step call of a moored run: nothing else is built."""
        started = time.perf_counter()
        try:
            if self._silent:
                ahead = self._step(self._system, pos, vel, self.t, dt)
            else:
                with _quiet():
                    ahead = self._step(self._system, pos, vel, self.t, dt)
        except RuntimeError:  # MoorDyn found NaN in its nodes: its own step was too long for the lines
            ahead = (math.nan,)
        self.seconds += time.perf_counter() - started
        if not math.isfinite(sum(ahead)):
            raise SimulationDiverged(f"the mooring lines (MoorDyn) diverged at t = {self.t:g} s: try a smaller time step or more segments "
                                     f"(a mooring file's dtM: at most {CROSSINGS:g} of an axial wave's crossing of a segment, sqrt(mass / EA) per metre)")  # fmt: skip
        ahead = np.array(ahead, float).reshape(-1, 3)
        if self.energy is not None:  # MoorDyn moves each fairlead at vel over the step (the lines pull back with -force), from
            # pos: a jump from where its last step took it, pos + vel dt to second order, does work too
            jump = 0.0 if self._reached is None else float(np.sum(self._forces.ravel() * (pos - self._reached)))
            self.work_in -= jump + 0.5 * dt * float(np.sum((self._forces + ahead) * np.reshape(vel, (-1, 3))))
            self._reached = pos + dt * np.asarray(vel)
            power = self.energy.dissipation()
            self.dissipated += 0.5 * dt * (self._power + power)
            self._power = power
        self._forces, self.t = ahead, self.t + dt
        return self._forces

    def settle(self, R: np.ndarray) -> None:
        """`load`: the pull now on the body with orientation R (after steps taken with `pull`)."""
        self.load = self._wrench(self._forces, R)

    def advance(self, x, R, u, omega, dt: float) -> np.ndarray:
        """Move the lines from self.t over dt with the fairleads at the body's pose and twist at self.t;
        return the wrench to hold over that step (the mean of the pull at both ends)."""
        lever = self.r_body @ R.T
        now = self._forces
        ahead = self.pull(*self._kinematics(x, lever, u, omega), dt)
        later, turn_later = ahead.sum(axis=0), _moment(lever, ahead)
        self.load = np.concatenate([later, turn_later])
        return np.concatenate([0.5 * (now.sum(axis=0) + later), 0.5 * (_moment(lever, now) + turn_later)])

    def lines(self) -> list[np.ndarray]:
        """Each line's node positions, (segments + 1, 3), world frame, m: anchor end first."""
        md = self._md
        return [np.array([md.GetLineNodePos(ln, i) for i in range(md.GetLineN(ln) + 1)], float) for ln in self._lines]

    def line_tensions(self) -> list[np.ndarray]:
        """Each line's tension at its nodes, (segments + 1,), N, anchor end first (MoorDyn's node tension: the
        viewer colours the lines by it)."""
        md = self._md
        return [np.linalg.norm([md.GetLineNodeTen(ln, i) for i in range(md.GetLineN(ln) + 1)], axis=1) for ln in self._lines]

    def end_forces(self) -> tuple[np.ndarray, np.ndarray]:
        """((lines,) at end A, (lines,) at end B): the magnitude of the net force on each line's end nodes, N: what
        OpenFAST's MoorDyn reports as AnchTen and FairTen (the end segment's tension with the half segment lumped at the
        node: GetLineFairTen, the segment's alone, is lower by about its weight's share)."""
        md = self._md
        ends = [
            (np.linalg.norm(md.GetLineNodeForce(ln, 0)), np.linalg.norm(md.GetLineNodeForce(ln, md.GetLineN(ln)))) for ln in self._lines
        ]
        return np.array([a for a, _ in ends]), np.array([b for _, b in ends])

    def fairlead_tensions(self) -> np.ndarray:
        """(k,) the magnitude of each fairlead's pull, N."""
        return np.linalg.norm(self._forces, axis=1)

    def close(self) -> None:
        if getattr(self, "_system", None) is not None:
            with _quiet():
                self._md.Close(self._system)
            self._system = None
        if getattr(self, "_folder", None) is not None:
            self._folder.cleanup()
            self._folder = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        try:
            self.close()
        except Exception:  # noqa: BLE001 - at interpreter shutdown MoorDyn's module may be gone already
            pass


def rest_pull(scene, x: np.ndarray, R: np.ndarray) -> np.ndarray:
    """(3,) the scene's lines' summed pull on the body held still at x (its centre of mass) with orientation R (input
    frame to world), N, world frame: each line of a spread or of anchors given as an elastic catenary on the seabed
    (sim.lines.catenary, MoorDyn's rest shape to its discretisation); a MoorDyn file's lines from MoorDyn's own start-up."""

    spread = lines_of(scene.moorings)
    if spread is not None and not scene.moorings.line_file:
        rho, g = scene.fluid.rho, scene.fluid.g
        w, total = spread.weight_in_water(rho, g), np.zeros(3)
        for anchor, fair in spread.ends(np.asarray(x, float), R):
            gap = (anchor - fair)[:2]
            span = float(np.hypot(*gap))
            H, V = catenary(span, float(fair[2] - anchor[2]), spread.line_length, w, spread.line_stiffness)
            total += [H * gap[0] / span, H * gap[1] / span, -V]
        return total
    start = np.asarray(scene.initial.position, float)  # (a file's fairleads are where the body starts: held at x, they move)
    lines = Moorings.of_scene(scene, start, R, np.zeros(3), np.zeros(3), at=np.asarray(x, float))
    if lines is None:
        return np.zeros(3)
    with lines:
        return lines.load[:3].copy()


def moored(scene) -> bool:
    """Whether the scene has mooring lines (a spread, anchor points or a MoorDyn file)."""
    return bool(scene.moorings.lines or scene.moorings.line_file or scene.moorings.anchors)

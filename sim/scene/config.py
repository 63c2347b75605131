"""Scene configuration: TOML presets, overrides and validation, the one place bad input becomes a clear error.

Each table of a scene ([body], [fluid], [initial], [step]) is a frozen dataclass generated from its
parameter declarations (`parameters.Param`); [fluid] also holds every force term's own parameters
(`forces.TERMS`), so a new term's coefficient is a scene key, a flag and a control at once.
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from sim.bodies.body import UNITS
from sim.bodies.surface import FORCE_MODELS
from sim.control.laws import CONTROLLERS
from sim.dynamics.integrators import INTEGRATORS
from sim.dynamics.joints import JOINTS
from sim.errors import ConfigError
from sim.hydro.forces import TERMS
from sim.limits import (
    JOINT_DOFS,
    NS_PER_SAMPLE_STEP,
    NS_PER_SAMPLE_STEP_WAVES,
    NS_PER_SAMPLE_STEP_WAVES_DRAG,
    Cost,
    check_cost,
    check_samples,
)
from sim.lines.moorings import SURFACE, check_start, lines_of, moored
from sim.parameters import Param
from sim.scene.apart import check_apart
from sim.scene.farm import expand
from sim.scene.gauges import Gauge, check_gauges, parse_gauges
from sim.water.records import components as record_components
from sim.water.records import measured, peak_period
from sim.water.seas import ramp_seconds, wavenumber

SCENES_DIR = Path(__file__).resolve().parents[2] / "assets" / "scenes"

# The declaration tables keep one parameter to a line or two: it reads better than the formatter's layout.
# fmt: off
BODY = (
    Param("body", "shape", "cube", "Body shape: cube (side `size`), box (sides `extents`) or mesh (a watertight file)",
          kind="choice", choices=("cube", "box", "mesh"), name="body shape"),
    Param("body", "size", 1.0, "Cube side", "m", lo=1e-3, hi=1e3, name="cube size"),
    Param("body", "extents", (1.0, 1.0, 1.0), "Box sides along body x, y, z", "m", lo=1e-3, hi=1e3, kind="vector", size=3,
          name="box extents"),
    Param("body", "points_per_edge", 10, "Cube/box samples: N x N cell-centred samples per face", lo=1, hi=1000, kind="int",
          name="points per edge", label="Points per edge", gui=(1, 60, 1), live=(1, 100)),  # 60 000 samples at most in the viewer
    Param("body", "mesh", "", "Mesh file (shape mesh), relative to the scene file or the working directory", kind="text", name="mesh file"),
    Param("body", "mesh_unit", "m", "Unit of the mesh file's coordinates (scaled to metres)", kind="choice", choices=tuple(UNITS),
          name="mesh unit"),
    Param("body", "samples", 600, "Mesh: target number of samples (triangles are subdivided until there are this many)", lo=1, hi=1e6,
          kind="int", name="mesh samples", label="Samples", gui=(100, 20000, 100), live=(1, 60000)),
    Param("body", "density", 900.0, "Body density: mass / enclosed volume (ignored when mass is set)", "kg/m^3", lo=1e-3,
          hi=1e5, live=(1.0, 1e5), kind="optional", gui=(1.0, 5000.0, 1.0), label="Density"),
    Param("body", "mass", None, "Total mass; overrides density when given", "kg", lo=1e-6, hi=1e12, kind="optional"),
    Param("body", "centre_of_mass", None, "The centre of mass in the shape's own frame (a mesh: its file's coordinates in metres; "
          "unset: the surface's area centroid, a uniform shell's)", "m", lo=-1e5, hi=1e5, kind="vector", size=3, name="centre of mass"),
    Param("body", "inertia", None, "Principal moments of inertia about the centre of mass, along the shape's own axes "
          "(unset: a uniform shell's)", "kg m^2", lo=0.0, lo_open=True, hi=1e16, kind="vector", size=3, name="moments of inertia"),
)
FLUID = (
    Param("fluid", "rho", 1000.0, "Water density", "kg/m^3", lo=0.0, hi=1e5, name="water density rho"),
    Param("fluid", "g", 9.81, "Gravitational acceleration", "m/s^2", lo=0.0, hi=1e3, name="gravity g"),
    Param("fluid", "forces", "points", "How water forces are integrated: points (over the samples, the report's model), cells (the samples "
          "with each cell clipped at the water line: continuous wetting) or panels (exactly over the mesh triangles clipped at the water line)", kind="choice", choices=FORCE_MODELS, name="force model", label="Force model", gui=()),
    Param("fluid", "radiation", "none", "Radiation: none (the report's water) or bem (added mass and radiation damping from a "
          "boundary-element solve about the rest pose, Cummins' equation)", kind="choice", choices=("none", "bem"), label="Radiation", gui=()),
    Param("fluid", "hydro", "nonlinear", "Hydrostatics and Froude-Krylov force: nonlinear (the exact wet surface at each instant) or "
          "linear (a stiffness matrix and the undisturbed wave's pressure over the wet surface at rest, WEC-Sim's default: "
          "fast in many-component seas; scenes of several bodies)", kind="choice", choices=("nonlinear", "linear")),
    Param("fluid", "bem_min_period", None, "Radiation: the shortest wave period of the BEM solve's frequency grid (unset: waves half as "
          "long as the body); below a gap's sloshing resonance (a float around a spar) it keeps the solve clear of it", "s", lo=0.0,
          lo_open=True, hi=1e3, kind="optional"),
    Param("fluid", "bem_max_period", None, "Radiation: the longest wave period of the BEM solve's frequency grid, where that is longer "
          "than its own (waves 100 times the body's length): a body on a soft spring swings slower than that", "s", lo=0.0, lo_open=True,
          hi=1e4, kind="optional"),
    Param("fluid", "bem_file", "", "Radiation: the bodies' coefficients from a file instead of a Capytaine solve: WAMIT's output "
          "(.out), WAMIT's numeric files (.1 with its .3 beside it), a Capytaine dataset (.nc) or floatsim's own (.npz), told by "
          "their content; one body per "
          "[[bodies]] entry, relative to the scene file or the working directory (docs/own-case.md)", kind="text", name="BEM file"),
    *(p for term in TERMS for p in term.params),
)
INITIAL = (
    Param("initial", "position", (0.0, 0.0, 0.0), "Centre of mass, world frame", "m", lo=-1e7, hi=1e7, kind="vector", size=3,
          name="initial position", flag=False),
    Param("initial", "orientation", (1.0, 0.0, 0.0, 0.0), "Body-to-world rotation as a unit quaternion (w, x, y, z)", lo=-1.0, hi=1.0,
          kind="vector", size=4, name="initial orientation q0", flag=False),
    Param("initial", "velocity", (0.0, 0.0, 0.0), "Centre-of-mass velocity, world frame", "m/s", lo=-1e4, hi=1e4, kind="vector", size=3,
          name="initial velocity u0", flag=False),
    Param("initial", "omega", (0.0, 0.0, 0.0), "Angular velocity, world frame", "rad/s", lo=-1e3, hi=1e3, kind="vector", size=3,
          name="initial angular velocity omega0", label="Initial ω", flag=False, gui=()),
)
STEP = (
    Param("step", "integrator", "implicit", "Time integrator", kind="choice", choices=tuple(INTEGRATORS), label="Integrator", gui=()),
    Param("step", "dt", 0.005, "Time step (the output interval for the adaptive methods)", "s", lo=1e-7, hi=1.0, live=(1e-5, 1.0),
          gui=(0.0005, 0.05, 0.0005), label="Time step"),
    Param("step", "t_end", 30.0, "Simulated duration", "s", lo=0.0, hi=1e7),
    Param("step", "rtol", 1e-8, "Relative tolerance of the adaptive methods", lo=0.0, lo_open=True, hi=1.0),
    Param("step", "atol", 1e-10, "Absolute tolerance of the adaptive methods", lo=0.0, lo_open=True, hi=1e3),
)
WAVES = (
    Param("waves", "kind", "still", "The sea: still water, regular (Airy) waves, an irregular JONSWAP sea, or a measured record of "
          "the elevation at a point (record)", kind="choice", choices=("still", "regular", "jonswap", "record"), name="waves", flag_name="waves", label="Waves", gui=()),
    Param("waves", "height", 1.0, "Regular waves: crest-to-trough height H", "m", lo=0.0, hi=30.0, name="wave height", flag_name="wave_height",
          label="Height", gui=(0.0, 4.0, 0.05)),
    Param("waves", "period", 8.0, "Regular waves: period T", "s", lo=0.0, lo_open=True, hi=60.0, live=(0.5, 60.0), name="wave period",
          flag_name="wave_period", label="Period", gui=(1.0, 20.0, 0.1)),
    Param("waves", "direction", 0.0, "Direction the waves travel to, degrees from +x", "deg", lo=-360.0, hi=360.0, name="wave direction",
          flag_name="wave_direction", label="Direction", gui=(-180.0, 180.0, 1.0)),
    Param("waves", "hs", 2.0, "JONSWAP: significant wave height Hs = 4 sqrt(m0)", "m", lo=0.0, hi=30.0, label="Hs", gui=(0.0, 8.0, 0.05)),
    Param("waves", "tp", 10.0, "JONSWAP: peak period Tp", "s", lo=0.0, lo_open=True, hi=60.0, live=(1.0, 60.0), label="Tp", gui=(2.0, 25.0, 0.1)),
    Param("waves", "gamma", 3.3, "JONSWAP: peak enhancement gamma (1: Pierson-Moskowitz)", lo=1.0, hi=10.0),
    Param("waves", "components", 64, "JONSWAP: number of wave components", lo=1, hi=4096, kind="int", name="wave components",
          flag_name="wave_components"),
    Param("waves", "seed", 0, "JONSWAP: random seed of the phases and frequencies (the same seed, the same sea)", lo=0, hi=2**32 - 1, kind="int"),
    Param("waves", "depth", None, "Water depth h (unset: deep water)", "m", lo=0.0, lo_open=True, hi=1e5, kind="optional"),
    Param("waves", "spreading", 0.0, "JONSWAP: directional spreading exponent s of cos^(2s) (0: long-crested)", lo=0.0, hi=100.0),
    Param("waves", "ramp", None, "Time over which the sea grows from still water at t = 0 to full height (a half-cosine, as WEC-Sim's "
          "ramp): every wave load and the drawn surface, so a body is not kicked by waves at full height (unset: 3.5 periods of the sea, "
          "the regular period or JONSWAP's Tp; 0: full height from the start)", "s", lo=0.0, hi=1e4, kind="optional", name="wave ramp",
          flag_name="wave_ramp"),
    Param("waves", "record", "", "Measured sea: a CSV of time (s) and surface elevation (m) at record_point, equal steps, relative to "
          "the scene file or the working directory; taken apart by FFT into components travelling in `direction` (docs/physics.md)",
          kind="text", name="wave record", flag_name="wave_record"),
    Param("waves", "record_point", (0.0, 0.0), "Measured sea: where the record was taken (x, y), world frame", "m", lo=-1e7, hi=1e7,
          kind="vector", size=2, flag_name="wave_record_point"),
    Param("waves", "cutoff_period", None, "Measured sea: the shortest period kept (unset: a quarter of the record's peak period; "
          "components under 1e-6 of the largest are left out; at most 4096 remain)", "s", lo=0.0, lo_open=True, hi=1e3, kind="optional", flag_name="wave_cutoff_period"),
    Param("waves", "drift", False, "The mean and slow drift force of the waves (from the BEM solve's far field, Newman's approximation "
          "in an irregular sea; needs radiation = bem; several bodies: joined in one tree; docs/physics.md)", kind="switch",
          name="wave drift", flag_name="wave_drift", label="Drift", gui=()),
    Param("waves", "diffraction", None, "The linear diffraction force of the waves the body scatters (from the BEM solve; needs "
          "radiation = bem; unset: on wherever radiation is bem)", kind="switch", label="Diffraction", gui=()),
)
WATER = (
    Param("water", "current", (0.0, 0.0), "Uniform current (u, v), world frame: the water and its waves move with it", "m/s", lo=-20.0,
          hi=20.0, kind="vector", size=2, name="current", label="Current (u, v)", gui=()),
)
MOORINGS = (
    Param("moorings", "lines", 0, "Mooring lines on MoorDyn (the .[moorings] extra): a symmetric spread of this many identical lines "
          "(0: none)", lo=0, hi=64, kind="int", name="mooring lines"),
    Param("moorings", "line_file", "", "A MoorDyn v2 input file instead of the spread: its Coupled points are the fairleads (world "
          "positions at the starting pose), relative to the scene file or the working directory", kind="text", name="mooring file"),
    Param("moorings", "first_heading", 0.0, "Direction of the first line's anchor from the body, degrees from +x (the others evenly "
          "around)", "deg", lo=-360.0, hi=360.0),
    Param("moorings", "anchor_radius", 20.0, "Horizontal distance of the anchors from the world's vertical axis (x = y = 0)", "m", lo=0.0, hi=1e5),
    Param("moorings", "anchor_depth", 10.0, "Depth of the seabed the anchors sit on (MoorDyn's water depth)", "m", lo=0.0, lo_open=True, hi=1e4),
    Param("moorings", "fairlead_radius", 0.5, "Horizontal distance of the fairleads from the centre of mass (starting pose)", "m", lo=0.0, hi=1e4),
    Param("moorings", "fairlead_height", 0.0, "Height of the fairleads above the centre of mass (starting pose)", "m", lo=-1e4, hi=1e4),
    Param("moorings", "line_length", 25.0, "Unstretched length of each line", "m", lo=0.0, lo_open=True, hi=1e5),
    Param("moorings", "line_mass", 1.0, "Mass per unit length of each line", "kg/m", lo=0.0, lo_open=True, hi=1e5),
    Param("moorings", "line_diameter", 0.01, "Volume-equivalent diameter (buoyancy and drag)", "m", lo=0.0, lo_open=True, hi=100.0),
    Param("moorings", "line_stiffness", 1.0e6, "Axial stiffness EA", "N", lo=0.0, lo_open=True, hi=1e13),
    Param("moorings", "segments", 20, "Segments per line (lumped masses: segments + 1 nodes)", lo=1, hi=500, kind="int"),
    Param("moorings", "anchors", (), "Anchor points instead of the spread's, world frame (one line each, on or above the seabed at anchor_depth)", "m",
          lo=-1e5, hi=1e5, kind="points", size=64, flag=False),
    Param("moorings", "fairleads", (), "Fairlead points for the anchors given, relative to the centre of mass in the scene's input frame "
          "(as the body is at orientation 1 0 0 0)", "m", lo=-1e4, hi=1e4, kind="points", size=64, flag=False),
    Param("moorings", "body", "", "A scene of several bodies: the name of the one the lines hold (default: the first listed)", kind="text",
          name="moored body", flag=False),
    Param("moorings", "energy", False, "Count the lines' energy: the CSV's E_lines (what they store: motion, wet weight lifted, "
          "stretch, the seabed's spring) and D_lines (what their drag, internal damping and the seabed have dissipated), read node "
          "by node from MoorDyn (a few hundred calls a step; docs/lines.md)", kind="switch", name="line energy",
          flag_name="line_energy"),
    Param("moorings", "attach", "", "A scene of several bodies with a line_file: the body each Coupled point is on, in the file's order "
          "(names separated by spaces), or 'nearest' (each on the body whose centre of mass starts nearest it); empty: all on [moorings] "
          "body. Lines may join two bodies, and several lines share an anchor", kind="text", name="mooring attachments", flag=False),
)
CONSTRAINT = (
    Param("constraint", "joint", "free", "A joint to the world (the seabed): free (none), fixed, prismatic (slides along axis, without "
          "turning), revolute (turns about axis through the pivot) or, for a [[bodies]] entry, planar (moves in the plane normal to axis "
          "and turns about it: surge, heave and pitch for axis y)", kind="choice", choices=JOINTS, label="Joint", gui=()),
    Param("constraint", "axis", (0.0, 0.0, 1.0), "The joint's axis, world frame (normalised)", lo=-1e3, hi=1e3, kind="vector", size=3,
          name="joint axis"),
    Param("constraint", "pivot", (0.0, 0.0, 0.0), "A point on a revolute joint's axis, from the starting centre of mass, world frame", "m",
          lo=-1e5, hi=1e5, kind="vector", size=3, name="joint pivot"),
    Param("constraint", "start", None, "A [[bodies]] joint's coordinate at the start, from the pose the scene gives it (the pose the BEM "
          "solve, the linear hydrostatics and the take-off spring are about): a release from a displaced pose, a decay test (m for a slide, "
          "rad for a hinge, a planar joint's turn)", lo=-1e5, hi=1e5, kind="optional", name="joint start"),
    Param("constraint", "pto_stiffness", 0.0, "Power take-off spring on the joint's coordinate (N/m sliding, N m/rad turning), about the "
          "starting pose; negative with controller reactive (or pi: its integral gain)", lo=-1e9, hi=1e9, name="PTO stiffness"),
    Param("constraint", "pto_damping", 0.0, "Power take-off damper on the joint's coordinate (N s/m sliding, N m s/rad turning): the "
          "power it absorbs is the CSV's P_pto", lo=0.0, hi=1e9, live=(0.0, 1e7), name="PTO damping", label="PTO damping",
          gui=(0.0, 20000.0, 10.0)),
    Param("constraint", "controller", "passive", "The take-off's control (docs/control.md): passive (its spring and damper), reactive "
          "(the same, a negative spring allowed), latching (held latch_time at each stop), declutching (no force for declutch_time after "
          "each stop) or pi (on the rate: Kp = pto_damping, Ki = pto_stiffness)", kind="choice", choices=CONTROLLERS, label="Control",
          gui=()),
    Param("constraint", "latch_time", 0.0, "Latching control: how long the joint is held at each stop (regular waves: about (T - T_n) / 2)",
          "s", lo=0.0, hi=1e4, live=(0.0, 30.0), name="latch time", label="Latch time", gui=(0.0, 10.0, 0.01)),
    Param("constraint", "declutch_time", 0.0, "Declutching control: how long the take-off is off after each stop", "s", lo=0.0, hi=1e4,
          live=(0.0, 30.0), name="declutch time", label="Declutch time", gui=(0.0, 10.0, 0.01)),
    Param("constraint", "pto_max_force", None, "The largest force (N) or moment (N m) the take-off gives: its controller's law limited "
          "to it", lo=0.0, hi=1e12, lo_open=True, kind="optional", name="PTO force limit"),
)
FARM = (
    Param("farm", "rows", 1, "A farm: rows of copies of the scene's device (sim/scene/farm.py: the scene becomes [[bodies]] d1, d2, ...)", lo=1,
          hi=100, kind="int", flag=False),
    Param("farm", "columns", 1, "A farm: copies of the device in each row, along x", lo=1, hi=100, kind="int", flag=False),
    Param("farm", "spacing", 20.0, "A farm: the distance between neighbouring devices, along x and y", "m", lo=0.0, lo_open=True, hi=1e5,
          flag=False),
)
# fmt: on
SECTIONS = {
    "body": BODY,
    "fluid": FLUID,
    "initial": INITIAL,
    "step": STEP,
    "waves": WAVES,
    "water": WATER,
    "moorings": MOORINGS,
    "constraint": CONSTRAINT,
    "farm": FARM,
}
PARAMS = {f"{p.section}.{p.key}": p for section in SECTIONS.values() for p in section}
"""Every scene parameter by 'section.key'. Keys are unique across sections too: the viewer's commands are named by key."""
assert len({p.key for p in PARAMS.values()}) == len(PARAMS), "a parameter key is declared in two sections"


def _section(name: str, params: tuple[Param, ...]):
    fields = [(p.key, object, field(default=p.default, metadata={"param": p})) for p in params]
    cls = dataclasses.make_dataclass(name, fields, frozen=True)
    cls.__module__ = __name__
    cls.__doc__ = f"The [{params[0].section}] table of a scene: " + ", ".join(f"{p.key} ({p.unit or p.kind})" for p in params) + "."
    return cls


BodyConfig = _section("BodyConfig", BODY)
FluidConfig = _section("FluidConfig", FLUID)
InitialConfig = _section("InitialConfig", INITIAL)
StepConfig = _section("StepConfig", STEP)
WavesConfig = _section("WavesConfig", WAVES)
WaterConfig = _section("WaterConfig", WATER)
MooringsConfig = _section("MooringsConfig", MOORINGS)
FarmConfig = _section("FarmConfig", FARM)
ConstraintConfig = _section("ConstraintConfig", CONSTRAINT)
SECTION_TYPES = {
    "body": BodyConfig,
    "fluid": FluidConfig,
    "initial": InitialConfig,
    "step": StepConfig,
    "waves": WavesConfig,
    "water": WaterConfig,
    "moorings": MooringsConfig,
    "constraint": ConstraintConfig,
    "farm": FarmConfig,
}


ENTRY_SECTIONS = ("body", "initial", "constraint")
"""The tables a [[bodies]] entry gives flat (their keys are unique), beside its name, parent, force model and loads."""
BODY_LOADS = tuple(dataclasses.replace(p, default=None, kind="optional") for term in TERMS for p in term.params)
"""The force terms' parameters ([fluid] damping, drag_coefficient, and any term's registered in forces.TERMS): a
[[bodies]] entry may give its own, flat, for its body alone (None: the scene's [fluid] value)."""
BodyLoadsConfig = _section("BodyLoadsConfig", BODY_LOADS)


@dataclass(frozen=True)
class BodyEntry:
    """One of a scene's [[bodies]]: a body, its starting pose and its joint to its parent."""

    name: str
    parent: str = "world"
    """The body it is jointed to (listed before it), or 'world' (the seabed)."""
    body: BodyConfig = field(default_factory=BodyConfig)
    initial: InitialConfig = field(default_factory=InitialConfig)
    constraint: ConstraintConfig = field(default_factory=ConstraintConfig)
    """Its joint to the parent: free (world only), fixed (welded), prismatic or revolute, with the take-off;
    `axis` in world axes at the start, `pivot` from its starting centre of mass."""
    forces: str | None = None
    """Its own force model (None: the scene's [fluid] forces)."""
    fluid: BodyLoadsConfig = field(default_factory=BodyLoadsConfig)
    """Its own values of the force terms' parameters (BODY_LOADS; each None: the scene's [fluid] value)."""

    def fluid_of(self, fluid: FluidConfig) -> FluidConfig:
        """The scene's [fluid] table as this body feels it: its own force model and terms' parameters in."""
        own = {k: v for k, v in dataclasses.asdict(self.fluid).items() if v is not None}
        return dataclasses.replace(fluid, forces=self.forces or fluid.forces, **own)


@dataclass(frozen=True)
class SceneConfig:
    name: str = "custom"
    description: str = ""
    body: BodyConfig = field(default_factory=BodyConfig)
    fluid: FluidConfig = field(default_factory=FluidConfig)
    initial: InitialConfig = field(default_factory=InitialConfig)
    step: StepConfig = field(default_factory=StepConfig)
    waves: WavesConfig = field(default_factory=WavesConfig)
    water: WaterConfig = field(default_factory=WaterConfig)
    moorings: MooringsConfig = field(default_factory=MooringsConfig)
    constraint: ConstraintConfig = field(default_factory=ConstraintConfig)
    farm: FarmConfig = field(default_factory=FarmConfig)
    """[farm]: copies of the device on a grid; validation lays them out as [[bodies]] and sets it back to one (scene/farm.py)."""
    bodies: tuple[BodyEntry, ...] = ()
    """[[bodies]]: several bodies on joints (system/tree.py); empty: the one body of [body], [initial], [constraint]."""
    gauges: tuple[Gauge, ...] = ()
    """[[gauges]]: points where the run writes the water's elevation (scene/gauges.py)."""
    base_dir: str = "."
    """Folder that relative mesh paths are resolved against (the scene file's)."""

    def value(self, qualname: str):
        """A parameter's value by 'section.key'."""
        section, key = qualname.split(".")
        return getattr(getattr(self, section), key)


def available_scenes() -> list[str]:
    return sorted(p.stem for p in SCENES_DIR.glob("*.toml"))


def one_body_scenes() -> list[str]:
    """The presets of one body (the viewer, sweeps and the compiled kernels take these; [[bodies]] run headless)."""
    return [name for name in available_scenes() if not load_scene(name).bodies]


def load_scene(name_or_path: str) -> SceneConfig:
    """A preset by name (assets/scenes/NAME.toml) or a TOML file by path, validated."""
    path = Path(name_or_path)
    if path.suffix != ".toml":
        path = SCENES_DIR / f"{name_or_path}.toml"
        if not path.is_file():
            raise ConfigError(f"unknown scene '{name_or_path}'; presets: {', '.join(available_scenes())}, or a path to a .toml file")
    data = read_toml(path, "scene")
    data.setdefault("name", path.stem)
    return validate(dataclasses.replace(_from_dict(data, str(path)), base_dir=str(path.parent)))


def read_toml(path: Path, what: str) -> dict:
    """A TOML file's document; a missing or malformed file is one ConfigError line."""
    if not path.is_file():
        raise ConfigError(f"{what} file not found: {path}")
    try:
        return tomllib.loads(path.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise ConfigError(f"{path}: not valid TOML: {e}") from None
    except RecursionError:  # tomllib parses nested arrays and tables recursively
        raise ConfigError(f"{path}: nested too deeply to be a scene file") from None
    except (OSError, MemoryError) as e:
        raise ConfigError(f"{path}: cannot be read as a scene file ({type(e).__name__})") from None


def _from_dict(data: dict, where: str) -> SceneConfig:
    """A SceneConfig from a TOML document, refusing unknown keys by name."""
    known = [f.name for f in dataclasses.fields(SceneConfig) if f.name != "base_dir"]
    kwargs = {}
    for key, value in data.items():
        if key not in known:
            raise ConfigError(f"{where}: unknown key '{key}' (known: {', '.join(known)})")
        if key == "bodies":
            if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
                raise ConfigError(f"{where}: bodies must be an array of tables ([[bodies]])")
            value = tuple(_body_entry(v, f"{where} [[bodies]] #{i + 1}") for i, v in enumerate(value))
        elif key == "gauges":
            value = parse_gauges(value, where)
        elif key in SECTION_TYPES:
            if not isinstance(value, dict):
                raise ConfigError(f"{where}: [{key}] must be a table")
            params = {p.key for p in SECTIONS[key]}
            for k in value:
                if k not in params:
                    raise ConfigError(f"{where} [{key}]: unknown key '{k}' (known: {', '.join(sorted(params))})")
            value = SECTION_TYPES[key](**{k: tuple(v) if isinstance(v, list) else v for k, v in value.items()})
        kwargs[key] = value
    body, fluid = data.get("body", {}), data.get("fluid", {})
    if isinstance(body, dict) and body.get("shape") == "mesh" and not (isinstance(fluid, dict) and "forces" in fluid):
        kwargs["fluid"] = dataclasses.replace(kwargs.get("fluid", FluidConfig()), forces=MESH_FORCES)
    return SceneConfig(**kwargs)


def _body_entry(data: dict, where: str) -> BodyEntry:
    """A [[bodies]] table: name, parent, forces and the keys of [body], [initial], [constraint] and the terms', flat."""
    owner = ENTRY_KEYS
    own = {"name", "parent", "forces"}
    tables: dict[str, dict] = {name: {} for name in (*ENTRY_SECTIONS, "fluid")}
    for k, v in data.items():
        if k not in owner and k not in own:
            raise ConfigError(f"{where}: unknown key '{k}' (known: {', '.join(sorted(own | set(owner)))})")
        if k in owner:
            tables[owner[k]][k] = tuple(v) if isinstance(v, list) else v
    if not isinstance(data.get("name"), str) or not data["name"]:
        raise ConfigError(f'{where}: give the body a name (name = "float")')
    if tables["body"].get("shape") == "mesh" and "forces" not in data:
        data = {**data, "forces": MESH_FORCES}
    return BodyEntry(data["name"], data.get("parent", "world"), *(SECTION_TYPES[name](**tables[name]) for name in ENTRY_SECTIONS),
                     data.get("forces"), BodyLoadsConfig(**tables["fluid"]))  # fmt: skip


def _check_body(b, i, c, where: str = "") -> None:
    """The rules between a body's fields, its pose's and its joint's (one body, or each of [[bodies]], prefixed by `where`)."""
    if b.shape == "mesh" and not b.mesh:
        raise ConfigError(f"{where}body shape 'mesh' needs a mesh file")
    if b.mass is None and b.density is None:
        raise ConfigError(f"{where}give the body a density or a mass")
    check_samples(body_samples(b), "--samples ([body] samples)" if b.shape == "mesh" else "--points-per-edge")  # before any array is made
    if c.joint != "free" and not any(c.axis):
        raise ConfigError(f"{where}[constraint] axis must not be zero")
    if c.start is not None and c.joint not in ("prismatic", "revolute", "planar"):
        raise ConfigError(
            f"{where}[constraint] start is a joint's coordinate: it needs a prismatic, revolute or planar joint, not {c.joint!r}"
        )
    if c.joint == "planar" and (c.pto_damping or c.pto_stiffness or c.controller != "passive"):
        raise ConfigError(
            f"{where}a planar joint has three coordinates: a take-off (pto_damping, pto_stiffness, controller) acts on a prismatic or "
            "revolute one"
        )
    _check_controller(c, where)
    norm = math.sqrt(sum(q * q for q in i.orientation))
    if abs(norm - 1.0) > QUATERNION_SLACK:
        raise ConfigError(
            f"{where}initial orientation q0 must be a unit quaternion (w, x, y, z), got {i.orientation} with norm {norm:.6g} "
            f"(one within {QUATERNION_SLACK:g} of 1 is normalised)"
        )


def _check_controller(c, where: str = "") -> None:
    """A take-off's controller and its settings agree (sim/control/laws.py)."""
    if c.pto_stiffness < 0 and c.controller not in ("reactive", "pi"):
        raise ConfigError(f"{where}[constraint] pto_stiffness {c.pto_stiffness:g} < 0 needs controller = \"reactive\" (a negative spring is "
                          "reactive control)")  # fmt: skip
    if c.pto_damping < 0:
        raise ConfigError(f"{where}[constraint] pto_damping must be >= 0, got {c.pto_damping:g}")
    needs = {"latching": ("latch_time", c.latch_time), "declutching": ("declutch_time", c.declutch_time)}.get(c.controller)
    if needs and needs[1] <= 0:
        raise ConfigError(f"{where}{c.controller} control needs [constraint] {needs[0]} > 0 (regular waves: about (T - T_n) / 2)")
    if c.controller != "passive" and c.joint not in ("prismatic", "revolute"):
        raise ConfigError(f"{where}controller {c.controller!r} acts on a joint's take-off: it needs a prismatic or revolute joint, not "
                          f"{c.joint!r}")  # fmt: skip


def _validate_entries(scene: SceneConfig) -> tuple[BodyEntry, ...]:
    """Each [[bodies]] entry checked as its tables are, then the tree: unique names, parents listed first."""
    entries, seen = [], []
    for e in scene.bodies:
        if not isinstance(e.name, str) or not e.name or e.name in seen or e.name == "world":
            raise ConfigError(f"[[bodies]]: body names must be distinct and not 'world', got {e.name!r}")
        where = f"[[bodies]] {e.name}"
        if not isinstance(e.parent, str) or (e.parent != "world" and e.parent not in seen):
            raise ConfigError(f"{where}: parent {e.parent!r} is not a body listed before it (or 'world')")
        if e.forces is not None and e.forces not in FORCE_MODELS:
            raise ConfigError(f"{where}: forces must be one of {', '.join(FORCE_MODELS)}, got {e.forces!r}")
        try:
            tables = {name: dataclasses.replace(getattr(e, name), **{p.key: p.check(getattr(getattr(e, name), p.key)) for p in params})
                      for name, params in [*((n, SECTIONS[n]) for n in ENTRY_SECTIONS), ("fluid", BODY_LOADS)]}  # fmt: skip
        except ConfigError as err:
            raise ConfigError(f"{where}: {err}") from None
        if scene.fluid.hydro == "linear" and (tables["fluid"].drag_coefficient or 0.0) > 0:
            raise ConfigError(
                f'{where}: quadratic drag needs the instantaneous wet surface: with [fluid] hydro = "linear" set its drag_coefficient = 0'
            )
        _check_body(tables["body"], tables["initial"], tables["constraint"], f"{where}: ")
        if tables["constraint"].joint == "free" and e.parent != "world":
            raise ConfigError(f"{where}: a free body has no parent (give it a joint: fixed, prismatic or revolute)")
        entries.append(dataclasses.replace(e, **tables))
        seen.append(e.name)
    untouched = [f"[{name}]" for name in ENTRY_SECTIONS if getattr(scene, name) != SECTION_TYPES[name]()]
    if untouched:
        raise ConfigError(f"a scene with [[bodies]] gives each body its own shape, pose and joint: {', '.join(untouched)} (and their flags) "
                          "do not apply; set them in the [[bodies]] entries")  # fmt: skip
    if moored(scene) and scene.moorings.body not in ("", *seen):
        raise ConfigError(f"[moorings] body = {scene.moorings.body!r} is not one of the [[bodies]]: {', '.join(seen)}")
    attach = scene.moorings.attach.split()
    if attach and attach != ["nearest"]:
        if not scene.moorings.line_file:
            raise ConfigError("[moorings] attach names the bodies of a line_file's Coupled points: give a line_file")
        unknown = [name for name in attach if name not in seen]
        if unknown:
            raise ConfigError(f"[moorings] attach: {', '.join(dict.fromkeys(unknown))} is not one of the [[bodies]]: {', '.join(seen)}")
    return tuple(entries)


def validate(scene: SceneConfig, grown_by: str = "the [[bodies]] (fewer, or fewer samples each)") -> SceneConfig:
    """Check every field against its declaration, then the rules between fields; raise ConfigError
    with a one-line message on the first problem. Vectors come back as tuples of floats. `grown_by`: what the bodies'
    memory check names to lower (a farm's rows and columns)."""
    checked = {}
    for name, params in SECTIONS.items():
        section = getattr(scene, name)
        checked[name] = dataclasses.replace(section, **{p.key: p.check(getattr(section, p.key)) for p in params})
    if (farm := checked["farm"]).rows * farm.columns > 1:  # laid out as [[bodies]] once (the table goes back to one device)
        grown = f"[farm] rows and columns ({farm.rows} x {farm.columns} devices)"
        return validate(dataclasses.replace(expand(dataclasses.replace(scene, **checked), BodyEntry), farm=FarmConfig()), grown)
    _check_body(checked["body"], checked["initial"], checked["constraint"])
    if checked["fluid"].g == 0.0 and (checked["waves"].kind != "still" or checked["fluid"].radiation != "none" or moored(scene)):
        raise ConfigError("waves, radiation and mooring lines need gravity: g = 0 (a torque-free body, say) is for still water alone")
    _check_steepness(checked["waves"], checked["fluid"].g, scene.base_dir)
    gauges = check_gauges(scene.gauges, checked["waves"].kind == "record", checked["waves"].record_point)
    if checked["waves"].kind == "record" and any(checked["water"].current):
        raise ConfigError("a measured record with a current is not modelled (the record's frequencies would be met, not intrinsic): "
                          "set [water] current = [0, 0]")  # fmt: skip
    if checked["fluid"].radiation != "none" and any(checked["water"].current):
        raise ConfigError(
            "a current with radiation is not modelled (the radiation memory assumes water at rest): "
            'set [water] current = [0, 0] or [fluid] radiation = "none"'
        )
    m = checked["moorings"]
    if m.attach and not scene.bodies:
        raise ConfigError("[moorings] attach places a line_file's points on several bodies: it is for scenes of [[bodies]]")
    if len(m.anchors) != len(m.fairleads):
        raise ConfigError(f"[moorings] gives {len(m.anchors)} anchors and {len(m.fairleads)} fairleads: one of each per line")
    if m.anchors and m.lines and m.lines != len(m.anchors):
        raise ConfigError(f"[moorings] lines = {m.lines} but {len(m.anchors)} anchors: give one or the other (anchors: a line each)")
    for i, anchor in enumerate(m.anchors):
        if anchor[2] > SURFACE:
            raise ConfigError(f"[moorings] anchor {i + 1} is at z = {anchor[2]:g} m, above the water: MoorDyn would take its line as "
                              "submerged all along; put anchors at or below z = 0")  # fmt: skip
    if not m.line_file and (spread := lines_of(m)) is not None:
        check_start(spread, checked["fluid"].rho, scene.step.dt)  # before MoorDyn: its start-up cannot be cut short
    if checked["waves"].drift and checked["fluid"].radiation != "bem":
        raise ConfigError('the drift force comes from the boundary-element solve: it needs [fluid] radiation = "bem" (--radiation bem)')
    if checked["fluid"].bem_file and (checked["fluid"].radiation != "bem" or not scene.bodies):
        raise ConfigError('[fluid] bem_file is for scenes of [[bodies]] (one entry for one body) with radiation = "bem"')
    if checked["waves"].diffraction and checked["fluid"].radiation != "bem":
        raise ConfigError('diffraction comes from the boundary-element solve: it needs [fluid] radiation = "bem" (--radiation bem)')
    checked = dataclasses.replace(scene, **checked, gauges=gauges)
    if not scene.bodies and checked.constraint.start is not None:
        raise ConfigError("[constraint] start is for a [[bodies]] entry for now: one body starts where [initial] puts it")
    if not scene.bodies and checked.constraint.joint == "planar":
        raise ConfigError("[constraint] joint 'planar' is for a [[bodies]] entry: one body takes fixed, prismatic or revolute")
    if checked.fluid.hydro == "linear" and not scene.bodies:
        raise ConfigError(
            '[fluid] hydro = "linear" is for scenes of several bodies ([[bodies]]) for now: one body takes the exact wet surface'
        )
    if checked.fluid.hydro == "linear" and checked.fluid.drag_coefficient > 0:
        raise ConfigError('quadratic drag needs the instantaneous wet surface: with [fluid] hydro = "linear" set drag_coefficient = 0')
    if not scene.bodies and checked.moorings.body:
        raise ConfigError(f"[moorings] body = {checked.moorings.body!r} names one of several bodies: this scene has one ([body])")
    if not scene.bodies:
        return checked
    checked = dataclasses.replace(checked, bodies=_validate_entries(checked))
    check_apart(checked.bodies)
    check_cost(scene_cost(checked), grown_by)  # the system's dense matrices grow as the square of its degrees of freedom
    return checked


def body_samples(b) -> int:
    """The surface samples a body's table asks for (a mesh's count is near it: its triangles are split to reach it)."""
    return int(b.samples) if b.shape == "mesh" else 6 * int(b.points_per_edge) ** 2


def scene_cost(scene: SceneConfig) -> Cost:
    """The samples and degrees of freedom of a validated scene's bodies and its sea's components, and so its set-up's and
    steps' estimated time and its memory."""
    components = wave_components(scene.waves, scene.base_dir)
    fluids = [e.fluid_of(scene.fluid) for e in scene.bodies] or [scene.fluid]
    drag = any((f.drag_coefficient or 0.0) > 0 for f in fluids)
    per_step = NS_PER_SAMPLE_STEP if not components else NS_PER_SAMPLE_STEP_WAVES_DRAG if drag else NS_PER_SAMPLE_STEP_WAVES
    if not scene.bodies:
        return Cost(body_samples(scene.body), 0, components, per_step)
    dofs = sum(JOINT_DOFS[e.constraint.joint] for e in scene.bodies)
    return Cost(sum(body_samples(e.body) for e in scene.bodies), dofs, components, per_step)


def wave_components(waves, base_dir: str) -> int:
    """How many wave components the sea sums (0: still water): a record's are those its spectrum keeps."""
    if waves.kind == "still":
        return 0
    if waves.kind == "record":
        return len(record_components(*measured(waves, base_dir), waves.cutoff_period)[0])
    return 1 if waves.kind == "regular" else int(waves.components)


def diffracting(scene: SceneConfig) -> bool:
    """Whether the scene's body feels the diffraction force: in waves, with radiation from the BEM, unless switched off."""
    return scene.waves.kind != "still" and scene.fluid.radiation == "bem" and scene.waves.diffraction is not False


def points_per_edge(scene: SceneConfig) -> int:
    """N of the samples' grid: a mesh's from its sample count (6 N^2 on a cube's faces)."""
    b = scene.body
    return b.points_per_edge if b.shape != "mesh" else max(1, round(math.sqrt(b.samples / 6)))


def wave_ramp(scene: SceneConfig) -> float:
    """The wave ramp the run uses, s (water.ramp_seconds: 3.5 periods of the sea when unset)."""

    return ramp_seconds(scene.waves, scene.base_dir)


IN_EFFECT = {"waves.diffraction": diffracting, "body.points_per_edge": points_per_edge, "waves.ramp": wave_ramp}
"""Parameters whose value in effect is not simply the one written: decided by others when unset, or moot."""


def in_effect(scene: SceneConfig, qualname: str):
    """The value of a parameter the run uses (what a control shows and a share link compares)."""
    derived = IN_EFFECT.get(qualname)
    return derived(scene) if derived is not None else scene.value(qualname)


MESH_FORCES = "panels"
"""A mesh body's force model unless the scene or a flag names one. The samples' midpoint rule misses
the torque of the pressure's variation across each triangle; on a triangulation with a handedness
(its triangles laid out with a twist) those errors add up to a yaw torque that turns a body at
rest (7.6 N m on trimesh's capsule of 4096 triangles at 500 kg/m^3, shrinking as they are split); panels are exact."""

QUATERNION_SLACK = 1e-3
"""A hand-typed quaternion (four digits: 0.9659 0.2588 0 0 has norm 0.99997) this close to unit norm is
normalised, with a note (simulation.Simulation.notes); farther, it is no rotation and is refused."""

BREAKING_STEEPNESS = 1 / 7
"""H / wavelength above which a wave breaks (Michell 1893: 0.142 in deep water)."""


def _check_steepness(w, g: float, base_dir: str = ".") -> None:
    """Refuse a sea steeper than breaking: regular H / lambda, JONSWAP Hs / lambda_p, a record's 4 std(eta) / lambda_p
    (a record read in millimetres as metres is caught here). A record that cannot be read is refused too."""

    if w.kind == "still" or g == 0:
        return
    if w.kind == "record":
        dt, eta = measured(w, base_dir)
        height, period, what = 4 * float(np.std(eta)), peak_period(dt, eta, w.cutoff_period), "the record's 4 std(eta) / peak wavelength"
    else:
        height, period, what = (
            (w.height, w.period, "wave height / wavelength") if w.kind == "regular" else (w.hs, w.tp, "Hs / peak wavelength")
        )
    depth = math.inf if w.depth is None else w.depth
    wavelength = 2 * math.pi / float(wavenumber(2 * math.pi / period, g, depth))
    if height / wavelength > BREAKING_STEEPNESS:
        raise ConfigError(f"{what} = {height / wavelength:.3g} is past the breaking limit 1/7: the wave would break "
                          f"(wavelength {wavelength:.3g} m at period {period:g} s); use a smaller height or a longer period")  # fmt: skip


ENTRY_KEYS = {p.key: p.section for params in [*(SECTIONS[name] for name in ENTRY_SECTIONS), BODY_LOADS] for p in params}
"""A body's own parameters (its shape, pose, joint and terms' parameters) by key, and the table each belongs to (a term's:
'fluid', the scene-wide default's table)."""


def entry_value(scene: SceneConfig, entry: BodyEntry, key: str):
    """The value of a body's own parameter `key` (ENTRY_KEYS) in effect for the [[bodies]] `entry`: a term's parameter the
    body does not give is the scene's [fluid] one."""
    value = getattr(getattr(entry, ENTRY_KEYS[key]), key)
    return getattr(scene.fluid, key) if value is None and ENTRY_KEYS[key] == "fluid" else value


def body_own(param: Param) -> bool:
    """Whether `param` is one each body has (named BODY__key: its shape, pose, joint, terms' parameters)."""
    return ENTRY_KEYS.get(param.key) == param.section


def body_names(scene: SceneConfig) -> list[str]:
    """The scene's bodies by name: its [[bodies]], or the one body of a one-body scene, named `body`."""
    return [e.name for e in scene.bodies] if scene.bodies else ["body"]


def with_overrides(scene: SceneConfig, **changes) -> SceneConfig:
    """Return `scene` with the given fields replaced, validated: 'section__key' (fluid__damping=100) or a body's own
    parameter as 'BODY__key', BODY a body's name (float__pto_damping=1e6 in a scene of several bodies; `body` in a
    one-body scene: body__density=500, body__pto_damping=...). None means 'keep' (an unset flag)."""
    sections: dict[str, dict] = {}
    entries: dict[str, dict] = {}
    for key, value in changes.items():
        if value is None:
            continue
        section, _, name = key.partition("__")
        if scene.bodies and section in body_names(scene) and name in ENTRY_KEYS | {"forces": None}:
            entries.setdefault(section, {})[name] = value
            continue
        if section == "body" and not scene.bodies and name in ENTRY_KEYS:
            section = ENTRY_KEYS[name]  # the one body's pose or joint, named as a body's
        if section not in SECTION_TYPES or name not in {p.key for p in SECTIONS[section]}:
            raise ConfigError(_unknown(scene, section, name))
        if scene.bodies and section in ENTRY_SECTIONS and value != getattr(getattr(scene, section), name):
            raise ConfigError(f"'{section}.{name}': this scene's bodies are its [[bodies]] ({', '.join(body_names(scene))}): name the "
                              f"body, e.g. {body_names(scene)[-1]}.{name}")  # fmt: skip
        sections.setdefault(section, {})[name] = value
    if entries:
        scene = dataclasses.replace(scene, bodies=tuple(_entry_with(e, entries.get(e.name, {})) for e in scene.bodies))
    if sections.get("body", {}).get("mesh") and "shape" not in sections["body"]:
        sections["body"]["shape"] = "mesh"  # --mesh FILE alone means: this file is the body
    if (
        sections.get("body", {}).get("shape") == "mesh"
        and scene.body.shape != "mesh"
        and "forces" not in sections.get("fluid", {})
        and scene.fluid.forces == "points"
    ):
        sections.setdefault("fluid", {})["forces"] = MESH_FORCES  # a body becoming a mesh takes the mesh default
    if "density" in sections.get("body", {}):
        sections["body"]["mass"] = None  # an explicit density wins over a preset's mass
    replaced = {sec: dataclasses.replace(getattr(scene, sec), **vals) for sec, vals in sections.items()}
    return validate(dataclasses.replace(scene, **replaced))


def _entry_with(entry: BodyEntry, changes: dict) -> BodyEntry:
    """A [[bodies]] entry with some of its own parameters (ENTRY_KEYS, forces) replaced (a density wins over a mass)."""
    tables: dict[str, dict] = {}
    for key, value in changes.items():
        if key != "forces":
            tables.setdefault(ENTRY_KEYS[key], {})[key] = value
    if "density" in tables.get("body", {}):
        tables["body"]["mass"] = None
    own = {"forces": changes["forces"]} if "forces" in changes else {}
    return dataclasses.replace(entry, **own, **{t: dataclasses.replace(getattr(entry, t), **v) for t, v in tables.items()})


def _unknown(scene: SceneConfig, section: str, name: str) -> str:
    """The one line for a parameter no scene has: what a scene's parameters are named."""
    bodies = body_names(scene)
    if section not in SECTION_TYPES and section not in bodies and scene.bodies:
        return f"unknown scene parameter '{section}.{name}': '{section}' is not a section or one of the bodies ({', '.join(bodies)})"
    if section in bodies and scene.bodies:
        return f"unknown parameter '{name}' of body {section!r} (a body's are: {', '.join(sorted(ENTRY_KEYS))}, forces)"
    if section not in SECTION_TYPES and name in ENTRY_KEYS:
        return f"unknown scene parameter '{section}.{name}': the one body of this scene is named 'body' (body.{name})"
    return f"unknown scene parameter '{section}.{name}'"

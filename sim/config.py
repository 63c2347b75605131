"""Typed scene configuration, TOML presets and validation: the one place bad input becomes a clear error."""

from __future__ import annotations

import dataclasses
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

SCENES_DIR = Path(__file__).resolve().parent.parent / "assets" / "scenes"


class ConfigError(ValueError):
    """A user mistake in a scene or a flag; its message is one line meant for the user."""


@dataclass(frozen=True)
class BodyConfig:
    shape: str = "cube"
    """'cube' (side `size`), 'box' (sides `extents`) or 'mesh' (watertight file `mesh`)."""
    size: float = 1.0
    """Cube side, m."""
    extents: tuple[float, float, float] = (1.0, 1.0, 1.0)
    """Box sides along body x, y, z, m (shape 'box')."""
    points_per_edge: int = 10
    """Cube/box: N, giving N x N cell-centred samples per face."""
    mesh: str = ""
    """Mesh file (shape 'mesh'), relative to the scene file or the working directory."""
    samples: int = 600
    """Mesh: target number of samples (triangles are subdivided until there are at least this many)."""
    density: float | None = 900.0
    """Mass / enclosed volume, kg/m^3 (the report's ice cube: 900). Ignored when `mass` is set."""
    mass: float | None = None
    """Total mass, kg; overrides `density` when given."""


@dataclass(frozen=True)
class FluidConfig:
    rho: float = 1000.0
    """Water density, kg/m^3."""
    g: float = 9.81
    """Gravitational acceleration, m/s^2."""
    damping: float = 0.0
    """Viscous damping coefficient d, N s/m^3 (force -d * area * velocity on wet samples)."""
    forces: str = "points"
    """'points': water forces summed over the samples (the report's model); 'panels': integrated
    exactly over the mesh's triangles clipped at the water line."""


@dataclass(frozen=True)
class InitialConfig:
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """Centre of mass, world frame, m."""
    orientation: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    """Body-to-world rotation as a unit quaternion (w, x, y, z)."""
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """Centre-of-mass velocity, world frame, m/s."""
    omega: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """Angular velocity, world frame, rad/s."""


@dataclass(frozen=True)
class StepConfig:
    integrator: str = "implicit"
    """Integrator name (see `sim.integrators.INTEGRATORS`)."""
    dt: float = 0.005
    """Time step, s (the output interval for the adaptive solve_ivp methods)."""
    t_end: float = 30.0
    """Simulated duration, s."""
    rtol: float = 1e-8
    """Relative tolerance of the adaptive methods."""
    atol: float = 1e-10
    """Absolute tolerance of the adaptive methods."""


@dataclass(frozen=True)
class SceneConfig:
    name: str = "custom"
    description: str = ""
    body: BodyConfig = field(default_factory=BodyConfig)
    fluid: FluidConfig = field(default_factory=FluidConfig)
    initial: InitialConfig = field(default_factory=InitialConfig)
    step: StepConfig = field(default_factory=StepConfig)
    base_dir: str = "."
    """Folder that relative mesh paths are resolved against (the scene file's)."""


def available_scenes() -> list[str]:
    return sorted(p.stem for p in SCENES_DIR.glob("*.toml"))


def load_scene(name_or_path: str) -> SceneConfig:
    """A preset by name (assets/scenes/NAME.toml) or a TOML file by path, validated."""
    path = Path(name_or_path)
    if path.suffix != ".toml":
        path = SCENES_DIR / f"{name_or_path}.toml"
        if not path.is_file():
            raise ConfigError(f"unknown scene '{name_or_path}'; presets: {', '.join(available_scenes())}, or a path to a .toml file")
    elif not path.is_file():
        raise ConfigError(f"scene file not found: {name_or_path}")
    try:
        data = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as e:
        raise ConfigError(f"{path}: not valid TOML: {e}") from None
    data.setdefault("name", path.stem)
    scene = _from_dict(SceneConfig, data, str(path))
    return validate(dataclasses.replace(scene, base_dir=str(path.parent)))


def _from_dict(cls, data: dict, where: str):
    """Build a (nested) config dataclass from a TOML table, refusing unknown keys."""
    if not isinstance(data, dict):
        raise ConfigError(f"{where}: expected a table for {cls.__name__}")
    fields = {f.name: f for f in dataclasses.fields(cls)}
    kwargs = {}
    for key, value in data.items():
        if key not in fields:
            raise ConfigError(f"{where}: unknown key '{key}' (known: {', '.join(fields)})")
        sub = {"body": BodyConfig, "fluid": FluidConfig, "initial": InitialConfig, "step": StepConfig}.get(key)
        if cls is SceneConfig and sub is not None:
            value = _from_dict(sub, value, f"{where} [{key}]")
        elif isinstance(value, list):
            value = tuple(value)
        kwargs[key] = value
    return cls(**kwargs)


def _number(value, what: str, *, positive=False, nonneg=False, integer=False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ConfigError(f"{what} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise ConfigError(f"{what} must be finite, got {value}")
    if integer and int(value) != value:
        raise ConfigError(f"{what} must be a whole number, got {value}")
    if positive and value <= 0:
        raise ConfigError(f"{what} must be > 0, got {value}")
    if nonneg and value < 0:
        raise ConfigError(f"{what} must be >= 0, got {value}")
    return value


def _vector(value, what: str, n: int) -> tuple[float, ...]:
    if not isinstance(value, (tuple, list)) or len(value) != n:
        raise ConfigError(f"{what} must have {n} numbers, got {value!r}")
    return tuple(float(_number(v, what)) for v in value)


def validate(scene: SceneConfig) -> SceneConfig:
    """Check every field; raise ConfigError with a one-line message on the first problem."""
    from .integrators import INTEGRATORS  # late import: integrators need no config

    b, f, i, s = scene.body, scene.fluid, scene.initial, scene.step
    if b.shape not in ("cube", "box", "mesh"):
        raise ConfigError(f"body shape must be 'cube', 'box' or 'mesh', got {b.shape!r}")
    _number(b.size, "cube size", positive=True)
    for e in _vector(b.extents, "box extents", 3):
        _number(e, "box extents", positive=True)
    _number(b.points_per_edge, "points per edge", integer=True)
    if b.points_per_edge < 1:
        raise ConfigError(f"points per edge must be >= 1, got {b.points_per_edge}")
    _number(b.samples, "mesh samples", integer=True, positive=True)
    if b.shape == "mesh" and not b.mesh:
        raise ConfigError("body shape 'mesh' needs a mesh file")
    if b.mass is not None:
        _number(b.mass, "mass", positive=True)
    elif b.density is not None:
        _number(b.density, "density", positive=True)
    else:
        raise ConfigError("give the body a density or a mass")
    _number(f.rho, "water density rho", nonneg=True)
    _number(f.g, "gravity g", nonneg=True)
    _number(f.damping, "damping", nonneg=True)
    if f.forces not in ("points", "panels"):
        raise ConfigError(f"forces must be 'points' or 'panels', got {f.forces!r}")
    _vector(i.position, "initial position", 3)
    q = _vector(i.orientation, "initial orientation q0", 4)
    if abs(math.sqrt(sum(c * c for c in q)) - 1.0) > 1e-6:
        raise ConfigError(f"initial orientation q0 must be a unit quaternion (w, x, y, z), got {q} with norm {math.sqrt(sum(c * c for c in q)):.6g}")
    _vector(i.velocity, "initial velocity u0", 3)
    _vector(i.omega, "initial angular velocity omega0", 3)
    if s.integrator not in INTEGRATORS:
        raise ConfigError(f"unknown integrator '{s.integrator}'; choose one of: {', '.join(INTEGRATORS)}")
    _number(s.dt, "dt", positive=True)
    _number(s.t_end, "t_end", nonneg=True)
    _number(s.rtol, "rtol", positive=True)
    _number(s.atol, "atol", positive=True)
    return scene


def with_overrides(scene: SceneConfig, **changes) -> SceneConfig:
    """Return `scene` with the given section fields replaced, e.g. body__density=500; validated."""
    sections: dict[str, dict] = {}
    for key, value in changes.items():
        if value is None:
            continue
        section, name = key.split("__")
        sections.setdefault(section, {})[name] = value
    if "density" in sections.get("body", {}):
        sections["body"]["mass"] = None  # an explicit density wins over a preset's mass
    replaced = {sec: dataclasses.replace(getattr(scene, sec), **vals) for sec, vals in sections.items()}
    return validate(dataclasses.replace(scene, **replaced))

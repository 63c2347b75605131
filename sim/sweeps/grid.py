"""A sweep: a scene, the parameters it varies (each a list or a range) and how the cases run; the
product of the values, the scene of each case, and the chunks the cases run in.

Besides any declared number or choice of the body, the water, the waves and the step (density,
damping, drag_coefficient, hs, integrator, ...), a sweep can vary three things of the start:
`z0` (initial height, m), `tilt` (initial heel about the world x axis, degrees) and
`orientation_seed` (an initial orientation drawn uniformly at random, the same for the same seed;
tilt is applied after it). (`seed` is the JONSWAP sea's.)

Chunks group cases that can share one compiled ensemble (same shape, water, force model,
integrator, dt and force terms), in the product's order: they depend on the sweep alone, never on
the backend, so every backend runs the same chunks and gets the same numbers.
"""

from __future__ import annotations

import dataclasses
import hashlib
import itertools
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from sim.bodies.rotation import quat_multiply
from sim.errors import ConfigError
from sim.hydro import forces
from sim.limits import MAX_CASES
from sim.scene.config import PARAMS, SceneConfig, body_own, load_scene, read_toml, with_overrides

START = {"z0": "initial height of the centre of mass, m", "tilt": "initial heel about the world x axis, degrees",
         "orientation_seed": "random initial orientation (uniform over rotations), by seed"}  # fmt: skip
VARIABLE = {p.key: p for p in PARAMS.values() if p.section in ("body", "fluid", "waves", "step") and p.kind in ("float", "int", "optional", "choice")
            and p.key not in ("shape", "mass", "t_end")}  # fmt: skip
"""Scene parameters a sweep can vary, by key."""
assert not set(START) & set(VARIABLE), "a start parameter shadows a scene parameter"
BODY_VARIABLE = {p.key: p for p in PARAMS.values() if body_own(p) and p.kind in ("float", "int", "optional", "choice")}
"""What a sweep can vary of a body, named BODY.KEY: BODY one of a scene's [[bodies]] (float.pto_damping: a power matrix), or
`body`, the one body of a one-body scene (body.pto_damping, body.density); KEY any number or choice of its shape, pose, joint or
terms' parameters (float.drag_coefficient)."""
SHARED = ("body.shape", "body.size", "body.extents", "body.points_per_edge", "body.mesh", "body.mesh_unit", "body.samples", "fluid.rho",
          "fluid.g", "fluid.forces", "step.integrator", "step.dt")  # fmt: skip


def parse_values(name: str, text: str) -> tuple:
    """'a:b:n' (n values from a to b, ends included), 'v1,v2,...' or one value."""
    param = BODY_VARIABLE.get(name.split(".", 1)[1]) if "." in name else VARIABLE.get(name)
    choice = param is not None and param.kind == "choice"
    text = text.strip()
    if not text:
        raise ConfigError(f"--param {name}=: no values")
    if ":" in text and not choice:
        parts = text.split(":")
        if len(parts) != 3:
            raise ConfigError(f"--param {name}={text}: a range is FROM:TO:COUNT")
        try:
            lo, hi, n = float(parts[0]), float(parts[1]), int(parts[2])
        except ValueError:
            raise ConfigError(f"--param {name}={text}: a range is FROM:TO:COUNT with numbers") from None
        if n < 1:
            raise ConfigError(f"--param {name}={text}: the range is empty (COUNT must be >= 1)")
        if n > MAX_CASES:
            raise ConfigError(f"--param {name}={text}: {n:,} values is over the limit of {MAX_CASES:,} cases")
        values = tuple(np.linspace(lo, hi, n).tolist()) if n > 1 else (lo,)
    else:
        items = [v.strip() for v in text.split(",") if v.strip()]
        if not items:
            raise ConfigError(f"--param {name}={text}: no values")
        if choice:
            return tuple(items)
        try:
            values = tuple(float(v) for v in items)
        except ValueError:
            raise ConfigError(f"--param {name}={text}: values must be numbers") from None
    if name == "orientation_seed" or (param is not None and param.kind == "int"):
        if any(v != int(v) for v in values):
            raise ConfigError(f"--param {name}: values must be whole numbers")
        values = tuple(int(v) for v in values)
    if name == "orientation_seed" and any(not 0 <= v < 2**32 for v in values):
        raise ConfigError(f"--param {name}: seeds must be in 0..{2**32 - 1}")
    return values


def parse_param(spec: str) -> tuple[str, tuple]:
    """'name=values' -> (name, values), refusing unknown names by name."""
    if "=" not in spec:
        raise ConfigError(f"--param {spec!r}: write NAME=VALUES, e.g. density=100:900:41 or orientation_seed=0:9:10")
    name, text = spec.split("=", 1)
    name = name.strip()
    if "." in name:
        body, key = name.split(".", 1)
        if not body or key not in BODY_VARIABLE:
            raise ConfigError(f"--param {name}: a body's parameter is BODY.KEY, KEY one of {', '.join(sorted(BODY_VARIABLE))} "
                              "(e.g. float.pto_damping; body.KEY for the body of a one-body scene)")  # fmt: skip
        return name, parse_values(name, text)
    if name not in VARIABLE and name not in START:
        raise ConfigError(f"--param {name}: unknown parameter (known: {', '.join(sorted(VARIABLE) + sorted(START))}, "
                          "and BODY.KEY for a body of several)")  # fmt: skip
    return name, parse_values(name, text)


@dataclass(frozen=True)
class Sweep:
    """Everything that defines a sweep's cases and numbers (its hash names the results)."""

    scene: str = "damped"
    params: tuple[tuple[str, tuple], ...] = ()
    overrides: tuple[tuple[str, object], ...] = ()
    """Fixed changes to the scene, ('section__key', value)."""
    settle: bool = False
    """Stop a case once at rest (and record when)."""
    chunk: int = 64
    history_every: int = 0
    """Keep one history row per case every K steps (0: none)."""
    base_dir: str = field(default=".", compare=False)

    def base(self) -> SceneConfig:
        return with_overrides(load_scene(self.scene), **dict(self.overrides))

    def cases(self) -> list[dict]:
        names = [n for n, _ in self.params]
        return [dict(zip(names, combo)) for combo in itertools.product(*(v for _, v in self.params))]

    def case(self, i: int) -> dict:
        """Case i of the product (the last parameter varies fastest), without forming the others."""
        sizes = [len(v) for _, v in self.params]
        index = np.unravel_index(i, sizes) if sizes else ()
        return {name: values[int(k)] for (name, values), k in zip(self.params, index)}

    def __len__(self) -> int:
        return math.prod(len(v) for _, v in self.params)

    def key(self) -> str:
        """A digest of what the numbers depend on (the scene file's contents included)."""
        base = self.base()
        text = json.dumps([repr(base), self.params, self.overrides, self.settle, self.chunk, self.history_every], default=str)
        return hashlib.sha256(text.encode()).hexdigest()[:16]


def case_scene(base: SceneConfig, case: dict) -> SceneConfig:
    """The scene of one case: the base with the case's values (a body's BODY.KEY as with_overrides names it, BODY__KEY)."""
    changes = {f"{VARIABLE[k].section}__{k}": v for k, v in case.items() if k in VARIABLE}
    changes |= {k.replace(".", "__", 1): v for k, v in case.items() if "." in k}
    try:
        scene = with_overrides(base, **changes) if changes else base
    except ConfigError as e:
        raise ConfigError(f"--param: {e}") from None
    if base.bodies:
        if start := [k for k in case if k in START]:
            raise ConfigError(f"--param {start[0]}: the start parameters are for one-body scenes (set a body's [initial] in the scene)")
        return scene
    position, orientation = scene.initial.position, np.array(scene.initial.orientation, float)
    if "orientation_seed" in case:
        from scipy.spatial.transform import Rotation

        orientation = Rotation.random(random_state=int(case["orientation_seed"])).as_quat(scalar_first=True)
    if "tilt" in case:
        half = math.radians(float(case["tilt"])) / 2
        heel = np.array([math.cos(half), math.sin(half), 0.0, 0.0])

        orientation = quat_multiply(heel, orientation)
    if "z0" in case:
        position = (position[0], position[1], float(case["z0"]))
    if "orientation_seed" in case or "tilt" in case or "z0" in case:
        q = tuple(float(c) for c in np.asarray(orientation) / np.linalg.norm(orientation))
        scene = dataclasses.replace(scene, initial=dataclasses.replace(scene.initial, position=tuple(position), orientation=q))
    return scene


def group_key(scene: SceneConfig) -> tuple:
    """Cases with equal keys run in one ensemble: shared geometry and stepping, the same force terms, one sea."""
    terms = tuple(t.name for t in forces.TERMS if t.is_used(scene.fluid))
    return tuple(scene.value(k) for k in SHARED) + (terms, scene.waves, scene.water, scene.fluid.radiation)


def chunks(sweep: Sweep, scenes: list[SceneConfig]) -> list[list[int]]:
    """Case indices per chunk: groups in order of first appearance, each cut into runs of `chunk`."""
    groups: dict[tuple, list[int]] = {}
    for i, scene in enumerate(scenes):
        groups.setdefault(group_key(scene), []).append(i)
    return [idx[j : j + sweep.chunk] for idx in groups.values() for j in range(0, len(idx), sweep.chunk)]


def load_sweep_file(path: str) -> dict:
    """A TOML sweep file: `scene`, `params` (a table of NAME = "VALUES" or lists), `set` (a table of
    'section.key' = value), `settle`, `chunk`, `history_every`, and the run's `t_end`, `dt`, `integrator`."""
    p = Path(path)
    data = read_toml(p, "sweep")
    known = {"scene", "params", "set", "settle", "chunk", "history_every", "t_end", "dt", "integrator", "description"}
    for k in data:
        if k not in known:
            raise ConfigError(f"{path}: unknown key '{k}' (known: {', '.join(sorted(known))})")
    params = []
    for name, value in data.get("params", {}).items():
        text = ",".join(str(v) for v in value) if isinstance(value, list) else str(value)
        params.append(parse_param(f"{name}={text}"))
    data["params"] = params
    scene = data.get("scene", "damped")
    if not scene.endswith(".toml") or Path(scene).is_absolute():
        data["scene"] = scene
    else:
        data["scene"] = str(p.parent / scene)
    return data

"""The compiled twin of the numpy reference (numba): one module per reference module, same function
names, sharing the array contract in layout.py. Compiled per scene, once, and cached on disk.

A scene compiles only what it uses: `specialised(spec)` imports this folder's modules afresh under a
name of their own (sim.kernels_<spec>), whose spec.py holds the scheme, force model, terms, water
kind and radiation as constants that numba folds before it compiles (a still-water drop: one
scheme, two terms). Each copy caches its own compiled code.

numba checks a cached kernel against its own file only, not the files of the kernels it calls, so
the cache lives in a folder named after a hash of every kernel source, of the term registry and of the
integrators' constants: any change to them compiles afresh instead of running stale code.
"""

from __future__ import annotations

import hashlib
import importlib
import os
import sys
import threading
import types
from pathlib import Path
from typing import NamedTuple

import numba
from numba.core.caching import UserProvidedCacheLocator

from sim.hydro import forces

from .layout import COMPILED_TERMS, MODELS, NO_RADIATION, SCHEMES, Model, pack, radiation_pack, sea_pack

_HERE = Path(__file__).resolve().parent


def _cache_dir() -> str:
    sources = sorted(_HERE.glob("*.py")) + [_HERE.parent / "hydro/forces.py", _HERE.parent / "dynamics/integrators.py"]
    digest = hashlib.sha256(b"".join(p.read_bytes() for p in sources)).hexdigest()[:16]
    root = os.environ.get("NUMBA_CACHE_DIR") or os.path.join(os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "floatsim")
    return os.path.join(root, f"kernels-{digest}")


KERNEL_CACHE = _cache_dir()


class Spec(NamedTuple):
    """What a scene needs compiled: its scheme, force model, terms (registry order), waves or still water,
    radiation, and whether still water flows in a current (in waves the current costs no code of its own)."""

    scheme: str
    model: str
    terms: tuple[str, ...]
    waves: bool
    radiating: bool
    current: bool = False
    held: bool = False
    """Whether another model gives the body a load held over each step (the mooring lines)."""
    system: bool = False
    """Whether the body is one of several on joints (system/tree.py): only its loads are compiled, no scheme's step."""

    @property
    def key(self) -> str:
        """A name for this specialisation, usable in a module name."""
        mask = sum(1 << i for i, name in enumerate(COMPILED_TERMS) if name in self.terms)
        return f"{self.scheme}_{self.model}_t{mask:x}_{self._water}{'_rad' if self.radiating else ''}{'_held' if self.held else ''}{'_sys' if self.system else ''}"

    @property
    def _water(self) -> str:
        return "waves" if self.waves else "current" if self.current else "still"

    def describe(self) -> str:
        if self == SYSTEM_STEP:
            return "step of several bodies on joints (kinematics, kicks, radiation memory)"
        if self == SYSTEM_LINEAR:
            return "step of several bodies on joints with linear loads (kinematics, n steps a call, radiation memory)"
        terms = " + ".join(self.terms) or "no forces"
        water = {"waves": "waves", "current": "still water in a current", "still": "still water"}[self._water]
        return f"{'loads of one of several bodies' if self.system else self.scheme + ' scheme'}, {self.model} model, {terms}, {water}{', radiation' if self.radiating else ''}{', a held load' if self.held else ''}"


SYSTEM_STEP = Spec("system-step", "any", (), False, False, False, False, True)
"""The kernels of the step of several bodies (system/compiled.py) whose loads Python asks at each kick: one set for every
such scene, compiled and loaded as a Spec is (in a child while the numpy reference runs, then from the disk cache)."""
SYSTEM_LINEAR = Spec("system-linear", "any", (), False, False, False, False, True)
"""The kernels of the step of several bodies with linear loads (`[fluid] hydro = "linear"`): n steps in one call. Apart
from SYSTEM_STEP, so that a scene compiles only the loop it runs."""


def spec_of(model, scheme: str) -> Spec:
    """The specialisation a forces.Model stepped by `scheme` needs. Every compiled term is in (compiled_terms): a linear
    one vanishes exactly with its coefficient, and the nonlinear one (drag) is skipped at run time where its
    coefficient is zero (forces.nonlinear_acting): a scene whose damping or drag goes from 0 to 100 keeps its kernels."""
    water = model.water
    return Spec(scheme, model.fluid.forces, compiled_terms(model.term_names, scheme, every=model.held is None), not water.flat, model.radiation is not None, water.flat and not water.at_rest,
                model.held is not None)  # fmt: skip


EVERY_TERM = ("euler", "splitting", "implicit", "rk4")
"""The schemes whose kernels compile every term, drag too: all of them. Drag at a zero coefficient adds exactly nothing
(its loop is skipped), and the implicit and splitting steps choose their linear path (exact modes) at run time when it
is zero (forces.nonlinear_acting): one specialisation a scheme serves a scene with drag and without (issue 57: fewer
compiles; the waves and storm presets share theirs). Not a moored step's (its held loads) nor a system's bodies' loads:
drag's code would cost their compile 3-7 s of CPU (moored-buoy 27 s to 34 s) and no preset of theirs shares."""


def compiled_terms(used, scheme: str = "implicit", every: bool = True) -> tuple[str, ...]:
    """The terms kernels compile for a scene using the terms `used` stepped by `scheme`: every linear one, and the
    nonlinear ones used; every one for EVERY_TERM's schemes unless `every` is False (a moored step's, a body's loads
    in a system's: see EVERY_TERM)."""
    every = every and scheme in EVERY_TERM
    return tuple(t.name for t in forces.TERMS if t.name in COMPILED_TERMS and (t.linear or every or t.name in used))


def missing_terms(model) -> tuple[str, ...]:
    """Terms of the model without a compiled twin (such a scene runs on the numpy reference)."""
    return tuple(name for name in model.term_names if name not in COMPILED_TERMS)


SHARED = ("jit", "layout", "rotation", "state", "surface", "directional", "water", "modes", "radiation", "expm", "kinematics", "system")
"""The kernel modules that read no spec (spec.py): one compiled copy serves every specialisation."""
_instances: dict[Spec, types.ModuleType] = {}
_lock = threading.Lock()


def specialised(spec: Spec) -> types.ModuleType:
    """The kernels compiled for `spec` (loaded from the disk cache, or compiled on first call): a
    package whose `integrators`, `simulation`, `forces`, ... are this folder's modules with spec.py's constants."""
    with _lock:
        if spec in _instances:
            return _instances[spec]
        name = f"{__name__}_{spec.key}"
        if os.environ.get(COMPILE_LOG) and not cached(spec):
            _log_compile(spec)
        package = types.ModuleType(name, f"floatsim kernels for {spec.describe()}")
        package.__path__, package.__package__, package.SPEC = [str(_HERE)], name, spec
        sys.modules[name] = package
        users = numba.config.CACHE_DIR
        try:
            # the modules that read no spec are compiled once for all (_import_shared): each copy imports them as they are.
            # CACHE_DIR is read as each kernel is decorated; others' code keeps the user's.
            for module in SHARED:
                sys.modules[f"{name}.{module}"] = sys.modules[f"{__name__}.{module}"]
            # a folder per spec: numba names a cached kernel after its file and function, not its module, so
            # copies sharing one folder would load each other's code
            numba.config.CACHE_DIR = _spec_cache(spec)
            for module in ("schemes", "simulation", "forces", "terms", "wet", "surface", "water"):
                setattr(package, module, importlib.import_module(f"{name}.{module}"))
        except BaseException:
            for module in [m for m in sys.modules if m == name or m.startswith(name + ".")]:
                sys.modules.pop(module)
            raise
        finally:
            numba.config.CACHE_DIR = users
        _instances[spec] = package
        return package


COMPILE_LOG = "FLOATSIM_COMPILE_LOG"
"""A file to which `specialised` appends a line for each spec it compiles rather than loads, with the test
running it (PYTEST_CURRENT_TEST): how the test suite's covering set of specialisations is checked."""


def _log_compile(spec: Spec, note: str = "compiling") -> None:
    import time

    test = os.environ.get("PYTEST_CURRENT_TEST", "-").removesuffix(" (call)").removesuffix(" (setup)")
    with open(os.environ[COMPILE_LOG], "a") as log:  # one short write per line: concurrent processes do not interleave
        log.write(f"{time.time():.1f}\t{os.getpid()}\t{spec.key}\t{note}\t{test}\n")


def _spec_cache(spec: Spec) -> str:
    return os.path.join(KERNEL_CACHE, spec.key)


def _import_shared() -> None:
    users = numba.config.CACHE_DIR
    numba.config.CACHE_DIR = os.path.join(KERNEL_CACHE, "shared")  # read as each kernel is decorated
    try:
        for module in SHARED:
            importlib.import_module(f"{__name__}.{module}")
    finally:
        numba.config.CACHE_DIR = users


_import_shared()


def cached(spec: Spec) -> bool:
    """Whether the kernels for `spec` were compiled on this machine before (their disk cache has the step and the frame).
    Not for SYSTEM_STEP or SYSTEM_LINEAR, whose kernels the system package drives (compiling.cached asks it)."""
    found = compiled_here(_spec_cache(spec))
    if spec.system:
        return "simulation.linearised_loads" in found
    return {"schemes.step_held" if spec.held else "schemes.advance", "simulation.observe"} <= found


def compiled_here(folder: str) -> set[str]:
    """The kernels ('module.function') whose compiled code numba will read from `folder` for this checkout. numba keeps
    each source folder's code in a subfolder named after that folder's path, so a cache filled from another checkout
    (another clone on this machine) counts for nothing here: it would compile anew in every process that loads it."""
    here = os.path.join(folder, UserProvidedCacheLocator.get_suitable_cache_subpath(str(_HERE / "jit.py")))
    return {name.split("-")[0] for name in (os.listdir(here) if os.path.isdir(here) else ()) if name.endswith(".nbi")}


def entry_point(kernel, args: tuple):
    """The compiled function behind `kernel` for these arguments' types, called without the dispatcher's typing of each
    argument (6 us a call for the moored step's nested tuples); the kernel itself where it has none compiled yet."""
    compiled = kernel.overloads.get(tuple(numba.typeof(a) for a in args))
    return kernel if compiled is None else compiled.entry_point


def warm_up(spec: Spec) -> float:
    """Compile (first run ever) or load from the disk cache the kernels of `spec`; returns the seconds taken. Not for
    SYSTEM_STEP or SYSTEM_LINEAR (compiling.warm_up)."""
    import time

    start = time.perf_counter()
    fresh = os.environ.get(COMPILE_LOG) and not cached(spec)
    specialised(spec).schemes.warm_up()
    seconds = time.perf_counter() - start
    if fresh:
        _log_compile(spec, f"warmed up in {seconds:.1f} s")
    return seconds


__all__ = ["KERNEL_CACHE", "MODELS", "NO_RADIATION", "SCHEMES", "COMPILED_TERMS", "SYSTEM_LINEAR", "SYSTEM_STEP", "Model", "Spec", "cached", "EVERY_TERM", "compiled_terms", "missing_terms", "pack", "radiation_pack",
           "sea_pack", "spec_of", "specialised", "warm_up"]  # fmt: skip

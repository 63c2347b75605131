"""The compiled kernels without the wait: a child process fills their disk cache while the numpy reference runs.

A scene's kernels (sim.kernels.specialised: its scheme, force model, terms and water) compile once per
machine, in 20 s to a few minutes (compile_estimate.py says how long here). A compiler thread in the running
process would hold the GIL against the simulation thread for most of that time, so `Compiler` runs `python -m sim.commands.compile` instead: a child
that compiles the kernels of one scene into the disk cache (sim/kernels/__init__.py) and exits. The caller keeps
stepping on the numpy reference, polls `done`, then loads the kernels from the cache (a second or two) and switches
between two steps: the state is the same vector either way.

`FLOATSIM_COMPILER` replaces the child's command (tests fill the cache by copying a warm one).
"""

from __future__ import annotations

import os
import shlex
import subprocess
import sys
import tempfile
import threading
import time

from sim.compile_estimate import compile_wall, shares_of
from sim.system import compiled

COMMAND_ENV = "FLOATSIM_COMPILER"


def default_backend() -> str:
    """'numba' (compiled, the default) unless FLOATSIM_BACKEND=numpy or numba is missing."""
    choice = os.environ.get("FLOATSIM_BACKEND", "numba")
    if choice == "numba":
        try:
            import numba  # noqa: F401
        except ImportError:
            return "numpy"
    return choice


def kernels_ready(spec) -> bool:
    """Whether the compiled kernels for `spec` (kernels.Spec) can be used at once: numba is the backend and
    this machine compiled them before."""
    return default_backend() == "numba" and cached(spec)


def cached(spec) -> bool:
    """Whether this machine compiled the kernels of `spec` before (kernels.SYSTEM_STEP or SYSTEM_LINEAR: a system step's)."""
    from sim import kernels  # numba's import (0.6 s): only where compiled kernels run

    return compiled.ready(spec) if spec.scheme in compiled.KERNELS else kernels.cached(spec)


def warm_up(spec) -> float:
    """Compile (first run ever) or load from the disk cache the kernels of `spec`; the seconds taken."""
    from sim import kernels  # numba's import (0.6 s): only where compiled kernels run

    return compiled.warm(spec) if spec.scheme in compiled.KERNELS else kernels.warm_up(spec)


def spec_argument(spec) -> str:
    """A kernels.Spec as one command-line word (for the child)."""
    return ",".join(
        [
            spec.scheme,
            spec.model,
            "+".join(spec.terms),
            str(int(spec.waves)),
            str(int(spec.radiating)),
            str(int(spec.current)),
            str(int(spec.held)),
            str(int(spec.system)),
        ]
    )


def parse_spec(word: str):
    from sim.kernels import Spec  # numba's import (0.6 s): only where compiled kernels run

    parts = word.split(",")
    if len(parts) != 8:
        raise ValueError(f"{word!r} is not a kernels spec: scheme,model,terms,waves,radiating,current,held,system (spec_argument)")
    scheme, model, terms, waves, radiating, current, held, system = parts
    return Spec(
        scheme, model, tuple(t for t in terms.split("+") if t), waves == "1", radiating == "1", current == "1", held == "1", system == "1"
    )


class Compiler:
    """Child processes that compile the kernels of `specs` into the disk cache, side by side on this machine's cores (a
    scene of several bodies: its bodies' loads and the system step at once); they die with this process."""

    def __init__(self, specs):
        self.specs = tuple(specs)
        command = shlex.split(os.environ.get(COMMAND_ENV, "")) or [sys.executable, "-m", "sim.commands.compile", str(os.getpid())]
        shares = shares_of(self.specs)
        self.log = tempfile.TemporaryFile()  # their output, for the note when one fails
        self.expected = compile_wall(self.specs)
        """The seconds it should take on this machine now (compile_estimate.py), from an empty cache."""
        self.started = time.monotonic()
        self.seconds: float | None = None
        """How long the compile took (None until it ends)."""
        self._children = [
            subprocess.Popen(
                command + [spec_argument(s) for s in share], stdin=subprocess.DEVNULL, stdout=self.log, stderr=subprocess.STDOUT
            )
            for share in shares
        ]

    @property
    def done(self) -> bool:
        if any(child.poll() is None for child in self._children):
            return False
        if self.seconds is None:
            self.seconds = time.monotonic() - self.started
        return True

    @property
    def ok(self) -> bool:
        """Done, and the kernels are in the disk cache."""
        return self.done and all(child.returncode == 0 for child in self._children)

    def wait(self) -> bool:
        """Wait until every child has ended; whether all compiled."""
        for child in self._children:
            child.wait()
        return self.ok

    def failure(self) -> str:
        """The last line a child wrote (why it failed)."""
        self.log.seek(0)
        lines = self.log.read().decode(errors="replace").strip().splitlines()
        return lines[-1][:200] if lines else f"exit status {[child.returncode for child in self._children]}"

    def stop(self) -> None:
        for child in self._children:
            if child.poll() is None:
                child.kill()
                child.wait()


class Loader:
    """Loads the kernels of `spec` from the disk cache on a thread of this process (a second or two, or longer
    when another process is still writing them): the simulation thread keeps answering meanwhile. The same
    `done` / `ok` / `seconds` / `failure()` as Compiler."""

    def __init__(self, spec, compiled_in: float | None = None):
        self.spec = spec
        self.compiled_in = compiled_in
        """Seconds the child took to compile these kernels just before (None: they were on disk already)."""
        self.seconds: float | None = None
        self.error: BaseException | None = None
        self._thread = threading.Thread(target=self._load, name="floatsim-kernels", daemon=True)
        self._thread.start()

    def _load(self) -> None:
        try:
            self.seconds = load(self.spec)
        except BaseException as e:  # noqa: BLE001 -- reported by failure(); the numpy reference runs on
            self.error = e

    @property
    def done(self) -> bool:
        return not self._thread.is_alive()

    @property
    def ok(self) -> bool:
        return self.done and self.error is None

    def failure(self) -> str:
        return f"{type(self.error).__name__}: {self.error}"[:200]


def compile_all(specs) -> float:
    """Compile the kernels of `specs` (those not cached yet) and load them into this process; the seconds taken. Several:
    in child processes side by side first (Compiler), then loaded from the disk cache."""
    started = time.monotonic()
    todo = [spec for spec in specs if not cached(spec)]
    if len(todo) > 1 and not (compiler := Compiler(todo)).wait():
        raise RuntimeError(f"the kernels did not compile: {compiler.failure()}")
    for spec in specs:
        warm_up(spec)
    return time.monotonic() - started


def load(spec) -> float:
    """Load the kernels of `spec` from the disk cache into this process (compiling what is missing); seconds taken."""
    return warm_up(spec)

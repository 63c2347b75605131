"""The compiled kernels without the wait: a child process fills their disk cache while the numpy reference runs.

A first run on a machine compiles the kernels for minutes. A compiler thread in the running process would
hold the GIL against the simulation thread for most of that time, so `Compiler` runs `python -m
sim.compiling` instead: a child that compiles every kernel into the disk cache (sim/kernels/__init__.py)
and exits. The caller keeps stepping on the numpy reference, polls `done`, then loads the kernels from
the cache (a second or two) and switches between two steps: the state is the same vector either way.

`FLOATSIM_COMPILER` replaces the child's command (tests fill the cache by copying a warm one).
"""

from __future__ import annotations

import os
import shlex
import subprocess
import sys
import tempfile
import time

COMMAND_ENV = "FLOATSIM_COMPILER"


def kernels_ready() -> bool:
    """Whether the compiled kernels can be used at once: numba is the backend and this machine compiled them before."""
    from .simulation import default_backend

    if default_backend() != "numba":
        return False
    from .kernels import cached

    return cached()


class Compiler:
    """A child process that compiles the kernels into the disk cache; it dies with this process."""

    def __init__(self):
        command = shlex.split(os.environ.get(COMMAND_ENV, "")) or [sys.executable, "-m", "sim.compiling", str(os.getpid())]
        self.log = tempfile.TemporaryFile()  # its output, for the note when it fails
        self.started = time.monotonic()
        self.seconds: float | None = None
        """How long the compile took (None until it ends)."""
        self._child = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=self.log, stderr=subprocess.STDOUT)

    @property
    def done(self) -> bool:
        if self._child.poll() is None:
            return False
        if self.seconds is None:
            self.seconds = time.monotonic() - self.started
        return True

    @property
    def ok(self) -> bool:
        """Done, and the kernels are in the disk cache."""
        return self.done and self._child.returncode == 0

    def failure(self) -> str:
        """The last line the child wrote (why it failed)."""
        self.log.seek(0)
        lines = self.log.read().decode(errors="replace").strip().splitlines()
        return lines[-1][:200] if lines else f"exit status {self._child.returncode}"

    def stop(self) -> None:
        if self._child.poll() is None:
            self._child.kill()
            self._child.wait()


def load() -> float:
    """Load the kernels from the disk cache into this process (compiling what is missing); seconds taken."""
    from .kernels import warm_up

    return warm_up()


def _main(parent: int) -> int:
    from .backends import _die_with

    _die_with(parent)  # a viewer stopped by SIGKILL leaves no compiler behind
    seconds = load()
    print(f"floatsim: compiled the kernels in {seconds:.1f} s", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(_main(int(sys.argv[1]) if len(sys.argv) > 1 else os.getppid()))

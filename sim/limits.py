"""Stated limits on every setting whose cost grows, checked before anything is allocated, with the
estimated memory (or time) in the message and the flag that changes it.

Measured here (AMD EPYC, `python -m sim run --scene drop --points-per-edge N --t-end 0.01`, peak RSS over the 0.23 GB of
N = 10): about 950 bytes per surface sample at its peak (0.22 GB for 240,000 samples, 0.91 GB for 960,000), 3 us
(a cube) to 7 us (a mesh: `--scene sphere --samples 1000000`) per sample to set up, about 5 ns per sample and step.
Several bodies add the system's dense matrices (farm.toml with [farm] rows = columns = 14, 20, 32: 196, 400 and 1024
degrees of freedom): a step's matrix exponential grows as n^3 (0.107 s, 0.90 s, 29 s a step; `system_step_time`), its
set-up likewise (about a step's worth), its memory as n^2 (0.45 GB at n = 1024).
In waves a step costs more (`--points-per-edge 100 --t-end 1`): 20-22 ns per sample (waves), 63-72 ns with drag
(storm; waves with --drag-coefficient 1), and the first frame, taken on the numpy reference before anything compiles,
evaluates every wave component at every sample: 60 ns per sample and component (storm, 60,000 samples in 4096
components: 14.8 s of its 16 s set-up; 64 components: 0.2 s).
"""

from __future__ import annotations

from dataclasses import dataclass

from sim.errors import ConfigError

BYTES_PER_SAMPLE = 950
SETUP_US_PER_SAMPLE = 7.0
NS_PER_SAMPLE_STEP = 5.0
"""A step in still water, ns per surface sample."""
NS_PER_SAMPLE_STEP_WAVES = 25.0
"""A step in waves, ns per surface sample."""
NS_PER_SAMPLE_STEP_WAVES_DRAG = 75.0
"""A step in waves with quadratic drag, ns per surface sample."""
NS_PER_SAMPLE_COMPONENT = 60.0
"""The first frame (numpy), ns per surface sample and wave component."""
BYTES_PER_DOF2 = 430
"""The system of several bodies: bytes per (degree of freedom)^2."""
NS_PER_DOF3 = 14.0
"""The system's step: ns per (degree of freedom)^3, growing by a further (1 + n / 1000) as its matrices leave the caches."""
SETUP_STEPS = 1.0
"""The system's set-up (its first configuration and rest) in steps' worth."""
MAX_SAMPLES = 2_000_000
"""Surface samples of one body (a cube of N = 577 per edge): about 1.9 GB."""
MAX_HOURS = 24.0
"""Estimated hours on one core past which `run` refuses unless given --max-hours."""
SETUP_NOTE_SECONDS = 3.0
"""A scene whose set-up is estimated past this many seconds is announced with its estimate before it starts."""
JOINT_DOFS = {"free": 6, "fixed": 0, "prismatic": 1, "revolute": 1, "planar": 3}
MAX_CASES = 200_000
"""Cases in one sweep (each case's scene is checked up front)."""
MAX_HISTORY_BYTES = 4e9
"""All of a sweep's history rows together, on disk."""
MEMORY_SHARE = 0.5
"""At most this share of the memory available now may one body, one chunk or one record take."""


def available_bytes() -> float:
    """Memory available now (Linux's MemAvailable), or a generous guess where it is unknown."""
    try:
        for line in open("/proc/meminfo"):
            if line.startswith("MemAvailable:"):
                return float(line.split()[1]) * 1024
    except OSError:
        pass
    return 16e9


def size(n_bytes: float) -> str:
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n_bytes >= scale:
            return f"{n_bytes / scale:.3g} {unit}"
    return f"{n_bytes:.0f} B"


def check_memory(what: str, n_bytes: float, flag: str) -> None:
    """ConfigError when `what` would take more than MEMORY_SHARE of the memory available."""
    free = available_bytes()
    if n_bytes > MEMORY_SHARE * free:
        raise ConfigError(f"{what} needs about {size(n_bytes)} of memory, more than half of the {size(free)} available: lower {flag}")


def check_samples(n: int, flag: str) -> None:
    """The surface samples of one body, against MAX_SAMPLES and the memory available."""
    if n > MAX_SAMPLES:
        raise ConfigError(
            f"{n:,} surface samples (about {size(n * BYTES_PER_SAMPLE)} of memory) is over the limit of {MAX_SAMPLES:,}: lower {flag}"
        )
    check_memory(f"{n:,} surface samples", n * BYTES_PER_SAMPLE, flag)


def system_step_time(dofs: int) -> float:
    """Estimated seconds of a step of a system of `dofs` degrees of freedom, apart from its bodies' loads."""
    return NS_PER_DOF3 * 1e-9 * dofs**3 * (1.0 + dofs / 1000.0)


@dataclass(frozen=True)
class Cost:
    """What a scene's bodies cost before the first step: their surface samples and degrees of freedom in all (dofs 0:
    one body), the sea's wave components (0: still water) and a step's ns per sample (NS_PER_SAMPLE_STEP...): the
    estimated seconds of set-up and of the steps on one core, and the peak memory."""

    samples: int
    dofs: int
    components: int = 0
    ns_per_sample_step: float = NS_PER_SAMPLE_STEP

    @property
    def setup_seconds(self) -> float:
        sea = self.samples * self.components * NS_PER_SAMPLE_COMPONENT * 1e-9
        return self.samples * SETUP_US_PER_SAMPLE * 1e-6 + sea + SETUP_STEPS * system_step_time(self.dofs)

    def step_seconds(self, steps: int) -> float:
        """Estimated seconds of `steps` steps on one core."""
        return steps * (self.samples * self.ns_per_sample_step * 1e-9 + system_step_time(self.dofs))

    @property
    def memory(self) -> float:
        return self.samples * BYTES_PER_SAMPLE + self.dofs**2 * BYTES_PER_DOF2

    def describe(self) -> str:
        system = f" and {self.dofs:,} degrees of freedom" if self.dofs else ""
        sea = f" in {self.components:,} wave components" if self.components > 1 else ""
        return f"{self.samples:,} surface samples{system}{sea}: about {duration(self.setup_seconds)} to set up and {size(self.memory)} of memory"


def check_cost(cost: Cost, flag: str) -> None:
    """ConfigError when the bodies would take more than MEMORY_SHARE of the memory available, before any is built."""
    check_memory(
        f"a scene of {cost.samples:,} surface samples" + (f" and {cost.dofs:,} degrees of freedom" if cost.dofs else ""), cost.memory, flag
    )


def duration(seconds: float) -> str:
    if seconds >= 3600:
        return f"{seconds / 3600:.3g} h"
    return f"{seconds / 60:.0f} min" if seconds >= 90 else f"{seconds:.0f} s"

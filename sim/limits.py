"""Stated limits on every setting whose cost grows, checked before anything is allocated, with the
estimated memory (or time) in the message and the flag that changes it.

Measured here (`python -m sim bench`, RSS of a Simulation): about 400 bytes per surface sample
(body arrays, the compiled kernels' workspace, one frame), about 5 ns per sample and step.
"""

from __future__ import annotations

from sim.errors import ConfigError

BYTES_PER_SAMPLE = 450
NS_PER_SAMPLE_STEP = 5.0
MAX_SAMPLES = 2_000_000
"""Surface samples of one body (a cube of N = 577 per edge): about 0.9 GB."""
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


def step_time(samples: int, steps: int) -> float:
    """Estimated seconds to take `steps` steps of a body of `samples` samples on one core."""
    return samples * steps * NS_PER_SAMPLE_STEP * 1e-9

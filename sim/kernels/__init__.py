"""The compiled twin of the numpy reference (numba): one module per reference module, same function
names, sharing the array contract in layout.py. Compiled once and cached on disk.

numba checks a cached kernel against its own file only, not the files of the kernels it calls, so
the cache lives in a folder named after a hash of every kernel source, of the term registry and of the integrators' constants:
any change to them compiles afresh instead of running stale code.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numba
from numba import njit

_HERE = Path(__file__).resolve().parent


def _cache_dir() -> str:
    sources = sorted(_HERE.glob("*.py")) + [_HERE.parent / "forces.py", _HERE.parent / "integrators.py"]
    digest = hashlib.sha256(b"".join(p.read_bytes() for p in sources)).hexdigest()[:16]
    root = os.environ.get("NUMBA_CACHE_DIR") or os.path.join(os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "floatsim")
    return os.path.join(root, f"kernels-{digest}")


def cached() -> bool:
    """Whether these kernels were compiled on this machine before (their disk cache has entries)."""
    return any(name.endswith(".nbi") for _, _, names in os.walk(KERNEL_CACHE) for name in names)


JIT = {"cache": True, "nogil": True, "fastmath": False, "error_model": "numpy"}

_users_cache_dir = numba.config.CACHE_DIR
KERNEL_CACHE = _cache_dir()
numba.config.CACHE_DIR = KERNEL_CACHE  # read by numba as each kernel below is decorated; others' code keeps the user's
try:
    from .integrators import advance, advance_many, warm_up  # noqa: E402
    from .layout import MODELS, NO_RADIATION, SCHEMES, pack, radiation_pack, sea_pack  # noqa: E402
    from .simulation import observe  # noqa: E402, F401
finally:
    numba.config.CACHE_DIR = _users_cache_dir

__all__ = ["cached", "JIT", "njit", "advance", "advance_many", "warm_up", "MODELS", "NO_RADIATION", "SCHEMES", "pack", "radiation_pack", "sea_pack"]

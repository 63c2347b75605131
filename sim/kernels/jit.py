"""The JIT settings every kernel is compiled with (their own module, so no kernel imports the package face)."""

from __future__ import annotations

from numba import njit  # noqa: F401  (re-exported: every kernel module takes both from here)

JIT = {"cache": True, "nogil": True, "fastmath": False, "error_model": "numpy"}

"""Compiled twin of bodies/state.py."""

from __future__ import annotations

from .jit import JIT, njit
from .rotation import mtv, mv


@njit(**JIT)
def angular_velocity(R, L, inertia):
    """omega = R I^-1 R^T L."""
    return mv(R, mtv(R, L) / inertia)

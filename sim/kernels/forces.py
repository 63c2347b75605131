"""Compiled twin of forces.Model: the loads of the scene's terms (spec.USED), each term's own function in
kernels/terms.py, summed in the reference's order.

`model` is the body (layout.Model), `s` the scratch one pose's loads leave for the next evaluation
(layout.Scratch), `sea` the water (layout.sea_pack). Term bits, masks and coefficient slots all come from
the registry (spec.py, layout.py), so a new term adds its function to terms.py and its line below.
"""

from __future__ import annotations

import numpy as np

from .jit import JIT, njit
from .layout import HELD
from .spec import DAMPING, DRAG, GRAVITY, HAS_NONLINEAR, HEAVE_DAMPING, HOLDING, LINEAR_TWIST, PRESSURE, TWIST_TERMS, USED, WET_TERMS
from .terms import C_DRAG, damping, drag, gravity, heave_damping, pressure
from .wet import wet_surface


@njit(**JIT)
def pose_loads(x, R, t, model, s, sea):
    """(F, T, D, wet): the pose terms' force and torque at a pose and time (and the held load), the linear twist terms' matrix
    D there (damping's and the heave damping's), and whether any twist term has a wet surface to act on. Damping's part from the water's
    motion (its affine part, zero in still water) goes to s.ws[4] for twist_loads and linearised."""
    load = np.zeros(6)
    D = np.zeros((6, 6))
    if USED & GRAVITY:
        load += gravity(model, None)
    if HOLDING:  # (forces.Model.held)
        load += model.coef[HELD : HELD + 6]
    s.ws[4][:] = 0.0
    is_wet = False
    if USED & WET_TERMS:
        wet = wet_surface(x, R, t, model, s, sea)
        if USED & PRESSURE:
            load += pressure(model, wet)
        is_wet = (USED & TWIST_TERMS) != 0 and wet.area > 0.0
        if is_wet and USED & DAMPING:
            D, affine = damping(model, wet)
            s.ws[4][:] = affine
        if is_wet and USED & HEAVE_DAMPING:
            D[2, 2] += heave_damping(model, wet)
    return load[:3], load[3:], D, is_wet


@njit(**JIT)
def nonlinear_loads(x, R, u, w, model, s, need_D):
    """Force, torque and (need_D) Jacobian of the nonlinear twist terms the scene uses."""
    F = np.zeros(3)
    T = np.zeros(3)
    D = np.zeros((6, 6))
    if USED & DRAG:
        Fd, Td, Dd = drag(x, R, u, w, model, s, need_D)
        F += Fd
        T += Td
        D += Dd
    return F, T, D


@njit(inline="always", **JIT)
def nonlinear_acting(model):
    """Whether a nonlinear twist term acts: every scheme's kernels compile drag (kernels.EVERY_TERM), scenes without it
    too, where its coefficient is zero: skipped then, and the implicit and splitting steps take their linear path."""
    return HAS_NONLINEAR and (USED & DRAG) != 0 and model.coef[C_DRAG] != 0.0


@njit(inline="always", **JIT)
def twist_loads(x, R, u, w, model, D, wet, s, F, T):
    """Add the force and torque of the twist terms at (u, w) to F, T in place (no allocation in the
    hot loop): d u_water - D (u, w) for linear damping (ws[4], zero in still water), plus the nonlinear ones."""
    if not wet:
        return
    if USED & LINEAR_TWIST:
        affine = s.ws[4]
        for i in range(3):
            F[i] += affine[i] - (D[i, 0] * u[0] + D[i, 1] * u[1] + D[i, 2] * u[2] + D[i, 3] * w[0] + D[i, 4] * w[1] + D[i, 5] * w[2])
            T[i] += affine[3 + i] - (D[3 + i, 0] * u[0] + D[3 + i, 1] * u[1] + D[3 + i, 2] * u[2] + D[3 + i, 3] * w[0] + D[3 + i, 4] * w[1]
                                     + D[3 + i, 5] * w[2])  # fmt: skip
    if nonlinear_acting(model):
        Fn, Tn, _ = nonlinear_loads(x, R, u, w, model, s, False)
        for i in range(3):
            F[i] += Fn[i]
            T[i] += Tn[i]


@njit(**JIT)
def linearised(x, R, u, w, model, F, T, D, wet, s):
    """(f, D) with loads ~ f - D (u, w) near (u, w), as forces.Model.linearised: the pose loads
    (F, T), damping's part from the water's motion, plus each nonlinear term's affine part, and the
    sum of the Jacobians. Linear only: those, D."""
    f = np.empty(6)
    f[:3] = F
    f[3:] = T
    if wet and USED & DAMPING:
        f += s.ws[4]
    if not nonlinear_acting(model) or not wet:
        return f, D
    Fn, Tn, Dn = nonlinear_loads(x, R, u, w, model, s, True)
    for i in range(6):
        acc = 0.0
        for j in range(3):
            acc += Dn[i, j] * u[j] + Dn[i, 3 + j] * w[j]
        f[i] += (Fn[i] if i < 3 else Tn[i - 3]) + acc
    return f, D + Dn

"""The explicit stability numbers of PHYSICS.md for a model and a time step, and the messages built
from them: warnings before a run, and the likely cause named when one diverges."""

from __future__ import annotations

import math

import numpy as np

from sim.bodies.surface import wet_points
from sim.hydro.forces import Model, damping_matrix
from sim.water.seas import StillWater


def numbers(model: Model, dt: float) -> dict[str, float]:
    """dt * omega_heave (water-plane area ~ V^(2/3)) and dt * lambda_max, the fastest damping rate:
    the largest eigenvalue of diag(M, I)^(-1/2) D diag(M, I)^(-1/2) with the whole surface wet (sway
    and roll couple, so it exceeds d A / M), the heave damping's B_33 in it. Quadratic drag's rate depends on the speed and is not
    counted here."""
    body, p = model.body, model.fluid
    omega = math.sqrt(p.rho * p.g * body.volume ** (2 / 3) / body.mass)
    rate = 0.0
    if model.has("damping") or model.has("heave_damping"):
        D = np.zeros((6, 6))
        if model.has("damping"):
            D += damping_matrix(p, wet_points(body, StillWater(p.rho, p.g), np.array([0.0, 0.0, -1e9]), np.eye(3), 0.0))
        D[2, 2] += p.heave_damping  # (forces.heave_damping)
        w = np.concatenate([np.full(3, body.mass), body.inertia]) ** -0.5
        rate = float(np.linalg.eigvalsh(w[:, None] * D * w[None, :]).max())
    return {"heave": dt * omega, "damping": dt * rate}


def warnings(n: dict[str, float], integ, dt: float) -> list[str]:
    """Settings past the integrator's stability limits (a run may blow up, or wander without blowing up)."""
    out = []
    if n["damping"] > integ.damping_limit:
        out.append(f"dt*lambda_max = {n['damping']:.3g} is past the damping limit {integ.damping_limit:.3g} of '{integ.name}': "
                   f"use --integrator implicit or --dt below {dt * integ.damping_limit / n['damping']:.3g}")  # fmt: skip
    if n["heave"] > integ.heave_limit:
        out.append(f"dt*omega_heave = {n['heave']:.3g} is past the heave limit {integ.heave_limit:.3g} of '{integ.name}': "
                   f"use --dt below {dt * integ.heave_limit / n['heave']:.3g}")  # fmt: skip
    return out


def diagnosis(n: dict[str, float], integ, dt: float, t: float, what: str) -> str:
    """The one-line divergence message: when, what, and the likely cause with what to change."""
    if n["damping"] > 0.5 * integ.damping_limit:
        cause = (f"dt = {dt:g} s is too large for this damping with '{integ.name}' (dt*lambda_max = {n['damping']:.3g}, "
                 f"its limit {integ.damping_limit:.3g}): use --integrator implicit or a smaller --dt")  # fmt: skip
    elif n["heave"] > 0.5 * integ.heave_limit:
        cause = (f"dt = {dt:g} s is too large for this body's heave oscillation (dt*omega = {n['heave']:.3g}, "
                 f"limit {integ.heave_limit:.3g}): use a smaller --dt")  # fmt: skip
    else:
        cause = "try a smaller --dt or another --integrator"
    return f"simulation diverged at t = {t:.6g} s: {what}; likely cause: {cause}"

"""The elastic catenary in closed form: a mooring line at rest, for checking MoorDyn and for the
linearised stiffness of a spread (what the moored body's slow surge period follows from).

A line of unstretched length L, weight in water w per unit length and axial stiffness EA hangs from
its anchor on a flat, frictionless seabed to its fairlead, a horizontal span X and a height Z above the
anchor. With H the horizontal tension (constant along the line) and V the vertical one at the
fairlead, the suspended part is V / w long; where it is shorter than L the rest lies on the seabed
(Irvine, *Cable Structures*, 1981; the equations of MAP++ and MoorPy without seabed friction):

  on the seabed in part (L_b = L - V / w > 0):
    X = L_b + (H / w) asinh(V / H) + H L / EA
    Z = (H / w) (sqrt(1 + (V / H)^2) - 1) + V^2 / (2 EA w)
  fully suspended:
    X = (H / w) (asinh(V / H) - asinh((V - w L) / H)) + H L / EA
    Z = (H / w) (sqrt(1 + (V / H)^2) - sqrt(1 + ((V - w L) / H)^2)) + (V L - w L^2 / 2) / EA
"""

from __future__ import annotations

import math

import numpy as np


def _ends(H: float, V: float, L: float, w: float, EA: float) -> tuple[float, float]:
    """(X, Z) of the fairlead above the anchor for tensions H, V."""
    on_bed = L - V / w
    if on_bed > 0:
        return (on_bed + H / w * math.asinh(V / H) + H * L / EA,
                H / w * (math.sqrt(1 + (V / H) ** 2) - 1) + V * V / (2 * EA * w))  # fmt: skip
    Va = V - w * L
    return (H / w * (math.asinh(V / H) - math.asinh(Va / H)) + H * L / EA,
            H / w * (math.sqrt(1 + (V / H) ** 2) - math.sqrt(1 + (Va / H) ** 2)) + (V * L - w * L * L / 2) / EA)  # fmt: skip


def _guesses(X: float, Z: float, L: float, w: float) -> list[tuple[float, float]]:
    """Starting (H, V) for the solve: the inextensible line's profile estimate of Peyrot and Goulois (1979), as MoorPy
    starts, then a shallow sag's, then a line barely taut's."""
    span = math.hypot(X, Z)
    lam = 1e6 if X == 0 else 0.2 if span >= L else math.sqrt(3 * ((L * L - Z * Z) / (X * X) - 1))
    first = (max(abs(w * X / (2 * lam)), 1e-6 * w * L), max(0.5 * w * (Z / math.tanh(lam) + L), 1e-6 * w * L))
    H = w * max(X + Z - L, 1e-12 * L)  # barely taut: the hanging part nearly vertical, H asinh(w Z / H) = w (X + Z - L)
    for _ in range(20):
        H = w * max(X + Z - L, 1e-12 * L) / math.asinh(max(w * Z / H, 1e-12))
    sag = (max(w * L * 1e-2, w * X * X / (2 * max(Z, 1e-6)) * 0.5), min(w * L, w * Z + 1e-3 * w * L))
    return [first, sag, (H, w * Z + H)]


def catenary(X: float, Z: float, L: float, w: float, EA: float) -> tuple[float, float]:
    """(H, V): the horizontal and vertical tension at the fairlead, N, of a line spanning X horizontally
    and Z vertically (m) from its anchor on the seabed; w its weight in water, N/m, EA its axial stiffness, N."""
    from scipy.optimize import fsolve  # scipy.optimize takes 0.5 s to import: paid by the scenes with lines

    hanging = EA * (math.sqrt(1 + 2 * w * Z / EA) - 1)  # V of a line hanging straight down, stretched: Z = V / w + V^2 / (2 EA w)
    if X <= L - hanging / w:  # slack: it hangs straight down from the fairlead and the rest lies (folded) on the seabed
        return 0.0, hanging

    def residual(p):
        H, V = np.exp(p)  # positive by construction
        x, z = _ends(H, V, L, w, EA)
        return [(x - X) / L, (z - Z) / L]

    msg = ""
    for guess in _guesses(X, Z, L, w):  # a heavy, stiff chain can lead fsolve from one start to H -> 0: then the next
        try:
            with np.errstate(all="ignore"):
                p, _, _, msg = fsolve(residual, np.log(guess), full_output=True, xtol=1e-13)
                if max(abs(r) for r in residual(p)) <= 1e-10:
                    break
        except (ArithmeticError, ValueError):  # a step to H = 0 or past float range
            continue
    else:
        raise ValueError(f"the catenary did not converge ({msg.strip() or 'no start converged'})")
    H, V = np.exp(p)
    return float(H), float(V)


def fairlead_tension(X: float, Z: float, L: float, w: float, EA: float) -> float:
    H, V = catenary(X, Z, L, w, EA)
    return math.hypot(H, V)


def surge_stiffness(spread, x0: np.ndarray, rho: float, g: float, step: float = 1e-4) -> float:
    """-d(F_x)/dx of a moorings.LineSet on a body upright at x0 moved along x (translation only), N/m: the
    central difference of the lines' summed horizontal pull, each line a catenary from an anchor on the seabed."""

    def pull(dx: float) -> float:
        w, total = spread.weight_in_water(rho, g), 0.0
        for anchor, fair in spread.ends(np.asarray(x0, float) + [dx, 0.0, 0.0], np.eye(3)):
            gap = (anchor - fair)[:2]
            X = float(np.hypot(*gap))
            H, _ = catenary(X, float(fair[2] - anchor[2]), spread.line_length, w, spread.line_stiffness)
            total += H * gap[0] / X  # towards the anchor
        return total

    return -(pull(step) - pull(-step)) / (2 * step)

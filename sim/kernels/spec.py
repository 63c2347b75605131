"""The constants one copy of the kernels is compiled for (sim.kernels.specialised).

numba treats module globals as compile-time constants and drops a branch on one before it compiles,
so `if USED & DRAG:` costs nothing where the scene has no drag: a still-water drop compiles one scheme,
one force model and two terms, not every combination. The term bits and masks come from the registry
(forces.TERMS), never by hand.
"""

from __future__ import annotations

import sys

from sim.hydro.forces import TERMS

from .layout import MODELS, SCHEMES, bit

SPEC = getattr(sys.modules[__package__], "SPEC", None)
if SPEC is None:
    raise ImportError("compiled kernels are specialised: import them through sim.kernels.specialised(spec)")

SCHEME = SCHEMES[SPEC.scheme]
"""0 euler, 1 splitting, 2 implicit, 3 rk4 (layout.SCHEMES)."""
EULER, SPLITTING, IMPLICIT, RK4 = SCHEMES["euler"], SCHEMES["splitting"], SCHEMES["implicit"], SCHEMES["rk4"]
MODEL = MODELS[SPEC.model]
"""0 points, 1 panels, 2 cells (layout.MODELS)."""
POINTS, PANELS, CELLS = MODELS["points"], MODELS["panels"], MODELS["cells"]
WAVES = bool(SPEC.waves)
"""Whether the water surface moves (else still water: no sea components at all)."""
CURRENT = bool(SPEC.current)
"""Whether still water flows in a uniform current (sea_pack's last item): damping and drag act on the velocity relative to it."""
MOVING = WAVES or CURRENT
"""Whether the water moves: damping gains an affine part d u_water."""
RADIATING = bool(SPEC.radiating)
"""Whether the body radiates (the kernels also drop that code by testing their `rad` argument against None)."""

HOLDING = bool(SPEC.held)
"""Whether another model gives the body a load held over each step (the mooring lines: layout.HELD)."""

GRAVITY, PRESSURE, DAMPING, DRAG, HEAVE_DAMPING = bit("gravity"), bit("pressure"), bit("damping"), bit("drag"), bit("heave_damping")
LINEAR_TWIST = DAMPING | HEAVE_DAMPING
"""Twist terms whose load is affine in the twist: their Jacobians sum into the pose's D (kernels/forces.py)."""
USED = sum(bit(name) for name in SPEC.terms)
"""The scene's terms (bit i: forces.TERMS[i])."""
TWIST_TERMS = sum(bit(t.name) for t in TERMS if t.twist)
WET_TERMS = sum(bit(t.name) for t in TERMS if t.name != "gravity")  # as forces.Model.needs_wet
NONLINEAR = sum(bit(t.name) for t in TERMS if t.twist and not t.linear)
"""Twist terms whose load is not affine in the twist: relinearised by the implicit scheme."""
HAS_NONLINEAR = bool(USED & NONLINEAR)
"""Whether the nonlinear terms' code is compiled (always, kernels.EVERY_TERM); whether it acts is decided at run time
(forces.nonlinear_acting: a zero drag coefficient takes the linear paths)."""

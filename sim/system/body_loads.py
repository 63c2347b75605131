"""One body's loads near a twist, f - D nu, for a scheme that steps bodies on joints (system/tree.py): from the
numpy reference (forces.Model.linearised) or its compiled twin (kernels/simulation.py: linearised_loads).

The compiled twin of a body among several is its own small specialisation (kernels.Spec.system): its force
model, terms and water, the loads only, no scheme's loop; the system's kinematics and kicks stay in numpy.
A kick at the end of a step and the next step's first kick see the same pose and time: where every twist term
is linear (f and D do not depend on the twist) the second asks nothing of the water.
"""

from __future__ import annotations

import numpy as np

from sim.hydro.forces import Model, compiled_model


class BodyLoads:
    def __init__(self, model: Model):
        self.model = model
        self.linear = all(term.linear for term in model.twist_terms)
        self._compiled = None  # (the kernels' simulation module, their packed model, the sea packed for them)
        self._last: tuple = (None, None)  # (pose and time, (f, D))
        self._wet: tuple = (None, None)  # (pose and time, its wet surface)

    @property
    def spec(self):
        """The kernels.Spec of this body's loads."""
        from sim.kernels import compiled_terms, spec_of  # numba's import (0.6 s): only where compiled kernels run

        terms = compiled_terms(self.model.term_names, "implicit", every=False)  # (kernels.EVERY_TERM: not a system's loads)
        return spec_of(self.model, "implicit")._replace(terms=terms, radiating=False, held=False, system=True)

    @property
    def has_twin(self) -> bool:
        from sim.kernels import missing_terms  # numba's import (0.6 s): only where compiled kernels run

        return compiled_model(self.model) and not missing_terms(self.model) and self.model.held is None

    @property
    def compiled(self) -> bool:
        return self._compiled is not None

    def use_kernels(self, on: bool, expand: bool = True) -> None:
        """Ask the compiled twin (loaded from the disk cache, or compiled now) or, off, the numpy reference."""
        self._last = self._wet = (None, None)
        if not on:
            self._compiled = None
            return
        from sim import kernels  # numba's import (0.6 s): only where compiled kernels run

        body = self.model.body
        _, coef = kernels.pack(self.model)
        packed = kernels.Model(body.packed, body.mass, body.inertia, coef)
        self._compiled = (kernels.specialised(self.spec).simulation, packed, kernels.sea_pack(self.model.water, body, expand))

    def __call__(self, x: np.ndarray, R: np.ndarray, t: float, nu: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """(f, D): the loads near the twist nu = (u, omega) (world frame, at the centre of mass) as f - D nu."""
        key = (t, x.tobytes(), R.tobytes())
        if self._last[0] == key and self.linear:
            return self._last[1]
        if self._compiled is not None:
            simulation, packed, sea = self._compiled
            out = simulation.linearised_loads(x, R, t, nu[:3], nu[3:], packed, sea)
        else:  # the wet surface is kept for the next twist at this pose (a nonlinear term's relinearisation)
            wet = self._wet[1] if self._wet[0] == key else self.model.wetted(x, R, t)
            self._wet = (key, wet)
            out = self.model.linearised(wet, nu, t)
        self._last = (key, out)
        return out

"""Many independent bodies of one shape advanced together (sweeps over density, damping, initial state)."""

from __future__ import annotations

import dataclasses

import numpy as np

from sim.bodies.body import body_mass, exact_inertia, make_body, with_mass
from sim.bodies.state import State
from sim.compiling import default_backend
from sim.scene.config import ConfigError, SceneConfig
from sim.simulation import Simulation, SimulationDiverged
from sim.system.frame import Frame

SHARED = ("body.shape", "body.size", "body.extents", "body.points_per_edge", "body.mesh", "body.samples", "body.centre_of_mass", "body.inertia", "fluid.rho", "fluid.g", "fluid.forces",
          "step.integrator", "step.dt")  # fmt: skip
"""What the bodies of an ensemble must share; they may differ in mass, term coefficients and initial state."""


class Ensemble:
    """B bodies sharing shape, water, integrator and dt; each has its own density (or mass), force
    term coefficients (damping, drag, ...) and initial state. Fixed-step integrators run B x K steps in one compiled call; a body that
    diverges stops at its last good state and is reported, the others go on."""

    def __init__(self, scenes: list[SceneConfig], backend: str | None = None):
        if not scenes:
            raise ConfigError("an ensemble needs at least one body")
        base = scenes[0]
        for s in scenes[1:]:
            if any(s.value(key) != base.value(key) for key in SHARED):
                raise ConfigError("ensemble bodies must share shape, water, force model, integrator and dt; they may differ in density, "
                                  "force coefficients and initial state")  # fmt: skip

        # unit mass: each body's inertia is then this times its own mass, whatever the other bodies (bit for bit)
        shape = make_body(dataclasses.replace(base.body, mass=1.0), base.base_dir, exact_inertia(base))
        self.sims = []
        for s in scenes:
            self.sims.append(Simulation(s, body=with_mass(shape, body_mass(s, shape.volume), s.body.inertia), backend=backend))
        self.shape = shape
        self.dt = float(base.step.dt)
        self.backend = backend or default_backend()
        self.diverged: list[str | None] = [None] * len(scenes)
        self.stopped = [False] * len(scenes)
        """Bodies taken out of the run on purpose (a sweep's case at rest); they keep their last state."""

    @property
    def states(self) -> list[State]:
        return [s.body_state for s in self.sims]

    def frames(self) -> list[Frame]:
        return [s.frame() for s in self.sims]

    def step(self, n: int = 1, check_energy: bool = True) -> None:
        """Advance every body still running by n steps. check_energy=False skips the energy blow-up check
        after the compiled steps (a non-finite state is still caught): for callers that step in many
        small blocks and check at their own, sparser points."""
        live = [i for i, why in enumerate(self.diverged) if why is None and not self.stopped[i]]
        if not live:
            return
        first = self.sims[live[0]]
        one_sea = all(self.sims[i].scene.waves == first.scene.waves and self.sims[i].scene.water == first.scene.water and self.sims[i].body_state.t == first.body_state.t and self.sims[i].model.radiation is None
                      and self.sims[i].moorings is None  # (moored bodies step on their own: MoorDyn between steps)
                      for i in live)  # fmt: skip
        if self.backend == "numba" and first.compiled and one_sea:
            self._step_compiled(live, n, check_energy)
            return
        for i in live:
            try:
                self.sims[i].step(n)
            except SimulationDiverged as e:
                self.diverged[i] = str(e)

    def spec(self, live: list[int] | None = None):
        """The kernels.Spec that steps the bodies `live` together (default: all): every term any of them uses
        (a term some body leaves out has a zero coefficient there: it adds nothing)."""
        from sim.kernels import compiled_terms  # numba's import (0.6 s): only where compiled kernels run

        sims = self.sims if live is None else [self.sims[i] for i in live]
        return sims[0].spec._replace(terms=compiled_terms({name for s in sims for name in s.model.term_names}, sims[0].spec.scheme))

    def _step_compiled(self, live: list[int], n: int, check_energy: bool = True) -> None:
        from sim import kernels  # numba's import (0.6 s): only where compiled kernels run

        sims = [self.sims[i] for i in live]
        Y = np.array([s.body_state.as_vector() for s in sims])
        masses = np.array([s.body.mass for s in sims])
        inertias = np.array([s.body.inertia for s in sims])
        coefs = np.array([kernels.pack(s.model)[1] for s in sims])
        sea = kernels.sea_pack(sims[0].model.water, self.shape)
        Y, done = kernels.specialised(self.spec(live)).schemes.advance_many(Y, sims[0].body_state.t, n, self.dt, self.shape.packed, masses, inertias, coefs, sea,
                                                         kernels.NO_RADIATION)  # fmt: skip
        for i, s, y, k in zip(live, sims, Y, done):
            before = s.body_state
            s.body_state = State(before.t + k * self.dt, y[0:3], y[3:7], y[7:10], y[10:13])  # the ensemble steps bodies without radiation
            if k < n:
                self.diverged[i] = s.diagnose(s.body_state.t + self.dt, "the state became non-finite")
            elif check_energy and s.frame().E_total - s._E_ref > 10.0 * s._E_scale:
                self.diverged[i] = s.diagnose(s.body_state.t, "the energy blew up")
                s.body_state = before  # the last state that passed the check, as Simulation.step does

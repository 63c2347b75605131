"""Many independent bodies of one shape advanced together (sweeps over density, damping, initial state)."""

from __future__ import annotations

import numpy as np

from .body import make_body
from .config import ConfigError, SceneConfig
from .simulation import Frame, SimulationDiverged, with_mass
from .state import State


class Ensemble:
    """B bodies sharing shape, water, integrator and dt; each has its own density (or mass), damping
    and initial state. Fixed-step integrators run B x K steps in one compiled call; a body that
    diverges stops at its last good state and is reported, the others go on."""

    def __init__(self, scenes: list[SceneConfig], backend: str | None = None):
        if not scenes:
            raise ConfigError("an ensemble needs at least one body")
        base = scenes[0]
        for s in scenes[1:]:
            same = (s.body.shape, s.body.size, s.body.extents, s.body.points_per_edge, s.body.mesh, s.body.samples, s.fluid.rho, s.fluid.g, s.fluid.forces, s.step.integrator, s.step.dt)
            if same != (base.body.shape, base.body.size, base.body.extents, base.body.points_per_edge, base.body.mesh, base.body.samples,
                        base.fluid.rho, base.fluid.g, base.fluid.forces, base.step.integrator, base.step.dt):  # fmt: skip
                raise ConfigError("ensemble bodies must share shape, water, force model, integrator and dt; they may differ in density, damping and initial state")
        from .simulation import Simulation, default_backend

        shape = make_body(base.body, base.base_dir)
        self.sims = []
        for s in scenes:
            mass = s.body.mass if s.body.mass is not None else s.body.density * shape.volume
            self.sims.append(Simulation(s, body=with_mass(shape, mass), backend=backend))
        self.shape = shape
        self.dt = float(base.step.dt)
        self.backend = backend or default_backend()
        self.diverged: list[str | None] = [None] * len(scenes)

    @property
    def states(self) -> list[State]:
        return [s.state for s in self.sims]

    def frames(self) -> list[Frame]:
        return [s.frame() for s in self.sims]

    def step(self, n: int = 1) -> None:
        """Advance every body still running by n steps."""
        live = [i for i, why in enumerate(self.diverged) if why is None]
        if not live:
            return
        if self.backend == "numba" and self.sims[0].compiled:
            self._step_compiled(live, n)
            return
        for i in live:
            try:
                self.sims[i].step(n)
            except SimulationDiverged as e:
                self.diverged[i] = str(e)

    def _step_compiled(self, live: list[int], n: int) -> None:
        from . import fast

        sims = [self.sims[i] for i in live]
        p = sims[0].params
        Y = np.array([s.state.as_vector() for s in sims])
        masses = np.array([s.body.mass for s in sims])
        inertias = np.array([s.body.inertia for s in sims])
        ds = np.array([s.params.damping for s in sims])
        scheme = fast.SCHEMES[sims[0].integrator.name]
        Y, done = fast.advance_many(Y, n, self.dt, scheme, fast.MODELS[p.forces], self.shape.packed, masses, inertias, p.rho, p.g, ds)
        for i, s, y, k in zip(live, sims, Y, done):
            before = s.state
            s.state = State(before.t + k * self.dt, y[0:3], y[3:7], y[7:10], y[10:13])
            if k < n:
                self.diverged[i] = s._diagnose(s.state.t + self.dt, "the state became non-finite")
            elif s.frame().E_total - s._E_ref > 10.0 * s._E_scale:
                self.diverged[i] = s._diagnose(s.state.t, "the energy blew up")
                s.state = before  # the last state that passed the check, as Simulation.step does


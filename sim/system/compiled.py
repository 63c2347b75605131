"""The compiled system step (kernels/system.py, kinematics.py, expm.py) for a run of several bodies on the numba backend: the same
SystemState in and out as System.step, so a run can switch between the two between steps.

With linear loads (`[fluid] hydro = "linear"`) n steps are one compiled call. Otherwise each body's loads (its compiled
twin, system/body_loads.py, or the numpy reference) are asked from Python at each kick, between two compiled calls a step;
the kinematics, the kicks, the drift, the radiation memory and the take-offs are compiled either way. The held
loads (the mooring lines') are read from system.held at each call: fixed over the steps of one call.
"""

from __future__ import annotations

import os

import numpy as np

from sim.hydro.linear_hydro import LinearLoads
from sim.scene.config import load_scene, with_overrides
from sim.system.tree import System, SystemState, build

KERNELS = {"system-step": "system.half_step", "system-linear": "system.advance"}
"""The compiled function each system step uses (its disk cache tells whether it is ready), by its Spec's scheme: the
kick loop whose loads Python asks at each kick, and the linear loads' n steps a call. Each also gives a configuration's
kinematics alone (CompiledStep.configuration): one entry point a step, as each entry point compiles all it calls."""


def step_spec(system: System):
    """The kernels.Spec of the step `system` runs: SYSTEM_LINEAR where every body's loads are linear, else SYSTEM_STEP."""
    from sim.kernels import SYSTEM_LINEAR, SYSTEM_STEP  # numba's import (0.6 s): only where compiled kernels run

    return SYSTEM_LINEAR if all(isinstance(lo, LinearLoads) for lo in system.loads) else SYSTEM_STEP


def ready(spec) -> bool:
    """Whether this machine compiled the system step of `spec` before (its disk cache has every kernel it uses)."""
    from sim.kernels import KERNEL_CACHE, compiled_here  # numba's import (0.6 s): only where compiled kernels run

    return KERNELS[spec.scheme] in compiled_here(os.path.join(KERNEL_CACHE, "shared"))


def warm(spec) -> float:
    """Compile (first run ever) or load the kernels of the system step of `spec`, on scenes that call every one of them
    with each signature a run passes; seconds taken. The kick loop: rm3 as shipped (nonlinear loads, radiation,
    diffraction) and without radiation in still water. Linear loads: rm3's spar on a planar joint (n steps in one call;
    the configuration a controller's inertia and the lines ask)."""
    import dataclasses
    import time

    started = time.perf_counter()
    rm3 = load_scene("rm3")
    if spec.scheme == "system-linear":
        spar = rm3.bodies[0]
        planar = dataclasses.replace(spar, constraint=dataclasses.replace(spar.constraint, joint="planar", axis=(0.0, 1.0, 0.0)))
        scenes = [with_overrides(dataclasses.replace(rm3, bodies=(planar, *rm3.bodies[1:])), fluid__hydro="linear")]
    else:
        plain = dataclasses.replace(
            rm3, fluid=dataclasses.replace(rm3.fluid, radiation="none"), waves=dataclasses.replace(rm3.waves, kind="still")
        )
        scenes = [rm3, plain]
    for scene in scenes:
        system, state = build(scene)
        step = CompiledStep(system)
        step.configuration(state, float(scene.step.dt))
        step.step(state, float(scene.step.dt), 2)
    return time.perf_counter() - started


class CompiledStep:
    """A system packed for the compiled step (kernels/system_layout.py), once; the radiation's per time step."""

    def __init__(self, system: System):
        from sim.kernels.system_layout import linear_pack, tree_pack  # numba's import (0.6 s): only where compiled kernels run

        self.system = system
        self.tree = tree_pack(system)
        self.linear = linear_pack(system)
        self._memory: tuple = (None, None)
        self._config: tuple = (None, None)

    def memory(self, dt: float):
        if self._memory[0] != dt:
            from sim.kernels.system_layout import memory_pack  # numba's import (0.6 s): only where compiled kernels run

            self._memory = (dt, memory_pack(self.system, dt))
        return self._memory[1]

    def held(self) -> np.ndarray:
        """(k, 6) each body's held load (zeros: none)."""
        return np.array([np.zeros(6) if h is None else np.asarray(h, float) for h in self.system.held]).reshape(-1, 6)

    def step(self, s: SystemState, dt: float, n: int = 1, before=None) -> tuple[SystemState, int]:
        """n steps of dt from s (stopping after one whose state is non-finite): the state and the steps taken. `before`:
        called at each step's start as before(t, theta, v, absorbed, inertia) (the take-offs' controllers: they set the
        tree's laws and may change v and absorbed in place; inertia() the mass matrix there); then a compiled call a step."""
        from sim.kernels import system as kernels  # numba's import (0.6 s): only where compiled kernels run

        if n < 1:
            return s, 0
        mem, held = self.memory(dt), self.held()
        args = (float(s.t), s.x_free, s.q_free, s.theta, s.v, s.absorbed, s.memory, float(s.E_rad))
        if self.linear.on and before is None:
            *out, taken, config = kernels.advance(self.tree, self.linear, mem, *args, held, dt, n)
            state = self._state(*out)
            self._config = (state, config)
            return state, taken
        if self.linear.on:  # a controller between the steps: one compiled call each
            taken, state = 0, s
            for taken in range(1, n + 1):
                v, absorbed = state.v.copy(), state.absorbed.copy()
                before(state.t, state.theta, v, absorbed, lambda: self.configuration(state, dt)[3])  # noqa: B023 (called at once)
                args = (float(state.t), state.x_free, state.q_free, state.theta, v, absorbed, state.memory, float(state.E_rad))
                *out, _, config = kernels.advance(self.tree, self.linear, mem, *args, held, dt, 1)
                state = self._state(*out)
                self._config = (state, config)
                if not state.is_finite():
                    break
            return state, taken
        t, x_free, q_free, theta, v, absorbed, memory, E_rad = args
        v, absorbed = v.copy(), absorbed.copy()
        config = self.configuration(s, dt)
        for taken in range(1, n + 1):
            if before is not None:
                before(t, theta, v, absorbed, lambda: config[3])  # noqa: B023 (called at once)
            f, D = self._loads(config, t, v)
            config, x_free, q_free, theta, v, absorbed, memory, E_rad = kernels.half_step(
                self.tree, mem, config, t, x_free, q_free, theta, v, absorbed, memory, E_rad, f, D, held, dt, kernels.OPEN
            )
            t = t + dt
            f, D = self._loads(config, t, v)
            v, absorbed = kernels.half_step(
                self.tree, mem, config, t, x_free, q_free, theta, v, absorbed, memory, E_rad, f, D, held, dt, kernels.CLOSE
            )[4:6]
            if not (np.isfinite(v).all() and np.isfinite(theta).all() and np.isfinite(x_free).all() and np.isfinite(q_free).all()):
                break
        out = self._state(t, x_free, q_free, theta, v, absorbed, memory, E_rad)
        self._config = (out, config)
        return out, taken

    def configuration(self, s: SystemState, dt: float):
        """The configuration's kinematics at s (kernels.system.configure's: x, R, J, M, G, along), from the step's own
        entry point (the last step's end kept: the next step starts there)."""
        from sim.kernels import system as kernels  # numba's import (0.6 s): only where compiled kernels run

        if self._config[0] is not s:
            mem, held = self.memory(dt), self.held()
            args = (float(s.t), s.x_free, s.q_free, s.theta, s.v, s.absorbed, s.memory, float(s.E_rad))
            if self.linear.on:
                config = kernels.advance(self.tree, self.linear, mem, *args, held, dt, 0)[-1]
            else:
                k, n = len(self.system.loads), self.tree.n_dofs
                blank = (np.zeros((k, 3)), np.zeros((k, 3, 3)), np.zeros((k, 6, n)), np.zeros((n, n)), np.zeros((6 * k, n)),
                         np.zeros((0, k, 6, n)))  # fmt: skip
                f, D = np.zeros((k, 6)), np.zeros((k, 6, 6))
                config = kernels.half_step(self.tree, mem, blank, *args, f, D, held, dt, kernels.CONFIGURE)[0]
            self._config = (s, config)
        return self._config[1]

    def pose(self, s: SystemState, dt: float, b: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x, R, J) of body b at s (System.pose's), from the compiled kinematics."""
        x, R, J = self.configuration(s, dt)[:3]
        return x[b], R[b], J[b]

    def _loads(self, config, t: float, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(f (k, 6), D (k, 6, 6)): each body's loads near its twist, from its own loads (body_loads.BodyLoads)."""
        x, R, J = config[0], config[1], config[2]
        k = len(self.system.loads)
        f, D = np.zeros((k, 6)), np.zeros((k, 6, 6))
        for b, loads in enumerate(self.system.loads):
            fb, Db = loads(x[b], R[b], t, J[b] @ v)
            f[b] = fb
            if Db is not None:
                D[b] = Db
        return f, D

    @staticmethod
    def _state(t, x_free, q_free, theta, v, absorbed, memory, E_rad) -> SystemState:
        return SystemState(float(t), x_free, q_free, theta, v, absorbed, memory, float(E_rad))

"""A running scene of several bodies ([[bodies]]): the system (system/tree.py), its state and step, its mooring lines;
`Simulation(scene)` returns one for such a scene, with the one-body class's methods (step, frame, reset, update,
columns, use_backend, close). Stops loudly on a non-finite state.

`update` names a body's parameters 'BODY__key' (float__pto_damping=1e6, spar__density=900; config.with_overrides).
A take-off's damping or stiffness changes in place; any other change rebuilds the system from the scene (the
coefficients come from the disk cache) and carries the motion over: every body stays where it is and moves as it did
(the joints' coordinates and rates as they are; a free group's centre of mass and its velocity moved with it where a
welded member's mass changed). A new joint kind or tree starts the scene afresh from its starting pose, saying so.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from sim.bodies.state import State
from sim.compiling import default_backend, kernels_ready, warm_up
from sim.control.laws import JointState, WaveState
from sim.errors import ConfigError, SimulationDiverged
from sim.scene.config import SceneConfig, validate, with_overrides
from sim.simulation import Simulation
from sim.system.carry import carried, only_take_offs, tree_shape, with_take_off
from sim.system.compiled import CompiledStep
from sim.system.frame import AssemblyFrame, observe
from sim.system.linear import exact_linear
from sim.system.tree import SystemState, body_frames, build


class Assembly(Simulation):
    """A running scene of several bodies: the system, its state and step. On the numba backend the bodies' loads come
    from their compiled twins when this machine has them (`kernels_ready`; `use_backend` loads or compiles them)."""

    def __init__(self, scene: SceneConfig, body=None, backend: str | None = None, mesh=None):

        if body is not None or mesh is not None:
            raise ConfigError("a scene of several bodies takes each body's mesh from its [[bodies]] entry (mesh = FILE)")
        scene = validate(scene)
        if not scene.bodies:
            raise ConfigError(f"scene {scene.name!r} has one body: run it with Simulation")
        self.scene = scene
        self.system, self.state = build(scene)
        self.start = self.state
        self.check_seconds = 0.0
        self.stepper = None
        """The compiled system step (system_compiled.CompiledStep) on the numba backend, else None: System.step."""
        self.moorings = None
        self._moor()
        self.notes: list[str] = []
        self._custom: dict = {}  # controllers given from Python (`control`), by joint
        self.controllers = self._make_controllers()

        self.exact = None if self.switching else exact_linear(self.system, self.state)
        """The exact stepper of a linear system (system/linear.py), or None: Stormer-Verlet."""
        if self.exact is not None:
            self.notes.append(
                "linear hydrostatics on slides: the system is linear and stepped exactly (its solution over each step, at any dt)"
            )
        if scene.step.integrator != "implicit" and self.exact is None:
            self.notes.append(
                f"several bodies step by their own scheme (Stormer-Verlet, damping implicit): integrator '{scene.step.integrator}' is not used"
            )
        self.backend = "numpy"
        wanted = backend or default_backend()
        if wanted == "numba" and not self.system.has_twin:
            self.notes.append("a body's force model or term has no compiled twin: the scene runs on the numpy reference (slower)")
        elif wanted == "numba" and self.kernels_ready:
            self.use_backend("numba")
        self._frame: tuple | None = None
        self._parts: tuple | None = None

    @property
    def compiled(self) -> bool:
        return self.backend == "numba"

    # take-off control (control/laws.py)

    def _make_controllers(self) -> list:
        """Each joint's controller (Simulation._make_controllers), its law into the system for the first step."""

        out = super()._make_controllers()
        system = self.system
        system.laws = [c.linear or law for c, law in zip(out, system.passive_laws())]
        self._group_index = [system.groups.index(g) for g in system.joints]
        return out

    def _constraint_of(self, name: str) -> tuple:
        return next(e.constraint for e in self.scene.bodies if e.name == name), f"[[bodies]] {name}: "

    @property
    def _start(self):
        return self.start

    def _controllers_changed(self) -> None:
        self.controllers = self._make_controllers()
        self._check_exact()
        self._repack()

    def _laws_into(self, t: float, theta: np.ndarray, v: np.ndarray, absorbed: np.ndarray, inertia) -> None:
        """Each switching controller's law for the step from (t, theta, v), into the system and the compiled step's tree.
        Where a spring's stiffness changes, the difference of its energy goes to the take-off's absorbed energy (E_total +
        E_pto stays whole); where a lock engages, the joint's rate is zeroed and the kinetic energy that takes is absorbed.
        `v` and `absorbed` change in place; `inertia()` gives the mass matrix there (asked only when a lock engages)."""

        system, tree = self.system, None if self.stepper is None else self.stepper.tree
        for j, (g, controller) in enumerate(zip(system.joints, self.controllers)):
            if controller.linear is not None:
                continue
            i, c = g.dofs.start, g.coordinate
            q, rate = float(theta[c]), float(v[i])
            law, old = controller.law(JointState(t, q, rate, self.dt), WaveState(system.water, g.origin[:2], t)), system.laws[j]
            absorbed[c] -= 0.5 * (law.stiffness - old.stiffness) * q * q
            if law.held and rate != 0.0:
                M = inertia()
                before = float(v @ M @ v)
                v[i] = 0.0
                absorbed[c] += 0.5 * (before - float(v @ M @ v))
            system.laws[j] = law
            if tree is not None:
                gi = self._group_index[j]
                tree.stiffness[gi], tree.damping[gi], tree.force[gi], tree.held[gi] = law.stiffness, law.damping, law.force, float(law.held)

    def _repack(self) -> None:
        """The laws into the compiled step's tree (read at each call)."""
        if self.stepper is not None:
            from sim.kernels.system_layout import take_offs  # numba's import (0.6 s): only where compiled kernels run

            tree = self.stepper.tree
            tree.stiffness[:], tree.damping[:], tree.force[:], tree.held[:] = take_offs(self.system)

    @property
    def kernels_ready(self) -> bool:
        """Whether the bodies' compiled loads can be loaded at once (this machine compiled them before)."""

        return self.system.has_twin and all(kernels_ready(spec) for spec in self.specs)

    def use_backend(self, backend: str) -> None:
        """The step compiled ('numba': the bodies' loads from their compiled twins and the system step,
        system/compiled.py, each loaded from the disk cache or compiled now) or numpy, from the next step on; the state
        is kept as it is. Without a twin for every body's loads, numpy. A linear system stepped exactly keeps its stepper."""

        backend = backend if self.system.has_twin else "numpy"
        if backend == "numba":
            for spec in self.system.specs:
                warm_up(spec)
        self.system.use_kernels(backend == "numba")
        self.stepper = CompiledStep(self.system) if backend == "numba" and self.exact is None else None
        if self.stepper is not None:
            self.stepper.step(self.state, self.dt, 1)  # compiled now, or loaded from the disk cache
        self.backend = backend

    @property
    def has_twin(self) -> bool:
        """Whether every body's loads have a compiled twin."""
        return self.system.has_twin

    @property
    def specs(self) -> list:
        """The kernels.Spec of the bodies' compiled loads, each once, and the system step's (kernels.SYSTEM_STEP) where it
        runs (not for a linear system stepped exactly)."""
        from sim.kernels import SYSTEM_STEP  # numba's import (0.6 s): only where compiled kernels run

        return self.system.specs + ([] if self.exact is not None else [SYSTEM_STEP])

    @property
    def spec(self):
        raise AttributeError("a scene of several bodies compiles one specialisation per kind of body: see .specs")

    @property
    def body(self):
        raise AttributeError("a scene of several bodies: its bodies are .system.members (each .body), its state .state")

    @property
    def model(self):
        raise AttributeError("a scene of several bodies: each body's model is .system.members[i].model")

    @property
    def body_names(self) -> list[str]:
        return [m.name for m in self.system.members]

    @property
    def bodies(self) -> list:
        return [m.body for m in self.system.members]

    @property
    def water(self):
        return self.system.water

    integrator = None
    """(Several bodies step by their own scheme: system/tree.py.)"""

    system = None
    state = None

    step_seconds = None
    """(No adaptive method steps several bodies.)"""

    expand_waves = True

    @property
    def n_samples(self) -> int:
        return sum(m.body.n_samples for m in self.system.members)

    def stability_numbers(self) -> dict[str, float]:
        return {}

    def warnings(self) -> list[str]:
        return []

    def validity_notes(self) -> list[str]:
        return []

    def diagnose(self, t: float, what: str) -> str:
        return f"{what} at t = {t:.6g} s: try a smaller time step"

    def update(self, **changes) -> None:
        """Change scene parameters between steps, validated ('section__key', or a body's 'BODY__key'): the scene stays the
        description of what runs. A take-off's damping or stiffness changes in place; another change rebuilds the system
        and carries the motion over (the module's docstring says how)."""
        old, scene = self.scene, with_overrides(self.scene, **changes)
        if scene == old:
            return
        if only_take_offs(old, scene):
            groups = [with_take_off(g, scene) for g in self.system.groups]
            joints = [g for g in groups if g.kind in ("prismatic", "revolute")]
            kept = (self.scene, self.system.groups, self.system.joints)
            self.scene, self.system.groups, self.system.joints = scene, groups, joints
            try:
                self.controllers = self._make_controllers()
            except ConfigError:
                self.scene, self.system.groups, self.system.joints = kept
                self.controllers = self._make_controllers()
                raise
            self._frame = None
            self._check_exact()
            if self.stepper is not None:  # the take-offs are packed in the compiled step's tree
                self.use_backend("numba")
            return
        system, start = build(scene)  # a failure here leaves the run as it was
        restarted = tree_shape(system) != tree_shape(self.system)
        state = start if restarted else carried(self.system, system, self.state, start)
        if restarted:
            self.notes.append("a joint's kind or the bodies' tree changed: the scene started again from its starting pose")
        backend, lines = self.backend, (old.moorings, old.fluid.rho, old.fluid.g) != (scene.moorings, scene.fluid.rho, scene.fluid.g)
        self.scene, self.system, self.state, self.start, self._frame = scene, system, state, start, None
        self.controllers = self._make_controllers()
        if self.moorings is not None and not (lines or restarted):
            self._hold_lines()
        else:
            self._moor()
        self._check_exact()
        self.use_backend(backend if backend == "numpy" or self.kernels_ready else "numpy")

    def _check_exact(self) -> None:

        self.exact = None if self.switching else exact_linear(self.system, self.state)

    def _kinematics_at_rest(self) -> list:
        return self._kinematics(self.state, from_system=True)

    def _hold_lines(self) -> None:
        for b in self.attached:
            self.system.held[b] = (self.moorings.loads[b] if len(self.moorings.bodies) > 1 else self.moorings.load).copy()

    def _kinematics(self, s: SystemState, from_system: bool = False) -> list:
        """Each body's (x, R, u, omega) at s, from the kinematics of the step that runs."""
        out = []
        for b in range(len(self.system.members)):
            if self.stepper is not None and not from_system:
                x, R, J = self.stepper.pose(s, self.dt, b)
            else:
                pose = self.system.pose(s)
                x, R, J = pose.x[b], pose.R[b], pose.J[b]
            nu = J @ s.v
            out.append((x, R, nu[:3], nu[3:]))
        return out

    def reset(self, state: SystemState | None = None) -> None:
        """Back to the starting state, or to `state` (the system, its coefficients and kernels kept; the lines start afresh)."""
        self.state = self.start if state is None else state
        for controller in self.controllers:
            controller.reset()
        self.system.laws = [c.linear or law for c, law in zip(self.controllers, self.system.passive_laws())]
        self._repack()
        self._moor()
        self._frame = None

    def close(self) -> None:
        if self.moorings is not None:
            self.moorings.close()

    def step(self, n: int = 1) -> SystemState:

        if self.exact is not None:  # a linear system: all n steps at once (no lines: they rule it out)
            new = self.exact.advance(self.state, self.dt, n)
            if not new.is_finite():
                raise SimulationDiverged(f"the state became non-finite by t = {new.t:.6g} s")
            self.state = new
            return new
        switching = self.switching
        if self.stepper is not None and self.moorings is None:  # all n steps in one compiled call (or a loop of two a step)
            new, _ = self.stepper.step(self.state, self.dt, n, self._laws_into if switching else None)
            if not new.is_finite():
                raise SimulationDiverged(f"the state became non-finite at t = {new.t:.6g} s: try a smaller time step")
            self.state = new
            return new
        for _ in range(n):
            if switching:  # the controllers' laws for this step (a call back into Python a step)
                s, system = self.state, self.system
                v, absorbed = s.v.copy(), s.absorbed.copy()
                self._laws_into(s.t, s.theta, v, absorbed, lambda: system.inertia(system.pose(s)))
                self.state = replace(s, v=v, absorbed=absorbed)
            if self.moorings is not None and len(self.moorings.bodies) > 1:  # lines on several bodies: each holds its share
                loads = self.moorings.advance_bodies(self._kinematics(self.state), self.dt)
                for b in self.attached:
                    self.system.held[b] = loads[b]
            elif self.moorings is not None:  # the lines over the step, their mean pull held over it (as for one body)
                x, R, J = self._moored_pose()
                nu = J @ self.state.v
                self.system.held[self.moored] = self.moorings.advance(x, R, nu[:3], nu[3:], self.dt)
            new = self.system.step(self.state, self.dt) if self.stepper is None else self.stepper.step(self.state, self.dt, 1)[0]
            if not new.is_finite():
                raise SimulationDiverged(f"the state became non-finite at t = {self.state.t + self.dt:.6g} s: try a smaller time step")
            self.state = new
        return self.state

    def _moored_pose(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x, R, J) of the moored body now, from the kinematics of the step that runs."""
        if self.stepper is not None:
            return self.stepper.pose(self.state, self.dt, self.moored)
        pose = self.system.pose(self.state)
        return pose.x[self.moored], pose.R[self.moored], pose.J[self.moored]

    def frame(self) -> AssemblyFrame:
        if self._frame is None or self._frame[0] is not self.state:
            s = self.state
            joints = []
            for g, law in zip(self.system.joints, self.system.laws):
                theta, rate = float(s.theta[g.coordinate]), float(s.v[g.dofs.start])
                joints.append(
                    (g.name, theta, rate, (law.damping * rate - law.force) * rate, float(s.absorbed[g.coordinate]), law.at(theta, rate))
                )
            lines, pull, tensions, energy = (), (), (), ()
            if self.moorings is not None:
                energy = self.moorings.energy_now()
                lines, tensions = tuple(self.moorings.lines()), tuple(self.moorings.line_tensions())
                each = self.moorings.fairlead_tensions()
                total = self.moorings.loads[:, :3].sum(axis=0) if len(self.moorings.bodies) > 1 else self.moorings.load[:3]
                pull = (*total, float(each.max()), *(float(t) for t in each))
            self._frame = (s, AssemblyFrame(s.t, body_frames(self.system, s), joints, self.system.energies(s), self.system.joint_axes(s), lines,
                                            pull, float(s.E_rad), tensions, energy))  # fmt: skip
        return self._frame[1]

    def parts(self) -> list:
        """Each body's one-body Frame at the current state (its pose and twist, its wet surface, the water's force and
        gravity on it about its centre of mass, its energies; not the joints' reactions, the lines' pull or the radiation
        of the bodies together): what a viewer draws of each body. Computed once per state, on the numpy reference."""
        if self._parts is None or self._parts[0] is not self.state:
            s, frames = self.state, []
            for m, b, R in zip(self.system.members, body_frames(self.system, s), self.system.pose(s).R):
                L = R @ (m.body.inertia * (R.T @ b["omega"]))
                frames.append(observe(m.model, State(s.t, b["x"].copy(), b["q"], b["u"].copy(), L)))
            self._parts = (self.state, frames)
        return self._parts[1]

    def columns(self) -> list[str]:
        """The CSV's header (AssemblyFrame.columns)."""
        return self.frame().columns()


Simulation.several = Assembly  # Simulation(scene) of several bodies makes one of these

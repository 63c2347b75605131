"""A running scene: set up from a scene, advanced in steps, observed as frames; stops loudly on divergence.

One runner for every scene. A scene is a system of bodies (system/tree.py); a body alone is a system of one
(system/single.py). The runner owns the scene, the system and its state (system/tree.SystemState), the take-offs'
controllers (control/laws.py) and the mooring lines (MoorDyn, lines/moorings.py), and changes them between steps
(`update`, `reset`, `control`). What differs between scenes is the step, each a specialisation of the system's:
- a body alone steps by its own schemes (system/single.py): the scene's integrator (seven, explicit to adaptive), on its
  joint to the world, or its compiled twin many steps a call; the lines coupled each step;
- bodies on joints step by the tree's Stormer-Verlet (system/tree.py), its compiled twin (system/compiled.py), or exactly
  where the system is linear (system/linear.py); the lines coupled each step.
Every scene's frame is a Frame (system/frame.py): each joint's take-off, the lines, the radiated energy, each body's
pose and twist (a body alone's observed besides: its loads, wet surface and energies) and the energies of all.

`update` names a body's parameters 'BODY__key' (float__pto_damping=1e6, spar__density=900; a body alone's: 'body__key'
or 'fluid__key'; config.with_overrides). A take-off's damping or stiffness changes in place; any other change rebuilds
what it touches and carries the motion over: every body stays where it is and moves as it did (a body alone: a new
geometry keeps its pose and twist, a new mass its u and omega; bodies on joints: the joints' coordinates and rates as
they are, a free group's centre of mass and its velocity moved with it where a welded member's mass changed). A new
joint kind or tree of several bodies starts the scene afresh from its starting pose, saying so.
"""

from __future__ import annotations

import dataclasses
import os
import time
from dataclasses import replace

import numpy as np

from sim.bodies.body import Body, body_mass, exact_inertia, make_body, make_mesh_body, with_mass
from sim.bodies.rotation import normalized, quat_multiply
from sim.bodies.state import State, angular_momentum, angular_velocity, initial_state
from sim.compiling import default_backend, kernels_ready, warm_up
from sim.control.laws import JointState, Law, WaveState, of_constraint, stiffness_check, wrap
from sim.dynamics.integrators import make_integrator
from sim.dynamics.joints import WorldJoint
from sim.errors import ConfigError, SimulationDiverged
from sim.hydro.forces import Model
from sim.hydro.hydrostatics import sampled_model_warning
from sim.hydro.radiation import make_radiation
from sim.lines.moorings import Moorings, line_file, moored
from sim.scene.config import SceneConfig, diffracting, validate, with_overrides
from sim.system import stability
from sim.system.carry import carried, only_take_offs, tree_shape, with_take_off
from sim.system.compiled import CompiledStep, step_spec
from sim.system.frame import Frame, body_frames, joint_reading, line_shapes, lines_reading, observe, of_body, system_frame
from sim.system.frequency import stiffness
from sim.system.linear import exact_linear
from sim.system.single import Motion, Single, StepFailed, from_system, system_of_one, to_system
from sim.system.tree import SystemState, build, lines_scene, moored_body
from sim.water.gauges import Gauges
from sim.water.records import describe, measured
from sim.water.seas import make_water

GEOMETRY = ("shape", "size", "extents", "points_per_edge", "mesh", "mesh_unit", "samples", "centre_of_mass", "inertia")
"""Body keys whose change rebuilds the body (the others only change its mass)."""


def sea_reach(water, g: float) -> float:
    """J/kg: the most energy per unit mass a sea can give a body that follows it, g times the most its surface can rise
    and fall (twice the sum of its amplitudes) plus the square of the most its surface can move (the sum of a_i omega_i).
    The energy is measured against still water, so a body lifted by a crest or down in a trough reads as energy gained:
    without this a body riding a 20 m sea read as a blow-up (a real one passes any such bound within steps)."""
    amplitude = np.abs(np.asarray(getattr(water, "amplitude", ()), float))
    omega = np.asarray(getattr(water, "omega", np.zeros_like(amplitude)), float)
    return g * 2.0 * float(amplitude.sum()) + float((amplitude * omega).sum()) ** 2


class Simulation:
    """A running scene, of one body or several: steps, frames, resets and updates it. Not thread-safe: one thread drives it.

    `scene` always describes what runs: `update` changes it and rebuilds only what the change touches. backend 'numba'
    runs the compiled twins (loaded from the disk cache, or compiled now); 'numpy' is the plain reference the tests
    compare them with.
    """

    def __init__(self, scene: SceneConfig, body: Body | None = None, backend: str | None = None, mesh=None):
        """`scene` is checked here too (a hand-built SceneConfig gets the same one-line ConfigError as a scene file).
        `mesh`: a trimesh.Trimesh (or a mesh file) to use as a body alone with the scene's [body] settings (samples,
        density or mass), instead of [body] mesh; `body`: a body made already (bodies/body.py), the ensemble's."""
        if getattr(scene, "bodies", ()) and (body is not None or mesh is not None):
            raise ConfigError("a scene of several bodies takes each body's mesh from its [[bodies]] entry (mesh = FILE)")
        if mesh is not None:
            name = str(mesh) if isinstance(mesh, (str, os.PathLike)) else "(trimesh object)"
            scene = with_overrides(scene, body__shape="mesh", body__mesh=name)
        self._mesh = mesh
        self.scene = validate(scene)
        self.notes: list[str] = []
        """Things the user should know about how this runs (a fallback to numpy, a scheme not used, ...)."""
        self.check_seconds = 0.0
        """What the last `step` call's blow-up check cost, s: a viewer sizes its chunks by it."""
        self.largest_turn = 0.0
        """A body alone with radiation: its largest rotation away from the rest orientation so far, degrees."""
        self.controllers: list = []
        """Each joint's take-off controller (control/laws.py), in the order of the system's joints."""
        self._custom: dict = {}  # controllers given from Python (`control`), by joint, kept over scene changes
        self.moorings: Moorings | None = None
        """The scene's mooring lines in MoorDyn, or None."""
        self.attached: list[int] = []
        """The bodies the lines hold (scene order)."""
        self.moored: int | None = None
        """The index of the body the mooring lines hold (None: no lines)."""
        self.single: Single | None = None
        """A body alone's step (system/single.py: its model, integrator, joint and compiled twin); None for several bodies."""
        self.stepper: CompiledStep | None = None
        """Several bodies' compiled system step (system/compiled.py) on the numba backend, else None: System.step."""
        self.exact = None
        """Several bodies' exact stepper where the system is linear (system/linear.py), else None: Stormer-Verlet."""
        self._frame: tuple = (None, None)  # (what the frame is of, the frame)
        g = self.scene.gauges
        self.gauges = Gauges([x.name for x in g], [(x.x, x.y) for x in g], [x.at_record for x in g],
                             measured(self.scene.waves, self.scene.base_dir) if any(x.at_record for x in g) else None)  # fmt: skip
        self._parts: tuple = (None, None)
        if self.scene.bodies:
            self._start_bodies(backend)
        else:
            self._start_body(body, backend)

    # a body alone: its system of one

    def _start_body(self, body: Body | None, backend: str | None) -> None:
        scene = self.scene
        self.backend = backend or default_backend()
        body = body or self._make_body(scene)
        self.single = Single(self._model(body), make_integrator(scene.step.integrator, scene.step.rtol, scene.step.atol), None)
        self._memory_of = None  # the radiation whose memory the state carries
        start = initial_state(body, scene)
        self.system = system_of_one(self.model, None, start)
        self._m, self._view = Motion(start), (None, None, None)
        self._join()
        self._moor()
        norm = float(np.linalg.norm(scene.initial.orientation))
        if abs(norm - 1.0) > 1e-6:  # a hand-typed one (a preset's, rounded to many digits, passes silently)
            self.notes.append(f"initial orientation q0 had norm {norm:.6g}: normalised")
        self._check_backend()
        self._sync_memory()
        self._rebase_energy()

    def _make_body(self, scene: SceneConfig) -> Body:
        if self._mesh is not None and scene.body.shape == "mesh" and not isinstance(self._mesh, (str, os.PathLike)):
            b = scene.body
            return make_mesh_body(self._mesh, int(b.samples), b.mass, b.density, "mesh", b.mesh_unit, exact_inertia(scene), b.centre_of_mass,
                                  b.inertia)  # fmt: skip
        return make_body(scene.body, scene.base_dir, exact_inertia(scene))

    def _model(self, body: Body) -> Model:
        scene = self.scene
        fluid = scene.fluid
        water = make_water(scene.waves, fluid.rho, fluid.g, scene.water.current, scene.base_dir)
        if scene.waves.kind == "record":
            if (note := describe(water, scene.waves)) not in self.notes:
                self.notes.append(note)
        radiation = None
        if fluid.radiation == "bem":
            R = initial_state(body, scene).R_world_body
            drift = water if scene.waves.drift and not water.flat else None
            radiation = make_radiation(body, scene, R, water=water if diffracting(scene) else None, drift=drift,
                                       joint_at=lambda rest: WorldJoint.of_scene(scene, rest, R))  # fmt: skip
            depth = scene.waves.depth
            if depth is not None:
                note = (f"the radiation{' and diffraction' if diffracting(scene) else ''} coefficients are a deep-water solve: at the sea's "
                        f"depth {depth:g} m they hold for waves shorter than about {2 * depth:g} m (k h > pi: tanh k h > 0.996)")  # fmt: skip
                if note not in self.notes:
                    self.notes.append(note)
        return Model(body, water, fluid, radiation, held=moored(scene))

    @property
    def state(self) -> SystemState:
        """The run's state: its system's (a body alone's, made from its motion when asked, whose .x_world, .q_world_body,
        .u_world, .L_world and .body read the body's own state exactly)."""
        if self.single is None:
            return self._state
        m, system, view = self._view
        if m is not self._m or system is not self.system:
            self._view = (self._m, self.system, to_system(self.system, self.joint, self._m))
        return self._view[2]

    @state.setter
    def state(self, state: SystemState) -> None:
        if self.single is None:
            self._state = state
        else:
            self._m = from_system(self.system, self.joint, state)

    def _resystem(self, model: Model, joint: WorldJoint | None) -> None:
        """A body alone's model or joint replaced: its system of one made again (its motion is kept as it is)."""
        self.single.model, self.single.joint = model, joint
        self.system = system_of_one(model, joint, initial_state(model.body, self.scene))

    @property
    def body_state(self) -> State:
        """A body alone's own state (bodies/state.State: x_world, q_world_body, u_world, L_world, exact)."""
        return self._m.state

    @body_state.setter
    def body_state(self, state: State) -> None:
        self._m = replace(self._m, state=state)

    @property
    def joint_theta(self) -> float:
        """A body alone's joint coordinate, a hinge's whole turns counted (the pose alone gives it up to them); 0 when free."""
        return self._m.theta

    @property
    def pto_energy(self) -> float:
        """The energy a body alone's take-off has absorbed since the start, J."""
        return self._m.absorbed

    def _join(self) -> None:
        """The joint to the world about the scene's starting pose; the state put on it (its velocity projected)."""
        start = initial_state(self.body, self.scene)
        s = self.body_state
        self._resystem(self.model, WorldJoint.of_scene(self.scene, start.x_world, start.R_world_body))
        joint, theta = self.joint, 0.0
        if joint is not None:
            theta = joint.coordinate(s)
            s = joint.state(self.body, s.t, theta, joint.rate(self.body, s), s)
        self._m = Motion(s, theta, 0.0)
        self._make_controller()

    def _rejoin(self) -> None:
        """A changed joint or take-off: about the same starting pose, the run carried on (a new kind of joint: from where the body is)."""
        old, m = self.joint, self._m
        s = m.state
        start = (old.x0, old.R0) if old is not None else (s.x_world, s.R_world_body)
        self._resystem(self.model, WorldJoint.of_scene(self.scene, *start))
        joint, theta = self.joint, 0.0
        if joint is not None:
            theta = joint.coordinate(s, near=m.theta if old is not None and old.kind == joint.kind else 0.0)
            s = joint.state(self.body, s.t, theta, joint.rate(self.body, s), s)
        self._m = Motion(s, theta, m.absorbed)
        self._make_controller()
        self._check_backend()

    def _make_controller(self) -> None:
        """The joint's take-off controller (_make_controllers), its law set for the first step."""
        self.controllers = self._make_controllers()
        j = self.joint
        self._law = Law() if self.controller is None else self.controller.linear or Law(0.0, j.stiffness, j.damping)
        """The take-off's law over the last step (the frame's force and power)."""

    @property
    def controller(self):
        """A body alone's take-off controller (None without a joint that moves)."""
        return self.controllers[0] if self.single is not None and self.controllers else None

    def _next_law(self, s: State, theta: float) -> Law:
        """The controller's law for the step from s at the joint's coordinate theta."""
        if self.controller.linear is not None:  # a spring and damper: nothing to ask
            self._law = self.controller.linear
            return self._law
        j = self.joint
        self._law = self.controller.law(JointState(s.t, theta, j.rate(self.body, s), self.dt), WaveState(self.model.water, j.x0[:2], s.t))
        return self._law

    @property
    def model(self) -> Model:
        """A body alone's force model in its water (several bodies: each body's is .system.members[i].model)."""
        if self.single is None:
            raise AttributeError("a scene of several bodies: each body's model is .system.members[i].model")
        return self.single.model

    @property
    def body(self) -> Body:
        """A body alone's body: its samples, mass, inertia and mesh (several bodies: .bodies)."""
        if self.single is None:
            raise AttributeError("a scene of several bodies: its bodies are .system.members (each .body), its state .state")
        return self.single.model.body

    @property
    def integrator(self):
        """A body alone's integrator (dynamics/integrators.py); None for several bodies (they step by their own scheme)."""
        return None if self.single is None else self.single.integrator

    @property
    def joint(self) -> WorldJoint | None:
        """A body alone's joint to the world (dynamics/joints.py), or None (free)."""
        return None if self.single is None else self.single.joint

    @property
    def step_seconds(self) -> float | None:
        """Wall-time budget of one step of an adaptive method (None: only its evaluation cap); past it the
        step stops with SimulationDiverged naming a better integrator. The viewer sets it."""
        return None if self.single is None else self.single.step_seconds

    @step_seconds.setter
    def step_seconds(self, seconds: float | None) -> None:
        if self.single is not None:
            self.single.step_seconds = seconds

    @property
    def expand_waves(self) -> bool:
        """Whether the kernels may sum a many-component sea as a local expansion (kernels/water.py);
        False: every component at every node (benchmarks and checks)."""
        return True if self.single is None else self.single.expand_waves

    @expand_waves.setter
    def expand_waves(self, expand: bool) -> None:
        if self.single is not None:
            self.single.expand_waves = expand

    # several bodies: their tree

    def _start_bodies(self, backend: str | None) -> None:
        scene = self.scene
        self.system, self.state = build(scene)
        self.start = self.state
        self._moor()
        self.controllers = self._make_controllers()
        self._check_exact()
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

    def _check_exact(self) -> None:
        self.exact = None if self.switching else exact_linear(self.system, self.state)

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
                gi = system.groups.index(g)
                tree.stiffness[gi], tree.damping[gi], tree.force[gi], tree.held[gi] = law.stiffness, law.damping, law.force, float(law.held)

    def _repack(self) -> None:
        """The laws into the compiled step's tree (read at each call)."""
        if self.stepper is not None:
            from sim.kernels.system_layout import take_offs  # numba's import (0.6 s): only where compiled kernels run

            tree = self.stepper.tree
            tree.stiffness[:], tree.damping[:], tree.force[:], tree.held[:] = take_offs(self.system)

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

    # take-off control (control/laws.py): one path for every scene, over the system's joints (a body alone: its own)

    def _make_controllers(self) -> list:
        """Each joint's take-off controller (the one `control` gave, else its [constraint]'s), reset; a negative spring checked
        against the stiffness of the whole system at rest without it (system/frequency.stiffness, central differences). The
        tree's laws set for the first step."""
        system, stiff, out = self.system, None, []
        rest = self.state if self.single is not None else self.start
        for j, g in enumerate(system.joints):
            c, where = self._constraint_of(g.name)
            if j not in self._custom and c.pto_stiffness < 0:
                if stiff is None:
                    stiff = stiffness(system, replace(rest, theta=np.zeros_like(rest.theta), v=np.zeros_like(rest.v)))
                e = np.zeros(system.n_dofs)
                e[g.dofs.start] = 1.0
                stiffness_check(c.controller, c.pto_stiffness, stiff - c.pto_stiffness * np.outer(e, e), e, where)
            controller = self._custom.get(j) or of_constraint(c)
            controller.reset()
            out.append(controller)
        system.laws = [c.linear or law for c, law in zip(out, system.passive_laws())]
        return out

    def _constraint_of(self, name: str) -> tuple:
        """(the [constraint] of the joint's body, where to say it is in a message)."""
        if self.single is not None:
            return self.scene.constraint, ""
        return next(e.constraint for e in self.scene.bodies if e.name == name), f"[[bodies]] {name}: "

    @property
    def switching(self) -> bool:
        """Whether some take-off's law changes from step to step (a controller other than a spring and damper)."""
        return any(c.linear is None for c in self.controllers)

    def control(self, controller, body: str | None = None) -> None:
        """Drive the take-off of `body`'s joint (one of several: the body a joint's group is named by; a body alone: its own)
        by `controller`: a callable (t, control.JointState, control.WaveState) -> force (N or N m, held over each step) or a
        control.Controller; None: back to the scene's [constraint] controller."""
        names = [g.name for g in self.system.joints]
        if body is None and self.single is not None:
            if not names:
                raise ConfigError("a take-off controller needs the body on a prismatic or revolute joint ([constraint] joint)")
            body = names[0]
        if body not in names:
            raise ConfigError(f"no take-off on {body!r}: the joints with one are on {', '.join(names) or 'no body'}")
        j = names.index(body)
        if controller is None:
            self._custom.pop(j, None)
        else:
            self._custom[j] = wrap(controller)
        if self.single is not None:
            self._make_controller()
        else:
            self.controllers = self._make_controllers()
            self._check_exact()
            self._repack()

    # the mooring lines (MoorDyn, lines/moorings.py): one path for every scene, on one body or shared by several

    def _moor(self) -> None:
        """(Re)start the mooring lines where the bodies are now: MoorDyn finds their shape at rest there. Every fairlead on
        the one body the lines hold ([moorings] body), or each on its own ([moorings] attach)."""
        self.close()
        self.moorings, self.attached = None, []
        self.moored = (0 if moored(self.scene) else None) if self.single is not None else moored_body(self.scene)
        if self.moored is None:
            return
        k, bodies = self.moored, self._kinematics_at_rest()
        attach = self.scene.moorings.attach.split()
        if not attach:
            lines = Moorings.of_scene(lines_scene(self.scene, k), *bodies[k])
            self.attached = [k]
        else:
            owner = "nearest" if attach == ["nearest"] else [self.body_names.index(a) for a in attach]
            path = line_file(self.scene)
            lines = Moorings(path.read_text(), *bodies[0], bodies=bodies, owner=owner, folder=path.parent)
            lines = lines.counting(self.scene.moorings.energy)
            self.attached = sorted(set(lines.owner.tolist()))
        lines.t = self._m.state.t if self.single is not None else self.state.t
        self.moorings = lines
        self._hold_lines()

    def _kinematics_at_rest(self) -> list:
        """Each body's (x, R, u, omega) now, as the lines start from it (a body alone: its own state, exactly)."""
        if self.single is None:
            return self._kinematics(self.state, from_system=True)
        s = self.body_state
        return [(s.x_world, s.R_world_body, s.u_world, angular_velocity(self.body, s.R_world_body, s.L_world))]

    def _hold_lines(self) -> None:
        """The lines' pull now into the loads held on the bodies they hold (for the next step)."""
        if self.single is not None:
            self.model.held[:] = self.moorings.load
            return
        for b in self.attached:
            self.system.held[b] = (self.moorings.loads[b] if len(self.moorings.bodies) > 1 else self.moorings.load).copy()

    def close(self) -> None:
        """Let go of what runs beside the bodies (MoorDyn's lines)."""
        if self.moorings is not None:
            self.moorings.close()

    # what runs

    @property
    def params(self):
        """The fluid section of the scene: water, force model and every term's coefficients."""
        return self.scene.fluid

    @property
    def dt(self) -> float:
        """The time step, s."""
        return float(self.scene.step.dt)

    @property
    def body_names(self) -> list[str]:
        """The scene's bodies by the names update takes them by (config.body_names; a body alone: `body`)."""
        return [m.name for m in self.system.members]

    @property
    def bodies(self) -> list[Body]:
        """The running bodies, in the scene's order."""
        return [m.body for m in self.system.members]

    @property
    def water(self):
        """The running water (its surface, current and sea)."""
        return self.system.water

    @property
    def n_samples(self) -> int:
        """The bodies' samples together."""
        return sum(m.body.n_samples for m in self.system.members)

    @property
    def has_twin(self) -> bool:
        """Whether the scene has a compiled twin (a body alone: a fixed-step integrator with one, a force model it covers in
        this water, every term compiled; several bodies: every body's loads)."""
        return self.single.has_twin if self.single is not None else self.system.has_twin

    @property
    def compiled(self) -> bool:
        """Whether steps run in the compiled kernels."""
        return self.backend == "numba" and (self.single is None or self.has_twin)

    @property
    def spec(self):
        """What a body alone's compiled kernels specialise on (kernels.Spec)."""
        if self.single is None:
            raise AttributeError("a scene of several bodies compiles one specialisation per kind of body: see .specs")
        return self.single.spec

    @property
    def specs(self) -> list:
        """The kernels.Spec the scene's compiled kernels specialise on: a body alone's, or each kind of body's loads once and
        the system step's it runs (system/compiled.step_spec; none for a linear system stepped exactly)."""
        if self.single is not None:
            return [self.spec]
        return self.system.specs + ([] if self.exact is not None else [step_spec(self.system)])

    @property
    def kernels_ready(self) -> bool:
        """Whether the compiled kernels can be used at once: a twin exists and this machine compiled it before."""
        return self.has_twin and all(kernels_ready(spec) for spec in self.specs)

    def kernels(self):
        """A body alone's compiled kernels (kernels.specialised: loaded from the disk cache, or compiled now)."""
        return self.single.kernels()

    def _check_backend(self) -> None:
        self.notes += [n for n in self.single.backend_notes(self.backend) if n not in self.notes]

    def use_backend(self, backend: str) -> None:
        """Step on `backend` ('numba' or 'numpy') from the next step on; the state is kept as it is. Several bodies: their
        loads from their compiled twins and the compiled system step (system/compiled.py), each loaded from the disk
        cache or compiled now; without a twin for every body's loads, numpy; a linear system stepped exactly keeps its
        stepper."""
        if self.single is not None:
            self.backend = backend
            self._frame = (None, None)
            self.notes = [n for n in self.notes if "numpy reference" not in n]
            self._check_backend()
            return
        backend = backend if self.system.has_twin else "numpy"
        if backend == "numba":
            for spec in self.system.specs:
                warm_up(spec)
        self.system.use_kernels(backend == "numba")
        self.stepper = CompiledStep(self.system) if backend == "numba" and self.exact is None else None
        if self.stepper is not None:
            self.stepper.step(self.state, self.dt, 1)  # compiled now, or loaded from the disk cache
        self.backend = backend

    # stepping

    def step(self, n: int = 1) -> None:
        """Advance n steps; on blow-up raise SimulationDiverged, leaving the last state known good (`state`, `frame()`).
        (A body alone's system state is made only when asked: 40 us, more than a compiled step.)"""
        if self.single is not None:
            self._step_body(n)
        else:
            self._step_bodies(n)

    def _step_body(self, n: int) -> None:
        checked = self._m
        self.single.compiled = self.compiled
        law = None if self.controller is None else self._next_law
        try:
            m = self.single.advance(self._m, n, self.dt, law, self.moorings)
        except StepFailed as e:
            self._m = e.motion
            raise SimulationDiverged(self.diagnose(e.t, e.why)) from None
        self._m = m
        if self.model.radiation is not None:
            rest = initial_state(self.body, self.scene).q_world_body
            turn = 2 * np.degrees(np.arccos(min(1.0, abs(float(rest @ m.state.q_world_body)))))
            self.largest_turn = max(self.largest_turn, turn)
        started = time.perf_counter()
        frame = self._checked()
        self.check_seconds = time.perf_counter() - started
        energy = frame.E_total
        if not m.state.is_finite() or not np.isfinite(energy) or energy - self._E_ref > 10.0 * self._E_scale:
            # a finite state far off (z = -8.6e211 after 50 compiled steps) overflows the energy to nan: diverged too
            t, self._m = m.state.t, checked  # back to the last state that passed this check
            what = (
                f"the energy blew up ({energy:.3g} J from {self._E_ref:.3g} J)"
                if np.isfinite(energy)
                else "the state left every finite bound"
            )
            raise SimulationDiverged(self.diagnose(t, what))

    def _step_bodies(self, n: int) -> None:
        if self.exact is not None:  # a linear system: all n steps at once (no lines: they rule it out)
            new = self.exact.advance(self.state, self.dt, n)
            if not new.is_finite():
                raise SimulationDiverged(f"the state became non-finite by t = {new.t:.6g} s")
            self.state = new
            return
        switching = self.switching
        if self.stepper is not None and self.moorings is None:  # all n steps in one compiled call (or a loop of two a step)
            new, _ = self.stepper.step(self.state, self.dt, n, self._laws_into if switching else None)
            if not new.is_finite():
                raise SimulationDiverged(f"the state became non-finite at t = {new.t:.6g} s: try a smaller time step")
            self.state = new
            return
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

    def _moored_pose(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x, R, J) of the moored body now, from the kinematics of the step that runs."""
        if self.stepper is not None:
            return self.stepper.pose(self.state, self.dt, self.moored)
        pose = self.system.pose(self.state)
        return pose.x[self.moored], pose.R[self.moored], pose.J[self.moored]

    def _rebase_energy(self) -> None:
        """A body alone's energy reference for blow-up detection: a rise of 10x the body's energy scale (its weight and
        displaced water lifted by its own size, plus its kinetic energy, plus M |U|^2 in a current U) is no drift."""
        frame = self.frame()
        body, p = self.body, self.params
        if not (np.isfinite(frame.E_total) and np.all(np.isfinite(frame.force_world)) and np.all(np.isfinite(frame.torque_world))):
            raise SimulationDiverged(f"the state at t = {self.state.t:g} s gives non-finite forces or energy: check the initial "
                                     "position, velocities and the body's size and density")  # fmt: skip
        self._E_ref = frame.E_total
        # The energy is the seabed's: a current feeds a body up to its speed, 1/2 M |u' + U|^2 <= M |u'|^2 + M |U|^2
        # (u' its motion in the water): without that term a small body carried by a strong current read as a blow-up.
        carried_in = body.mass * float(np.dot(self.scene.water.current, self.scene.water.current))
        self._E_scale = (
            (body.mass + p.rho * body.volume) * (max(p.g, 1e-3) * 2 * body.radius + sea_reach(self.water, p.g)) + frame.E_kin + carried_in
        )

    # what a run shows

    def frame(self) -> Frame:
        """What the run shows now (computed once per state; system/frame.Frame): its Readings (its joints, its lines and
        their nodes, its radiated energy), each body's BodyFrame (a body alone's observed: its loads, wet surface and
        energies) and the energies of all."""
        if self.single is None:
            if self._frame[0] is not self.state:
                frame = system_frame(self.system, self.state, self.moorings)
                self._frame = (self.state, replace(frame, gauges=self.gauges.read(self.water, self.state.t)))
            return self._frame[1]
        frame = self._checked()
        if self.moorings is not None and not frame.lines:  # asked of MoorDyn node by node (126 calls): only for a frame shown
            frame = dataclasses.replace(frame, **line_shapes(self.moorings))
            self._frame = (self._frame[0], frame)
        return frame

    def _checked(self) -> Frame:
        """A body alone's frame without the lines' nodes: what a step's blow-up check reads."""
        s = self.body_state
        key = (s, self.model)
        if self._frame[0] != key:
            body = observe(self.model, s, self.kernels() if self.compiled else None, self.expand_waves, self.system.members[0].name)
            readings = lines_reading(self.moorings, shapes=False)
            j = self.joint
            if j is not None and j.kind != "fixed":
                reading = joint_reading(self.system.joints[0].name, self._law, self.joint_theta, j.rate(self.body, s), self.pto_energy)
                readings.update(joints=(reading,), joint_axes=(((j.pivot if j.kind == "revolute" else j.x0), j.axis),))
            self._frame = (key, of_body(body, s.t, E_rad=s.E_rad, gauges=self.gauges.read(self.water, s.t), **readings))
        return self._frame[1]

    def parts(self) -> list[Frame]:
        """Each body's frame by itself (a frame of one body): what a viewer draws of each. A body alone: the run's own. One
        of several: its pose and twist, its wet surface, the water's force and gravity on it about its centre of mass, its
        energies, on the numpy reference; not the joints' reactions, the lines' pull or the radiation of the bodies
        together. Computed once per state."""
        if self.single is not None:
            return [self.frame()]
        if self._parts[0] is not self.state:
            s = self.state
            frames = [of_body(observe(m.model, State(s.t, b.x_world.copy(), b.q_world_body, b.u_world.copy(), b.L_world), name=b.name), s.t)
                      for m, b in zip(self.system.members, body_frames(self.system, s))]  # fmt: skip
            self._parts = (self.state, frames)
        return self._parts[1]

    def columns(self) -> list[str]:
        """The CSV's header (the frame's `row` gives a row)."""
        return self.frame().columns()

    def stability_numbers(self) -> dict[str, float]:
        """A body alone's step's dimensionless numbers against the integrator's stability limits (system/stability.py)."""
        return {} if self.single is None else stability.numbers(self.model, self.dt)

    def validity_notes(self) -> list[str]:
        """Where the run has left the range of its models (a body alone's radiation is linear about its rest pose)."""
        if self.single is not None and self.model.radiation is not None and self.largest_turn > 20.0:
            return [f"radiation: the body turned up to {self.largest_turn:.0f} degrees from its rest pose; the added mass and radiation "
                    "damping are linear about that pose, so past about 20 degrees they are only indicative"]  # fmt: skip
        return []

    def warnings(self) -> list[str]:
        """Settings past a body alone's integrator's stability limits (a run may blow up, or wander without blowing up),
        and a body in the band where the points model is known to misbehave."""
        if self.single is None:
            return []
        leak = sampled_model_warning(self.body, self.params)
        return stability.warnings(self.stability_numbers(), self.integrator, self.dt) + ([leak] if leak else [])

    def diagnose(self, t: float, what: str) -> str:
        """A one-line cause of a blow-up at time t ('what' went wrong) and the setting to change."""
        if self.single is None:
            return f"{what} at t = {t:.6g} s: try a smaller time step"
        return stability.diagnosis(self.stability_numbers(), self.integrator, self.dt, t, what)

    # changes between steps (the viewer's commands); each replaces whole objects, never patches arrays

    def update(self, **changes) -> None:
        """Change scene parameters by 'section__key' (or a body's 'BODY__key'; config.with_overrides), validated, between
        steps: the scene stays the description of what runs. A take-off's damping or stiffness changes in place; another
        change rebuilds what it touches and carries the motion over (the module's docstring says how)."""
        old, scene = self.scene, with_overrides(self.scene, **changes)
        if scene == old:
            return
        if self.single is not None:
            self._update_body(old, scene)
        elif only_take_offs(old, scene):
            self._update_take_offs(scene)
        else:
            self._update_bodies(old, scene)

    def _update_body(self, old: SceneConfig, scene: SceneConfig) -> None:
        """A body alone: a new geometry rebuilds the body and carries the motion over; a new mass keeps u and omega (so L
        scales with I); fluid changes replace the model; step changes the integrator or dt. Velocities are kept."""
        kept = (self._m, self.system, self.model, self.joint, self.integrator)
        self.scene = scene
        try:
            self._apply(old, scene)
            if (old.moorings, old.fluid.rho, old.fluid.g) != (scene.moorings, scene.fluid.rho, scene.fluid.g):
                self._moor()  # the lines at rest for the body where it is now
            if old.constraint != scene.constraint:
                self._rejoin()
        except Exception:  # e.g. radiation asked for a body that sinks: nothing changed
            self.scene = old
            self._m, self.system, self.single.model, self.single.joint, self.single.integrator = kept
            raise
        if self.moorings is not None:
            self._hold_lines()  # (a new model starts with the pull as it is)
        self._sync_memory()
        self._rebase_energy()

    def _apply(self, old: SceneConfig, scene: SceneConfig) -> None:
        body = self.body
        if any(getattr(old.body, k) != getattr(scene.body, k) for k in GEOMETRY) or exact_inertia(old) != exact_inertia(scene):
            self._rebuild_body(self._make_body(scene))
        elif body_mass(scene, body.volume) != body.mass:
            m = self._m
            R = m.state.R_world_body
            omega = angular_velocity(body, R, m.state.L_world)
            self._resystem(self._model(with_mass(body, body_mass(scene, body.volume), scene.body.inertia)), self.joint)
            self._m = replace(m, state=dataclasses.replace(m.state, L_world=angular_momentum(self.body, R, omega)))
        elif (
            old.fluid != scene.fluid
            or old.waves != scene.waves
            or old.water != scene.water
            or (self.model.radiation is not None and old.initial != scene.initial)
        ):
            self._resystem(self._model(body), self.joint)  # (radiation is linear about the scene's starting orientation)
            self._check_backend()
        if (old.step.integrator, old.step.rtol, old.step.atol) != (scene.step.integrator, scene.step.rtol, scene.step.atol):
            self.single.integrator = make_integrator(scene.step.integrator, scene.step.rtol, scene.step.atol)
            self._check_backend()

    def _rebuild_body(self, body: Body) -> None:
        """Swap in a new body of the same shape given in the same world orientation (its principal frame may differ
        slightly), with the same position, velocity and angular velocity."""
        old, m = self.body, self._m
        state = m.state
        omega = angular_velocity(old, state.R_world_body, state.L_world)
        q_input = normalized(quat_multiply(state.q_world_body, old.q_input_body * np.array([1.0, -1.0, -1.0, -1.0])))
        q = normalized(quat_multiply(q_input, body.q_input_body))
        self._resystem(self._model(body), self.joint)
        turned = dataclasses.replace(state, q_world_body=q)
        self._m = replace(m, state=dataclasses.replace(turned, L_world=angular_momentum(body, turned.R_world_body, omega)))

    def _sync_memory(self) -> None:
        """A body alone's state carries the memory of its model's radiation: zeros when a new fit comes in (its states mean
        something else), none without radiation."""
        radiation = self.model.radiation
        if radiation is not self._memory_of:
            n = 0 if radiation is None else radiation.states
            m = self._m
            self._m = replace(m, state=dataclasses.replace(m.state, memory=np.zeros(n), E_rad=m.state.E_rad if n else 0.0))
            self._memory_of = radiation

    def _update_take_offs(self, scene: SceneConfig) -> None:
        """Several bodies' take-offs changed alone: in place."""
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
        self._frame = (None, None)
        self._check_exact()
        if self.stepper is not None:  # the take-offs are packed in the compiled step's tree
            self.use_backend("numba")

    def _update_bodies(self, old: SceneConfig, scene: SceneConfig) -> None:
        """Several bodies: the system rebuilt from the scene (the coefficients from the disk cache), the motion carried over."""
        system, start = build(scene)  # a failure here leaves the run as it was
        restarted = tree_shape(system) != tree_shape(self.system)
        state = start if restarted else carried(self.system, system, self.state, start)
        if restarted:
            self.notes.append("a joint's kind or the bodies' tree changed: the scene started again from its starting pose")
        backend, lines = self.backend, (old.moorings, old.fluid.rho, old.fluid.g) != (scene.moorings, scene.fluid.rho, scene.fluid.g)
        self.scene, self.system, self.state, self.start, self._frame = scene, system, state, start, (None, None)
        self.controllers = self._make_controllers()
        if self.moorings is not None and not (lines or restarted):
            self._hold_lines()
        else:
            self._moor()
        self._check_exact()
        self.use_backend(backend if backend == "numpy" or self.kernels_ready else "numpy")

    def set_params(self, **changes) -> None:
        """Replace fluid parameters (rho, g, damping, forces, any term's coefficient); velocities are kept."""
        self.update(**{f"fluid__{k}": v for k, v in changes.items()})

    def set_density(self, density: float) -> None:
        """New mass = density x volume, same geometry; keeps u and omega (so L scales with I)."""
        self.update(body__density=density)

    def set_dt(self, dt: float) -> None:
        """A new time step from the next step on (update(step__dt=dt))."""
        self.update(step__dt=dt)

    def set_integrator(self, name: str) -> None:
        """Another integrator from the next step on (update(step__integrator=name))."""
        self.update(step__integrator=name)

    def reset(self, state: SystemState | State | None = None) -> None:
        """Back to the scene's starting state, or to `state` (a body alone's may be its own bodies/state.State), keeping the
        current parameters; the lines start afresh."""
        if self.single is None:
            self.state = self.start if state is None else state
            for controller in self.controllers:
                controller.reset()
            self.system.laws = [c.linear or law for c, law in zip(self.controllers, self.system.passive_laws())]
            self._repack()
            self._moor()
            self._frame = (None, None)
            return
        if isinstance(state, SystemState):
            state = from_system(self.system, self.joint, state).state
        s = state or initial_state(self.body, self.scene)
        self._m = Motion(s)
        self.largest_turn = 0.0
        self._join()
        self._moor()
        self._memory_of = None if self.model.radiation is None or len(s.memory) != self.model.radiation.states else self.model.radiation
        self._sync_memory()
        self._rebase_energy()

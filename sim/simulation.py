"""A running simulation: set up from a scene, advanced in steps, observed as Frames; stops loudly on divergence."""

from __future__ import annotations

import dataclasses
import os
import time
from dataclasses import replace

import numpy as np

from sim.bodies.body import Body, body_mass, exact_inertia, make_body, make_mesh_body, with_mass
from sim.bodies.rotation import normalized, quat_multiply
from sim.bodies.state import State, angular_momentum, angular_velocity, initial_state
from sim.compiling import default_backend, kernels_ready
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
from sim.system.frame import Frame, observe
from sim.system.frequency import stiffness
from sim.system.single import Motion, Single, StepFailed, from_system, system_of_one, to_system
from sim.system.tree import System, SystemState, lines_scene, moored_body
from sim.water.records import describe
from sim.water.seas import make_water

GEOMETRY = ("shape", "size", "extents", "points_per_edge", "mesh", "mesh_unit", "samples", "centre_of_mass", "inertia")
"""Body keys whose change rebuilds the body (the others only change its mass)."""


class Simulation:
    """A running scene: steps, frames, resets and updates any scene. Not thread-safe: one thread drives it.

    A scene of several bodies ([[bodies]]) comes back as its subclass for systems (system.Assembly), with the same
    methods: step, frame, reset, update (a body's parameters named 'BODY__key', config.with_overrides), columns,
    use_backend, close. This class runs one body: it owns the scene, body, water, model, integrator and state.

    `scene` always describes what runs: `update` changes it and rebuilds only what the change
    touches. backend 'numba' advances fixed-step integrators that have a compiled twin many steps
    per call (GIL released); 'numpy' is the plain reference the tests compare it with.
    """

    several: type | None = None
    """The class that runs a scene of several bodies (assembly.Assembly, a subclass): it registers itself here, as the
    layer above this one (`import sim` loads it)."""

    def __new__(cls, scene: SceneConfig, *args, **kwargs):
        if cls is Simulation and getattr(scene, "bodies", ()):
            return super().__new__(Simulation.several)
        return super().__new__(cls)

    def __init__(self, scene: SceneConfig, body: Body | None = None, backend: str | None = None, mesh=None):
        """`scene` is checked here too (a hand-built SceneConfig gets the same one-line ConfigError as a
        scene file). `mesh`: a trimesh.Trimesh (or a mesh file) to use as the body with the scene's
        [body] settings (samples, density or mass), instead of [body] mesh."""
        if mesh is not None:
            name = str(mesh) if isinstance(mesh, (str, os.PathLike)) else "(trimesh object)"
            scene = with_overrides(scene, body__shape="mesh", body__mesh=name)
        self._mesh = mesh
        scene = validate(scene)
        self.scene = scene
        self.backend = backend or default_backend()
        self.notes: list[str] = []
        """Things the user should know about how this runs (a fallback to numpy, ...)."""
        self._frame_key: tuple | None = None
        self._frame: Frame | None = None
        self.largest_turn = 0.0
        """With radiation: the largest rotation away from the rest orientation so far, degrees."""
        self._memory_of = None  # the radiation whose memory the state carries
        self.check_seconds = 0.0
        """What the last `step` call's blow-up check (the frame of the state reached) cost, s: a viewer sizes its chunks by it."""
        body = body or self._make_body(scene)
        self.moorings = None
        """moorings.Moorings: the scene's mooring lines in MoorDyn, or None."""
        self.pto_energy = 0.0
        """The energy the joint's take-off has absorbed since the start, J."""
        self.controllers: list = []
        """Each joint's take-off controller (control/laws.py): a body alone's, one on a slide or a hinge."""
        self._custom: dict = {}  # controllers given from Python (`control`), by joint, kept over scene changes
        self.single = Single(self._model(body), make_integrator(scene.step.integrator, scene.step.rtol, scene.step.atol), None)
        """The step (system/single.py): the body's model, integrator and joint, and the compiled twin."""
        self.body_state = initial_state(body, scene)
        """The body's own state (bodies/state.State): what `state` shows as its system of one's."""
        self._system: tuple = (None, None)  # ((model, joint), the body as a system of one)
        self._state: tuple = (None, None)  # ((body_state, theta, absorbed), the system of one's state)
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
        fluid = self.scene.fluid
        water = make_water(self.scene.waves, fluid.rho, fluid.g, self.scene.water.current, self.scene.base_dir)
        if self.scene.waves.kind == "record":
            if (note := describe(water, self.scene.waves)) not in self.notes:
                self.notes.append(note)
        radiation = None
        if fluid.radiation == "bem":
            start = initial_state(body, self.scene)
            drift = water if self.scene.waves.drift and not water.flat else None
            R = start.R_world_body
            radiation = make_radiation(body, self.scene, R, water=water if diffracting(self.scene) else None, drift=drift,
                                       joint_at=lambda rest: WorldJoint.of_scene(self.scene, rest, R))  # fmt: skip
            depth = self.scene.waves.depth
            if depth is not None:
                note = (f"the radiation{' and diffraction' if diffracting(self.scene) else ''} coefficients are a deep-water solve: at the sea's "
                        f"depth {depth:g} m they hold for waves shorter than about {2 * depth:g} m (k h > pi: tanh k h > 0.996)")  # fmt: skip
                if note not in self.notes:
                    self.notes.append(note)
        return Model(body, water, fluid, radiation, held=moored(self.scene))

    def _join(self) -> None:
        """The joint to the world about the scene's starting pose; the state put on it (its velocity projected)."""

        start = initial_state(self.body, self.scene)
        self.joint = WorldJoint.of_scene(self.scene, start.x_world, start.R_world_body)
        self.pto_energy = 0.0
        self.joint_theta = 0.0
        """The joint's coordinate, a hinge's whole turns counted (the pose alone gives it up to them)."""
        if self.joint is not None:
            s = self.body_state
            self.joint_theta = self.joint.coordinate(s)
            self.body_state = self.joint.state(self.body, s.t, self.joint_theta, self.joint.rate(self.body, s), s)
        self._make_controller()

    def _rejoin(self) -> None:
        """A changed joint or take-off: about the same starting pose, the run carried on (a new kind of joint: from where the body is)."""

        old = self.joint
        start = (old.x0, old.R0) if old is not None else (self.body_state.x_world, self.body_state.R_world_body)
        self.joint = WorldJoint.of_scene(self.scene, *start)
        if self.joint is not None:
            s = self.body_state
            self.joint_theta = self.joint.coordinate(s, near=self.joint_theta if old is not None and old.kind == self.joint.kind else 0.0)
            self.body_state = self.joint.state(self.body, s.t, self.joint_theta, self.joint.rate(self.body, s), s)
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
        """control.Controller: the joint's take-off control (None without a joint that moves)."""
        return self.controllers[0] if self.controllers else None

    # take-off control (control/laws.py), one path for every scene: each joint of the system (a body alone: its own)

    def _make_controllers(self) -> list:
        """Each joint's take-off controller (the one `control` gave, else its [constraint]'s), reset; a negative spring checked
        against the stiffness of the whole system at rest without it (system/frequency.stiffness, central differences)."""

        system, stiff, out = self.system, None, []
        for j, g in enumerate(system.joints):
            c, where = self._constraint_of(g.name)
            if j not in self._custom and c.pto_stiffness < 0:
                if stiff is None:
                    stiff = stiffness(system, replace(self._start, theta=np.zeros_like(self._start.theta), v=np.zeros_like(self._start.v)))
                e = np.zeros(system.n_dofs)
                e[g.dofs.start] = 1.0
                stiffness_check(c.controller, c.pto_stiffness, stiff - c.pto_stiffness * np.outer(e, e), e, where)
            controller = self._custom.get(j) or of_constraint(c)
            controller.reset()
            out.append(controller)
        return out

    def _constraint_of(self, name: str) -> tuple:
        """(the [constraint] of the joint's body, where to say it is in a message)."""
        return self.scene.constraint, ""

    @property
    def _start(self) -> SystemState:
        """The system's starting state (the joints' coordinates are 0 there)."""
        return self.state

    @property
    def switching(self) -> bool:
        """Whether some take-off's law changes from step to step (a controller other than a spring and damper)."""
        return any(c.linear is None for c in self.controllers)

    def control(self, controller, body: str | None = None) -> None:
        """Drive the take-off of `body`'s joint (one of several: the body a joint's group is named by; a body alone: its own)
        by `controller`: a callable (t, control.JointState, control.WaveState) -> force (N or N m, held over each step) or a
        control.Controller; None: back to the scene's [constraint] controller."""

        names = [g.name for g in self.system.joints]
        if body is None and not self.scene.bodies:
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
        self._controllers_changed()

    def _controllers_changed(self) -> None:
        self._make_controller()

    def _next_law(self, s: State, theta: float):
        """The controller's law for the step from s at the joint's coordinate theta."""

        if self.controller.linear is not None:  # a spring and damper: nothing to ask
            self._law = self.controller.linear
            return self._law
        j = self.joint
        self._law = self.controller.law(JointState(s.t, theta, j.rate(self.body, s), self.dt),
                                        WaveState(self.model.water, j.x0[:2], s.t))  # fmt: skip
        return self._law

    # the mooring lines (MoorDyn, lines/moorings.py), one path for every scene: on one body, or shared by several

    def _moor(self) -> None:
        """(Re)start the mooring lines where the bodies are now: MoorDyn finds their shape at rest there. Every fairlead on
        the one body the lines hold ([moorings] body), or each on its own ([moorings] attach)."""
        self.close()
        self.moorings, self.attached = None, []
        self.moored = moored_body(self.scene)
        """The index of the body the mooring lines hold (None: no lines)."""
        if self.moored is None:
            return
        k, bodies = self.moored, self._kinematics_at_rest()
        attach = self.scene.moorings.attach.split()
        if not attach:
            lines = Moorings.of_scene(lines_scene(self.scene, k), *bodies[k])
            self.attached = [k]
            """The bodies the lines hold (scene order)."""
        else:
            owner = "nearest" if attach == ["nearest"] else [self.body_names.index(a) for a in attach]
            path = line_file(self.scene)
            lines = Moorings(path.read_text(), *bodies[0], bodies=bodies, owner=owner, folder=path.parent).counting(
                self.scene.moorings.energy
            )
            self.attached = sorted(set(lines.owner.tolist()))
        lines.t = self.state.t
        self.moorings = lines
        self._hold_lines()

    def _kinematics_at_rest(self) -> list:
        """Each body's (x, R, u, omega) now, as the lines start from it (a body alone: its own state, exactly)."""
        s = self.body_state
        return [(s.x_world, s.R_world_body, s.u_world, angular_velocity(self.body, s.R_world_body, s.L_world))]

    def _hold_lines(self) -> None:
        """The lines' pull now into the loads held on the bodies they hold (for the next step)."""
        self.model.held[:] = self.moorings.load

    @property
    def model(self) -> Model:
        """The body's force model in its water."""
        return self.single.model

    @model.setter
    def model(self, model: Model) -> None:
        self.single.model = model

    @property
    def integrator(self):
        """The free body's integrator (dynamics/integrators.py)."""
        return self.single.integrator

    @integrator.setter
    def integrator(self, integrator) -> None:
        self.single.integrator = integrator

    @property
    def joint(self) -> WorldJoint | None:
        """The body's joint to the world (dynamics/joints.py), or None (free)."""
        return self.single.joint

    @joint.setter
    def joint(self, joint: WorldJoint | None) -> None:
        self.single.joint = joint

    @property
    def step_seconds(self) -> float | None:
        """Wall-time budget of one step of an adaptive method (None: only its evaluation cap); past it the
        step stops with SimulationDiverged naming a better integrator. The viewer sets it."""
        return self.single.step_seconds

    @step_seconds.setter
    def step_seconds(self, seconds: float | None) -> None:
        self.single.step_seconds = seconds

    @property
    def expand_waves(self) -> bool:
        """Whether the kernels may sum a many-component sea as a local expansion (kernels/water.py);
        False: every component at every node (benchmarks and checks)."""
        return self.single.expand_waves

    @expand_waves.setter
    def expand_waves(self, expand: bool) -> None:
        self.single.expand_waves = expand

    @property
    def system(self) -> System:
        """The body as a system of one (system/single.py): its group free or on its joint to the world."""
        key = (self.model, self.joint)
        if self._system[0] != key:
            self._system = (key, system_of_one(self.model, self.joint, initial_state(self.body, self.scene)))
        return self._system[1]

    @property
    def state(self) -> SystemState:
        """The run's state, as every scene's: its system's (here a system of one, whose .x_world, .q_world_body, .u_world,
        .L_world and .body are the body's own state)."""
        key = (self.body_state, self.joint_theta, self.pto_energy)
        if self._state[0] != key:
            self._state = (key, to_system(self.system, self.joint, Motion(*key)))
        return self._state[1]

    @state.setter
    def state(self, state: SystemState | State) -> None:
        if isinstance(state, SystemState):
            m = from_system(self.system, self.joint, state)
            self.body_state, self.joint_theta, self.pto_energy = m.state, m.theta, m.absorbed
        else:
            self.body_state = state

    @property
    def body(self) -> Body:
        """The running body (its samples, mass, inertia and mesh)."""
        return self.model.body

    @property
    def params(self):
        """The fluid section of the scene: water, force model and every term's coefficients."""
        return self.scene.fluid

    @property
    def dt(self) -> float:
        """The time step, s."""
        return float(self.scene.step.dt)

    def frame(self) -> Frame:
        """Diagnostics of the current state (computed once per state and model), with the mooring lines' nodes."""
        frame = self._checked()
        if self.moorings is not None and not frame.lines:  # asked of MoorDyn node by node (126 calls): only for a frame shown
            frame = dataclasses.replace(frame, lines=tuple(self.moorings.lines()), line_tensions=tuple(self.moorings.line_tensions()))
            self._frame = frame
        return frame

    def _checked(self) -> Frame:
        """The frame without the lines' nodes: what a step's blow-up check reads."""
        key = (self.body_state, self.model)
        if self._frame_key != key:
            frame = observe(self.model, self.body_state, self.kernels() if self.compiled else None, self.expand_waves)
            if self.moorings is not None:
                frame = dataclasses.replace(frame, mooring_force=self.moorings.load[:3].copy(),
                                            fairlead_tensions=self.moorings.fairlead_tensions(), line_energy=self.moorings.energy_now())  # fmt: skip
            if self.joint is not None:
                rate = self.joint.rate(self.body, self.body_state)
                j = self.joint
                axis = None if j.kind == "fixed" else ((j.pivot if j.kind == "revolute" else j.x0), j.axis)
                law = self._law  # its spring's power is stored, not absorbed
                frame = dataclasses.replace(frame, P_pto=(law.damping * rate - law.force) * rate, E_pto=self.pto_energy,
                                            F_pto=law.at(self.joint_theta, rate), joint_axis=axis)  # fmt: skip
            self._frame, self._frame_key = frame, key
        return self._frame

    def columns(self) -> list[str]:
        """The CSV's header (Frame.row gives a row)."""
        return self.frame().columns()

    @property
    def body_names(self) -> list[str]:
        """The scene's bodies by the names update takes them by (config.body_names): here `body`."""
        return ["body"]

    @property
    def bodies(self) -> list[Body]:
        """The running bodies, in the scene's order."""
        return [self.body]

    @property
    def water(self):
        """The running water (its surface, current and sea)."""
        return self.model.water

    def parts(self) -> list[Frame]:
        """Each body's one-body Frame (here the run's own): what a viewer draws of each."""
        return [self.frame()]

    @property
    def n_samples(self) -> int:
        """The body's samples (a system: its bodies' together)."""
        return self.body.n_samples

    def close(self) -> None:
        """Let go of what runs beside the body (MoorDyn's lines)."""
        if self.moorings is not None:
            self.moorings.close()

    @property
    def kernels_ready(self) -> bool:
        """Whether the compiled kernels can be used at once: a twin exists and this machine compiled it before."""

        return self.has_twin and kernels_ready(self.spec)

    @property
    def specs(self) -> list:
        """The kernels.Spec the scene's compiled kernels specialise on (one here; a system's bodies may have several)."""
        return [self.spec]

    @property
    def compiled(self) -> bool:
        """Whether steps run in the compiled kernels (a fixed-step integrator with a compiled twin)."""
        return self.backend == "numba" and self.has_twin

    @property
    def has_twin(self) -> bool:
        """Whether the scene has a compiled twin: a fixed-step integrator with one, a force model it covers in this water, every term compiled."""
        return self.single.has_twin

    @property
    def spec(self):
        """What the compiled kernels specialise on for this scene (kernels.Spec)."""
        return self.single.spec

    def kernels(self):
        """The compiled kernels for this scene (kernels.specialised: loaded from the disk cache, or compiled now)."""
        return self.single.kernels()

    def _check_backend(self) -> None:
        self.notes += [n for n in self.single.backend_notes(self.backend) if n not in self.notes]

    def step(self, n: int = 1) -> State:
        """Advance n steps; on blow-up raise SimulationDiverged, leaving the last state known good."""
        checked, checked_theta = self.body_state, self.joint_theta
        self.single.compiled = self.compiled
        law = None if self.controller is None else self._next_law
        try:
            m = self.single.advance(Motion(self.body_state, self.joint_theta, self.pto_energy), n, self.dt, law, self.moorings)
        except StepFailed as e:
            self.body_state, self.joint_theta, self.pto_energy = e.state, e.theta, e.absorbed
            raise SimulationDiverged(self.diagnose(e.t, e.why)) from None
        self.body_state, self.joint_theta, self.pto_energy = m.state, m.theta, m.absorbed
        if self.model.radiation is not None:
            rest = initial_state(self.body, self.scene).q_world_body
            turn = 2 * np.degrees(np.arccos(min(1.0, abs(float(rest @ self.body_state.q_world_body)))))
            self.largest_turn = max(self.largest_turn, turn)
        started = time.perf_counter()
        frame = self._checked()
        self.check_seconds = time.perf_counter() - started
        energy = frame.E_total
        if not self.body_state.is_finite() or not np.isfinite(energy) or energy - self._E_ref > 10.0 * self._E_scale:
            # a finite state far off (z = -8.6e211 after 50 compiled steps) overflows the energy to nan: diverged too
            t, self.body_state, self.joint_theta = (
                self.body_state.t,
                checked,
                checked_theta,
            )  # back to the last state that passed this check
            what = (
                f"the energy blew up ({energy:.3g} J from {self._E_ref:.3g} J)"
                if np.isfinite(energy)
                else "the state left every finite bound"
            )
            raise SimulationDiverged(self.diagnose(t, what))
        return self.state

    def _rebase_energy(self) -> None:
        """Energy reference for blow-up detection: a rise of 10x the body's energy scale
        (its weight and displaced water lifted by its own size, plus its kinetic energy, plus M |U|^2 in a
        current U) is no drift."""
        frame = self.frame()
        body, p = self.body, self.params
        if not (np.isfinite(frame.E_total) and np.all(np.isfinite(frame.force_world)) and np.all(np.isfinite(frame.torque_world))):
            raise SimulationDiverged(f"the state at t = {self.body_state.t:g} s gives non-finite forces or energy: check the initial "
                                     "position, velocities and the body's size and density")  # fmt: skip
        self._E_ref = frame.E_total
        # The energy is the seabed's: a current feeds a body up to its speed, 1/2 M |u' + U|^2 <= M |u'|^2 + M |U|^2
        # (u' its motion in the water): without that term a small body carried by a strong current read as a blow-up.
        carried = body.mass * float(np.dot(self.scene.water.current, self.scene.water.current))
        self._E_scale = (body.mass + p.rho * body.volume) * max(p.g, 1e-3) * 2 * body.radius + frame.E_kin + carried

    def stability_numbers(self) -> dict[str, float]:
        """The step's dimensionless numbers against the integrator's stability limits (sim/system/stability.py)."""
        return stability.numbers(self.model, self.dt)

    def validity_notes(self) -> list[str]:
        """Where the run has left the range of its models (radiation is linear about the rest pose)."""
        if self.model.radiation is not None and self.largest_turn > 20.0:
            return [f"radiation: the body turned up to {self.largest_turn:.0f} degrees from its rest pose; the added mass and radiation "
                    "damping are linear about that pose, so past about 20 degrees they are only indicative"]  # fmt: skip
        return []

    def warnings(self) -> list[str]:
        """Settings past the integrator's stability limits (a run may blow up, or wander without blowing up),
        and a body in the band where the points model is known to misbehave."""
        leak = sampled_model_warning(self.body, self.params)
        return stability.warnings(self.stability_numbers(), self.integrator, self.dt) + ([leak] if leak else [])

    def diagnose(self, t: float, what: str) -> str:
        """A one-line cause of a blow-up at time t ('what' went wrong) and the setting to change."""
        return stability.diagnosis(self.stability_numbers(), self.integrator, self.dt, t, what)

    # Changes between steps (the viewer's commands). Each replaces whole objects, never patches arrays.

    def use_backend(self, backend: str) -> None:
        """Step on `backend` ('numba' or 'numpy') from the next step on; the state is kept as it is."""
        self.backend = backend
        self._frame_key = None
        self.notes = [n for n in self.notes if "numpy reference" not in n]
        self._check_backend()

    def update(self, **changes) -> None:
        """Change scene parameters by 'section__key' (as `config.with_overrides`), validated, between
        steps: the scene stays the description of what runs. A new geometry rebuilds the body and
        carries the motion over; a new mass keeps u and omega (so L scales with I); fluid changes
        replace the model; step changes the integrator or dt. Velocities are kept."""
        old, scene = self.scene, with_overrides(self.scene, **changes)
        self.scene = scene
        try:
            self._apply(old, scene)
            if (old.moorings, old.fluid.rho, old.fluid.g) != (scene.moorings, scene.fluid.rho, scene.fluid.g):
                self._moor()  # the lines at rest for the body where it is now
            if old.constraint != scene.constraint:
                self._rejoin()
        except Exception:
            self.scene = old  # e.g. radiation asked for a body that sinks: nothing changed
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
            R = self.body_state.R_world_body
            omega = angular_velocity(body, R, self.body_state.L_world)
            self.model = self._model(with_mass(body, body_mass(scene, body.volume), scene.body.inertia))
            self.body_state = dataclasses.replace(self.body_state, L_world=angular_momentum(self.body, R, omega))
        elif (
            old.fluid != scene.fluid
            or old.waves != scene.waves
            or old.water != scene.water
            or (self.model.radiation is not None and old.initial != scene.initial)
        ):
            self.model = self._model(body)  # (radiation is linear about the scene's starting orientation)
            self._check_backend()
        if (old.step.integrator, old.step.rtol, old.step.atol) != (scene.step.integrator, scene.step.rtol, scene.step.atol):
            self.integrator = make_integrator(scene.step.integrator, scene.step.rtol, scene.step.atol)
            self._check_backend()

    def _sync_memory(self) -> None:
        """The state carries the memory of the model's radiation: zeros when a new fit comes in (its
        states mean something else), none without radiation."""
        radiation = self.model.radiation
        if radiation is not self._memory_of:
            n = 0 if radiation is None else radiation.states
            self.body_state = dataclasses.replace(self.body_state, memory=np.zeros(n), E_rad=self.body_state.E_rad if n else 0.0)
            self._memory_of = radiation

    def _rebuild_body(self, body: Body) -> None:
        """Swap in a new body of the same shape given in the same world orientation (its principal
        frame may differ slightly), with the same position, velocity and angular velocity."""
        old, state = self.body, self.body_state
        omega = angular_velocity(old, state.R_world_body, state.L_world)
        q_input = normalized(quat_multiply(state.q_world_body, old.q_input_body * np.array([1.0, -1.0, -1.0, -1.0])))
        q = normalized(quat_multiply(q_input, body.q_input_body))
        self.model = self._model(body)
        carried = dataclasses.replace(state, q_world_body=q)
        self.body_state = dataclasses.replace(carried, L_world=angular_momentum(body, carried.R_world_body, omega))

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
        """Back to the scene's initial pose and velocities, keeping the current parameters."""
        if isinstance(state, SystemState):
            state = from_system(self.system, self.joint, state).state
        self.body_state = state or initial_state(self.body, self.scene)
        self.largest_turn = 0.0
        self._join()
        self._moor()
        self._memory_of = (
            None if self.model.radiation is None or len(self.body_state.memory) != self.model.radiation.states else self.model.radiation
        )
        self._sync_memory()
        self._rebase_energy()

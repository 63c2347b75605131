"""A run's motion carried over a rebuilt system of several bodies (a scene changed between steps): what changed, and the
state on the new system."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from sim.bodies.rotation import quat_to_matrix
from sim.scene.config import SceneConfig
from sim.system.tree import System, SystemState


def only_take_offs(old: SceneConfig, new: SceneConfig) -> bool:
    """Whether the scenes differ in their joints' take-offs alone."""

    def strip(scene):
        bodies = tuple(replace(e, constraint=replace(e.constraint, pto_damping=0.0, pto_stiffness=0.0, controller="passive", latch_time=0.0,
                                                     declutch_time=0.0, pto_max_force=None)) for e in scene.bodies)  # fmt: skip
        return replace(scene, bodies=bodies)

    return strip(old) == strip(new)


def with_take_off(group, scene: SceneConfig):
    """The group with its joint's take-off as the scene gives it (a group is named by its first body)."""
    entry = next(e for e in scene.bodies if e.name == group.name)
    return replace(group, stiffness=float(entry.constraint.pto_stiffness), damping=float(entry.constraint.pto_damping))


def tree_shape(system: System) -> list:
    return [(g.kind, g.parent, g.dofs, len(g.members)) for g in system.groups]


def carried(old: System, new: System, s: SystemState, start: SystemState) -> SystemState:
    """The motion of `s` on the rebuilt system: coordinates and velocities as they are; a free group moved by the shift of
    its centre of mass in its own frame (its frame's axes are the world's at the start), its velocity now that of its new
    centre of mass; the memory kept where the
    radiation is the same size (zeros otherwise: its states mean something else)."""
    x, v = s.x_free.copy(), s.v.copy()
    for g_old, g_new in zip(old.groups, new.groups):
        if g_new.kind == "free":
            shift = quat_to_matrix(s.q_free[g_new.coordinate]) @ (g_new.origin - g_old.origin)
            x[g_new.coordinate] += shift
            v[g_new.dofs.start : g_new.dofs.start + 3] += np.cross(v[g_new.dofs.start + 3 : g_new.dofs.stop], shift)  # u + omega x r
    memory = s.memory if len(s.memory) == len(start.memory) else np.zeros_like(start.memory)
    return replace(s, x_free=x, v=v, memory=memory, E_rad=s.E_rad if len(start.memory) else 0.0)

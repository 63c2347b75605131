"""The GUI inputs. Their callbacks only post commands; `show_setting` puts back the value the loop actually used.

viser runs `def` callbacks on a thread pool, concurrently with the simulation thread and possibly
out of order, so a callback never touches the simulation: it reads its handle and posts.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import viser

import sim

from .loop import Settings

LABELS = {
    "density": "Density (kg/m³)",
    "damping": "Damping d (N·s/m³)",
    "dt": "Time step (s)",
    "integrator": "Integrator",
    "points_per_edge": "Points per edge",
    "speed": "Speed (× real time)",
    "omega0": "Initial ω (rad/s)",
    "paused": "Pause",
    "step": "Step",
    "reset": "Reset",
    "scene": "Scene",
    "forces": "Force model",
}


class Controls:
    """Handles of every control, by setting name: `controls.density.value = 500` runs the same path as the browser."""

    def __init__(self, server: viser.ViserServer, post: Callable[[str, Any], None], settings: Settings, scene_options: tuple[str, ...]):
        gui = server.gui
        self._post = post
        self._quiet = threading.local()  # set while we write a handle ourselves: its callback must not post it back

        self.notice = gui.add_markdown("", visible=False)
        with gui.add_folder("Run"):
            self.paused = gui.add_checkbox(LABELS["paused"], settings.paused, hint="Freeze the simulation (the view stays live)")
            self.pause = self.paused  # the same handle, by its label
            self.step = gui.add_button(LABELS["step"], hint="Advance one time step")
            self.reset = gui.add_button(LABELS["reset"], hint="Back to the scene's initial state, keeping these parameters")
            self.speed = _slider(gui, LABELS["speed"], 0.1, 10.0, 0.1, settings.speed)
            self.scene = gui.add_dropdown(
                LABELS["scene"], scene_options, initial_value=settings.scene, hint="Load a preset with its own parameters"
            )
        with gui.add_folder("Body and water"):
            self.density = _slider(gui, LABELS["density"], 1.0, 5000.0, 1.0, settings.density)
            self.damping = _slider(gui, LABELS["damping"], 0.0, 5000.0, 1.0, settings.damping)
            self.points_per_edge = _slider(gui, LABELS["points_per_edge"], 1, 60, 1, settings.points_per_edge)
            self.forces = gui.add_dropdown(LABELS["forces"], sim.forces.FORCE_MODELS, initial_value=settings.forces,
                                           hint="points: summed over the samples (the report's model); panels: exact over the clipped triangles")  # fmt: skip
            self.omega0 = gui.add_vector3(LABELS["omega0"], settings.omega0, step=0.1, hint="Angular velocity given on Reset, world frame")
        with gui.add_folder("Integration"):
            self.dt = _slider(gui, LABELS["dt"], 0.0005, 0.05, 0.0005, settings.dt)
            self.integrator = gui.add_dropdown(LABELS["integrator"], tuple(sim.INTEGRATORS), initial_value=settings.integrator)

        for name in ("density", "damping", "dt", "speed", "points_per_edge", "omega0", "integrator", "scene", "forces"):
            self._bind(name, name)
        self._bind("paused", "pause")
        self.step.on_click(lambda _: self._post("step", None))
        self.reset.on_click(lambda _: self._post("reset", None))

    def _bind(self, field: str, command: str) -> None:
        handle = getattr(self, field)

        def posted(_event) -> None:
            if not getattr(self._quiet, "on", False):
                self._post(command, handle.value)

        handle.on_update(posted)

    def show_setting(self, field: str, value: Any) -> None:
        """Show a value the loop chose (a clamp, a scene's preset, a pause on divergence) without posting it again."""
        handle = getattr(self, field, None)
        if handle is None or field == "scene" and value not in handle.options:
            return
        if hasattr(handle, "max") and isinstance(value, (int, float)):  # sliders: widen the range rather than refuse the value
            handle.max = max(handle.max, value)
            handle.min = min(handle.min, value)
        self._quiet.on = True
        try:
            handle.value = value
        finally:
            self._quiet.on = False

    def show_notice(self, text: str) -> None:
        if text:
            self.notice.content = f"**⚠ {text}**"
        self.notice.visible = bool(text)


class Layers:
    """Checkboxes for what the scene shows; read by the viewer each frame (no commands: they change no physics)."""

    def __init__(self, server: viser.ViserServer):
        with server.gui.add_folder("Layers", expand_by_default=False):
            self.mesh = server.gui.add_checkbox("Show mesh", True)
            self.points = server.gui.add_checkbox("Show points", True, hint="Samples: blue under water, orange above")
            self.water = server.gui.add_checkbox("Show water", True)
            self.forces = server.gui.add_checkbox("Show force and torque", True, hint="Red: net force (1 m = body weight); green: torque")


def _slider(gui, label: str, lo, hi, step, value):
    """A slider whose range also holds `value` (a scene may start outside the usual range)."""
    lo, hi = min(lo, value), max(hi, value)
    return gui.add_slider(label, min=lo, max=hi, step=step, initial_value=type(step)(value))

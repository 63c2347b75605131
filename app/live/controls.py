"""The GUI inputs, one per declared parameter with a control (sim.scene.config.PARAMS with `gui`), plus the
viewer's own. Callbacks only post commands; `show_setting` puts back the value the loop actually used.

A callback never touches the simulation: it reads its handle and posts (a page's update on viser's event loop as it
arrives; viser would run a `def` callback on a thread pool, concurrently with the simulation thread and late).
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from typing import Any

import viser

from app.live.loop import CONTROLLED, SPEED, Settings
from sim.parameters import Param

FOLDERS = {
    "Body": ("body",),
    "Water": ("fluid", "water"),
    "Waves": ("waves",),
    "Joint": ("constraint",),
    "Start": ("initial",),
    "Integration": ("step",),
}
"""The folders of controls, each holding the scene sections named."""
VECTOR_STEP = 0.1


class Bound:
    """Controls bound to a simulation thread's commands: a page's update posts its command (`_bind`), and
    `show_setting` shows a value the loop chose without posting it again. Subclasses hold the handles as
    attributes named by field."""

    def __init__(self, post: Callable[[str, Any], None]):
        self._post = post
        self._quiet = threading.local()  # set while we write a handle ourselves: its callback must not post it back
        self._written: dict[str, Any] = {}  # the value the loop last wrote to each control (pages may show it)

    def _bind(self, field: str, command: str) -> None:
        handle = getattr(self, field)

        def assigned(event) -> None:  # from Python: viser calls it in the assigning thread, at once and in order
            if event.client_id is None and not getattr(self._quiet, "on", False):
                self._post(command, handle.value)

        async def from_page(event) -> None:
            # On viser's event loop, just after it set the page's value: a callback in its thread pool read the value
            # later, and a clamp the loop wrote back meanwhile was posted for the page's next value, which never ran.
            if event.client_id is not None:
                self._post(command, handle.value)

        handle.on_update(assigned)
        handle.on_update(from_page)

    def show_setting(self, field: str, value: Any) -> None:
        """Show a value the loop chose (a clamp, a scene's preset, a pause on divergence) without posting it again."""
        try:
            handle = getattr(self, field)
        except AttributeError:
            return
        if field == "scene" and value not in handle.options:
            return
        if handle.value == value:  # already shown: no echo to the pages (one dragging this slider would jump) ...
            if self._written.get(field, value) != value:  # ... unless a page's update overtook our last write here: viser
                handle._queue_update("value", value)  # echoes an update to the other pages only, so that page still shows our write
                self._written[field] = value
            return
        if field in BOXED and isinstance(value, (int, float)):  # another scene's or body's take-off: steps of its size
            handle.step = scaled_step(value, CONTROLLED[field].gui[2])
        elif hasattr(handle, "max") and isinstance(value, (int, float)):  # sliders: widen the range rather than refuse the value
            handle.max = max(handle.max, value)
            handle.min = min(handle.min, value)
        self._quiet.on = True
        try:
            handle.value = value
            self._written[field] = value
        finally:
            self._quiet.on = False


class Controls(Bound):
    """Handles of every control by parameter key (`controls.density.value = 500` runs the same path as
    the browser), plus paused, step, reset, speed and scene."""

    def __init__(self, server: viser.ViserServer, post: Callable[[str, Any], None], settings: Settings, scene_options: tuple[str, ...],
                 bodies: tuple[str, ...] = ("body",)):  # fmt: skip
        """`bodies`: the scene's bodies by name; with several, the Body folder starts with the choice of one (`focus`)."""
        super().__init__(post)
        gui = server.gui
        self._handles: dict[str, Any] = {}

        self.notice = gui.add_markdown("", visible=False)
        with gui.add_folder("Run"):
            self.paused = gui.add_checkbox("Pause", settings.paused, hint="Freeze the simulation (the view stays live)")
            self.step = gui.add_button("Step", hint="Advance one time step")
            self.reset = gui.add_button("Reset", hint="Back to the scene's initial state, keeping these parameters")
            self.speed = _control(gui, SPEED, settings.speed)
            self.scene = gui.add_dropdown(
                "Scene", scene_options, initial_value=settings.scene, hint="Load a preset with its own parameters"
            )
        for title, sections in FOLDERS.items():
            params = [p for p in CONTROLLED.values() if p.section in sections]
            if params:
                with gui.add_folder(title):
                    if title == "Body":
                        self.focus = gui.add_dropdown("Body", bodies, initial_value=settings.focus, visible=len(bodies) > 1,
                                                      hint="The body these controls, Water's damping and drag, Joint and Start show and change, and the camera follows")  # fmt: skip
                    for p in params:
                        self._handles[p.key] = _control(gui, p, settings.value(p.key))
        for key in (*CONTROLLED, "speed", "scene"):
            self._bind(key, key)
        self._bind("paused", "pause")
        self._bind("focus", "focus")
        self.step.on_click(lambda _: self._post("step", None))
        self.reset.on_click(lambda _: self._post("reset", None))

    def __getattr__(self, key: str):
        handles = self.__dict__.get("_handles", {})
        if key in handles:
            return handles[key]
        raise AttributeError(key)

    def show_setting(self, field: str, value: Any) -> None:
        if field == "bodies":  # another scene or body chosen: (its bodies' names, the chosen one's)
            names, focus = value
            if tuple(self.focus.options) != tuple(names):
                self._quiet.on = True
                try:
                    self.focus.options = names
                finally:
                    self._quiet.on = False
            self.focus.visible = len(names) > 1
            field, value = "focus", focus
        super().show_setting(field, value)

    def show_shape(self, shape: str) -> None:
        """Only the sampling control that applies to the body at hand: points per edge for a cube or
        box, samples for a mesh."""
        for key, shown in (("points_per_edge", shape != "mesh"), ("samples", shape == "mesh")):
            if key in self._handles and self._handles[key].visible != shown:
                self._handles[key].visible = shown

    def show_notice(self, text: str) -> None:
        if text:
            self.notice.content = f"**⚠ {text}**"
        self.notice.visible = bool(text)


def current_values_for_new_pages(server: viser.ViserServer) -> None:
    """A new page gets every shared control with the value it has now, in the message that creates the control.

    viser 1.1.1 replays its buffered messages to a new page in windows of at most 128. A control's creation
    message keeps the value the control was made with, and each later change is a separate update, later in
    the buffer. (The props, such as visible, options and max, are one object shared with the handle, so they
    stay current.) A backlog longer than one window, as in rm3-moored with its bodies and lines, sends the
    controls in the first window and their values in a later one. Under load that later window came more
    than 0.3 s after the first, and for that time the page showed the values the preset started with. The
    hostile campaign found this: a new page showed the spar's Samples 600 and Density 933 while the run used
    6 and 500. The server's handles and its buffered updates were right; only the page was behind.
    So before each new page's replay starts, each creation message is given the control's current value.
    viser runs these callbacks on its event loop before it starts the page's producers. The updates that
    follow hold the same value, and pages already connected have read these messages and are not sent
    them again."""
    buffer = server._websock_server._broadcast_buffer  # viser internals (pinned 1.1.1), as in app/guards/gate.py
    handles = server.gui._gui_input_handle_from_uuid

    def refresh(_connection) -> None:
        with buffer.buffer_lock:  # the simulation thread pushes while we read
            for message in buffer.message_from_id.values():
                if message.lifecycle_phase != "create" or not hasattr(message, "value"):
                    continue
                handle = handles.get(message.uuid)
                if handle is not None and not handle._impl.is_button:
                    message.value = handle._impl.value

    server._websock_server.on_client_connect(refresh)


def _control(gui, p: Param, value):
    """The control a declaration asks for: a dropdown for a choice, two or three numbers for a vector, else a
    slider whose range also holds `value` (a scene may start outside the usual range)."""
    if p.kind == "choice":
        return gui.add_dropdown(p.title, p.choices, initial_value=value, hint=p.help)
    if p.kind == "switch":
        return gui.add_checkbox(p.title, bool(value), hint=p.help)
    if p.kind == "vector":
        add = gui.add_vector2 if p.size == 2 else gui.add_vector3
        return add(p.title, value, step=VECTOR_STEP, hint=p.help)
    lo, hi, step = p.gui
    kind = int if p.kind == "int" else float
    if p.key in BOXED:
        lo, hi = p.live or (p.lo, p.hi)
        return gui.add_number(p.title, kind(value), min=kind(lo), max=kind(hi), step=scaled_step(value, step), hint=p.help)
    lo, hi = min(lo, value), max(hi, value)
    return gui.add_slider(p.title, min=kind(lo), max=kind(hi), step=kind(step), initial_value=kind(value), hint=p.help)


BOXED = {"pto_damping"}
"""Controls whose values span decades from one scene to another (a 1 m cube's take-off 2 kN s/m, rm3's 1.2 MN s/m): a
number box, which shows the value whole (a slider's box is 3 rem wide: 1200000 read as 120000) and steps by about a
hundredth of the value the scene gives (scaled_step), not a slider ranged for one size of body."""


def scaled_step(value: float, least: float) -> float:
    """A round step about a hundredth of `value` (a power of ten), at least `least`."""
    return max(float(least), 10.0 ** (math.floor(math.log10(abs(value))) - 2) if value else 0.0)


class Layers:
    """Checkboxes for what the scene shows; read by the viewer each frame (no commands: they change no physics)."""

    def __init__(self, server: viser.ViserServer):
        with server.gui.add_folder("Layers", expand_by_default=False):
            self.mesh = server.gui.add_checkbox("Show mesh", True)
            self.points = server.gui.add_checkbox("Show points", True, hint="Samples: blue under water, orange above")
            self.water = server.gui.add_checkbox("Show water", True)
            self.forces = server.gui.add_checkbox("Show force and torque", True, hint="Red: net force (1 m = body weight); green: torque")
            self.markers = server.gui.add_checkbox(
                "Show B, M, waterline", True, hint="Why it floats: centre of buoyancy B, metacentre M (GM > 0: rights itself), waterline"
            )
            self.axes = server.gui.add_checkbox(
                "Show body axes", False, hint="The body's principal axes at its centre of mass G (x red, y green, z blue)"
            )

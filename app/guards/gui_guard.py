"""What a GUI update from a browser may carry, checked (by app/guards/gate.py) before viser applies it.

viser applies a client's `GuiUpdateMessage` to the handle's state (any property it names, any value
its type can be cast to), broadcasts it to every other client, and only then runs our callbacks. So
one message could leave a value no client can decode (an int of 1e300 dropped every connection, for
good), switch controls off for everyone (`disabled`, `visible`, `min`...), or make the server send a
20 MB string to every tab. `refusal` lets through only the `value` property, of the handle's own type
(finite, bounded numbers; capped strings; a dropdown's own options; vectors of its length). Anything
else is dropped whole, with a short notice (`Refusals`) that never repeats the input. Range clamps with
a visible note stay the simulation loop's job (app/live/loop.py).

A control's declared properties live in `handle._impl.props` (viser 1.1.1: `props.label`, `props.options`);
its value in `handle._impl.value`. An update from a page viser does not count as connected yet (it sent no
camera message) is refused too: viser would apply and broadcast it but run no callback, so every page
would show a value the run never used.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from numbers import Real

MAX_NUMBER = 1e12
"""Largest magnitude a number control may carry (every declared range is far inside it)."""
MAX_TEXT = 4096
"""Longest text a control may carry (the page's own address, copied by share.probe_address, fits)."""
NO_TOKEN = "this page has no access token (open the link the viewer printed)"
NOT_CONNECTED = "this page has not finished connecting"
NOTICE_SECONDS = 2.0
"""At most one notice about refused updates per this many seconds (a flood gives one, with a count)."""


def refusal(state, updates: dict) -> str | None:
    """Why a GUI update must not reach the handle whose state is `state`, or None when it may."""
    if not isinstance(updates, dict) or set(updates) != {"value"}:
        return "it changed something other than a control's value"
    value, current = updates["value"], state.value
    if isinstance(current, bool):
        return None if isinstance(value, bool) else "not a yes/no value"
    if isinstance(current, Real):
        return _number(value, integral=isinstance(current, int))
    if isinstance(current, str):
        if not isinstance(value, str) or len(value) > MAX_TEXT:
            return "not a text of reasonable length"
        options = getattr(getattr(state, "props", None), "options", None)
        return None if options is None or value in options else "not one of the choices"
    if isinstance(current, tuple):
        if not isinstance(value, (list, tuple)) or len(value) != len(current):
            return "not a vector of the right length"
        return next((why for why in (_number(v, isinstance(c, int)) for v, c in zip(value, current)) if why), None)
    return "not a value a browser sets on this control"  # e.g. an upload button's file: those come by file transfer


def _number(value, integral: bool = False) -> str | None:
    if isinstance(value, bool) or not isinstance(value, Real) or not math.isfinite(value) or abs(value) > MAX_NUMBER:
        return "not a finite number of reasonable size"
    if integral and value != int(value):
        return "not a whole number"
    return None


class Refusals:
    """Counts refused updates (or other requests: `what`) and reports them through `notify`, at most
    once per NOTICE_SECONDS; refusals inside that interval are reported together at its end (a flood
    gives one notice with a count, and the last refusal of a burst is never left unsaid)."""

    def __init__(self, notify: Callable[[str], None], what: str = "control update"):
        self.notify = notify
        self.what = what
        self.count = 0
        self._pending = 0
        self._why = ""
        self._last = -math.inf
        self._timer: threading.Timer | None = None
        self._lock = threading.Lock()

    def __call__(self, why: str) -> None:
        with self._lock:
            self.count += 1
            self._pending += 1
            self._why = why
            wait = self._last + NOTICE_SECONDS - time.monotonic()
            if wait > 0:
                if self._timer is None:
                    self._timer = threading.Timer(wait, self._flush)
                    self._timer.daemon = True
                    self._timer.start()
                return
        self._flush()

    def _flush(self) -> None:
        with self._lock:
            self._timer = None
            n, why, self._pending, self._last = self._pending, self._why, 0, time.monotonic()
        if n:
            self.notify(f"Ignored {n} {self.what}{'s' if n > 1 else ''} from a browser: {why}.")

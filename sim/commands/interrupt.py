"""Ctrl-C that ends a command cleanly: the first SIGINT asks the running loop to stop at its next
check (a loop checks at least every `CHECK_SECONDS`), which then says what it kept and exits 130;
a second SIGINT stops at once. Compiled kernels are never interrupted mid-call (numba cannot unwind
one: Python would report a SystemError)."""

from __future__ import annotations

import contextlib
import signal
import sys
import threading

from sim.errors import Interrupted

CHECK_SECONDS = 0.2
"""Longest stretch of work between two checks: Ctrl-C is answered well within a second."""
EXIT = 130


_asked_before = False  # a Ctrl-C outside any loop: its KeyboardInterrupt may have been swallowed


def ctrl_c(signum, frame) -> None:
    """A command's SIGINT handler outside its loops (commands.dispatch): KeyboardInterrupt, remembered, for a library that
    swallows it (trimesh imports its optional modules under `except BaseException`): the command's next check
    (`stop_if_asked`, or a loop's StopOnCtrlC) then stops it at once."""
    global _asked_before
    _asked_before = True
    raise KeyboardInterrupt


def listen() -> None:
    """A command's Ctrl-C from here on (the main thread): `ctrl_c`, quiet finalisers, no Ctrl-C seen yet."""
    global _asked_before
    _asked_before = False
    signal.signal(signal.SIGINT, ctrl_c)
    sys.unraisablehook = quiet_unraisable


def settled() -> None:
    """The command has ended (said its result or its interruption): a Ctrl-C it saw is forgotten."""
    global _asked_before
    _asked_before = False


def asked_before() -> bool:
    """Whether a Ctrl-C came outside any loop (its KeyboardInterrupt raised, perhaps swallowed, perhaps turned into
    another error by the code it landed in: a module left half imported)."""
    return _asked_before


def stop_if_asked() -> None:
    """Between a command's phases: a Ctrl-C that a library swallowed during the last one stops it here (KeyboardInterrupt),
    not after the next (loading a scene's kernels takes seconds)."""
    if _asked_before:
        raise KeyboardInterrupt


def quiet_unraisable(unraisable) -> None:
    """sys.unraisablehook: a KeyboardInterrupt that lands in a finaliser (__del__, a weakref callback) is not printed
    (Python would print it and go on: the one line the command says is enough); anything else as Python prints it."""
    if not isinstance(unraisable.exc_value, KeyboardInterrupt):
        sys.__unraisablehook__(unraisable)


class StopOnCtrlC:
    """Context manager: `stop.asked` turns True on the first Ctrl-C (only in the main thread)."""

    def __init__(self):
        self.asked = False
        self._old = None
        self._at_once = False

    def _handler(self, signum, frame) -> None:
        was, self.asked = self.asked, True
        if was or self._at_once:
            raise KeyboardInterrupt

    @contextlib.contextmanager
    def at_once(self):
        """Within: a Ctrl-C raises KeyboardInterrupt at once, for a set-up that keeps nothing yet and waits in calls that
        cannot check (a Dask cluster starting)."""
        if self.asked:
            raise KeyboardInterrupt
        self._at_once = True
        try:
            yield
        finally:
            self._at_once = False

    def __enter__(self) -> StopOnCtrlC:
        self.asked = _asked_before
        if threading.current_thread() is threading.main_thread():
            self._old = signal.signal(signal.SIGINT, self._handler)
        return self

    def __exit__(self, *exc) -> None:
        if self._old is not None:
            signal.signal(signal.SIGINT, self._old)

    def check(self) -> None:
        if self.asked:
            raise Interrupted


def interrupted_by_ctrl_c(e: BaseException) -> bool:
    """A KeyboardInterrupt, or the SystemError numba raises when one lands inside a compiled call."""
    while e is not None:
        if isinstance(e, (KeyboardInterrupt, Interrupted)):
            return True
        e = e.__cause__ or e.__context__
    return False

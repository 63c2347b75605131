"""Ctrl-C that ends a command cleanly: the first SIGINT asks the running loop to stop at its next
check (a loop checks at least every `CHECK_SECONDS`), which then says what it kept and exits 130;
a second SIGINT stops at once. Compiled kernels are never interrupted mid-call (numba cannot unwind
one: Python would report a SystemError)."""

from __future__ import annotations

import _thread
import contextlib
import signal
import sys
import threading
import time

from sim.errors import Interrupted

CHECK_SECONDS = 0.2
"""Longest stretch of work between two checks: Ctrl-C is answered well within a second."""
EXIT = 130


_asked_before = False  # a Ctrl-C outside any loop: its KeyboardInterrupt may have been swallowed


RESEND_AFTER = (1.0, 1.5, 2.0)
"""Seconds after a Ctrl-C at which, if no loop has taken it over and the command has not ended, it is raised again (one
a library swallowed): a KeyboardInterrupt on its way out has ended the command well within the first; three at most,
so a clean-up that takes longer is not cut again and again."""

_heard = threading.Event()  # a Ctrl-C came: the watcher's cue
_taken = False  # a loop (StopOnCtrlC) took the Ctrl-C over, or the command ended: no more resending
_watcher: threading.Thread | None = None


def ctrl_c(signum, frame) -> None:
    """A command's SIGINT handler outside its loops (commands.dispatch): KeyboardInterrupt, remembered, for a library that
    swallows it (trimesh imports its optional modules under `except BaseException`): the watcher raises it again at
    RESEND_AFTER until a loop takes it over (and stops at once, seeing it remembered) or the command ends."""
    global _asked_before
    _asked_before = True
    _heard.set()  # (no thread is started here: a signal handler may run while the main thread holds threading's locks)
    raise KeyboardInterrupt


def _watch() -> None:
    while True:
        _heard.wait()
        started = time.monotonic()
        for at in RESEND_AFTER:
            time.sleep(max(0.0, started + at - time.monotonic()))
            if _taken or not _asked_before or signal.getsignal(signal.SIGINT) is not ctrl_c:
                break
            _thread.interrupt_main(signal.SIGINT)
        _heard.clear()


def listen() -> None:
    """A command's Ctrl-C from here on (the main thread): `ctrl_c`, quiet finalisers, no Ctrl-C seen yet, and the watcher
    that raises a swallowed one again (started once a process)."""
    global _asked_before, _taken, _watcher
    _asked_before, _taken = False, False
    _heard.clear()
    if _watcher is None:
        _watcher = threading.Thread(target=_watch, name="floatsim-ctrl-c", daemon=True)
        _watcher.start()
    signal.signal(signal.SIGINT, ctrl_c)
    sys.unraisablehook = quiet_unraisable


def settled() -> None:
    """The command has ended (said its result or its interruption): a Ctrl-C it saw is not raised again."""
    global _asked_before, _taken
    _asked_before, _taken = False, True


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
        global _taken
        self.asked = _asked_before
        _taken = True  # this loop answers a Ctrl-C from here on (the watcher stops raising it)
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

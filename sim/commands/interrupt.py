"""Ctrl-C that ends a command cleanly: the first SIGINT asks the running loop to stop at its next
check (a loop checks at least every `CHECK_SECONDS`), which then says what it kept and exits 130;
a second SIGINT stops at once. Compiled kernels are never interrupted mid-call (numba cannot unwind
one: Python would report a SystemError)."""

from __future__ import annotations

import signal
import threading

from sim.errors import Interrupted

CHECK_SECONDS = 0.2
"""Longest stretch of work between two checks: Ctrl-C is answered well within a second."""
EXIT = 130


class StopOnCtrlC:
    """Context manager: `stop.asked` turns True on the first Ctrl-C (only in the main thread)."""

    def __init__(self):
        self.asked = False
        self._old = None

    def _handler(self, signum, frame) -> None:
        if self.asked:
            raise KeyboardInterrupt
        self.asked = True

    def __enter__(self) -> StopOnCtrlC:
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

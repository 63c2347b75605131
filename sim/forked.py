"""A blocking call that Ctrl-C can stop: run in a forked child, its result handed back through a pipe; and a pool of
worker processes that Ctrl-C ends at once.

A call into compiled code (MoorDyn's start-up, Capytaine's solve) runs seconds to minutes where Python's Ctrl-C does
not reach it. In a forked child it can be ended: the parent waits on the pipe, and a KeyboardInterrupt there kills the
child at once. The child ignores Ctrl-C (a terminal sends it to the whole group: the parent decides) and dies with its
parent.
"""

from __future__ import annotations

import contextlib
import ctypes
import multiprocessing
import os
import pickle
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures import wait as wait_for


class ChildDied(RuntimeError):
    """The child ended without handing back a result (a signal, or an exit before it wrote)."""


def in_child(work: Callable[[], object], quiet: bool = False):
    """work() in a forked child, its (picklable) result returned here, or its exception raised here as it was (one that
    does not pickle, as a RuntimeError of its type and text); `quiet`: the child's stdout to /dev/null. In this process
    where there is no fork, and off the main thread (the viewer's simulation thread), where no Ctrl-C arrives and a fork
    would copy a process whose other threads may hold locks the child needs."""
    if not hasattr(os, "fork") or threading.current_thread() is not threading.main_thread():
        return work()
    read, write = os.pipe()
    parent = os.getpid()
    pid = os.fork()
    if pid == 0:
        os.close(read)
        _child(work, write, quiet, parent)  # never returns
    os.close(write)
    try:
        with open(read, "rb") as pipe:
            data = pipe.read()
    except BaseException:  # Ctrl-C (KeyboardInterrupt) while it works: end it now
        os.kill(pid, signal.SIGKILL)
        raise
    finally:
        _, code = os.waitpid(pid, 0)
    if not data:
        status = os.waitstatus_to_exitcode(code)
        raise ChildDied(f"signal {-status}" if os.WIFSIGNALED(code) else f"exit status {status}")
    done, value = pickle.loads(data)  # (our own child's, down our own pipe)
    if not done:
        raise value
    return value


def _child(work, fd: int, quiet: bool, parent: int) -> None:
    """In the forked child: work(), its result or its exception pickled down the pipe, then out with os._exit (no Python
    clean-up: temporary folders and open outputs are the parent's)."""
    code = 1
    try:
        with contextlib.suppress(Exception):
            signal.signal(signal.SIGINT, signal.SIG_IGN)
        die_with(parent)
        if quiet:
            os.dup2(os.open(os.devnull, os.O_WRONLY), 1)
        try:
            said = pickle.dumps((True, work()))
        except BaseException as e:  # noqa: BLE001 -- handed to the parent, which raises it
            try:
                said = pickle.dumps((False, e))
            except Exception:  # noqa: BLE001 -- an error that does not pickle: its type and text
                said = pickle.dumps((False, RuntimeError(f"{type(e).__name__}: {e}")))
        with open(fd, "wb") as pipe:
            pipe.write(said)
        code = 0
    finally:
        os._exit(code)


def die_with(parent: int) -> None:
    """End this worker when the process `parent` ends, even by SIGKILL (which leaves it no time to stop its
    workers): on Linux the kernel sends SIGKILL (prctl PR_SET_PDEATHSIG), elsewhere a thread watches os.getppid()."""
    if sys.platform.startswith("linux"):
        try:
            ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # 1: PR_SET_PDEATHSIG
        except (OSError, AttributeError):
            pass
    if os.getppid() != parent:  # the parent died before the line above took effect
        os._exit(1)

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(0.5)
        os._exit(1)

    threading.Thread(target=watch, name="floatsim-parent-watch", daemon=True).start()


def _leave_ctrl_c_to(parent: int) -> None:
    """A pool worker's start: Ctrl-C is the parent's (which ends the workers), and it dies with the parent."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    die_with(parent)


@contextlib.contextmanager
def worker_pool(n: int) -> Iterator[ProcessPoolExecutor]:
    """A pool of `n` worker processes, forked where there is fork (they start with the kernels this process loaded;
    spawned ones import again: seconds each). They leave Ctrl-C to this process and die with it; on any way out of the
    block they are ended, not waited for (a worker's task can take seconds to minutes)."""
    method = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
    pool = ProcessPoolExecutor(max_workers=n, mp_context=multiprocessing.get_context(method), initializer=_leave_ctrl_c_to,
                               initargs=(os.getpid(),))  # fmt: skip
    try:
        yield pool
    finally:
        for process in list(getattr(pool, "_processes", {}).values()):
            process.terminate()
        pool.shutdown(wait=False, cancel_futures=True)


def results(futures: list[Future], slice_seconds: float = 0.2) -> list:
    """The futures' results in order, waited for in slices: a SIGINT that the kernel hands to another thread (the
    pool's own) does not wake a main thread blocked on a lock, so a Ctrl-C there is only seen when it next runs."""
    while wait_for(futures, timeout=slice_seconds).not_done:
        pass
    return [future.result() for future in futures]

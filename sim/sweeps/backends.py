"""Where a sweep's chunks run: `serial` (this process), `local` (one process per core of this machine)
or `dask` (dask.distributed: a LocalCluster of worker processes, or a running scheduler's workers).

Each chunk is one task (a compiled ensemble of up to `chunk` cases): a task per case would cost
more in scheduling than in physics. Workers load the compiled kernels once and run single-threaded
BLAS. Results come back to this process, which writes each chunk's file as it arrives (`done`).
"""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import time
from collections.abc import Callable, Iterable
from concurrent.futures import FIRST_COMPLETED
from concurrent.futures import wait as wait_any
from concurrent.futures.process import BrokenProcessPool

from sim.compiling import default_backend, warm_up
from sim.ensemble import Ensemble
from sim.errors import ConfigError, Interrupted
from sim.forked import worker_pool
from sim.sweeps.chunk import case_scene, run_chunk

from .grid import Sweep

BACKENDS = ("serial", "local", "dask")
SINGLE_THREAD = {k: "1" for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")}


class WorkerLost(RuntimeError):
    """A worker process died; the chunks finished before are kept."""


def _warm(sweep: Sweep | None = None, indices: list[int] | None = None) -> None:
    """Load (or compile, once per machine) the kernels of the cases `indices` of `sweep` (those of one chunk:
    the cases of a sweep share their scheme, force model and water)."""

    if sweep is None or not indices or default_backend() != "numba":
        return

    base = sweep.base()
    if base.bodies:  # several bodies: each case's run loads its own kernels
        return
    ensemble = Ensemble([case_scene(base, sweep.case(i)) for i in indices])
    if ensemble.sims[0].compiled:
        warm_up(ensemble.spec())


def _task(sweep: Sweep, indices: list[int], stop=None):
    """One chunk on a worker: (rows, history, seconds of compute)."""

    started = time.perf_counter()
    rows, history = run_chunk(sweep, indices, stop)
    return rows, history, time.perf_counter() - started


def run(sweep: Sweep, todo: Iterable[tuple[int, list[int]]], done: Callable[[int, dict, dict | None], None], backend: str = "serial",
        workers: int | None = None, scheduler: str | None = None, timeout: float = 10.0, stop=None) -> dict:  # fmt: skip
    """Run the chunks `todo` ((id, case indices) pairs) on `backend`, calling `done(id, rows, history)`
    in this process as each finishes. Returns {'busy': seconds the chunks computed for, summed over
    workers, 'startup': seconds until the first chunk began (workers starting, kernels loading),
    'finished': when each chunk's result arrived, seconds from the start}. `stop` (interrupt.StopOnCtrlC):
    once asked, the run ends within a fraction of a second by raising interrupt.Interrupted (chunks done
    so far have been handed to `done`)."""

    todo = list(todo)
    stats = {"busy": 0.0, "startup": 0.0, "finished": []}
    started = time.perf_counter()

    def finished(cid: int, result) -> None:
        rows, history, seconds = result
        if stats["busy"] == 0.0:
            stats["startup"] = max(0.0, time.perf_counter() - started - seconds)
        stats["busy"] += seconds
        stats["finished"].append(time.perf_counter() - started)
        done(cid, rows, history)

    if backend not in BACKENDS:
        raise ConfigError(f"--backend must be one of {', '.join(BACKENDS)}, got {backend!r}")
    if workers is not None and workers < 1:
        raise ConfigError(f"--workers must be >= 1, got {workers}")
    if backend == "serial":
        for cid, indices in todo:
            finished(cid, _task(sweep, indices, stop))
        return stats
    os.environ.update(SINGLE_THREAD)  # inherited by the worker processes started below
    n = workers or os.cpu_count() or 1
    if backend == "local":
        _run_local(sweep, todo, finished, n, stop)
    else:
        _run_dask(sweep, todo, finished, n, scheduler, timeout, stop)
    return stats


def _check(stop) -> None:
    if stop is not None and stop.asked:
        raise Interrupted


def _run_local(sweep, todo, done, n, stop=None) -> None:
    _warm(sweep, todo[0][1] if todo else None)  # here first: forked workers start with them, spawned ones load them from the disk cache
    with worker_pool(n) as pool:
        try:
            futures = {pool.submit(_task, sweep, indices): cid for cid, indices in todo}
            pending = set(futures)
            while pending:
                _check(stop)
                finished, pending = wait_any(pending, timeout=0.2, return_when=FIRST_COMPLETED)
                for future in finished:
                    done(futures[future], future.result())
        except BrokenProcessPool:
            raise WorkerLost("a worker process died") from None


def _run_dask(sweep, todo, done, n, scheduler, timeout, stop=None) -> None:
    try:
        from distributed import wait
    except ImportError:
        raise ConfigError("the dask backend needs dask.distributed: pip install -e '.[dask]'") from None
    first = todo[0][1] if todo else None
    with _at_once(stop):  # nothing to keep yet, and calls that cannot check: Ctrl-C ends them at once
        _warm(sweep, first)  # compiled here once, not by every worker at the same time
    cluster = None
    try:
        cluster, client = _connect(scheduler, timeout, n)  # (under a second; a cluster cut short in its start cannot close)
        with client:
            # each worker loads the kernels from the disk cache this process filled (as tasks: waited on with Ctrl-C heard)
            warming = [client.submit(_warm, sweep, first, workers=[address], pure=False) for address in client.scheduler_info()["workers"]]
            _until_done(warming, lambda future: None, stop, client, cluster, wait)
            futures = [client.submit(_task, sweep, indices, key=f"floatsim-chunk-{sweep.key()}-{cid}", retries=2) for cid, indices in todo]
            ids = {f.key: cid for f, (cid, _) in zip(futures, todo)}
            _until_done(futures, lambda future: done(ids[future.key], future.result()), stop, client, cluster, wait)
    finally:
        if cluster is not None:
            cluster.close()


def _at_once(stop):
    return stop.at_once() if stop is not None else contextlib.nullcontext()


def _connect(scheduler, timeout, n):
    """(cluster, client): a client of the running scheduler (no cluster of ours), or of a LocalCluster of n workers."""
    from distributed import Client, LocalCluster  # (the dask extra: _run_dask checked it is there)

    if scheduler:
        try:
            return None, Client(scheduler, timeout=f"{timeout}s")
        except (OSError, TimeoutError, ValueError) as e:
            raise ConfigError(
                f"cannot reach the Dask scheduler at {scheduler} within {timeout:g} s ({type(e).__name__}: {str(e)[:80]})"
            ) from None
    # no dashboard; the scheduler's HTTP server (health checks) on a free port: on 8787, taken by another cluster, it warned
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None, scheduler_kwargs={"dashboard_address": ":0"},
                           silence_logs=logging.ERROR)  # fmt: skip
    return cluster, Client(cluster)


def _until_done(futures, each, stop, client, cluster, wait) -> None:
    """Wait for the Dask futures, calling `each` on every one as it finishes; on Ctrl-C (`stop`), end them at once
    and raise Interrupted."""
    pending = set(futures)
    while pending:
        if stop is not None and stop.asked:
            _end_now(client, cluster, futures)
            raise Interrupted
        try:
            finished, pending = wait(pending, timeout=0.2, return_when="FIRST_COMPLETED")
        except TimeoutError:
            continue
        for future in finished:
            each(future)


def _end_now(client, cluster, futures) -> None:
    """Ctrl-C: drop the chunks still running at once rather than wait for them (a graceful close waits for each busy
    worker to finish its chunk: seconds). A LocalCluster's workers are this command's own: killed (their chunks would be
    dropped anyway); a running scheduler's are another's: their tasks are cancelled. Quietly: the command's one line
    says what was kept."""

    logging.getLogger("distributed").setLevel(logging.CRITICAL)  # (the comms the kill closes would each log a line)
    client.cancel(futures)
    for nanny in cluster.workers.values() if cluster is not None else ():
        with contextlib.suppress(OSError, TypeError):  # (a worker already gone: no pid)
            os.kill(nanny.pid, signal.SIGKILL)

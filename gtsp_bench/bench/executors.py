"""Where the runner's solves run: the local worker pool, or Dask workers on this or other machines.

An executor is chosen by name (:func:`gtsp_bench.checks.check_executor`):

``local`` (the default)
    :func:`gtsp_bench.bench.pool.run_jobs` on this machine: ``jobs`` fresh worker processes per solver.
``dask``
    a :class:`distributed.LocalCluster` on this machine: ``jobs`` worker processes with one
    thread each.
``tcp://HOST:PORT``
    an existing Dask scheduler (``dask scheduler``) and the workers attached to it
    (``dask worker tcp://HOST:PORT``), on any machines; ``jobs`` does not apply there.

On Dask every job is one Dask task that runs, *on the Dask worker*, through the local pool's own
harness (:class:`gtsp_bench.bench.pool.WorkerPool` with one worker process): the solve runs in a child
process with the pool's hard time limit, library isolation and retries of a dead child. As in the
local pool, that child is kept for the next task of the same solver in the same Dask worker thread
(a task of another solver stops it and starts a fresh one; the runner stops them all when a
solver's phase ends), so a Dask run pays process start-up and imports once per solver and worker,
not once per solve. Results come back as they
finish (``as_completed``) through the caller's ``on_result``, so they stream into the task log
exactly as the local pool's do. A Dask worker that dies under a task is the infrastructure's
fault, as a dead pool worker is: the scheduler gives the task to another worker, and after
:data:`gtsp_bench.bench.pool.MAX_ATTEMPTS` lost workers the job is recorded ``failed`` with cause
``infrastructure`` (which a later run retries). Every Dask worker needs the same installation of
gtsp-bench (and of any plug-in solver) as the machine running ``gtsp-bench bench``.

Executors are opened once per name and kept until :func:`close_executors` (or the interpreter's
exit), so the phases of one run share one cluster.
"""

from __future__ import annotations

import atexit
import contextlib
import math
import threading
import time
import uuid
from collections.abc import Callable, Hashable, Mapping, Sequence
from typing import Any, Protocol

from gtsp_bench.bench.pool import (
    INFRASTRUCTURE,
    MAX_ATTEMPTS,
    PhaseStats,
    WorkerPool,
    failure,
    one_line,
    run_jobs,
)
from gtsp_bench.errors import InputError

#: The executor used when none is named.
DEFAULT_EXECUTOR = "local"
#: Seconds to wait for a Dask scheduler to answer before giving up.
CONNECT_TIMEOUT_S = 10.0
#: What to install for the Dask executors.
DASK_EXTRA = "the dask extra (pip install 'gtsp-bench[dask]')"

OnResult = Callable[[Hashable, dict[str, Any], bool], None]
Jobs = Sequence[tuple[Hashable, Mapping[str, Any]]]


class Executor(Protocol):
    """Runs one solver's jobs and reports each result through ``on_result``, as
    :func:`gtsp_bench.bench.pool.run_jobs` does."""

    name: str

    def run(self, solver: str, target: str | None, description: str, jobs: Jobs,
            hard_limit: float, on_result: OnResult) -> PhaseStats:
        """Solve ``jobs``; ``on_result(job id, record, persist)`` once per job."""
        ...

    def close(self) -> None:
        """Release the executor's workers."""
        ...


class LocalExecutor:
    """The local pool: ``n_workers`` fresh worker processes per solver on this machine."""

    def __init__(self, n_workers: int) -> None:
        self.name = "local"
        self.n_workers = n_workers

    def run(self, solver: str, target: str | None, description: str, jobs: Jobs,
            hard_limit: float, on_result: OnResult) -> PhaseStats:
        return run_jobs(solver, target, description, jobs, self.n_workers, hard_limit, on_result)

    def close(self) -> None:
        pass


#: The pool of each Dask worker thread (one solver's one worker process, kept between tasks) by
#: thread id, and the threads solving now.
_POOLS: dict[int, WorkerPool] = {}
_BUSY: set[int] = set()
_POOLS_LOCK = threading.Lock()


def _thread_pool(solver: str, target: str | None, description: str) -> WorkerPool:
    me = threading.get_ident()
    with _POOLS_LOCK:
        _BUSY.add(me)
        pool = _POOLS.get(me)
        if pool is not None and (pool.solver, pool.target, pool.description) == (solver, target, description):
            return pool
        _POOLS.pop(me, None)
    if pool is not None:
        pool.close()
    with _POOLS_LOCK:
        # one thread a solve, as the Dask workers (single-threaded, one per core) are counted
        pool = _POOLS[me] = WorkerPool(solver, target, description, 1, threads=1)
    return pool


def close_idle_pools() -> int:
    """Stop the worker processes this Dask worker keeps for tasks to come (run on every worker at
    the end of a solver's phase); returns how many pools were closed."""
    with _POOLS_LOCK:
        idle = [_POOLS.pop(t) for t in list(_POOLS) if t not in _BUSY]
    for pool in idle:
        pool.close()
    return len(idle)


def solve_on_worker(solver: str, target: str | None, description: str, job: Hashable,
                    message: Mapping[str, Any], hard_limit: float) -> dict[str, Any]:
    """One job on a Dask worker, through the local pool's harness with one worker process
    (kept for this thread's next job of the same solver).

    Returns ``{"record", "persist", "solves", "solver_s"}``: the record and flag the pool gave to
    ``on_result`` and the pool's counts.
    """
    out: dict[str, Any] = {}

    def keep(_job: Hashable, record: dict[str, Any], persist: bool) -> None:
        out.update(record=record, persist=persist)

    try:
        stats = _thread_pool(solver, target, description).run([(job, message)], hard_limit, keep)
    finally:
        with _POOLS_LOCK:
            _BUSY.discard(threading.get_ident())
    out.update(solves=stats.solves, solver_s=stats.solver_s)
    return out


def _distributed() -> Any:
    try:
        import distributed
    except ImportError as e:
        raise InputError(f"the Dask executors need {DASK_EXTRA}: {e}") from None
    return distributed


class DaskExecutor:
    """Jobs as Dask tasks, each solved on its worker by :func:`solve_on_worker`.

    Parameters
    ----------
    address
        A scheduler's ``tcp://HOST:PORT``, or ``None`` for a new :class:`~distributed.LocalCluster`
        of ``n_workers`` processes with one thread each on this machine.
    """

    def __init__(self, address: str | None, n_workers: int) -> None:
        distributed = _distributed()
        import dask

        self.name = address or "dask"
        self.cluster = None
        # A worker lost under a task: the scheduler hands the task on MAX_ATTEMPTS - 1 times.
        with dask.config.set({"distributed.scheduler.allowed-failures": MAX_ATTEMPTS - 1}):
            if address is None:
                self.cluster = distributed.LocalCluster(
                    n_workers=n_workers, threads_per_worker=1, processes=True,
                    dashboard_address=None, memory_limit=0)
                self.client = distributed.Client(self.cluster)
            else:
                try:
                    self.client = distributed.Client(address, timeout=CONNECT_TIMEOUT_S)
                except (OSError, TimeoutError) as e:
                    reason = (str(e).splitlines() or [type(e).__name__])[0][:200]
                    raise InputError(f"{address}: cannot reach the Dask scheduler ({reason})") from None

    def workers(self) -> int:
        """Dask workers attached now."""
        return len(self.client.scheduler_info().get("workers", {}))

    def run(self, solver: str, target: str | None, description: str, jobs: Jobs,
            hard_limit: float, on_result: OnResult) -> PhaseStats:
        from distributed import as_completed

        stats = PhaseStats(solver, workers=min(self.workers(), len(jobs)))
        if not jobs:
            return stats
        start = time.perf_counter()
        tag = uuid.uuid4().hex[:8]
        futures = {}
        for i, (job, message) in enumerate(jobs):
            fut = self.client.submit(solve_on_worker, solver, target, description, job, message,
                                     hard_limit, key=f"gtsp-bench-{solver}-{tag}-{i}", pure=False)
            futures[fut] = job
        try:
            for fut in as_completed(futures):
                job = futures[fut]
                try:
                    out = fut.result()
                except BaseException as e:  # no result: lost workers, a lost scheduler, ...
                    if isinstance(e, (KeyboardInterrupt, SystemExit)):
                        raise
                    on_result(job, _lost(e), _is_lost_worker(e))
                    continue
                stats.solves += out["solves"]
                if math.isfinite(out["solver_s"]):
                    stats.solver_s += out["solver_s"]
                on_result(job, out["record"], out["persist"])
        finally:
            self.client.cancel([f for f in futures if not f.done()])
            stats.wall_s = time.perf_counter() - start
        with contextlib.suppress(Exception):  # a worker that cannot be reached has none to close
            self.client.run(close_idle_pools)
        return stats

    def close(self) -> None:
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()


def _is_lost_worker(e: BaseException) -> bool:
    return type(e).__name__ == "KilledWorker"


def _lost(e: BaseException) -> dict[str, Any]:
    """The failure record of a Dask task that gave no result."""
    if _is_lost_worker(e):
        return failure(f"Dask worker lost under this solve in {MAX_ATTEMPTS} attempts", cause=INFRASTRUCTURE)
    return failure(f"not run on the Dask cluster: {one_line(e)}", cause=INFRASTRUCTURE)


_OPEN: dict[tuple[str, int], Executor] = {}


def open_executor(name: str, n_workers: int) -> Executor:
    """The executor ``name`` (``local``, ``dask`` or ``tcp://HOST:PORT``), opened once and re-used.

    Raises
    ------
    InputError
        A bad name, Dask not installed, or a scheduler that cannot be reached.
    """
    from gtsp_bench.checks import check_executor

    name = check_executor(name)
    if name == "local":
        return LocalExecutor(n_workers)
    key = (name, n_workers)
    if key not in _OPEN:
        _OPEN[key] = DaskExecutor(None if name == "dask" else name, n_workers)
    return _OPEN[key]


def close_executors() -> None:
    """Close every executor :func:`open_executor` opened."""
    while _OPEN:
        _, ex = _OPEN.popitem()
        ex.close()


atexit.register(close_executors)

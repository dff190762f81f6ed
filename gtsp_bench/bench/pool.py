"""Worker processes for the runner: one solver per process, fresh interpreters, hard time limits.

Each worker is a new Python interpreter (``subprocess``) talking to the runner over a socket pair
wrapped in a :class:`multiprocessing.connection.Connection`. It imports only this module, the
harness and its one solver, never the caller's ``__main__``: start-up costs the same from the CLI,
a script or pytest, and solvers whose libraries cannot share a process (highspy and ortools) never
meet. A worker builds its solver once, then solves the tasks it is sent one at a time; the runner
kills a worker whose solve exceeds the hard limit and starts another. :func:`run_jobs` uses a
:class:`WorkerPool` once; the Dask executors (:mod:`gtsp_bench.bench.executors`) keep one on each Dask
worker thread, so that its worker process serves that thread's next solve of the same solver.

Runtimes come from :func:`gtsp_bench.registry.run_solver` inside the worker (the solver's own
``solve`` call), so process start-up and instance parsing are never counted.

Failures say whose they are (``cause``): a solver that raises gives a ``failed`` record with cause
``solver``; one that refuses its input by design (an :class:`~gtsp_bench.errors.InputError`, such
as dp above its memory limit) a ``refused`` record; a worker that dies under a solve (the OOM
killer, ``kill -9``, a crash in native code) or a solve that runs out of memory is the
infrastructure's fault: the job is tried again in a fresh worker, up to :data:`MAX_ATTEMPTS`
times, and only then recorded as ``failed`` with cause ``infrastructure`` (which a later run
retries).

A worker starts with the caller's import path less its working-directory entry (``python -P``
and an explicit ``sys.path``), so a file in the user's folder named like a module cannot shadow
it, and its file descriptor 1 points at stderr: a library that prints cannot reach the runner's
stdout.
"""

from __future__ import annotations

import json
import math
import os
import signal
import socket
import subprocess
import sys
import time
from collections import deque
from collections.abc import Callable, Hashable, Mapping, Sequence
from dataclasses import dataclass, field
from multiprocessing.connection import Connection, wait
from pathlib import Path
from typing import Any

from gtsp_bench.solver import SOLVE_THREADS_VAR, plain, usable_cores

#: Seconds a worker may take to import and build its solver.
INIT_TIMEOUT_S = 300.0
#: Thread-pool variables set to 1 in workers (unless already set): jobs x threads <= cores.
THREAD_VARS = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS")
#: Times a job is tried when its worker dies under it or it runs out of memory.
MAX_ATTEMPTS = 3
#: Cause of a failure outside the solver's control (see :data:`gtsp_bench.checks.FAILURE_CAUSES`).
INFRASTRUCTURE = "infrastructure"
#: How a row's note begins when its solve wrote a proof certificate (``-p certificate=true``):
#: the package's checker confirmed it, refused it, or the solve proved nothing to write.
CERTIFICATE_CHECKED, CERTIFICATE_FAILS, NO_CERTIFICATE = (
    "certificate checked", "certificate fails", "no certificate")


def certificate_verdict(note: object) -> str | None:
    """The certificate verdict a row's ``note`` begins with (:data:`CERTIFICATE_CHECKED`,
    :data:`CERTIFICATE_FAILS` or :data:`NO_CERTIFICATE`), else ``None``."""
    text = str(note)
    return next((v for v in (CERTIFICATE_CHECKED, CERTIFICATE_FAILS, NO_CERTIFICATE)
                 if text.startswith(v)), None)


def failure(note: str, status: str = "failed", cause: str = "solver") -> dict[str, Any]:
    """A result record for a solve that gave no solution (``cause``: whose fault it was)."""
    out: dict[str, Any] = {"status": status, "objective": None, "note": note}
    if status == "failed":
        out["cause"] = cause
    return out


def one_line(e: BaseException) -> str:
    """``"Type: message"`` of an exception, its first line, at most 300 characters."""
    text = f"{type(e).__name__}: {e}"
    return (text.splitlines() or [text])[0][:300]


def _limit_threads() -> None:
    torch = sys.modules.get("torch")
    if torch is not None and torch.get_num_threads() != 1:
        torch.set_num_threads(1)


def solve_message(solver: Any, name: str, msg: Mapping[str, Any], cache: dict[str, Any]) -> dict[str, Any]:
    """Solve one task message ``{fingerprint, text, omega, seed, time_limit[, options, initial,
    certificate]}`` (``initial``: a warm start ``[order, heads]``; ``certificate``: where the
    solver writes a proof's certificate, which is then checked, the verdict the record's note:
    :func:`check_written_certificate`) through the harness; a batch message
    (``batch``: a list of ``{fingerprint, text}``, ``repeats``) is solved in one call
    (:func:`gtsp_bench.registry.run_solver_batch`) and answered with one record per instance in
    ``items``.

    The instance text (JSON, or GTSPLIB's format) is parsed once per fingerprint; a message with
    solver ``options`` is solved by a solver built with them (once per set of options). An
    :class:`InputError` becomes a ``refused`` record, a :class:`MemoryError` a ``failed`` one with
    cause ``infrastructure``, any other exception a ``failed`` one with cause ``solver``. A solved
    record has the result's ``trajectory`` as ``[[time_s, objective, lower_bound], ...]``.
    """
    from gtsp_bench.data.parse import parse_instance_text
    from gtsp_bench.errors import InputError
    from gtsp_bench.registry import get_solver, run_solver, run_solver_batch

    start = time.perf_counter()
    certificate = msg.get("certificate")
    try:
        options = dict(msg.get("options") or {})
        if certificate is not None:
            options["certificate"] = certificate
            Path(certificate).parent.mkdir(parents=True, exist_ok=True)
            Path(certificate).unlink(missing_ok=True)  # an earlier attempt's proof is not this one's
        if options:
            built = "solver:" + json.dumps(options, sort_keys=True)
            if built not in cache:
                cache[built] = get_solver(name, **options)
            solver = cache[built]
        def parsed(item: Mapping[str, Any]) -> Any:
            inst = cache.get(item["fingerprint"])
            if inst is None:
                inst = cache[item["fingerprint"]] = parse_instance_text(item["text"])
            return inst

        _limit_threads()
        if "batch" in msg:
            insts = [parsed(item) for item in msg["batch"]]
            results, wall = run_solver_batch(solver, insts, msg["omega"], seed=msg["seed"], name=name,
                                             repeats=msg.get("repeats", 1))
            out = {"status": "batch", "items": [_record(r) for r in results], "batch_wall_s": wall}
        else:
            start_from = msg.get("initial")
            res = run_solver(solver, parsed(msg), msg["omega"], time_limit=msg["time_limit"],
                             seed=msg["seed"], name=name,
                             initial=None if start_from is None else tuple(start_from))
            out = _record(res)
            if certificate is not None:
                out["note"] = check_written_certificate(parsed(msg), certificate, res)
    except InputError as e:  # the solver declines this input by design
        out = failure(one_line(e), "refused")
    except MemoryError as e:
        out = failure(f"out of memory: {one_line(e)}", cause=INFRASTRUCTURE)
    except Exception as e:  # any solver error becomes a row; the run goes on
        out = failure(one_line(e))
    out["task_wall_s"] = time.perf_counter() - start
    return out


def check_written_certificate(instance: Any, path: str, res: Any) -> str:
    """Check the certificate that the solve ``res`` wrote at ``path`` with the package's checker
    (:func:`gtsp_bench.proof.check_certificate`, exact arithmetic); a row's note: ``certificate
    checked: proven optimal: VALUE (FILE)``, ``certificate fails: REASON (FILE)``, ``no
    certificate: WHY`` (a solve that says it proved optimality but wrote none), or nothing (a
    solve that proved nothing)."""
    from gtsp_bench.errors import InputError
    from gtsp_bench.proof import ProofError, check_certificate
    from gtsp_bench.proof.format import read_certificate

    if not Path(path).exists():
        if res.status != "optimal":
            return ""
        return f"{NO_CERTIFICATE}: {res.stats.get('certificate', 'none written')}"
    name = f"{Path(path).parent.name}/{Path(path).name}"  # as the output folder holds it
    try:
        result = check_certificate(instance, read_certificate(path))
    except (InputError, ProofError) as e:
        return f"{CERTIFICATE_FAILS}: {one_line(e)} ({name})"
    if not result.proven:
        return f"{CERTIFICATE_FAILS}: {result.summary()} ({name})"
    return f"{CERTIFICATE_CHECKED}: {result.summary()} ({name})"


def _record(res: Any) -> dict[str, Any]:
    """The log record of a checked result."""
    e = res.energy
    return {
        "status": res.status, "objective": res.objective, "lower_bound": res.lower_bound,
        "ground_J": e.ground if e else math.nan, "flight_J": e.flight if e else math.nan,
        "hover_J": e.hover if e else math.nan, "distance_m": res.distance,
        "runtime_s": res.runtime_s, "order": list(res.order), "heads": list(res.heads),
        "note": "", "stats": plain(res.stats),
        # each improvement as [seconds, objective, lower bound or null]; the last is the answer
        "trajectory": [[p.time_s, p.objective, p.lower_bound] for p in res.trajectory],
    }


def worker_main(fd: int) -> None:
    """Entry point of a worker process: ``fd`` is its end of the socket pair."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the runner handles Ctrl-C and stops workers
    sys.stdout.flush()
    os.dup2(2, 1)  # whatever a library prints goes to stderr, never to the caller's stdout
    conn = Connection(fd)
    try:
        name, target, description = conn.recv()
        from gtsp_bench.errors import InputError
        from gtsp_bench.registry import get_solver, register_solver, solver_names

        if name not in solver_names():
            if target is None:
                raise InputError(
                    f"solver {name!r} was registered by a class that a worker process cannot "
                    f"import (defined in __main__ or inside a function); register it by a "
                    f"'module:Class' string or a class from an importable module"
                )
            register_solver(name, target, description)
        solver = get_solver(name)
        _limit_threads()
        conn.send(("ready", None))
    except (EOFError, OSError):
        return
    except Exception as e:
        conn.send(("init_failed", one_line(e)))
        return
    cache: dict[str, Any] = {}
    while True:
        try:
            msg = conn.recv()
            if msg is None:
                return
            conn.send(("done", solve_message(solver, name, msg, cache)))
        except (EOFError, OSError):  # the runner is gone
            return


@dataclass
class _Worker:
    proc: subprocess.Popen
    conn: Connection
    ready: bool = False
    job: Hashable | None = None
    started: float = 0.0
    born: float = field(default_factory=time.monotonic)


def worker_path() -> list[str]:
    """The import path of a worker: this process's ``sys.path`` without the empty entry, which
    stands for the working directory (the worker's ``-P`` keeps Python from adding its own)."""
    return [p for p in sys.path if p]


def solve_threads(n_workers: int, cores: int | None = None) -> int:
    """Threads one solve may run when ``n_workers`` solves share the cores this process may run
    on (at least 1)."""
    return max(1, (usable_cores() if cores is None else cores) // max(1, n_workers))


def _start_worker(name: str, target: str | None, description: str, threads: int = 1) -> _Worker:
    ours, theirs = socket.socketpair()
    env = dict(os.environ)
    for var in THREAD_VARS:
        env.setdefault(var, "1")
    env.setdefault(SOLVE_THREADS_VAR, str(threads))  # a solver's own threads (lns's islands)
    code = ("import sys, json; sys.path[:] = json.loads(sys.argv[2]); "
            "from gtsp_bench.bench.pool import worker_main; worker_main(int(sys.argv[1]))")
    try:
        proc = subprocess.Popen([sys.executable, "-P", "-c", code, str(theirs.fileno()),
                                 json.dumps(worker_path())],
                                pass_fds=[theirs.fileno()], env=env, stdin=subprocess.DEVNULL)
    finally:
        theirs.close()
    conn = Connection(ours.detach())
    conn.send((name, target, description))
    return _Worker(proc, conn)


def _stop_worker(w: _Worker, *, kill: bool = False) -> None:
    if not kill:
        try:
            w.conn.send(None)
            w.proc.wait(timeout=2)
        except (OSError, subprocess.TimeoutExpired):
            pass
    if w.proc.poll() is None:
        w.proc.kill()
    w.proc.wait()
    w.conn.close()


@dataclass
class PhaseStats:
    """What one solver's phase cost: solves, the solvers' own time and the wall time."""

    solver: str
    solves: int = 0
    solver_s: float = 0.0
    wall_s: float = 0.0
    workers: int = 0


class WorkerPool:
    """Worker processes of one solver, kept between calls of :meth:`run` (at most
    ``n_workers``); :func:`run_jobs` is one pool used once. Close it (or use it as a context
    manager) to stop its workers."""

    def __init__(self, solver: str, target: str | None, description: str, n_workers: int,
                 threads: int | None = None) -> None:
        self.solver, self.target, self.description = solver, target, description
        self.n_workers = n_workers
        #: Threads one solve may run (default: :func:`solve_threads` of ``n_workers``).
        self.threads = solve_threads(n_workers) if threads is None else threads
        self.workers: list[_Worker] = []

    def __enter__(self) -> WorkerPool:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Stop every worker."""
        while self.workers:
            w = self.workers.pop()
            _stop_worker(w, kill=w.job is not None)

    def _start(self) -> None:
        self.workers.append(_start_worker(self.solver, self.target, self.description, self.threads))

    def run(self, jobs: Sequence[tuple[Hashable, Mapping[str, Any]]], hard_limit: float,
            on_result: Callable[[Hashable, dict[str, Any], bool], None]) -> PhaseStats:
        """Solve ``jobs`` as :func:`run_jobs` does, with the pool's workers (started as needed,
        idle ones kept for the next call; a worker still solving when this returns by an
        exception is killed)."""
        stats = PhaseStats(self.solver, workers=min(self.n_workers, len(jobs)))
        if not jobs:
            return stats
        start = time.perf_counter()
        pending = deque(jobs)
        messages = dict(jobs)
        attempts: dict[Hashable, int] = {}
        workers = self.workers
        while len(workers) < stats.workers:
            self._start()

        def limit_of(job: Hashable) -> float:
            """The job's own hard limit (its message's ``hard_limit``), else the phase's."""
            return float(messages[job].get("hard_limit", hard_limit))

        def retry(job: Hashable) -> bool:
            """Queue ``job`` again (first in line) unless it has had its attempts."""
            attempts[job] = attempts.get(job, 1) + 1
            if attempts[job] > MAX_ATTEMPTS:
                return False
            pending.appendleft((job, messages[job]))
            return True

        def fail_all(note: str) -> None:
            for job in [*(j for j, _ in pending), *(w.job for w in workers if w.job is not None)]:
                on_result(job, failure(note), False)
            pending.clear()
            for w in workers:
                w.job = None

        def dispatch(w: _Worker) -> None:
            if w.ready and w.job is None and pending:
                w.job, msg = pending.popleft()
                w.started = time.monotonic()
                w.conn.send(msg)

        try:
            while workers and (pending or any(w.job is not None for w in workers)):
                for w in workers:
                    dispatch(w)
                wait([w.conn for w in workers], timeout=0.5)
                now = time.monotonic()
                for w in list(workers):
                    reply: tuple[str, Any] | None = ("dead", None)
                    try:
                        if w.conn.poll():
                            reply = w.conn.recv()
                        elif w.proc.poll() is None:
                            reply = None
                    except (EOFError, OSError):
                        pass
                    if reply is None:
                        over = w.job is not None and now - w.started > limit_of(w.job)
                        stuck = not w.ready and now - w.born > INIT_TIMEOUT_S
                        if not (over or stuck):
                            continue
                        reply = ("killed", None) if over else ("stuck", None)
                    kind, payload = reply
                    if kind == "ready":
                        w.ready = True
                        continue
                    if kind == "done":
                        job, w.job = w.job, None
                        if payload.get("cause") == INFRASTRUCTURE and retry(job):
                            _stop_worker(w, kill=True)  # out of memory: start clean
                            workers.remove(w)
                            self._start()
                            continue
                        stats.solves += 1
                        spent = payload.get("runtime_s", payload.get("batch_wall_s", math.nan))
                        if spent is not None and math.isfinite(spent):
                            stats.solver_s += spent
                        dispatch(w)  # the next solve runs while the result is logged
                        on_result(job, payload, True)
                        continue
                    _stop_worker(w, kill=True)  # unusable from here on
                    workers.remove(w)
                    if kind == "init_failed" or not w.ready:
                        reason = payload if kind == "init_failed" else (
                            "its worker timed out starting" if kind == "stuck"
                            else f"its worker died (exit code {w.proc.returncode})")
                        fail_all(f"solver could not be built: {reason}")
                        return stats
                    if w.job is not None and kind == "killed":
                        on_result(w.job, failure(f"killed: no answer after {limit_of(w.job):g} s",
                                                 "time_limit"), True)
                    elif w.job is not None and not retry(w.job):
                        on_result(w.job, failure(f"worker died (exit code {w.proc.returncode}) in "
                                                 f"{MAX_ATTEMPTS} attempts", cause=INFRASTRUCTURE), True)
                    if pending:
                        self._start()
        finally:
            for w in [w for w in workers if w.job is not None]:  # interrupted mid-solve
                _stop_worker(w, kill=True)
                workers.remove(w)
            stats.wall_s = time.perf_counter() - start
        return stats


def run_jobs(
    solver: str, target: str | None, description: str,
    jobs: Sequence[tuple[Hashable, Mapping[str, Any]]], n_workers: int, hard_limit: float,
    on_result: Callable[[Hashable, dict[str, Any], bool], None],
) -> PhaseStats:
    """Solve ``jobs`` (``(job id, task message)`` pairs) with one solver in fresh workers.

    Parameters
    ----------
    solver, target, description
        The registered name, its ``"module:Class"`` import path (registered in the worker when
        the worker does not know the name; ``None`` when the class cannot be imported there) and
        its description.
    n_workers
        Worker processes to use (at most one per job).
    hard_limit
        Seconds after which a solve's worker is killed (the record gets status ``time_limit``).
    on_result
        Called as ``on_result(job id, record, persist)`` once for every job; ``persist`` is
        ``False`` when the solver could not even be built, so that a later run retries it. A job
        whose worker died under it, or that ran out of memory, is tried again in a fresh worker
        (at most :data:`MAX_ATTEMPTS` times in all) before its failure is reported.
    """
    with WorkerPool(solver, target, description, n_workers) as pool:
        return pool.run(jobs, hard_limit, on_result)

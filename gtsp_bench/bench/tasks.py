"""Solves as tasks: what the paper's runner and the sweeps share.

A :class:`Task` is one solve (a stored instance, a solver with its options, omega, seed and time
limit) under a log key (:func:`task_key`) that makes runs resumable; :func:`run_solver_tasks`
runs one solver's tasks in fresh worker processes with a hard time limit
(:func:`gtsp_bench.bench.pool.run_jobs`), on this machine or on Dask workers
(:mod:`gtsp_bench.bench.executors`); :class:`RunFolder` says where a run keeps its log and lock.
"""

from __future__ import annotations

import functools
import hashlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from gtsp_bench.bench.pool import PhaseStats
from gtsp_bench.instance import Instance

#: A worker gets ``HARD_LIMIT_FACTOR * time_limit + HARD_LIMIT_GRACE_S`` seconds per solve before
#: it is killed (solvers are expected to stop themselves at ``time_limit``).
HARD_LIMIT_FACTOR = 2.0
HARD_LIMIT_GRACE_S = 10.0
#: A solve without a time limit (a learned policy's batch) is killed after this many seconds.
NO_LIMIT_HARD_S = 900.0


class RunFolder:
    """What a run (the paper's experiments or a sweep) keeps in its output folder ``out_dir``:
    the task log and the lock; the hard limit of its solves (from ``time_limit``); and how it
    runs them (:meth:`run_phases`). A base of the frozen config dataclasses, which hold the fields
    below (declared here for readers and type checkers only: a plain class's annotations make no
    dataclass fields)."""

    out_dir: Path
    time_limit: float
    jobs: int
    executor: str

    @property
    def log_path(self) -> Path:
        """The task log that makes runs resumable."""
        return self.out_dir / "tmp" / "runs.jsonl"

    @property
    def lock_path(self) -> Path:
        """The lock a run holds on its output folder."""
        return self.out_dir / "tmp" / "bench.lock"

    def hard_limit(self) -> float:
        """Seconds after which a worker's solve is killed."""
        return HARD_LIMIT_FACTOR * self.time_limit + HARD_LIMIT_GRACE_S

    def run_phases(self, solvers: Sequence[str], todo: Sequence[Task],
                   on_record: Callable[[Task, dict[str, Any], bool], None],
                   describe: Callable[[str], Any]) -> list[PhaseStats]:
        """Run ``todo`` one solver after another, in the order of ``solvers``
        (:func:`run_solver_tasks` with this run's jobs, hard limit and executor); ``describe``
        gets each solver's name as its phase starts (a progress bar's label)."""
        phases = []
        for solver in solvers:
            mine = [t for t in todo if t.solver == solver]
            if mine:
                describe(solver)
                phases.append(run_solver_tasks(solver, mine, self.jobs, self.hard_limit(), on_record,
                                               executor=self.executor))
        return phases


def phase_lines(phases: Sequence[PhaseStats]) -> list[str]:
    """One log line per phase: solves, the solver's own time and the wall time."""
    return [f"  {p.solver}: {p.solves} solves, solver time {p.solver_s:.1f} s, wall "
            f"{p.wall_s:.1f} s on {p.workers} worker(s)" for p in phases]


def fingerprint(text: str) -> str:
    """An instance file's content hash in task keys: the first 16 hex digits of its SHA-256."""
    return hashlib.sha256(text.encode()).hexdigest()[:16]


@dataclass(frozen=True)
class StoredInstance:
    """An instance with its file text and content hash."""

    instance: Instance
    text: str
    fingerprint: str
    path: Path


@dataclass(frozen=True)
class Task:
    """One solve; ``key`` identifies it in the task log; ``options`` are the solver's keyword
    options (none: its defaults); ``initial``, a warm start's ``(order, heads)`` (none: the
    solver's own first tour); ``certificate``, the file a proof's certificate is written to and
    checked at (none: no certificate)."""

    key: str
    solver: str
    omega: float
    instance: StoredInstance
    seed: int
    time_limit: float
    options: tuple[tuple[str, Any], ...] = ()
    initial: tuple[tuple[int, ...], tuple[int, ...]] | None = None
    certificate: str | None = None


@dataclass(frozen=True)
class BatchTask:
    """Several tasks of one solver, options, omega and seed, solved as one batch
    (``solve_batch``, ``repeats`` times; each member's time is the median batch wall time over
    its size). Each member keeps its own key: the log holds one record per instance."""

    key: str
    solver: str
    members: tuple[Task, ...]
    repeats: int = 1

    @property
    def time_limit(self) -> float | None:
        return self.members[0].time_limit


def batch_key(members: Sequence[Task]) -> str:
    """A batch's job id: ``batch:`` and a hash of its members' keys."""
    digest = hashlib.sha256("\n".join(t.key for t in members).encode()).hexdigest()[:16]
    return f"batch:{members[0].solver}:{digest}"


def hard_limit_for(time_limit: float | None) -> float:
    """Seconds after which a worker's solve of that time limit is killed
    (:data:`HARD_LIMIT_FACTOR` x limit + :data:`HARD_LIMIT_GRACE_S`; :data:`NO_LIMIT_HARD_S` without
    a limit)."""
    if time_limit is None:
        return NO_LIMIT_HARD_S
    return HARD_LIMIT_FACTOR * time_limit + HARD_LIMIT_GRACE_S


@functools.cache
def _revision(solver: str) -> str:
    from gtsp_bench.registry import solver_revision

    try:
        return solver_revision(solver)
    except Exception:  # a solver that cannot be loaded fails in its worker, with the reason
        return ""


def task_key(inst: StoredInstance, solver: str, omega: float, seed: int, time_limit: float | None,
             options: Sequence[tuple[str, Any]] = ()) -> str:
    """The log key: the instance's name and content hash, the solver, its revision if it has one
    (a learned policy's weights, see :func:`gtsp_bench.registry.solver_revision`), its options if
    any, and the solve settings. A changed revision gives new keys, so those solves are run again."""
    revision = _revision(solver)
    name = f"{solver}@{revision}" if revision else solver
    if options:
        name += "[" + ",".join(f"{k}={v!r}" for k, v in options) + "]"
    tl = "none" if time_limit is None else f"{time_limit:g}"
    return f"{inst.instance.name}#{inst.fingerprint}|{name}|w={omega:g}|seed={seed}|tl={tl}"


def where_solves_run(executor: str, jobs: int) -> str:
    """How a run's log line names where its solves run, e.g. ``2 local Dask worker(s)``."""
    if executor == "local":
        return f"{jobs} worker(s)"
    return f"{jobs} local Dask worker(s)" if executor == "dask" else f"the Dask scheduler {executor}"


def _task_message(t: Task | BatchTask) -> dict[str, Any]:
    first = t.members[0] if isinstance(t, BatchTask) else t
    msg: dict[str, Any] = {"omega": first.omega, "seed": first.seed, "time_limit": first.time_limit}
    if isinstance(t, BatchTask):
        msg["batch"] = [{"fingerprint": m.instance.fingerprint, "text": m.instance.text} for m in t.members]
        msg["repeats"] = t.repeats
        msg["hard_limit"] = hard_limit_for(first.time_limit) * (1 if first.time_limit else t.repeats)
    else:
        msg.update(fingerprint=t.instance.fingerprint, text=t.instance.text)
        msg["hard_limit"] = hard_limit_for(t.time_limit)
        if t.initial is not None:
            msg["initial"] = [list(t.initial[0]), list(t.initial[1])]
        if t.certificate is not None:
            msg["certificate"] = t.certificate
    if first.options:
        msg["options"] = dict(first.options)
    return msg


def split_batch(batch: BatchTask, rec: dict[str, Any]) -> list[tuple[Task, dict[str, Any]]]:
    """A batch's record as one record per member: its ``items`` in order, or (a failed or killed
    batch) the batch's failure for every member."""
    items = rec.get("items")
    if not isinstance(items, list) or len(items) != len(batch.members):
        extra = {k: v for k, v in rec.items() if k != "items"}
        return [(m, dict(extra)) for m in batch.members]
    return list(zip(batch.members, items, strict=True))


def run_solver_tasks(
    solver: str, tasks: Sequence[Task | BatchTask], jobs: int, hard_limit: float,
    on_record: Callable[[Task, dict[str, Any], bool], None], *, executor: str = "local",
) -> PhaseStats:
    """Run one solver's tasks in the pool's worker processes, with its hard limit
    (:func:`gtsp_bench.bench.pool.run_jobs`): ``jobs`` of them on this machine (``executor`` ``local``),
    or on Dask workers (``dask``: ``jobs`` local Dask workers; ``tcp://HOST:PORT``: a scheduler's
    workers; see :mod:`gtsp_bench.bench.executors`). ``on_record`` gets each result as it arrives. A
    Dask executor stays open for the next call (one cluster for all phases of a run) until
    :func:`gtsp_bench.bench.executors.close_executors`, which the runs call at their end."""
    from gtsp_bench.bench.executors import open_executor
    from gtsp_bench.registry import solver_specs

    spec = next(s for s in solver_specs() if s.name == solver)
    target = spec.import_path()  # a solver registered by class is re-registered in the workers
    by_key = {t.key: t for t in tasks}

    def got(key: Any, rec: dict[str, Any], persist: bool) -> None:
        task = by_key[key]
        if isinstance(task, BatchTask):
            for member, item in split_batch(task, rec):
                on_record(member, item, persist)
        else:
            on_record(task, rec, persist)

    return open_executor(executor, jobs).run(
        solver, target, spec.description, [(t.key, _task_message(t)) for t in tasks], hard_limit, got)

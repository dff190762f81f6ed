"""Running tasks: what every benchmark's run shares (:func:`execute`).

It loads the output folder's task log (records checked, a torn last line dropped), runs the tasks
the log does not hold yet through the worker pool or Dask, solver by solver (a batched
benchmark's tasks as batches), appends each record as it arrives, and reports what it did in an
:class:`Outcome`.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from gtsp_bench.bench.pool import PhaseStats
from gtsp_bench.bench.tasklog import TaskLog, has_answer, needs_run
from gtsp_bench.bench.tasks import RunFolder, Task, phase_lines, where_solves_run

#: Bad task-log records named one by one before the rest are counted.
MAX_SKIP_WARNINGS = 5


@dataclass
class Outcome:
    """What a run did: task counts, the records by key, the phases, the files written."""

    tasks: int = 0
    cached: int = 0
    run: int = 0
    failed: int = 0
    refused: int = 0
    errors: list[str] = field(default_factory=list)
    records: dict[str, dict[str, Any]] = field(default_factory=dict)
    phases: list[PhaseStats] = field(default_factory=list)
    written: list[Path] = field(default_factory=list)
    wall_s: float = 0.0
    answer: str = ""


@dataclass(frozen=True)
class Folder(RunFolder):
    """A benchmark's output folder and how its solves run."""

    out_dir: Path
    time_limit: float
    jobs: int
    executor: str


def _say(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def execute(
    folder: RunFolder,
    tasks: Mapping[str, Task],
    order: Sequence[str],
    *,
    fresh: bool,
    retry_failed: bool,
    progress: bool,
    group: Callable[[Sequence[Task]], Sequence[Any]] | None = None,
    say: Callable[[str], None] = _say,
) -> Outcome:
    """Run the tasks the log of ``folder`` does not hold (all with ``fresh``), solver by solver in
    the order of ``order``, appending each record to the log; re-use the rest.

    ``group`` turns the tasks to run into jobs (batches). A record a solver could not even be
    built for is kept for this run only (a rerun retries it).
    """
    out = Outcome(tasks=len(tasks))
    log = TaskLog(folder.log_path)
    log.open()  # an output folder that cannot be written fails here, before any work
    log.close()
    out.records = log.load({k: tuple(int(n) for n in t.instance.instance.sizes) for k, t in tasks.items()})
    for line in log.skipped[:MAX_SKIP_WARNINGS]:
        say(f"warning: {line}; skipped, its solve is redone")
    if len(log.skipped) > MAX_SKIP_WARNINGS:
        say(f"warning: {folder.log_path}: {len(log.skipped) - MAX_SKIP_WARNINGS} more bad records skipped")
    todo = [t for t in tasks.values() if fresh or needs_run(out.records.get(t.key), retry_failed)]
    out.cached = len(tasks) - len(todo)
    say(
        f"{len(tasks)} solves, {out.cached} already in {folder.log_path}, {len(todo)} to run with "
        f"{where_solves_run(folder.executor, folder.jobs)}"
    )
    if todo:
        from tqdm import tqdm

        bar = tqdm(total=len(todo), unit="solve", disable=not progress, dynamic_ncols=True)
        unlogged: set[str] = set()

        def on_record(task: Task, rec: dict[str, Any], persist: bool) -> None:
            full = {
                "key": task.key,
                "instance": task.instance.instance.name,
                "solver": task.solver,
                "omega": task.omega,
                "seed": task.seed,
                "time_limit": task.time_limit,
                **rec,
            }
            if persist:
                log.append(full)
            elif task.solver not in unlogged:
                unlogged.add(task.solver)
                say(f"warning: {task.solver}: {rec.get('note')} (not recorded: a rerun retries it)")
            out.records[task.key] = full
            out.run += 1
            bar.update()

        jobs = list(group(todo)) if group is not None else todo
        solvers = list(dict.fromkeys([*order, *(t.solver for t in todo)]))
        try:
            out.phases += folder.run_phases(solvers, jobs, on_record, bar.set_description)
        finally:
            bar.close()
            log.close()
        for line in phase_lines(out.phases):
            say(line)
    finals = [out.records[k] for k in tasks if k in out.records]
    out.refused = sum(r.get("status") == "refused" for r in finals)
    out.failed = sum(not has_answer(r) and r.get("status") != "refused" for r in finals)
    return out


__all__ = ["MAX_SKIP_WARNINGS", "Folder", "Outcome", "execute"]

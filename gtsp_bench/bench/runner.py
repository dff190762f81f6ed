"""The benchmark runner: the paper's experiments (section VI) as CSV tables, PNG figures and a report.

Experiments (:data:`EXPERIMENTS`):

``ratio-omega``
    energy of each solver divided by the exact optimum, over a set of instances, for
    omega = 0, 0.1, ..., 0.9, at K = 4 and K = 7 (paper figs. "Energy consumption comparison for 4 /
    7 clusters");
``ratio-k``
    the same ratio for every K at omega = 0.5 (fig. "... when K varies");
``runtime``
    median seconds per instance for each solver and K (table "Running time comparison"); the same
    solves as ``ratio-k``;
``trajectories``
    instance 0, K = 4 at omega = 0, .3, .6, .9 and K = 7 at omega = .1, .3, .5, .8: nodes, chosen
    heads and each solver's tour;
``training``
    the training curves from ``<checkpoints>/<model>.train.csv``.

How a run works. Instance sets are generated once into ``instances/`` (one JSON file per instance,
seeded, re-used when present). Every (instance, omega, solver) solve is a *task* whose key holds the
instance's content hash, the solver, omega, seed and time limit. Finished tasks are appended as one
JSON line each to ``<out>/tmp/runs.jsonl`` (flushed and fsynced; a torn last line is dropped), so an
interrupted run resumes without redoing anything and experiments share their solves (``runtime``
re-uses ``ratio-k``). Tasks run solver by solver, each solver in fresh worker processes
(``forkserver``): highspy and ortools never meet in one process, and a worker that hangs past the
hard limit is killed without stopping the run (``executor``: the same workers on Dask, see
:mod:`gtsp_bench.bench.executors`). A solver that raises gives a row with status
``failed`` (cause ``solver``), one that refuses its input by design (an ``InputError``: dp above its
memory limit, drl on N != 20) ``refused``, one killed at the hard limit ``time_limit`` without an
answer. A worker that dies under a solve (the OOM killer, ``kill -9``) or a solve that runs out of
memory is retried (:data:`gtsp_bench.bench.pool.MAX_ATTEMPTS`), then recorded ``failed`` with cause
``infrastructure``; the next run retries such rows, and ``retry_failed`` (``--retry-failed``) the
solver's own failures too. Records read back from the log are checked
(:func:`gtsp_bench.checks.check_log_record`): a bad one is skipped with a warning naming its line,
and its solve is redone. Runtimes are the solver's own ``runtime_s`` from
:func:`gtsp_bench.registry.run_solver`, never process start-up. Finally each experiment's tidy CSV
and PNG are written atomically and the generated blocks of ``<out>/README.md`` are refreshed.
"""

from __future__ import annotations

import math
import os
import sys
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from gtsp_bench.bench.execute import Outcome, execute
from gtsp_bench.bench.tasklog import exclusive_lock
from gtsp_bench.bench.tasks import (
    RunFolder,
    StoredInstance,
    Task,
    task_key,
)
from gtsp_bench.checks import parse_ks, parse_names
from gtsp_bench.data.io import atomic_write_csv
from gtsp_bench.errors import InputError
from gtsp_bench.generator import DEFAULT_ZETA, check_generator_args
from gtsp_bench.report.paper import (
    ks_text,
    read_training_logs,
    write_report,
)

EXPERIMENTS = ("ratio-omega", "ratio-k", "runtime", "trajectories", "training")
#: The paper's cluster counts for the omega sweeps and the trajectory figures.
PAPER_OMEGA_KS = (4, 7)
OMEGAS = tuple(round(0.1 * i, 1) for i in range(10))
QUICK_OMEGAS = (0.0, 0.5, 0.9)
RATIO_K_OMEGA = 0.5
TRAJECTORY_OMEGAS = {4: (0.0, 0.3, 0.6, 0.9), 7: (0.1, 0.3, 0.5, 0.8)}
DEFAULT_KS = tuple(range(4, 11))
QUICK_KS = (4, 5)
DEFAULT_INSTANCES = 30
QUICK_INSTANCES = 3
DEFAULT_SEED = 1
DEFAULT_NODES = 20
DEFAULT_TIME_LIMIT = 10.0
SOLVER_SEED = 0
#: The default reference is ``dp`` up to this K, then ``milp``; ``brute`` when neither exists.
DP_MAX_K = 12
#: Bad task-log records named one by one before the rest are counted.
MAX_SKIP_WARNINGS = 5
#: Columns of every solve experiment's CSV, in order.
CSV_COLUMNS = (
    "experiment", "K", "N", "instance", "omega", "solver", "seed", "status", "objective",
    "optimum", "ratio", "gap_pct", "reference", "ref_status", "ground_J", "flight_J", "hover_J",
    "distance_m", "lower_bound", "runtime_s", "time_limit_s", "order", "heads",
    "same_tour_as_reference", "note",
)


# ---------------------------------------------------------------------- configuration
def _split_names(text: str | Sequence[str], what: str, valid: Sequence[str]) -> tuple[str, ...]:
    names = parse_names(text, what, valid)
    if not names:
        raise InputError(f"no {what} given")
    return names


@dataclass(frozen=True)
class BenchConfig(RunFolder):
    """A validated benchmark run; build it with :func:`make_config`."""

    experiments: tuple[str, ...]
    ks: tuple[int, ...]
    solvers: tuple[str, ...]
    references: Mapping[int, str]
    n_instances: int
    n_nodes: int
    seed: int
    time_limit: float
    jobs: int
    quick: bool
    out_dir: Path
    instance_dir: Path
    checkpoint_dir: Path
    fresh: bool = False
    progress: bool = True
    retry_failed: bool = False
    omegas: tuple[float, ...] = OMEGAS
    executor: str = "local"

    @property
    def omega_ks(self) -> tuple[int, ...]:
        """K values of the omega sweeps: the paper's 4 and 7 when selected, else min and max K."""
        ks = tuple(k for k in PAPER_OMEGA_KS if k in self.ks)
        return ks or tuple(sorted({min(self.ks), max(self.ks)}))



def resolve_references(reference: str | None, ks: Iterable[int], registered: Sequence[str]) -> dict[int, str]:
    """The exact solver giving the optimum for each K.

    ``None`` or ``"auto"``: ``dp`` for K <= :data:`DP_MAX_K`, else ``milp``, whichever is
    registered; ``brute`` (tiny instances only) when neither is.
    """
    ks = list(ks)
    if reference not in (None, "auto"):
        if reference not in registered:
            raise InputError(f"unknown reference solver {reference!r} (valid: {', '.join(registered)})")
        return dict.fromkeys(ks, reference)
    out = {}
    for k in ks:
        prefs = ("dp", "milp") if k <= DP_MAX_K else ("milp", "dp")
        choice = next((p for p in (*prefs, "brute") if p in registered), None)
        if choice is None:
            raise InputError("no exact reference solver is registered (dp, milp or brute); pass --reference")
        out[k] = choice
    return out


def shipped_checkpoints() -> Path:
    """The folder of the shipped models and their training logs (``solvers/learned/checkpoints``
    in the repository), found without importing the learned solvers."""
    from gtsp_bench.solvers.learned import CHECKPOINT_DIR

    return CHECKPOINT_DIR


def make_config(
    *,
    experiments: str | Sequence[str] = "all",
    ks: str | Sequence[int] | None = None,
    solvers: str | Sequence[str] | None = None,
    reference: str | None = None,
    n_instances: int | None = None,
    n_nodes: int = DEFAULT_NODES,
    seed: int = DEFAULT_SEED,
    time_limit: float = DEFAULT_TIME_LIMIT,
    jobs: int | None = None,
    quick: bool = False,
    out_dir: str | os.PathLike[str] | None = None,
    instance_dir: str | os.PathLike[str] = "instances",
    checkpoint_dir: str | os.PathLike[str] | None = None,
    fresh: bool = False,
    progress: bool = True,
    retry_failed: bool = False,
    executor: str = "local",
) -> BenchConfig:
    """Validate every option before anything is written.

    ``retry_failed`` redoes solves the log records as failed by the solver's own error (those
    whose cause was the infrastructure are retried anyway). ``executor`` is where the solves run:
    ``local``, ``dask`` or ``tcp://HOST:PORT`` (:mod:`gtsp_bench.bench.executors`). ``quick`` changes
    the defaults only (K = 4, 5; 3 instances; omega 0, .5, .9; output in ``results/quick``);
    explicit values win.

    Raises
    ------
    InputError
        A bad K, an unknown experiment, solver or reference, or a bad count or limit.
    """
    from gtsp_bench.checks import check_executor, check_int, check_seed, check_time_limit
    from gtsp_bench.registry import solver_names, solver_specs

    executor = check_executor(executor)
    registered = solver_names()
    if experiments in ("all", None):
        exps = EXPERIMENTS
    else:
        exps = _split_names(experiments, "experiment", (*EXPERIMENTS, "all"))
        exps = EXPERIMENTS if "all" in exps else exps
    if ks is None:
        k_tuple = QUICK_KS if quick else DEFAULT_KS
    elif isinstance(ks, str):
        k_tuple = parse_ks(ks)
    else:
        k_tuple = parse_ks(",".join(str(check_int("K", k, 1)) for k in ks))
    if solvers is None:
        chosen = tuple(s.name for s in solver_specs() if s.bench)
        if not chosen:
            raise InputError("no solver is registered for benchmarking; pass --solvers")
    else:
        chosen = _split_names(solvers, "solver", registered)
    n_inst = n_instances if n_instances is not None else (QUICK_INSTANCES if quick else DEFAULT_INSTANCES)
    n_inst = check_int("number of instances", n_inst, 1)
    n_nodes = check_int("number of nodes", n_nodes, 1)
    check_seed(seed)
    for k in (min(k_tuple), max(k_tuple)):
        check_generator_args(k, n_nodes, DEFAULT_ZETA, 1000.0)
    tl = check_time_limit(time_limit)
    if tl is None:
        raise InputError("the runner needs a per-solve time limit")
    n_jobs = (os.cpu_count() or 1) if jobs is None else jobs
    n_jobs = check_int("jobs", n_jobs, 1)
    if out_dir is None:
        out_dir = Path("results") / "quick" if quick else Path("results")
    return BenchConfig(
        experiments=exps, ks=k_tuple, solvers=chosen,
        references=resolve_references(reference, k_tuple, registered),
        n_instances=n_inst, n_nodes=n_nodes, seed=int(seed), time_limit=tl, jobs=n_jobs,
        quick=quick, out_dir=Path(out_dir), instance_dir=Path(instance_dir),
        checkpoint_dir=Path(checkpoint_dir) if checkpoint_dir is not None else shipped_checkpoints(),
        fresh=fresh, progress=progress, retry_failed=retry_failed,
        omegas=QUICK_OMEGAS if quick else OMEGAS, executor=executor,
    )


# ---------------------------------------------------------------------- instances
def load_instance_set(config: BenchConfig, k: int, n: int) -> list[StoredInstance]:
    """The first ``n`` instances of the seeded set for K = ``k`` under ``config.instance_dir``,
    written once and re-used (:func:`gtsp_bench.bench.sources.load_generated`)."""
    from gtsp_bench.bench.sources import load_generated

    return load_generated(config.instance_dir, k, n, config.seed, config.n_nodes)


# ---------------------------------------------------------------------- experiments -> tasks
@dataclass(frozen=True)
class Cell:
    """One (K, instance index, omega) point of an experiment."""

    k: int
    index: int
    omega: float


def experiment_cells(config: BenchConfig, experiment: str) -> list[Cell]:
    """The (K, instance, omega) points an experiment needs (none for ``training``)."""
    if experiment == "ratio-omega":
        return [Cell(k, i, w) for k in config.omega_ks for w in config.omegas
                for i in range(config.n_instances)]
    if experiment in ("ratio-k", "runtime"):
        return [Cell(k, i, RATIO_K_OMEGA) for k in config.ks for i in range(config.n_instances)]
    if experiment == "trajectories":
        return [Cell(k, 0, w) for k in config.omega_ks
                for w in TRAJECTORY_OMEGAS.get(k, TRAJECTORY_OMEGAS[4])]
    return []


def experiment_solvers(config: BenchConfig, k: int) -> tuple[str, ...]:
    """Solvers run at K = ``k``: the selected ones and the reference."""
    return tuple(dict.fromkeys((*config.solvers, config.references[k])))


#: Solver options of the paper's experiments. ``lns`` runs to its own convergence there, as it did
#: when the results were made: it finds every optimum at K <= 10 in well under a second, and its
#: runtime is then its time to converge, not the 10 s budget it would otherwise use up.
PAPER_SOLVER_OPTIONS: dict[str, dict[str, Any]] = {"lns": {"stop_at_convergence": True}}


def paper_options(solver: str) -> tuple[tuple[str, Any], ...]:
    """The options the paper's experiments give ``solver`` (sorted ``(name, value)`` pairs)."""
    return tuple(sorted(PAPER_SOLVER_OPTIONS.get(solver, {}).items()))


def plan(config: BenchConfig) -> tuple[dict[int, list[StoredInstance]], dict[str, Task]]:
    """Load the instance sets the selected experiments need and list their tasks (deduplicated)."""
    cells = [c for e in config.experiments for c in experiment_cells(config, e)]
    need: dict[int, int] = {}
    for c in cells:
        need[c.k] = max(need.get(c.k, 0), c.index + 1)
    sets = {k: load_instance_set(config, k, n) for k, n in sorted(need.items())}
    tasks: dict[str, Task] = {}
    for c in cells:
        inst = sets[c.k][c.index]
        for s in experiment_solvers(config, c.k):
            options = paper_options(s)
            key = task_key(inst, s, c.omega, SOLVER_SEED, config.time_limit, options)
            tasks.setdefault(key, Task(key, s, c.omega, inst, SOLVER_SEED, config.time_limit, options))
    return sets, tasks


# ---------------------------------------------------------------------- rows and tables
def _same_tour(a: Mapping[str, Any], b: Mapping[str, Any]) -> bool:
    oa, ob = a.get("order"), b.get("order")
    if not oa or not ob or a.get("heads") != b.get("heads"):
        return False
    return oa == ob or oa == ob[::-1]


def _number(value: Any) -> float:
    """A record's number, NaN for a missing one (``None``)."""
    return math.nan if value is None else float(value)


def _row(experiment: str, cell: Cell, inst: StoredInstance, solver: str, reference: str,
         rec: Mapping[str, Any], ref: Mapping[str, Any], time_limit: float) -> dict[str, Any]:
    obj = _number(rec.get("objective"))
    ref_ok = ref.get("status") == "optimal" and np.isfinite(_number(ref.get("objective")))
    optimum = float(ref["objective"]) if ref_ok else math.nan
    notes = [rec.get("note", "")] if rec.get("note") else []
    if not ref_ok:
        notes.append(f"reference {reference} not optimal ({ref.get('status')})")
    ratio = obj / optimum if ref_ok and np.isfinite(obj) else math.nan
    if np.isfinite(ratio) and ratio < 1 - 1e-9:
        notes.append("below the reference optimum")
    return {
        "experiment": experiment, "K": cell.k, "N": int(inst.instance.sizes[0]),
        "instance": inst.instance.name, "omega": cell.omega, "solver": solver,
        "seed": SOLVER_SEED, "status": rec.get("status"), "objective": obj, "optimum": optimum,
        "ratio": ratio, "gap_pct": 100 * (ratio - 1) if np.isfinite(ratio) else math.nan,
        "reference": reference, "ref_status": ref.get("status"),
        "ground_J": rec.get("ground_J", math.nan), "flight_J": rec.get("flight_J", math.nan),
        "hover_J": rec.get("hover_J", math.nan), "distance_m": rec.get("distance_m", math.nan),
        "lower_bound": rec.get("lower_bound"), "runtime_s": rec.get("runtime_s", math.nan),
        "time_limit_s": time_limit,
        "order": " ".join(map(str, rec.get("order") or [])),
        "heads": " ".join(map(str, rec.get("heads") or [])),
        "same_tour_as_reference": _same_tour(rec, ref), "note": "; ".join(notes),
    }


def experiment_rows(config: BenchConfig, experiment: str, sets: Mapping[int, list[StoredInstance]],
                    records: Mapping[str, Mapping[str, Any]]) -> pd.DataFrame:
    """The tidy table of one experiment: one row per instance x omega x solver."""
    rows = []
    for cell in experiment_cells(config, experiment):
        inst = sets[cell.k][cell.index]
        reference = config.references[cell.k]
        ref = records[task_key(inst, reference, cell.omega, SOLVER_SEED, config.time_limit,
                               paper_options(reference))]
        for s in experiment_solvers(config, cell.k):
            rec = records[task_key(inst, s, cell.omega, SOLVER_SEED, config.time_limit, paper_options(s))]
            rows.append(_row(experiment, cell, inst, s, reference, rec, ref, config.time_limit))
    return pd.DataFrame(rows, columns=list(CSV_COLUMNS))


# ---------------------------------------------------------------------- the run
@dataclass
class RunSummary(Outcome):
    """What :func:`run_bench` did: an :class:`~gtsp_bench.bench.execute.Outcome` (``failed``
    and ``refused`` count the run's tasks, run or re-used, that ended without a solution) plus the
    instance sets and the task of each key, which the paper benchmark turns into rows."""

    sets: dict[int, list[StoredInstance]] = field(default_factory=dict)
    task_map: dict[str, Task] = field(default_factory=dict)


def run_bench(config: BenchConfig, *, log: Callable[[str], None] | None = None) -> RunSummary:
    """Run the configured experiments; write their CSV and PNG files and refresh the report.

    Finished solves found in the task log are not redone (unless ``config.fresh``). The run holds
    :attr:`BenchConfig.lock_path` throughout: a second run on the same output folder stops at
    once with an :class:`InputError` naming the lock.
    """
    from gtsp_bench.bench.executors import close_executors

    say = log or (lambda msg: print(msg, file=sys.stderr))
    with exclusive_lock(config.lock_path, "another gtsp-bench bench"):
        try:
            return _run_bench(config, say)
        finally:
            close_executors()


def _run_bench(config: BenchConfig, say: Callable[[str], None]) -> RunSummary:
    t0 = time.perf_counter()
    refs: dict[str, list[int]] = {}
    for k, r in config.references.items():
        refs.setdefault(r, []).append(k)
    for r, ks in refs.items():
        note = " (neither dp nor milp is registered; brute handles tiny instances only)" \
            if r == "brute" else ""
        say(f"reference optimum: {r} for K = {ks_text(ks)}{note}")
    sets, tasks = plan(config)
    say(f"time limit {config.time_limit:g} s per solve")
    order = list(dict.fromkeys([*config.references.values(), *config.solvers]))
    outcome = execute(config, tasks, order, fresh=config.fresh, retry_failed=config.retry_failed,
                      progress=config.progress, say=say)
    summary = RunSummary(**vars(outcome), sets=sets, task_map=tasks)
    write_outputs(config, sets, outcome.records, summary, say)
    summary.wall_s = time.perf_counter() - t0
    say(f"done in {summary.wall_s:.1f} s: {summary.run} solves run, {summary.cached} re-used, "
        f"{summary.failed} failed, {summary.refused} refused"
        + (" (exit code 1: see the failed rows' notes)" if summary.failed else ""))
    return summary


def write_outputs(config: BenchConfig, sets: Mapping[int, list[StoredInstance]],
                  records: Mapping[str, Mapping[str, Any]], summary: RunSummary,
                  say: Callable[[str], None]) -> None:
    """Write each experiment's CSV and PNG, then refresh the report."""
    from gtsp_bench.report import figures

    for exp in config.experiments:
        csv_path, png_path = config.out_dir / f"{exp}.csv", config.out_dir / f"{exp}.png"
        if exp == "training":
            df = read_training_logs(config.checkpoint_dir)
            if df is None:
                say(f"training: no training log {config.checkpoint_dir}/<model>.train.csv; skipped")
                continue
            fig = figures.training_figure(df)
        else:
            df = experiment_rows(config, exp, sets, records)
            fig = figures.experiment_figure(exp, df, {k: s[0].instance for k, s in sets.items()})
        atomic_write_csv(csv_path, df)
        figures.save_png(fig, png_path)
        summary.written += [csv_path, png_path]
    path = write_report(config.out_dir, config.checkpoint_dir, config.jobs)
    summary.written.append(path)
    say("wrote " + ", ".join(str(p) for p in summary.written))


__all__ = [
    "CSV_COLUMNS", "EXPERIMENTS", "BenchConfig", "Cell", "RunSummary",
    "experiment_cells", "make_config", "plan", "resolve_references", "run_bench",
]

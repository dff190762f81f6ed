"""The one engine that runs every benchmark definition.

:func:`configure` applies a command line's choices to a definition (:class:`Settings`);
:func:`plan` reads its instances and lists its tasks (one per instance x solver run x omega x
seed, plus the exact reference solves, keyed by :func:`gtsp_bench.bench.tasks.task_key`; a
batched benchmark groups them into :class:`~gtsp_bench.bench.tasks.BatchTask`); :func:`execute`
runs what the task log does not hold yet through the worker pool or Dask (fresh processes, a hard
kill past the limit, retries) and appends each record to the log; :func:`run_benchmark` does all
of it, turns records into rows (:mod:`gtsp_bench.bench.rows`) and writes the outputs
(:mod:`gtsp_bench.bench.outputs`). Nothing is solved in the calling process.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from gtsp_bench.bench.definitions import (
    GLNS_MACHINE_FACTOR,
    Benchmark,
    Budget,
    Committed,
    Generated,
    Gtsplib,
    Run,
    fixed_budget,
    get_benchmark,
)
from gtsp_bench.bench.execute import Folder, Outcome, _say, execute
from gtsp_bench.bench.rows import Cell
from gtsp_bench.bench.sources import Entry, best_known_tour, load_sources
from gtsp_bench.bench.tasklog import exclusive_lock
from gtsp_bench.bench.tasks import (
    BatchTask,
    Task,
    batch_key,
    task_key,
)
from gtsp_bench.errors import InputError

#: The omega a distance-only task is keyed and run with (the solvers ignore it there).
DISTANCE_OMEGA = 0.0


@dataclass(frozen=True)
class Settings:
    """What a command line changes in a definition (``None``: the definition's value)."""

    quick: bool = False
    out_dir: Path | None = None
    solvers: tuple[str, ...] | None = None
    ks: tuple[int, ...] | None = None
    sets: tuple[str, ...] | None = None
    names: tuple[str, ...] | None = None
    instances: int | None = None
    nodes: int | None = None
    omegas: tuple[float, ...] | None = None
    seeds: tuple[int, ...] | None = None
    time_limit: float | None = None
    jobs: int | None = None
    executor: str = "local"
    instance_dir: Path = Path("instances")
    progress: bool = True
    fresh: bool = False
    retry_failed: bool = False
    update_reference: bool = False
    command: str = ""
    #: Solver options (``-p KEY=VALUE``) for every run: added to its options and its label.
    params: tuple[tuple[str, Any], ...] = ()

    def narrowed(self) -> list[str]:
        """The options that make this run other than its definition (a subset, another
        budget, other settings): such a run does not refresh the docs' generated tables."""
        given = {flag: getattr(self, name) for flag, name in _NARROWING.items()}
        given["-p"] = self.params or None  # no params: the empty tuple
        return [flag for flag, value in given.items() if value is not None]

    def whole(self, out_dir: Path) -> Settings:
        """These settings into ``out_dir`` without what :meth:`narrowed` names: the whole
        benchmark's outputs (``--merge-into`` redraws them)."""
        cleared = {name: () if name == "params" else None for name in _NARROWING.values()}
        return replace(self, out_dir=out_dir, **cleared)


#: The options that narrow a run (:meth:`Settings.narrowed`): flag -> field of :class:`Settings`.
_NARROWING = {"--solvers": "solvers", "-K": "ks", "--set": "sets", "--names": "names",
              "--instances": "instances", "--nodes": "nodes", "--omegas": "omegas",
              "--seeds": "seeds", "--time-limit": "time_limit", "-p": "params"}


#: The solver option (``-p initial=best-known``) that starts each solve of a GTSPLIB file from the
#: library's best-known tour (:func:`gtsp_bench.bench.sources.best_known_tour`); the engine
#: resolves it, the solver gets the tour as its ``initial`` solution.
WARM_START, BEST_KNOWN = "initial", "best-known"
#: The solver option (``-p certificate=true``) that has each solve that proves optimality write
#: its proof certificate into the output folder's ``proofs/`` (:func:`certificate_path`); the
#: worker checks it with the package's checker and the row's note says what the check found.
CERTIFICATE = "certificate"
#: Where a benchmark's certificates go, in its output folder.
PROOFS_DIR = "proofs"


def _with_instances(src: Any, n: int) -> Any:
    if isinstance(src, (Generated, Committed)):
        return replace(src, instances=n)
    if isinstance(src, Gtsplib) and src.per_group is not None:
        return replace(src, per_group=n)
    return src


def certificate_path(out_dir: str | Path, instance: str, key: str) -> Path:
    """Where the solve of task ``key`` on ``instance`` writes its proof certificate
    (``-p certificate=true``): ``OUT/proofs/<instance>.<key digest>.cert.json.gz``, an absolute
    path (the worker writes it)."""
    digest = hashlib.sha256(key.encode()).hexdigest()[:10]
    return Path(out_dir).resolve() / PROOFS_DIR / f"{instance}.{digest}.cert.json.gz"


def _select_runs(bench: Benchmark, given: Sequence[str]) -> tuple[Run, ...]:
    from gtsp_bench.registry import solver_names

    if not bench.runs:  # every registered benchmark solver: any registered name may be asked for
        valid = solver_names()
        bad = [s for s in given if s not in valid]
        if bad:
            raise InputError(f"unknown solver {bad[0]!r} (valid: {', '.join(valid)})")
        return tuple(Run(s) for s in given)
    picked = []
    for want in given:
        mine = [r for r in bench.runs if r.name == want or r.solver == want or r.name.startswith(want + " ")]
        if not mine:
            if want in solver_names():  # lns uses the budget, as in the benchmarks that list it
                mine = [fixed_budget(want) if bench.budget.seconds or bench.budget.factor else Run(want)]
            else:
                valid = ", ".join(dict.fromkeys(r.name for r in bench.runs))
                raise InputError(
                    f"--solvers: {want!r} is no solver of the {bench.name} benchmark "
                    f"(its solvers: {valid}) nor a registered solver"
                )
        picked += [r for r in mine if r not in picked]
    return tuple(picked)


def configure(name: str, settings: Settings) -> Benchmark:
    """The definition ``name`` with ``settings`` applied (its quick variant with ``quick``).

    Raises
    ------
    InputError
        An unknown benchmark or solver.
    """
    bench = get_benchmark(name)
    if settings.quick:
        bench = bench.quick_variant()
    changes: dict[str, Any] = {}
    if settings.sets is not None:
        changes["sources"] = (Committed(settings.sets),)
    if settings.instances is not None:
        changes["sources"] = tuple(
            _with_instances(s, settings.instances) for s in changes.get("sources", bench.sources)
        )
    if settings.nodes is not None:
        changes["sources"] = tuple(
            replace(s, nodes=settings.nodes) if isinstance(s, Generated) else s
            for s in changes.get("sources", bench.sources)
        )
    if settings.solvers is not None:
        changes["runs"] = _select_runs(bench, settings.solvers)
    if settings.params:
        if bench.planner == "paper":
            raise InputError(f"--param: the {bench.name} benchmark fixes its solvers' options "
                             "(run its solvers in another benchmark, e.g. 'sets', to change them)")
        changes["runs"] = with_params(changes.get("runs") or default_runs(bench), settings.params)
    if settings.omegas is not None:
        changes["omegas"] = settings.omegas
    if settings.seeds is not None:
        changes["seeds"] = settings.seeds
    if settings.time_limit is not None:
        changes["budget"] = Budget(settings.time_limit)
    if settings.out_dir is not None:
        changes["out_dir"] = str(settings.out_dir)
    return replace(bench, **changes)


def with_params(runs: Sequence[Run], params: Sequence[tuple[str, Any]]) -> tuple[Run, ...]:
    """``runs`` with the solver options ``params`` set where the run's solver takes them (over
    the run's own value), each named in the label (``lns`` with ``effort=fast``: ``lns
    effort=fast``); the other runs as they are.

    Raises
    ------
    InputError
        An option that no run's solver takes (the first run's options listed).
    """
    from gtsp_bench.registry import can_warm_start, check_option_names, option_names

    given = dict(params)
    warm = given.pop(WARM_START, None)
    if warm is not None and warm != BEST_KNOWN:
        raise InputError(f"--param {WARM_START}={warm}: the one warm start of a benchmark is "
                         f"{WARM_START}={BEST_KNOWN} (the library's best-known tour of each GTSPLIB file)")
    certify = given.pop(CERTIFICATE, None)
    if certify is not None and certify is not True:
        raise InputError(f"--param {CERTIFICATE}={_option_text(certify)}: in a benchmark it is "
                         f"{CERTIFICATE}=true (each proof's certificate is written to the output "
                         f"folder's {PROOFS_DIR}/ and checked)")
    used: set[str] = set()
    out = []
    for r in runs:
        takes = option_names(r.solver)
        mine = {k: v for k, v in given.items() if takes is None or k in takes}
        if warm is not None and can_warm_start(r.solver):
            mine[WARM_START] = warm
        if certify and takes is not None and CERTIFICATE in takes:
            mine[CERTIFICATE] = True
        used.update(mine)
        if not mine:
            out.append(r)
            continue
        label = " ".join([r.name, *(f"{k}={_option_text(v)}" for k, v in mine.items())])
        options = {**dict(r.options), **mine}
        out.append(replace(r, options=tuple(sorted(options.items())), label=label))
    # an option no run takes: the first run's solver does not take it either (one line, its
    # options listed)
    check_option_names(runs[0].solver, [k for k in given if k not in used])
    if certify and CERTIFICATE not in used:
        raise InputError(f"--param {CERTIFICATE}=true: no solver of the run writes proof certificates "
                         f"(solvers: {', '.join(sorted({r.solver for r in runs}))})")
    if warm is not None and WARM_START not in used:
        raise InputError(f"--param {WARM_START}={warm}: no solver of the run can start from a tour "
                         f"(solvers: {', '.join(sorted({r.solver for r in runs}))})")
    return tuple(out)


def _option_text(value: Any) -> str:
    """An option's value as ``-p`` takes it (JSON, bare strings without quotes)."""
    return value if isinstance(value, str) else json.dumps(value)


def default_runs(bench: Benchmark) -> tuple[Run, ...]:
    """A definition's runs; none given: every registered solver marked for benchmarks."""
    if bench.runs:
        return bench.runs
    from gtsp_bench.registry import solver_specs

    return tuple(Run(s.name) for s in solver_specs() if s.bench)


def time_limit_of(bench: Benchmark, entry: Entry) -> float | None:
    """The budget of one solve of ``entry`` (rounded to milliseconds, so keys are stable)."""
    b = bench.budget
    if b.factor is None:
        return b.seconds
    if entry.glns_s is None:
        raise InputError(
            f"{entry.stem}: no GLNS time for a budget relative to GLNS's (glns-45.csv); give --time-limit"
        )
    return round(max(0.01, b.factor * GLNS_MACHINE_FACTOR * entry.glns_s), 3)


@dataclass
class Plan:
    """What a run of a grid benchmark solves: its entries, cells (the rows to come), tasks by key
    (reference solves included) and the exact reference task of each point."""

    entries: list[Entry]
    cells: list[Cell]
    tasks: dict[str, Task]
    exact: dict[tuple[str, str, float | None], tuple[str, str]] = field(default_factory=dict)


def plan(bench: Benchmark, settings: Settings) -> Plan:
    """Read the instances and list the cells and tasks of a grid benchmark."""
    from gtsp_bench.registry import solver_names

    entries = load_sources(
        bench.sources,
        settings.instance_dir,
        ks=settings.ks,
        names=settings.names,
        scratch=Path(bench.output_dir) / "instances",
    )
    runs = default_runs(bench)
    registered = set(solver_names())
    cells: list[Cell] = []
    tasks: dict[str, Task] = {}
    exact: dict[tuple[str, str, float | None], tuple[str, str]] = {}
    tours: dict[str, tuple[tuple[tuple[int, ...], tuple[int, ...]], str]] = {}

    def add(
        e: Entry,
        solver: str,
        options: tuple[tuple[str, Any], ...],
        w: float | None,
        seed: int,
        tl: float | None,
    ) -> str:
        run_w = DISTANCE_OMEGA if w is None else w
        mine = dict(options)
        initial, keyed = None, options
        if mine.pop(WARM_START, None) is not None:
            if e.stem not in tours:
                tours[e.stem] = best_known_tour(e)
            initial, tour_file = tours[e.stem]
            # the key names the tour file, so a shorter tour kept since starts new solves
            keyed = (*tuple(sorted(mine.items())), (WARM_START, tour_file))
        # the key keeps certificate=True (a search that logs its proof is another search); the
        # worker gets the file to write
        certify = mine.pop(CERTIFICATE, None) is True
        options = tuple(sorted(mine.items()))
        key = task_key(e.stored, solver, run_w, seed, tl, keyed)
        certificate = None
        if certify:
            certificate = str(certificate_path(bench.output_dir, e.stored.instance.name, key))
        tasks.setdefault(key, Task(key, solver, run_w, e.stored, seed, tl, options, initial, certificate))
        return key

    for e in entries:
        tl = time_limit_of(bench, e)
        omegas: Sequence[float | None] = bench.omegas if e.stored.instance.is_uav else (None,)
        for w in omegas:
            for r in runs:
                if r.max_k is not None and e.k > r.max_k:
                    continue
                for seed in bench.seeds[:1] if r.one_seed else bench.seeds:
                    cells.append(Cell(e, r, w, seed, tl, add(e, r.solver, r.options, w, seed, tl)))
            ref = next(
                (s for s, k in bench.reference.exact if s in registered and (k is None or e.k <= k)), None
            )
            if ref is not None:
                exact[(e.set, e.stem, w)] = (add(e, ref, (), w, 0, bench.reference.exact_time_limit), ref)
    return Plan(entries, cells, tasks, exact)


def batches(bench: Benchmark, p: Plan, todo: Sequence[Task]) -> list[Task | BatchTask]:
    """``todo`` as jobs: in a batched benchmark, the cells' tasks of one set, K, run, omega and
    seed become one :class:`BatchTask` (reference solves stay single)."""
    if not bench.batched:
        return list(todo)
    wanted = {t.key for t in todo}
    groups: dict[tuple[Any, ...], list[Task]] = {}
    for c in p.cells:
        t = p.tasks.get(c.key)
        if t is not None and c.key in wanted and t.initial is None and t.certificate is None:
            # a warm start or a certified solve is solved alone
            groups.setdefault((c.entry.set, c.entry.k, c.run, c.omega, c.seed), []).append(t)
    grouped = {t.key for g in groups.values() for t in g}
    jobs: list[Task | BatchTask] = [t for t in todo if t.key not in grouped]
    for members in groups.values():
        unique = tuple(dict((t.key, t) for t in members).values())
        jobs.append(BatchTask(batch_key(unique), unique[0].solver, unique, bench.repeats))
    return jobs


def jobs_for(bench: Benchmark, settings: Settings) -> int:
    """Worker processes: ``--jobs``, else the definition's, else the cores."""
    from gtsp_bench.checks import check_int

    n = settings.jobs if settings.jobs is not None else bench.jobs or (os.cpu_count() or 1)
    return check_int("jobs", n, 1)


def run_benchmark(name: str, settings: Settings, *, say: Callable[[str], None] = _say) -> Outcome:
    """Run the benchmark ``name`` with ``settings``: plan, execute, rows, outputs.

    The run holds a lock on its output folder: a second run on the same folder stops at once
    with an :class:`InputError` naming the lock.
    """
    from gtsp_bench.bench import outputs
    from gtsp_bench.bench.executors import close_executors
    from gtsp_bench.checks import check_executor

    bench = configure(name, settings)
    executor = check_executor(settings.executor)
    out_dir = Path(bench.output_dir)
    folder = Folder(out_dir, bench.budget.seconds or 0.0, jobs_for(bench, settings), executor)
    t0 = time.perf_counter()
    if bench.planner == "paper":
        from gtsp_bench.bench.paper import paper_config, run_paper

        config = paper_config(bench, settings, folder.jobs)  # bad options fail before any file
        with exclusive_lock(folder.lock_path, "another gtsp-bench bench"):
            try:
                outcome = run_paper(bench, settings, config, say)
            finally:
                close_executors()
        outcome.wall_s = time.perf_counter() - t0
        return outcome
    p = plan(bench, settings)  # bad sets or files fail before anything is written
    order = [*dict.fromkeys(s for s, _ in bench.reference.exact), *(r.solver for r in default_runs(bench))]
    with exclusive_lock(folder.lock_path, "another gtsp-bench bench"):
        say(
            f"{bench.name}: {len(p.entries)} instances, {len(p.cells)} solves in its rows, "
            f"{bench.budget.describe()}; reference: {bench.reference.describe()}"
        )
        try:
            outcome = execute(
                folder,
                p.tasks,
                order,
                fresh=settings.fresh,
                retry_failed=settings.retry_failed,
                progress=settings.progress,
                group=lambda todo: batches(bench, p, todo),
                say=say,
            )
        finally:
            close_executors()
        outputs.write_all(bench, settings, p, outcome, say)
        _say_certificates(p, outcome, out_dir, say)
    outcome.wall_s = time.perf_counter() - t0
    say(
        f"done in {outcome.wall_s:.1f} s: {outcome.run} solves run, {outcome.cached} re-used, "
        f"{outcome.failed} failed, {outcome.refused} refused"
        + (f", {len(outcome.errors)} error(s)" if outcome.errors else "")
        + (" (exit code 1: see the failed rows' notes)" if outcome.failed or outcome.errors else "")
    )
    return outcome


def _say_certificates(p: Plan, outcome: Outcome, out_dir: Path, say: Callable[[str], None]) -> None:
    """One line on the certificates of a ``-p certificate=true`` run; a certificate the checker
    refused, or a proof that wrote none, is an error of the run (exit code 1)."""
    from gtsp_bench.bench.pool import CERTIFICATE_CHECKED, certificate_verdict

    notes = [str(outcome.records.get(k, {}).get("note") or "") for k, t in p.tasks.items() if t.certificate]
    if not notes:
        return
    verdicts = [certificate_verdict(n) for n in notes]
    checked = verdicts.count(CERTIFICATE_CHECKED)
    bad = [n for n, v in zip(notes, verdicts, strict=True) if v not in (None, CERTIFICATE_CHECKED)]
    say(f"certificates: {checked} written to {out_dir / PROOFS_DIR} and checked, {len(bad)} not; "
        f"{len(notes) - checked - len(bad)} solve(s) proved nothing")
    outcome.errors += bad


__all__ = [
    "CERTIFICATE",
    "DISTANCE_OMEGA",
    "PROOFS_DIR",
    "Outcome",
    "Plan",
    "Settings",
    "batches",
    "certificate_path",
    "configure",
    "default_runs",
    "execute",
    "plan",
    "run_benchmark",
    "time_limit_of",
]

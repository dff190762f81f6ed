"""``gtsp-bench bench --set``: a sweep of solvers over any instance sets, gaps to their references.

A sweep plans one task per set instance x solver x omega x solver seed (omega is ignored for a
distance-only instance: GTSPLIB) and runs them through the paper runner's harness
(:func:`gtsp_bench.bench.tasks.run_solver_tasks`: fresh worker processes per solver, a hard kill past
the limit). Tasks are keyed by :func:`gtsp_bench.bench.tasks.task_key` and logged in
``<out>/tmp/runs.jsonl`` (:class:`gtsp_bench.bench.tasklog.TaskLog`), so a second invocation re-uses
every finished solve and an interrupted one resumes.

Each solve is compared with its set's reference (:mod:`gtsp_bench.data.sets`): the gap is labelled
``to optimum`` or ``to best known`` by the reference's status, ``to best found`` (the best of the
sweep's own solves) where the set has no reference for it. A tour better than a ``best_known``
value is reported, and written into the set's ``reference.csv`` with ``update_reference``; one
below a proven ``optimal`` value is an error (the run exits 1).

Outputs in ``<out>``: ``sweep.csv`` (one row per solve, :data:`TIDY_COLUMNS`), ``summary.md``
(per set and solver: mean gap, hits, median time, failures; also the command's answer on stdout),
``profile.csv`` / ``profile.png`` (the performance profile, :mod:`gtsp_bench.report.profiles`),
``gap-k.csv`` / ``gap-k.png`` when the rows span several K and ``gap-time.csv`` /
``gap-time.png`` when they have gaps.
"""

from __future__ import annotations

import math
import os
import statistics
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from gtsp_bench.bench.pool import PhaseStats
from gtsp_bench.bench.runner import MAX_SKIP_WARNINGS
from gtsp_bench.bench.tasklog import TaskLog, exclusive_lock, needs_run
from gtsp_bench.bench.tasks import (
    RunFolder,
    StoredInstance,
    Task,
    phase_lines,
    task_key,
    where_solves_run,
)
from gtsp_bench.data.io import atomic_write_text
from gtsp_bench.data.sets import (
    Improvement,
    InstanceSet,
    ReferenceRow,
    read_set_file,
    resolve_set,
    strictly_better,
    update_reference,
)
from gtsp_bench.errors import InputError

DEFAULT_OUT = Path("benchmarks") / "out" / "sets"
DEFAULT_OMEGAS = (0.5,)
DEFAULT_SEEDS = (0,)
DEFAULT_TIME_LIMIT = 10.0
#: The omega a distance-only task is keyed and run with (the solvers ignore it there).
DISTANCE_OMEGA = 0.0
#: A gap at most this (in percent) is a hit of the reference.
HIT_GAP_PCT = 1e-6
#: Notes of a row whose tour is below its reference: an error for a proven optimum, an
#: improvement for a best known value.
BELOW_OPTIMUM = "below the proven optimum"
BETTER_THAN_BEST_KNOWN = "better than the best known"
#: Columns of ``sweep.csv``, in order.
TIDY_COLUMNS = (
    "set", "instance", "K", "N", "omega", "solver", "seed", "time_limit", "status", "objective",
    "reference_value", "reference_status", "reference_source", "gap_percent", "gap_label",
    "lower_bound", "runtime_s", "note",
)


# ---------------------------------------------------------------------- configuration
@dataclass(frozen=True)
class SweepConfig(RunFolder):
    """A validated sweep; build it with :func:`make_sweep_config`."""

    sets: tuple[str, ...]
    solvers: tuple[str, ...]
    omegas: tuple[float, ...] = DEFAULT_OMEGAS
    seeds: tuple[int, ...] = DEFAULT_SEEDS
    time_limit: float = DEFAULT_TIME_LIMIT
    n_instances: int | None = None
    names: tuple[str, ...] | None = None
    max_nodes: int | None = None
    ks: tuple[int, ...] | None = None
    jobs: int = 1
    out_dir: Path = DEFAULT_OUT
    instance_dir: Path = Path("instances")
    fresh: bool = False
    retry_failed: bool = False
    progress: bool = True
    update_reference: bool = False
    executor: str = "local"


def parse_seeds(text: str | Sequence[int]) -> tuple[int, ...]:
    """Solver seeds: a list ``0,1,2``, a range ``0..4`` or a mix; order kept, repeats dropped."""
    from gtsp_bench.checks import check_seed

    if not isinstance(text, str):
        seeds = tuple(dict.fromkeys(check_seed(s) for s in text))
        if not seeds:
            raise InputError("bad seeds: no seed given")
        return seeds
    out: list[int] = []
    for part in text.replace(" ", "").split(","):
        lo, sep, hi = part.partition("..")
        try:
            a, b = int(lo), int(hi) if sep else int(lo)
            if b < a:
                raise ValueError
            out += [check_seed(s) for s in range(a, b + 1)]
        except (ValueError, InputError):
            raise InputError(f"bad seeds {text!r}: {part!r} is not a seed or a range "
                             "(expected e.g. 0,1,2 or 0..4)") from None
    return tuple(dict.fromkeys(out))


def make_sweep_config(
    *, sets: Sequence[str], solvers: str | Sequence[str] | None = None,
    omegas: str | Sequence[float] | None = None, seeds: str | Sequence[int] | None = None,
    time_limit: float | None = None, n_instances: int | None = None,
    names: str | Sequence[str] | None = None, max_nodes: int | None = None,
    ks: str | None = None, jobs: int | None = None, out_dir: str | os.PathLike[str] | None = None,
    instance_dir: str | os.PathLike[str] | None = None, fresh: bool = False,
    retry_failed: bool = False, progress: bool = True, update_reference: bool = False,
    executor: str = "local",
) -> SweepConfig:
    """Check every option before anything runs.

    Raises
    ------
    InputError
        An unknown solver, a bad omega, seed, count or time limit, or no set.
    """
    from gtsp_bench.bench.runner import _split_names
    from gtsp_bench.checks import (
        check_executor,
        check_int,
        check_omega,
        check_time_limit,
        parse_ks,
        parse_names,
        parse_omegas,
    )
    from gtsp_bench.registry import solver_names, solver_specs

    chosen_sets = tuple(dict.fromkeys(s.strip() for s in sets if s.strip()))
    if not chosen_sets:
        raise InputError("--set: no set given")
    if solvers is None:
        chosen = tuple(s.name for s in solver_specs() if s.bench)
    else:
        chosen = _split_names(solvers, "solver", solver_names())
    if omegas is None:
        ws = DEFAULT_OMEGAS
    elif isinstance(omegas, str):
        ws = parse_omegas(omegas)
    else:
        ws = tuple(check_omega(w) for w in omegas)
    tl = check_time_limit(DEFAULT_TIME_LIMIT if time_limit is None else time_limit)
    if tl is None:
        raise InputError("a sweep needs a per-solve time limit")
    name_list = None
    if names is not None:
        name_list = parse_names(names, "instance") or None
    return SweepConfig(
        sets=chosen_sets, solvers=chosen, omegas=tuple(dict.fromkeys(ws)),
        seeds=DEFAULT_SEEDS if seeds is None else parse_seeds(seeds), time_limit=tl,
        n_instances=None if n_instances is None else check_int("number of instances", n_instances, 1),
        names=name_list, max_nodes=None if max_nodes is None else check_int("max nodes", max_nodes, 1),
        ks=None if ks is None else parse_ks(ks),
        jobs=check_int("jobs", (os.cpu_count() or 1) if jobs is None else jobs, 1),
        out_dir=Path(out_dir) if out_dir is not None else DEFAULT_OUT,
        instance_dir=Path(instance_dir) if instance_dir is not None else Path("instances"),
        fresh=fresh, retry_failed=retry_failed, progress=progress, update_reference=update_reference,
        executor=check_executor(executor),
    )


# ---------------------------------------------------------------------- sets -> tasks
@dataclass(frozen=True)
class Entry:
    """One instance of a set in the sweep."""

    set_name: str
    stem: str
    stored: StoredInstance

    @property
    def k(self) -> int:
        return self.stored.instance.n_clusters

    @property
    def n(self) -> int:
        return self.stored.instance.n_nodes


@dataclass(frozen=True)
class Solve:
    """One cell of the sweep: an entry, a solver, an omega (``None``: distance-only) and a seed."""

    entry: Entry
    solver: str
    omega: float | None
    seed: int
    key: str


def load_sets(config: SweepConfig) -> list[tuple[InstanceSet, list[Entry]]]:
    """Resolve and read the sets, keeping the instances the config selects: ``names`` (file
    stems), ``ks``, ``max_nodes``, then the first ``n_instances`` per K in file order.

    Raises
    ------
    InputError
        A bad set or file, a name in ``names`` that no set holds, or a set left empty.
    """
    out, found, folders = [], set(), {}
    for arg in config.sets:
        s = resolve_set(arg, config.instance_dir)
        if s.name in folders:
            if folders[s.name] == s.folder.resolve():
                continue  # the same set named twice
            raise InputError(f"--set {arg}: another set is also named {s.name!r} ({folders[s.name]}); "
                             "rename one of the folders")
        folders[s.name] = s.folder.resolve()
        files = [f for f in s.files if config.names is None or f.stem in config.names]
        if config.max_nodes is not None:
            files = [f for f in files if f.nodes is None or f.nodes <= config.max_nodes]
        if config.ks is not None:
            files = [f for f in files if f.clusters is None or f.clusters in config.ks]
        entries, per_k = [], {}
        for f in files:
            full = config.n_instances is not None and per_k.get(f.clusters, 0) >= config.n_instances
            if f.clusters is not None and full:
                continue  # its K has its instances: not read
            inst, text, digest = read_set_file(f)
            k = inst.n_clusters
            if (config.ks is not None and k not in config.ks) or (
                    config.max_nodes is not None and inst.n_nodes > config.max_nodes):
                continue
            if config.n_instances is not None and per_k.get(k, 0) >= config.n_instances:
                continue
            per_k[k] = per_k.get(k, 0) + 1
            entries.append(Entry(s.name, f.stem, StoredInstance(inst, text, digest, f.path)))
            found.add(f.stem)
        if not entries:
            raise InputError(f"{s.folder}: set {s.name!r} has no instance left after the selection "
                             "(--names, -K, --max-nodes)")
        out.append((s, entries))
    missing = [n for n in config.names or () if n not in found]
    if missing:
        raise InputError(f"--names: no selected set holds {missing[0]!r}")
    return out


def plan_sweep(config: SweepConfig, loaded: Sequence[tuple[InstanceSet, list[Entry]]]
               ) -> tuple[list[Solve], dict[str, Task]]:
    """The sweep's cells and its tasks by key (an instance in two sets is solved once)."""
    cells, tasks = [], {}
    for _, entries in loaded:
        for e in entries:
            omegas: Sequence[float | None] = config.omegas if e.stored.instance.is_uav else (None,)
            for solver in config.solvers:
                for w in omegas:
                    run_w = DISTANCE_OMEGA if w is None else w
                    for seed in config.seeds:
                        key = task_key(e.stored, solver, run_w, seed, config.time_limit)
                        cells.append(Solve(e, solver, w, seed, key))
                        tasks.setdefault(key, Task(key, solver, run_w, e.stored, seed, config.time_limit))
    return cells, tasks


# ---------------------------------------------------------------------- rows
def _num(value: Any) -> float:
    return math.nan if value is None else float(value)


def sweep_rows(config: SweepConfig, loaded: Sequence[tuple[InstanceSet, list[Entry]]],
               cells: Sequence[Solve], records: Mapping[str, Mapping[str, Any]]) -> pd.DataFrame:
    """The tidy table: one row per cell, with its reference and gap (:data:`TIDY_COLUMNS`)."""
    refs = {s.name: s.references for s, _ in loaded}
    rows = []
    for c in cells:
        rec = records.get(c.key, {"status": "failed", "objective": None, "note": "no record"})
        ref: ReferenceRow | None = refs[c.entry.set_name].get((c.entry.stem, c.omega))
        obj = _num(rec.get("objective"))
        notes = [str(rec["note"])] if rec.get("note") else []
        gap = math.nan
        if ref is not None and math.isfinite(obj):
            gap = 100.0 * (obj - ref.value) / abs(ref.value) if ref.value else math.nan
            if strictly_better(obj, ref.value):
                notes.append(BELOW_OPTIMUM if ref.status == "optimal" else BETTER_THAN_BEST_KNOWN)
        rows.append({
            "set": c.entry.set_name, "instance": c.entry.stem, "K": c.entry.k, "N": c.entry.n,
            "omega": c.omega, "solver": c.solver, "seed": c.seed, "time_limit": config.time_limit,
            "status": rec.get("status"), "objective": obj,
            "reference_value": ref.value if ref else math.nan,
            "reference_status": ref.status if ref else "", "reference_source": ref.source if ref else "",
            "gap_percent": gap, "gap_label": ref.label if ref else "",
            "lower_bound": _num(rec.get("lower_bound")), "runtime_s": _num(rec.get("runtime_s")),
            "note": "; ".join(notes),
        })
    df = pd.DataFrame(rows, columns=list(TIDY_COLUMNS))
    return _gaps_to_best_found(df)


def _gaps_to_best_found(df: pd.DataFrame) -> pd.DataFrame:
    """Rows without a reference get a gap to the best objective of the sweep's own solves of the
    same set, instance and omega, labelled ``to best found``."""
    no_ref = df["reference_status"] == ""
    if not no_ref.any():
        return df
    omega = df["omega"].astype(float).fillna(-1.0)
    best = df["objective"].groupby([df["set"], df["instance"], omega]).transform("min")
    fill = no_ref & best.notna() & (best != 0)
    df.loc[fill, "reference_value"] = best[fill]
    df.loc[fill, "reference_source"] = "best of this sweep"
    df.loc[fill, "gap_label"] = "to best found"
    ok = fill & df["objective"].notna()
    df.loc[ok, "gap_percent"] = 100.0 * (df.loc[ok, "objective"] - best[ok]) / best[ok].abs()
    return df


def summary_table(df: pd.DataFrame) -> pd.DataFrame:
    """Per set and solver: solves, what the gap is measured to, mean and max gap in percent,
    hits (solves within :data:`HIT_GAP_PCT` of the reference), median seconds, solves the
    solver refused (e.g. an asymmetric instance for a symmetric-only solver) and solves that
    failed (no answer otherwise)."""
    out = []
    for (set_name, solver), g in df.groupby(["set", "solver"], sort=False):
        gaps = g["gap_percent"].dropna()
        refused = g["status"] == "refused"
        times = g["runtime_s"].dropna()
        labels = sorted({lab for lab in g["gap_label"] if lab})
        out.append({
            "set": set_name, "solver": solver, "solves": len(g),
            "gap": " / ".join(labels) or "none",
            "mean_gap_pct": gaps.mean() if len(gaps) else math.nan,
            "max_gap_pct": gaps.max() if len(gaps) else math.nan,
            "hits": int((gaps <= HIT_GAP_PCT).sum()),
            "median_s": statistics.median(times) if len(times) else math.nan,
            "refused": int(refused.sum()),
            "failed": int((g["objective"].isna() & ~refused).sum()),
        })
    return pd.DataFrame(out, columns=["set", "solver", "solves", "gap", "mean_gap_pct",
                                      "max_gap_pct", "hits", "median_s", "refused", "failed"])


def summary_markdown(table: pd.DataFrame) -> str:
    """The summary as a markdown table (gaps to 3 decimals, seconds to 2)."""
    def cell(v: Any, digits: int) -> str:
        return "-" if isinstance(v, float) and not math.isfinite(v) else f"{v:.{digits}f}"

    lines = ["| set | solver | solves | gap | mean gap % | max gap % | hits | median s | refused | failed |",
             "|---|---|---:|---|---:|---:|---:|---:|---:|---:|"]
    for r in table.itertuples():
        lines.append(f"| {r.set} | {r.solver} | {r.solves} | {r.gap} | {cell(r.mean_gap_pct, 3)} | "
                     f"{cell(r.max_gap_pct, 3)} | {r.hits}/{r.solves} | {cell(r.median_s, 2)} | "
                     f"{r.refused} | {r.failed} |")
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------- the run
@dataclass
class SweepSummary:
    """What :func:`run_sweep` did."""

    tasks: int = 0
    cached: int = 0
    run: int = 0
    failed: int = 0
    refused: int = 0
    below_optimum: int = 0
    improvements: list[Improvement] = field(default_factory=list)
    updated: list[str] = field(default_factory=list)
    phases: list[PhaseStats] = field(default_factory=list)
    written: list[Path] = field(default_factory=list)
    table: str = ""
    wall_s: float = 0.0


def run_sweep(config: SweepConfig, *, log: Callable[[str], None] | None = None) -> SweepSummary:
    """Run the sweep (finished solves in the task log are re-used unless ``config.fresh``), write
    its outputs and, with ``config.update_reference``, the improved references.

    The sweep holds :attr:`SweepConfig.lock_path` throughout: a second run on the same output
    folder stops at once with an :class:`InputError` naming the lock.
    """
    from gtsp_bench.bench.executors import close_executors

    say = log or (lambda msg: print(msg, file=sys.stderr))
    loaded = load_sets(config)  # a bad set or file fails before anything is written
    with exclusive_lock(config.lock_path, "another gtsp-bench bench"):
        try:
            return _run_sweep(config, loaded, say)
        finally:
            close_executors()


def _run_sweep(config: SweepConfig, loaded: Sequence[tuple[InstanceSet, list[Entry]]],
               say: Callable[[str], None]) -> SweepSummary:
    t0 = time.perf_counter()
    task_log = TaskLog(config.log_path)
    task_log.open()  # an output folder that cannot be written fails here, before any solve
    task_log.close()
    cells, tasks = plan_sweep(config, loaded)
    summary = SweepSummary(tasks=len(tasks))
    records = task_log.load({k: tuple(int(n) for n in t.instance.instance.sizes) for k, t in tasks.items()})
    for line in task_log.skipped[:MAX_SKIP_WARNINGS]:
        say(f"warning: {line}; skipped, its solve is redone")
    todo = [t for t in tasks.values() if config.fresh or needs_run(records.get(t.key), config.retry_failed)]
    summary.cached = len(tasks) - len(todo)
    say(f"{', '.join(f'{s.name} ({len(e)} instances)' for s, e in loaded)}: {len(tasks)} solves, "
        f"{summary.cached} already in {config.log_path}, {len(todo)} to run with "
        f"{where_solves_run(config.executor, config.jobs)}, time limit {config.time_limit:g} s")
    if todo:
        from tqdm import tqdm

        bar = tqdm(total=len(todo), unit="solve", disable=not config.progress, dynamic_ncols=True)
        unlogged: set[str] = set()

        def on_record(task: Task, rec: dict[str, Any], persist: bool) -> None:
            full = {"key": task.key, "instance": task.instance.instance.name, "solver": task.solver,
                    "omega": task.omega, "seed": task.seed, "time_limit": task.time_limit, **rec}
            if persist:
                task_log.append(full)
            elif task.solver not in unlogged:
                unlogged.add(task.solver)
                say(f"warning: {task.solver}: {rec.get('note')} (not recorded: a rerun retries it)")
            records[task.key] = full
            summary.run += 1
            bar.update()

        try:
            summary.phases += config.run_phases(config.solvers, todo, on_record, bar.set_description)
        finally:
            bar.close()
            task_log.close()
        for line in phase_lines(summary.phases):
            say(line)
    df = sweep_rows(config, loaded, cells, records)
    refused = df["status"] == "refused"
    summary.refused = int(refused.sum())
    summary.failed = int((df["objective"].isna() & ~refused).sum())
    _references(config, loaded, df, summary, say)
    write_sweep_outputs(config.out_dir, df, summary)
    summary.wall_s = time.perf_counter() - t0
    say("wrote " + ", ".join(str(p) for p in summary.written))
    say(f"done in {summary.wall_s:.1f} s: {summary.run} solves run, {summary.cached} re-used, "
        f"{summary.failed} failed, {summary.refused} refused")
    return summary


def _references(config: SweepConfig, loaded: Sequence[tuple[InstanceSet, list[Entry]]],
                df: pd.DataFrame, summary: SweepSummary, say: Callable[[str], None]) -> None:
    """Report tours below a proven optimum (errors) and better than a best known value; write
    the latter into the sets' ``reference.csv`` when asked."""
    below = df[df["note"].str.contains(BELOW_OPTIMUM, regex=False)]
    for r in below.itertuples():
        say(f"error: {r.set}/{r.instance}: {r.solver} seed {r.seed} found {r.objective!r}, below the "
            f"proven optimum {r.reference_value!r} ({r.reference_source}): the reference or the "
            "solver is wrong")
    summary.below_optimum = len(below)
    better = df[df["note"].str.contains(BETTER_THAN_BEST_KNOWN, regex=False)]
    by_set: dict[str, list[Improvement]] = {}
    for r in better.itertuples():
        omega = None if pd.isna(r.omega) else float(r.omega)
        imp = Improvement(r.set, r.instance, omega, float(r.objective), r.solver, int(r.seed),
                          float(r.time_limit))
        by_set.setdefault(r.set, []).append(imp)
        summary.improvements.append(imp)
        say(f"better than the best known: {r.set}/{r.instance}"
            f"{'' if omega is None else f' omega {omega:g}'}: {r.solver} seed {r.seed} found "
            f"{r.objective!r} < {r.reference_value!r}"
            + ("" if config.update_reference else " (--update-reference writes it)"))
    if not config.update_reference:
        return
    for s, _ in loaded:
        found = by_set.get(s.name)
        if not found:
            continue
        if s.reference_path is None:
            say(f"warning: {s.folder}: not updated: GTSPLIB's values are GLKH's tours "
                "(best_known.csv and tours/); add a better tour there by hand")
            continue
        for line in update_reference(s.reference_path, found):
            summary.updated.append(f"{s.reference_path}: {line}")
            say(f"updated {s.reference_path}: {line}")


def write_sweep_outputs(out_dir: Path, df: pd.DataFrame, summary: SweepSummary) -> None:
    """Write ``sweep.csv``, ``summary.md``, the profile and the gap plots (CSV + PNG), atomically."""
    from gtsp_bench.report import profiles
    from gtsp_bench.report.figures import save_png

    def csv(name: str, table: pd.DataFrame) -> None:
        path = out_dir / name
        atomic_write_text(path, table.to_csv(index=False, float_format="%.10g"))
        summary.written.append(path)

    def png(name: str, fig: Any) -> None:
        save_png(fig, out_dir / name)
        summary.written.append(out_dir / name)

    csv("sweep.csv", df)
    summary.table = summary_markdown(summary_table(df))
    atomic_write_text(out_dir / "summary.md", summary.table)
    summary.written.append(out_dir / "summary.md")
    prof = profiles.performance_profile(df)
    csv("profile.csv", prof)
    png("profile.png", profiles.profile_figure(prof))
    if df.loc[df["gap_percent"].notna(), "K"].nunique() > 1:
        gk = profiles.gap_by_k(df)
        csv("gap-k.csv", gk)
        png("gap-k.png", profiles.gap_k_figure(gk))
    if df["gap_percent"].notna().any():
        gt = profiles.gap_time(df)
        csv("gap-time.csv", gt)
        png("gap-time.png", profiles.gap_time_figure(df))


__all__ = [
    "TIDY_COLUMNS", "SweepConfig", "SweepSummary", "load_sets", "make_sweep_config", "parse_seeds",
    "plan_sweep", "run_sweep", "summary_markdown", "summary_table", "sweep_rows",
]

"""The ``paper`` benchmark: the paper's experiments (:mod:`gtsp_bench.bench.runner`) run by the
engine, with the rows, summary and manifest every benchmark writes.

Its cells are the experiments' (the omega sweeps at K = 4 and 7, omega 0.5 at every K, the
trajectory instances), not a full grid, and its outputs are the experiments' CSV and PNG files
and the report ``README.md`` in its folder (``results/paper``). Task keys are the runner's, so
a run re-uses every solve of an earlier ``make bench``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import fields, replace
from pathlib import Path
from typing import Any

from gtsp_bench.bench.definitions import Benchmark, Generated, Run
from gtsp_bench.bench.rows import Cell, make_rows, references
from gtsp_bench.bench.sources import Entry
from gtsp_bench.data.sets import read_reference


def paper_config(bench: Benchmark, settings: Any, jobs: int) -> Any:
    """The runner's configuration of a (configured) paper definition."""
    from gtsp_bench.bench.runner import make_config

    src = next(s for s in bench.sources if isinstance(s, Generated))
    ks = settings.ks if settings.ks is not None else src.ks
    config = make_config(
        ks=",".join(map(str, ks)),
        solvers=",".join(r.solver for r in bench.runs) if bench.runs else None,
        n_instances=src.instances,
        n_nodes=src.nodes,
        seed=src.seed,
        time_limit=bench.budget.seconds or 10.0,
        jobs=jobs,
        quick=settings.quick,
        out_dir=bench.output_dir,
        instance_dir=settings.instance_dir,
        fresh=settings.fresh,
        progress=settings.progress,
        retry_failed=settings.retry_failed,
        executor=settings.executor,
    )
    return replace(config, omegas=tuple(bench.omegas))


def paper_cells(
    config: Any, sets: Mapping[int, Sequence[Any]], tasks: Mapping[str, Any]
) -> tuple[list[Cell], dict[tuple[str, str, float | None], tuple[str, str]], list[Entry]]:
    """One cell per task of the experiments (``sets`` and ``tasks`` as the runner planned them),
    the reference task of each point, the entries."""
    from gtsp_bench.bench.runner import SOLVER_SEED, paper_options
    from gtsp_bench.bench.tasks import task_key

    entries: dict[str, Entry] = {}
    for insts in sets.values():
        folder = Path(insts[0].path).parent
        refs = read_reference(folder / "reference.csv")  # once per set
        for stored in insts:
            stem = Path(stored.path).stem
            entries[stored.fingerprint] = Entry(
                folder.name, stem, stored, {w: r for (s, w), r in refs.items() if s == stem}
            )
    cells, exact = [], {}
    for key, t in tasks.items():
        e = entries[t.instance.fingerprint]
        cells.append(Cell(e, Run(t.solver, t.options), t.omega, t.seed, t.time_limit, key))
        ref = config.references[e.k]
        exact[(e.set, e.stem, t.omega)] = (
            task_key(t.instance, ref, t.omega, SOLVER_SEED, config.time_limit, paper_options(ref)),
            ref,
        )
    return cells, exact, list(entries.values())


def run_paper(bench: Benchmark, settings: Any, config: Any, say: Callable[[str], None]) -> Any:
    """Run the experiments of ``config`` (:func:`paper_config`), then write the rows, summary and
    manifest beside their files."""
    from gtsp_bench.bench.execute import Outcome
    from gtsp_bench.bench.outputs import _rel, errors_of, write_core
    from gtsp_bench.bench.runner import _run_bench

    summary = _run_bench(config, say)
    cells, exact, entries = paper_cells(config, summary.sets, summary.task_map)
    refs = references(bench.reference, cells, summary.records, exact)
    df = make_rows(bench.name, cells, summary.records, refs)
    extra = {
        "tasks": summary.tasks,
        "reused": summary.cached,
        "run": summary.run,
        "failed": summary.failed,
        "refused": summary.refused,
        "jobs": config.jobs,
        "executor": config.executor,
        "experiments": list(config.experiments),
    }
    bench = replace(bench, runs=tuple(dict.fromkeys(c.run for c in cells)))
    written, text = write_core(
        Path(bench.output_dir),
        bench,
        df,
        settings.command,
        {_rel(e.stored.path): e.sha256 for e in entries},
        extra,
    )
    out = Outcome(**{f.name: getattr(summary, f.name) for f in fields(Outcome)})
    out.written += written
    out.answer = text
    out.errors += errors_of(df)
    for e in out.errors:
        say(f"error: {e}")
    say("wrote " + ", ".join(str(p) for p in written))
    return out


__all__ = ["paper_cells", "paper_config", "run_paper"]

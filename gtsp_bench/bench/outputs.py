"""What a benchmark run writes: ``rows.csv``, ``summary.md``, ``manifest.json`` and its named outputs.

Every output folder gets the three files: the rows (:data:`gtsp_bench.bench.rows.COLUMNS`), the
summary per set and solver (also the command's answer on stdout) and the provenance
(:func:`manifest`: git commit and whether the tree was dirty, package versions, CPU model, cores,
RAM, the command line, the budget and reference rules, the SHA-256 of every instance file). A
definition's ``outputs`` name more (:data:`OUTPUTS`): figures, GLNS's table, the generated
blocks of a documentation page, the sets' improved ``reference.csv`` rows. Each output is a
function of the rows alone, so :func:`render` redraws them from a committed ``rows.csv``
(``gtsp-bench bench NAME --report-only``). Files are written atomically.
"""

from __future__ import annotations

import datetime as dt
import os
import platform
import subprocess
import sys
from collections.abc import Callable, Mapping
from importlib import metadata
from pathlib import Path
from typing import Any

import pandas as pd

from gtsp_bench.bench.best_known import keep_hint
from gtsp_bench.bench.definitions import Benchmark, Reference
from gtsp_bench.bench.rows import (
    BELOW_OPTIMUM,
    BETTER_THAN_BEST_KNOWN,
    make_rows,
    references,
    summary_markdown,
    summary_table,
)
from gtsp_bench.data.io import atomic_write_csv, atomic_write_json, atomic_write_text

#: Packages whose versions the manifest records (those installed).
PACKAGES = (
    "gtsp-bench",
    "numpy",
    "scipy",
    "pandas",
    "matplotlib",
    "highspy",
    "ortools",
    "cvxpy",
    "torch",
    "numba",
    "pyvrp",
    "elkai",
    "gurobipy",
    "dask",
    "distributed",
)


#: Folders whose changes do not make a run's checkout dirty: what runs write (tables, doc blocks).
OUTPUT_FOLDERS = ("results", "docs")


def _git(*args: str, cwd: Path | None = None) -> str:
    try:
        return subprocess.run(
            ["git", *args], capture_output=True, text=True, timeout=10,
            cwd=cwd or Path(__file__).resolve().parent,
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return ""


def tree_dirty(cwd: Path | None = None) -> bool:
    """Whether tracked files outside :data:`OUTPUT_FOLDERS` differ from the commit: the code,
    instances or settings a run used were not the commit's. A run's own outputs (a rerun rewrites
    ``results/NAME`` before its manifest) do not count."""
    excludes = [f":(top,exclude){folder}" for folder in OUTPUT_FOLDERS]
    return bool(_git("status", "--porcelain", "--untracked-files=no", "--", ":/", *excludes, cwd=cwd))


def _cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _ram_gib() -> float | None:
    try:
        return round(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30, 1)
    except (ValueError, OSError, AttributeError):
        return None


def manifest(
    bench: Benchmark, command: str, instances: Mapping[str, str], extra: Mapping[str, Any]
) -> dict[str, Any]:
    """The provenance of a run: where, with what, how (``instances``: path -> SHA-256)."""
    versions = {}
    for name in PACKAGES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            continue
    commit = _git("rev-parse", "HEAD")
    return {
        "benchmark": bench.name,
        "description": bench.description,
        "date": dt.datetime.now(dt.UTC).isoformat(timespec="seconds"),
        "command": command or " ".join(["gtsp-bench", *sys.argv[1:]]),
        "git_commit": commit or None,
        "git_dirty": tree_dirty() if commit else None,
        "python": platform.python_version(),
        "packages": versions,
        "cpu_model": _cpu_model(),
        "cores": os.cpu_count(),
        "ram_gib": _ram_gib(),
        "platform": platform.platform(),
        "budget_rule": bench.budget.describe(),
        "reference_rule": bench.reference.describe(),
        "omegas": list(bench.omegas),
        "seeds": list(bench.seeds),
        "batched": bench.batched,
        "repeats": bench.repeats,
        "sources": [s.describe() for s in bench.sources],
        "solvers": [{"solver": r.solver, "label": r.name, "options": dict(r.options)} for r in bench.runs],
        **extra,
        "instances": dict(sorted(instances.items())),
    }


def _rel(path: Path) -> str:
    try:
        return str(path.resolve().relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(path)


def write_core(
    out_dir: Path,
    bench: Benchmark,
    df: pd.DataFrame,
    command: str,
    instances: Mapping[str, str],
    extra: Mapping[str, Any],
) -> tuple[list[Path], str]:
    """Write ``rows.csv``, ``summary.md`` and ``manifest.json``; the paths and the summary text."""
    rows_path, summary_path, manifest_path = (
        out_dir / "rows.csv",
        out_dir / "summary.md",
        out_dir / "manifest.json",
    )
    atomic_write_csv(rows_path, df)
    text = summary_markdown(summary_table(df))
    atomic_write_text(summary_path, f"# {bench.name}\n\n{bench.description}.\n\n{text}")
    atomic_write_json(manifest_path, manifest(bench, command, instances, extra))
    return [rows_path, summary_path, manifest_path], text


def errors_of(df: pd.DataFrame) -> list[str]:
    """Rows that mean a wrong solver or reference: tours below a proven optimum, and proven
    optima of one point that disagree."""
    errors = [
        f"{r.set}/{r.instance} omega {r.omega}: {r.label} seed {r.seed} found {r.objective!r}, "
        f"{BELOW_OPTIMUM} {r.reference_value!r} ({r.reference_source})"
        for r in df[df["note"].str.contains(BELOW_OPTIMUM, regex=False)].itertuples()
    ]
    proven = df[df["status"] == "optimal"]
    for (s, i, w), g in proven.groupby(["set", "instance", proven["omega"].astype(float).fillna(-1.0)]):
        lo, hi = g["objective"].min(), g["objective"].max()
        if hi - lo > 1e-6 * max(1.0, abs(lo)):
            errors.append(
                f"{s}/{i} omega {w:g}: proven optima disagree: "
                + ", ".join(f"{r.label} {r.objective!r}" for r in g.itertuples())
            )
    return errors


def write_all(bench: Benchmark, settings: Any, p: Any, outcome: Any, say: Callable[[str], None]) -> None:
    """The rows of a grid run and every output of its definition."""
    table_refs = references(Reference(table=True), p.cells, {}, {})
    refs = references(bench.reference, p.cells, outcome.records, p.exact)
    df = make_rows(
        bench.name,
        p.cells,
        outcome.records,
        refs,
        {k: v for k, v in table_refs.items() if v.kind != "best_found"},
    )
    out_dir = Path(bench.output_dir)
    instances = {_rel(e.stored.path): e.sha256 for e in p.entries}
    extra = {
        "tasks": outcome.tasks,
        "reused": outcome.cached,
        "run": outcome.run,
        "failed": outcome.failed,
        "refused": outcome.refused,
        "jobs": settings.jobs,
        "executor": settings.executor,
    }
    written, text = write_core(out_dir, bench, df, settings.command, instances, extra)
    outcome.errors += errors_of(df)
    for e in outcome.errors:
        say(f"error: {e}")
    better = df[df["note"].str.contains(BETTER_THAN_BEST_KNOWN, regex=False)]
    for r in better.itertuples():
        say(f"{BETTER_THAN_BEST_KNOWN}: {r.set}/{r.instance}: {r.label} seed {r.seed} found {r.objective!r}")
    if not better.empty and not getattr(settings, "update_reference", False):
        say(keep_hint(better, getattr(settings, "command", "")))
    written += render(bench, df, out_dir, settings, say)
    outcome.written = written
    outcome.answer = text
    say("wrote " + ", ".join(str(w) for w in written))


def render(
    bench: Benchmark, df: pd.DataFrame, out_dir: Path, settings: Any, say: Callable[[str], None]
) -> list[Path]:
    """Every named output of ``bench`` from its rows; the files written."""
    from gtsp_bench.bench.output_kinds import OUTPUTS

    written: list[Path] = []
    names = list(bench.outputs)
    if getattr(settings, "update_reference", False):  # --update-reference works on any benchmark
        names += [n for n in ("update-references", "best-known") if n not in names]
    for name in names:
        written += OUTPUTS[name](bench, df, out_dir, settings, say)
    return written


__all__ = ["PACKAGES", "errors_of", "manifest", "render", "write_all", "write_core"]

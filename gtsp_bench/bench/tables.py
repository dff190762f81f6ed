"""Rows, cells, tables and CSV files of the benchmark suites (:mod:`gtsp_bench.bench.suites`).

One solve is a :class:`Row`; :func:`solve` makes one through the checked harness
(:func:`gtsp_bench.registry.run_solver`), turning a refusal or failure into a ``failed`` row. The
cell formatters (:func:`time_to_proof_cell`, :func:`gap_time_cell`) and :func:`grid_header` give
the suites' tables one look; :func:`write_csv` writes a suite's rows atomically; :func:`median_wall`
times a batched call.
"""

from __future__ import annotations

import csv
import io
import math
import os
import statistics
import sys
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TypeVar

from gtsp_bench.data.io import atomic_write_text
from gtsp_bench.errors import InputError, SolverError
from gtsp_bench.instance import Instance

T = TypeVar("T")


@dataclass(frozen=True)
class Row:
    """One solve: where it belongs (``group``, e.g. ``K=4`` or ``GTSPLIB``) and what it gave.

    ``reference`` and ``reference_kind`` are the value a gap is measured against and where it
    comes from (``optimum (dp)``, ``best found``, ...), when the suite has one.
    """

    group: str
    instance: str
    omega: float | None
    solver: str
    status: str
    objective: float
    lower_bound: float = math.nan
    runtime_s: float = math.nan
    note: str = ""
    reference: float = math.nan
    reference_kind: str = ""

    @property
    def gap(self) -> float:
        """Gap in percent to the reference (NaN without one)."""
        return 100.0 * (self.objective - self.reference) / self.reference

    def against(self, reference: float, kind: str) -> Row:
        """This row with its reference set."""
        return replace(self, reference=reference, reference_kind=kind)


def solve(group: str, instance: Instance, omega: float | None, solver: str, time_limit: float | None,
          seed: int) -> Row:
    """One solve of the registered ``solver`` (a fresh object) through the checked harness.

    A refusal by design (an :class:`InputError`: an unknown or unavailable solver, an instance the
    solver does not take) becomes a ``refused`` row, a solver's failure (a :class:`SolverError`) a
    ``failed`` row, and so does any other exception the solver raises; each has the error's first
    line as its note."""
    from gtsp_bench.registry import run_solver

    try:
        r = run_solver(solver, instance, omega, time_limit=time_limit, seed=seed)
    except Exception as e:
        status = "refused" if isinstance(e, InputError) else "failed"
        text = str(e) if isinstance(e, (InputError, SolverError)) else f"{type(e).__name__}: {e}"
        return Row(group, instance.name, omega, solver, status, math.nan,
                   note=(text.splitlines() or [type(e).__name__])[0][:200])
    lower = math.nan if r.lower_bound is None else r.lower_bound
    return Row(group, instance.name, omega, solver, r.status, r.objective, lower, r.runtime_s)


def count_failed(rows: Sequence[Row]) -> int:
    """How many rows are ``failed`` (a refusal by design is not a failure), said on stderr."""
    failed = sum(r.status == "failed" for r in rows)
    if failed:
        print(f"{failed} solve(s) failed: see the status and note columns of the CSV", file=sys.stderr)
    return failed


def time_to_proof_cell(rows: Sequence[Row], limit: float) -> str:
    """Median time to a proven optimum (an unproven solve counts as above the limit) and how
    many were proven, e.g. ``   0.23s 5/5`` or ``>    60s 2/5``."""
    times = sorted(r.runtime_s if r.status == "optimal" else math.inf for r in rows)
    proven = sum(math.isfinite(t) for t in times)
    med = statistics.median(times)
    text = f"{med:7.2f}s" if math.isfinite(med) else f">{limit:6.0f}s"
    return f"{text} {proven}/{len(times)}"


def gap_time_cell(rows: Sequence[Row]) -> str:
    """Mean gap to the reference and median solve time, ``*`` when a solve hit the time limit."""
    gap = statistics.fmean(r.gap for r in rows)
    median = statistics.median(r.runtime_s for r in rows)
    limit = "*" if any(r.status == "time_limit" for r in rows) else " "
    return f"{gap:>6.3f}% {median:>5.2f}s{limit}"


def grid_header(left: str, columns: Sequence[str], width: int) -> list[str]:
    """A table's heading line (``left``, then one right-aligned column per name) and its rule."""
    head = left + "".join(f" | {c:>{width}}" for c in columns)
    return [head, "-" * len(head)]


def grid_line(left: str, cells: Sequence[str], width: int) -> str:
    """One table line under :func:`grid_header`; a missing cell is ``None`` -> ``-``."""
    return left + "".join(f" | {'-' if c is None else c:>{width}}" for c in cells)


def median_wall(call: Callable[[], T], repeats: int) -> tuple[T, float]:
    """Run ``call`` ``repeats`` times; its last result and the median wall time in seconds."""
    if repeats < 1:
        raise InputError(f"repeats must be >= 1, got {repeats!r}")
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        result = call()
        times.append(time.perf_counter() - start)
    return result, statistics.median(times)


def write_csv(path: str | os.PathLike[str], columns: Sequence[str],
              records: Iterable[Sequence[object]]) -> Path:
    """Write a header and one line per record atomically (the folder is created); the path."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(columns)
    writer.writerows(records)
    out = Path(path)
    atomic_write_text(out, buf.getvalue())  # creates the folder
    return out

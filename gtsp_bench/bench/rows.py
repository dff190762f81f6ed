"""One row schema for every benchmark, the reference rule that fills it, and the summary.

A row is one solve (:data:`COLUMNS`). ``gap_pct`` is always to the *reference* (named by
``reference_kind``: ``optimal`` a proven optimum, ``best_known`` a published or committed best
tour, ``best_found`` the best this run found) and ``bound_gap_pct`` always to the solver's *own*
lower bound (``(objective - lower_bound) / objective``), so the two cannot be mixed up. Every row
keeps its tour (``order`` and ``heads``, space-separated), so anyone can re-price it, and its
incumbents over time (``trajectory``) with the anytime metrics they give against the reference
(``primal_integral``, ``time_to_1pct_s``, ``time_to_0p1pct_s``: :mod:`gtsp_bench.bench.anytime`).
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import pandas as pd

from gtsp_bench.bench.anytime import format_trajectory, metrics, points_of
from gtsp_bench.bench.definitions import Reference, Run
from gtsp_bench.bench.sources import Entry
from gtsp_bench.checks import strictly_better

COLUMNS = (
    "benchmark",
    "set",
    "instance",
    "instance_sha256",
    "K",
    "N",
    "omega",
    "solver",
    "label",
    "seed",
    "time_limit",
    "status",
    "objective",
    "lower_bound",
    "runtime_s",
    "reference_value",
    "reference_kind",
    "reference_source",
    "gap_pct",
    "bound_gap_pct",
    "order",
    "heads",
    "note",
    "trajectory",
    "primal_integral",
    "time_to_1pct_s",
    "time_to_0p1pct_s",
)
REFERENCE_KINDS = ("optimal", "best_known", "best_found")
#: The columns that name one solve in a benchmark's rows (:func:`merge_rows`).
ROW_KEY = ("set", "instance", "omega", "label", "seed")
#: A gap at most this (percent) is a hit of the reference.
HIT_GAP_PCT = 1e-6
#: Notes of a row below its reference: an error for a proven optimum, news for a best known.
BELOW_OPTIMUM = "below the proven optimum"
BETTER_THAN_BEST_KNOWN = "better than the best known"


@dataclass(frozen=True)
class Cell:
    """One solve of a benchmark: an entry, a run, an omega (``None``: distance-only), a seed, its
    time limit and its task key."""

    entry: Entry
    run: Run
    omega: float | None
    seed: int
    time_limit: float | None
    key: str


@dataclass(frozen=True)
class RefValue:
    """The value a solve is measured against."""

    value: float
    kind: str
    source: str


def _num(value: Any) -> float:
    return math.nan if value is None else float(value)


def _answered(rec: Mapping[str, Any] | None) -> bool:
    return rec is not None and rec.get("objective") is not None and math.isfinite(_num(rec.get("objective")))


def references(
    rule: Reference,
    cells: Sequence[Cell],
    records: Mapping[str, Mapping[str, Any]],
    exact_keys: Mapping[tuple[str, str, float | None], tuple[str, str]],
) -> dict[tuple[str, str, float | None], RefValue]:
    """The reference of every (set, instance, omega) of ``cells`` by ``rule``.

    ``exact_keys`` maps a point to its exact reference task (key, solver). In order: that task's
    proven optimum; the set's table row; with ``own_proofs``, a proven optimum of the cells;
    else the best objective of the cells (and of the exact task). A ``best_known`` value that a
    cell beat becomes ``best_found`` (the notes say which solve did it).
    """
    points: dict[tuple[str, str, float | None], list[Cell]] = {}
    for c in cells:
        points.setdefault((c.entry.set, c.entry.stem, c.omega), []).append(c)
    out: dict[tuple[str, str, float | None], RefValue] = {}
    for point, mine in points.items():
        recs = [records.get(c.key) for c in mine]
        found = [(_num(r["objective"]), c) for r, c in zip(recs, mine, strict=True) if _answered(r)]
        exact = exact_keys.get(point)
        ref: RefValue | None = None
        if exact is not None:
            rec = records.get(exact[0])
            if rec is not None and rec.get("status") == "optimal" and _answered(rec):
                ref = RefValue(float(rec["objective"]), "optimal", f"{exact[1]} (proven)")
            elif _answered(rec):
                found.append((_num(rec["objective"]), None))  # type: ignore[arg-type]
        row = mine[0].entry.references.get(point[2])
        if ref is None and rule.table and row is not None:
            ref = RefValue(row.value, row.status, row.source + (f" {row.date}" if row.date else ""))
        if ref is None and rule.own_proofs:
            proofs = [
                (_num(r["objective"]), c)
                for r, c in zip(recs, mine, strict=True)
                if _answered(r) and r.get("status") == "optimal"
            ]
            if proofs:
                value, c = min(proofs, key=lambda p: p[0])
                ref = RefValue(value, "optimal", f"{c.run.name} (proven)")
        best = min((v for v, _ in found), default=math.nan)
        if ref is not None and ref.kind == "best_known" and strictly_better(best, ref.value):
            ref = RefValue(best, "best_found", f"best of this run, below {ref.source} {ref.value!r}")
        if ref is None and math.isfinite(best):
            ref = RefValue(best, "best_found", "best of this run")
        if ref is not None:
            out[point] = ref
    return out


def make_rows(
    benchmark: str,
    cells: Sequence[Cell],
    records: Mapping[str, Mapping[str, Any]],
    refs: Mapping[tuple[str, str, float | None], RefValue],
    table_refs: Mapping[tuple[str, str, float | None], RefValue] | None = None,
) -> pd.DataFrame:
    """One row per cell (:data:`COLUMNS`); a cell without a record is a ``failed`` row."""
    rows = []
    for c in cells:
        rec = records.get(c.key) or {"status": "failed", "objective": None, "note": "no record"}
        point = (c.entry.set, c.entry.stem, c.omega)
        ref = refs.get(point)
        obj, lb = _num(rec.get("objective")), _num(rec.get("lower_bound"))
        notes = [str(rec["note"])] if rec.get("note") else []
        gap = math.nan
        if ref is not None and math.isfinite(obj) and ref.value:
            gap = 100.0 * (obj - ref.value) / abs(ref.value)
            if ref.kind == "optimal" and obj < ref.value * (1 - 1e-7) - 1e-9:
                notes.append(BELOW_OPTIMUM)
        table = (table_refs or {}).get(point)
        if (
            table is not None
            and table.kind == "best_known"
            and math.isfinite(obj)
            and strictly_better(obj, table.value)
        ):
            notes.append(BETTER_THAN_BEST_KNOWN)
        bound_gap = (
            100.0 * (obj - lb) / abs(obj) if math.isfinite(obj) and math.isfinite(lb) and obj else math.nan
        )
        runtime = _num(rec.get("runtime_s"))
        points = points_of(rec.get("trajectory"), runtime, obj)
        horizon = c.time_limit if c.time_limit else runtime
        anytime = metrics(points, ref.value if ref else math.nan, horizon)
        rows.append(
            {
                "benchmark": benchmark,
                "set": c.entry.set,
                "instance": c.entry.stem,
                "instance_sha256": c.entry.sha256,
                "K": c.entry.k,
                "N": c.entry.n,
                "omega": c.omega,
                "solver": c.run.solver,
                "label": c.run.name,
                "seed": c.seed,
                "time_limit": c.time_limit,
                "status": rec.get("status"),
                "objective": obj,
                "lower_bound": lb,
                "runtime_s": runtime,
                "reference_value": ref.value if ref else math.nan,
                "reference_kind": ref.kind if ref else "",
                "reference_source": ref.source if ref else "",
                "gap_pct": gap,
                "bound_gap_pct": bound_gap,
                "order": " ".join(map(str, rec.get("order") or [])),
                "heads": " ".join(map(str, rec.get("heads") or [])),
                "note": "; ".join(notes),
                "trajectory": format_trajectory(points),
                **anytime,
            }
        )
    return pd.DataFrame(rows, columns=list(COLUMNS))


def summary_table(df: pd.DataFrame) -> pd.DataFrame:
    """Per set and label: solves, the reference kinds, mean and max gap, hits, proven optima,
    median seconds, refused and failed solves."""
    out = []
    for (set_name, label), g in df.groupby(["set", "label"], sort=False):
        gaps = g["gap_pct"].dropna()
        refused = g["status"] == "refused"
        times = g["runtime_s"].dropna()
        out.append(
            {
                "set": set_name,
                "label": label,
                "solves": len(g),
                "reference": " / ".join(sorted({k for k in g["reference_kind"] if isinstance(k, str) and k}))
                or "none",
                "mean_gap_pct": gaps.mean() if len(gaps) else math.nan,
                "max_gap_pct": gaps.max() if len(gaps) else math.nan,
                "hits": int((gaps <= HIT_GAP_PCT).sum()),
                "proven": int((g["status"] == "optimal").sum()),
                "median_s": statistics.median(times) if len(times) else math.nan,
                "refused": int(refused.sum()),
                "failed": int((g["objective"].isna() & ~refused).sum()),
            }
        )
    return pd.DataFrame(
        out,
        columns=[
            "set",
            "label",
            "solves",
            "reference",
            "mean_gap_pct",
            "max_gap_pct",
            "hits",
            "proven",
            "median_s",
            "refused",
            "failed",
        ],
    )


def _cell(v: Any, digits: int) -> str:
    return "-" if isinstance(v, float) and not math.isfinite(v) else f"{v:.{digits}f}"


def summary_markdown(table: pd.DataFrame) -> str:
    """The summary as a Markdown table (gaps to 3 decimals, seconds to 3)."""
    lines = [
        "| set | solver | solves | reference | mean gap % | max gap % | hits | proven | median s "
        "| refused | failed |",
        "|---|---|---:|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in table.itertuples():
        lines.append(
            f"| {r.set} | {r.label} | {r.solves} | {r.reference} | {_cell(r.mean_gap_pct, 3)} | "
            f"{_cell(r.max_gap_pct, 3)} | {r.hits}/{r.solves} | {r.proven} | {_cell(r.median_s, 3)} | "
            f"{r.refused} | {r.failed} |"
        )
    return "\n".join(lines) + "\n"


def read_rows(path: Any) -> pd.DataFrame:
    """A ``rows.csv`` back as a frame (its columns checked).

    Raises
    ------
    InputError
        When the file is missing or lacks a column of :data:`COLUMNS`.
    """
    from gtsp_bench.errors import InputError

    try:
        df = pd.read_csv(path, keep_default_na=True,
                         dtype={"order": str, "heads": str, "note": str, "trajectory": str})
    except (OSError, ValueError) as e:
        raise InputError(f"{path}: cannot read the rows ({e})") from None
    missing = [c for c in COLUMNS if c not in df.columns]
    if missing:
        raise InputError(f"{path}: not a rows.csv of a benchmark (no column {missing[0]!r})")
    for col in ("order", "heads", "note", "reference_kind", "reference_source", "label", "set", "trajectory"):
        df[col] = df[col].fillna("")
    return df


def _keys(df: pd.DataFrame) -> list[tuple[str, ...]]:
    """Each row's :data:`ROW_KEY` as text (a missing omega, of a GTSPLIB row, as ``""``)."""
    def text(v: Any, number: bool) -> str:
        return "" if pd.isna(v) else repr(float(v)) if number else str(v)

    cols = [[text(v, c == "omega") for v in df[c]] for c in ROW_KEY]
    return list(zip(*cols, strict=True))


def _check_best_found(old: pd.DataFrame, old_keys: list[tuple[str, ...]], new: pd.DataFrame,
                      new_keys: list[tuple[str, ...]]) -> None:
    """Refuse a merge that would leave a point (set, instance, omega: a key's first three) with
    old and new rows where a row of it has a ``best_found`` reference (:func:`merge_rows`)."""
    found = {k[:3] for df, ks in ((old, old_keys), (new, new_keys))
             for k, kind in zip(ks, df["reference_kind"], strict=True) if kind == "best_found"}
    fresh = set(new_keys)
    touched = {k[:3] for k in new_keys}
    for key in old_keys:
        point = key[:3]
        if point in found and point in touched and key not in fresh:
            where = f"{point[0]} {point[1]}" + (f" omega {point[2]}" if point[2] else "")
            raise ValueError(f"the rows of {where} have gaps to the best found of "
                             "their own run, and the new rows replace only some of them; run the "
                             "whole point (every label and seed of it) or the whole benchmark")


def merge_rows(old: pd.DataFrame, new: pd.DataFrame) -> tuple[pd.DataFrame, int, int]:
    """``old``'s rows with each solve of ``new`` (same :data:`ROW_KEY`) in place of its old row,
    and ``new``'s other rows appended: a partial rerun folded into a whole benchmark's rows.

    Returns
    -------
    tuple
        The merged frame (``old``'s order, then the added rows), the rows replaced, the rows
        added.

    Raises
    ------
    ValueError
        When the frames are rows of different benchmarks, when a solve appears twice in one of
        them, or when a point (set, instance, omega) would hold old and new rows and some row
        of it measures its gap to the best found of its own run (``best_found``: that depends on
        the other rows of the run's point, so the table could be left with a gap to a value that
        is no longer its point's best). A point the new rows replace whole, or do not touch,
        keeps its own rows' references and is merged.
    """
    benchmarks = set(old["benchmark"]) | set(new["benchmark"])
    if len(benchmarks) > 1:
        raise ValueError(f"rows of different benchmarks: {', '.join(sorted(map(str, benchmarks)))}")
    keys = {}
    for name, df in (("the old rows", old), ("the new rows", new)):
        keys[name] = _keys(df)
        if len(set(keys[name])) < len(keys[name]):
            twice = next(k for k in keys[name] if keys[name].count(k) > 1)
            raise ValueError(f"{name} hold one solve twice ({', '.join(twice)})")
    _check_best_found(old, keys["the old rows"], new, keys["the new rows"])
    where = {k: i for i, k in enumerate(keys["the old rows"])}
    merged, fresh = old[list(COLUMNS)].copy(), new[list(COLUMNS)]
    added = []
    for j, key in enumerate(keys["the new rows"]):
        if key in where:
            merged.iloc[where[key]] = fresh.iloc[j]
        else:
            added.append(j)
    if added:
        merged = pd.concat([merged, fresh.iloc[added]], ignore_index=True)
    return merged, len(new) - len(added), len(added)


__all__ = [
    "BELOW_OPTIMUM",
    "BETTER_THAN_BEST_KNOWN",
    "COLUMNS",
    "HIT_GAP_PCT",
    "REFERENCE_KINDS",
    "ROW_KEY",
    "Cell",
    "RefValue",
    "make_rows",
    "merge_rows",
    "read_rows",
    "references",
    "summary_markdown",
    "summary_table",
]

"""Measure a finished run's rows against today's reference tables, solving nothing.

A set's ``reference.csv`` and GTSPLIB's ``best_known.csv`` get better over time (new best-known
tours, proofs), while a run's ``rows.csv`` keeps the references it was measured against.
:func:`rereference` applies the benchmark's reference rule (:func:`~gtsp_bench.bench.rows.references`)
again, with today's tables and the rows' own answers. A point whose reference value changed has
its rows rebuilt (:func:`~gtsp_bench.bench.rows.make_rows`: gap, notes, anytime metrics, the
latter from the rows' trajectories, whose times have 4 significant digits); a point whose value
stayed keeps its numbers to the digit and takes the new kind and source (a best known since
proven, say). What the rows alone cannot show is kept: a reference proven by the run's exact
task stays, and a value the run found (``best_found``) stays among the answers, so a reference
only gets better.

Each row's instance must be the file the run solved (``instance_sha256``); rows whose instance
cannot be found are left as they were.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from gtsp_bench.bench.anytime import parse_trajectory
from gtsp_bench.bench.definitions import Benchmark, Reference, Run
from gtsp_bench.bench.rows import (
    BELOW_OPTIMUM,
    BETTER_THAN_BEST_KNOWN,
    COLUMNS,
    Cell,
    make_rows,
    references,
)
from gtsp_bench.data import gtsplib
from gtsp_bench.data.io import GZIP_SUFFIX, INSTANCE_SUFFIXES, instance_stem, read_text
from gtsp_bench.data.sets import ReferenceRow, resolve_set
from gtsp_bench.errors import InputError

#: Reference values this close (relative) are the same: a row keeps 10 significant digits.
REL_TOL = 1e-9
#: Row notes the reference rule writes (made again from today's reference).
RULE_NOTES = (BELOW_OPTIMUM, BETTER_THAN_BEST_KNOWN)


@dataclass(frozen=True)
class RowEntry:
    """What a row says of its instance (an :class:`~gtsp_bench.bench.sources.Entry` without the
    instance itself), with today's reference rows by omega."""

    set: str
    stem: str
    sha256: str
    k: int
    n: int
    references: Mapping[float | None, ReferenceRow] = field(default_factory=dict)


class Tables:
    """Today's reference rows of the instances a run's rows name, each table read once.

    An instance is found by the file its run's manifest lists with the row's SHA-256 (any folder:
    its ``reference.csv``, or a GTSPLIB folder's ``best_known.csv``), else as ``SET/STEM.*`` under
    one of ``instance_dirs`` (the rows folded in by ``--merge-into``), else as a GTSPLIB file of
    the package's library (distance-only rows).
    """

    def __init__(self, instance_dirs: Sequence[Path], listed: Mapping[str, str] | None = None) -> None:
        self.instance_dirs = list(instance_dirs)
        self.listed = {(instance_stem(path), sha): Path(path) for path, sha in (listed or {}).items()}
        self._tables: dict[Path, Mapping[tuple[str, float | None], ReferenceRow]] = {}
        self._digests: dict[Path, str] = {}

    def _table(self, folder: Path) -> Mapping[tuple[str, float | None], ReferenceRow]:
        if folder not in self._tables:  # its reference.csv, or a GTSPLIB folder's best_known.csv
            self._tables[folder] = resolve_set(str(folder)).references
        return self._tables[folder]

    def _digest(self, path: Path) -> str:
        if path not in self._digests:
            self._digests[path] = hashlib.sha256(read_text(path).encode()).hexdigest()
        return self._digests[path]

    def _file(self, set_name: str, stem: str, sha: str, omega: float | None) -> Path | None:
        path = self.listed.get((stem, sha))
        if path is not None and path.is_file():
            return path
        for where in self.instance_dirs:
            for suffix in INSTANCE_SUFFIXES:
                for name in (stem + suffix, stem + suffix + GZIP_SUFFIX):
                    if (where / set_name / name).is_file():
                        return where / set_name / name
        if omega is None and stem in gtsplib.best_known() and gtsplib.path(stem).is_file():
            return gtsplib.path(stem)
        return None

    def lookup(self, set_name: str, stem: str, sha: str, omega: float | None,
               ) -> tuple[ReferenceRow | None, str] | None:
        """Today's table row of a point (``None``: its table has none) and the SHA-256 of its
        instance file's text now; ``None`` when the file cannot be found."""
        path = self._file(set_name, stem, sha, omega)
        if path is None:
            return None
        return self._table(path.parent).get((stem, omega)), self._digest(path)


def _without(note: str, *drop: str) -> str:
    return "; ".join(n for n in str(note).split("; ") if n and n not in drop)


def _record(row: Any) -> dict[str, Any]:
    return {
        "status": row.status,
        "objective": None if math.isnan(row.objective) else float(row.objective),
        "lower_bound": None if math.isnan(row.lower_bound) else float(row.lower_bound),
        "runtime_s": None if math.isnan(row.runtime_s) else float(row.runtime_s),
        "note": _without(row.note, *RULE_NOTES),
        "order": [int(x) for x in str(row.order).split()],
        "heads": [int(x) for x in str(row.heads).split()],
        # the row's times have 4 digits: none may fall past the runtime by rounding
        "trajectory": [[min(t, row.runtime_s) if math.isfinite(row.runtime_s) else t, o, b]
                       for t, o, b in parse_trajectory(row.trajectory)],
    }


def _cells(g: pd.DataFrame, entry: RowEntry, omega: float | None,
           ) -> tuple[RowEntry, list[Cell], dict[str, dict[str, Any]]]:
    """The cells and records of one point's rows, keyed by their row index."""
    cells, records = [], {}
    for i, row in zip(g.index, g.itertuples(), strict=True):
        key = f"row{i}"
        limit = None if math.isnan(row.time_limit) else float(row.time_limit)
        cells.append(Cell(entry, Run(row.solver, label=row.label), omega, int(row.seed), limit, key))  # type: ignore[arg-type]
        records[key] = _record(row)
    return entry, cells, records


@dataclass(frozen=True)
class Rereferenced:
    """What :func:`rereference` made: the ``rows`` (in their order), how many were measured
    against a new reference value (``changed``), how many kept the value under a new kind or
    source (``renamed``: a best known since proven, a proof's new name), and the ``missing``
    sets, whose rows were left as they were."""

    rows: pd.DataFrame
    changed: int
    renamed: int
    missing: list[str]


def rereference(bench: Benchmark, df: pd.DataFrame, tables: Tables) -> Rereferenced:
    """``df`` measured against today's tables by ``bench``'s rule (:class:`Rereferenced`).

    Raises
    ------
    InputError
        When a row's instance is not the file it names today (a changed set: rerun it).
    """
    parts: list[pd.DataFrame] = []
    changed = renamed = 0
    missing: list[str] = []
    for (set_name, stem, w), g in df.groupby(["set", "instance", df["omega"].astype(float).fillna(-1.0)],
                                            sort=False):
        omega = None if w == -1.0 else float(w)
        found = tables.lookup(str(set_name), str(stem), str(g["instance_sha256"].iloc[0]), omega)
        if found is None:
            missing.append(str(set_name))
            parts.append(g)
            continue
        table_row, digest = found
        first = g.iloc[0]
        if any(sha != digest for sha in g["instance_sha256"]):
            raise InputError(f"{set_name}/{stem}: the instance file changed since the run "
                             "(instance_sha256 differs); rerun it instead")
        try:
            entry, cells, records = _cells(g, RowEntry(
                str(set_name), str(stem), digest, int(first["K"]), int(first["N"]),
                {omega: table_row} if table_row is not None else {}), omega)
        except (TypeError, ValueError) as e:
            raise InputError(f"{set_name}/{stem}: a row is malformed ({e})") from None
        exact: dict[tuple[str, str, float | None], tuple[str, str]] = {}
        kind, value, source = first["reference_kind"], first["reference_value"], first["reference_source"]
        if (kind == "optimal" and str(source).endswith("(proven)")) or kind == "best_found":
            records["kept"] = {"status": "optimal" if kind == "optimal" else "feasible",
                               "objective": float(value)}
            exact[(entry.set, entry.stem, omega)] = ("kept", str(source).removesuffix(" (proven)"))
        point = (entry.set, entry.stem, omega)
        refs = references(bench.reference, cells, records, exact)
        ref = refs.get(point)
        if ref is None or math.isclose(ref.value, float(value), rel_tol=REL_TOL):
            if ref is not None and (ref.kind, ref.source) != (kind, source):  # no number changes
                g = g.assign(reference_kind=ref.kind, reference_source=ref.source)
                if ref.kind != "best_found":  # the table caught up with the run's tour
                    g = g.assign(note=[_without(n, BETTER_THAN_BEST_KNOWN) for n in g["note"]])
                renamed += len(g)
            parts.append(g)  # its numbers as they were, to the digit
            continue
        table = references(Reference(table=True), cells, {}, {})
        new = make_rows(str(first["benchmark"]), cells, records, refs,
                        {k: v for k, v in table.items() if v.kind != "best_found"})
        new.index = g.index
        parts.append(new)
        changed += len(g)
    out = pd.concat(parts).loc[df.index] if parts else df.copy()
    return Rereferenced(out[list(COLUMNS)], changed, renamed, sorted(set(missing)))


__all__ = ["Rereferenced", "RowEntry", "Tables", "rereference"]

"""New best-known GTSPLIB tours: a solve that ends below a file's ``best_known`` value.

A run's rows carry their tours; a row below its file's best-known value is noted
(``better than the best known``, :mod:`gtsp_bench.bench.rows`) and the run says on stderr how
many there were and how to keep them (:func:`keep_hint`). With ``--update-reference`` the output
``best-known`` (:func:`best_known_output`, added to any benchmark by that flag) keeps the shortest
such tour per file in the library the run read: the tour, priced again by the evaluator, goes to
``tours/NAME.LENGTH.tour.gz`` and the file's row of ``best_known.csv`` gets its value, tour,
source (:func:`finder`) and date, its published value unchanged
(:func:`gtsp_bench.data.gtsplib.keep_tour`). A tour below a proven optimum is an error, never
kept. The UAV sets' counterpart, their ``reference.csv``, is the output ``update-references``.
"""

from __future__ import annotations

import datetime as dt
import hashlib
from pathlib import Path
from typing import Any

import pandas as pd

from gtsp_bench.bench.definitions import Benchmark
from gtsp_bench.checks import strictly_better
from gtsp_bench.errors import InputError


def keep_hint(better: pd.DataFrame, command: str) -> str:
    """What a run without ``--update-reference`` says of its solves below a best-known value
    (``better``: their rows): how many, of how many files, and the command that keeps them
    (the run's own, without ``--fresh``: with it the rerun would solve everything again)."""
    files = better["instance"].nunique()
    command = " ".join(w for w in command.split() if w != "--fresh")
    again = f"`{command} --update-reference`" if command else "the same command with --update-reference"
    return (f"{len(better)} solve(s) of {files} file(s) went below the best-known value; {again} "
            "keeps their tours (GTSPLIB: best_known.csv and tours/ of the library; a set: its "
            "reference.csv), re-using the solves of the task log")


def finder(bench: Benchmark | None, row: pd.Series) -> str:
    """Who found a row's tour, as ``best_known.csv``'s ``source`` says it: ``gtsp-bench``, the
    solver, the options of its run (by the row's label in ``bench``), the time limit and the seed
    (``gtsp-bench lns effort=budget 300s seed 2``)."""
    runs = {r.name: r for r in bench.runs} if bench is not None else {}
    run = runs.get(str(row["label"]))
    options = [f"{k}={v}" for k, v in run.options] if run is not None else []
    limit, seed = row["time_limit"], row["seed"]
    return " ".join(["gtsp-bench", str(row["solver"]), *options,
                     *([f"{float(limit):g}s"] if pd.notna(limit) else []),
                     *([f"seed {int(seed)}"] if pd.notna(seed) else [])])


def keep_best_known(df: pd.DataFrame, library: Path, today: str,
                    bench: Benchmark | None = None) -> list[tuple[str, float, float, str]]:
    """Keep each GTSPLIB tour of the rows shorter than its file's best-known value in ``library``
    (:func:`gtsp_bench.data.gtsplib.keep_tour`; the shortest per file, rows of the library's own
    file only, by its SHA-256; its source by :func:`finder`); returns ``(name, old value, new
    value, source)`` per kept tour.

    Raises
    ------
    InputError
        ``FILE: problem``: an unreadable table, or a tour below a file's proven optimum (the
        solver or the table is wrong: never kept, never passed over in silence).
    """
    from gtsp_bench.data import gtsplib
    from gtsp_bench.data.io import read_text

    table = gtsplib.read_best_known(library)
    has_tour = df["order"].notna() & (df["order"].astype(str).str.strip() != "")
    ok = df[df["objective"].notna() & df["instance"].isin(list(table)) & has_tour]
    kept = []
    for name, g in ok.groupby("instance", sort=False):
        ref = table[str(name)]
        best = g.iloc[int(g["objective"].to_numpy().argmin())]
        if not strictly_better(float(best["objective"]), ref.value):
            continue
        text = read_text(library / f"{name}.gtsp.gz")
        if hashlib.sha256(text.encode()).hexdigest() != best["instance_sha256"]:
            continue  # a file of the same name that is not the library's
        order, heads = (list(map(int, str(best[c]).split())) for c in ("order", "heads"))
        source = finder(bench, best)
        row = gtsplib.keep_tour(library, str(name), order, heads, source, today)  # raises below an optimum
        if row is not None:
            kept.append((str(name), ref.value, row.value, source))
    return kept


def libraries(df: pd.DataFrame, settings: Any) -> dict[Path, pd.DataFrame]:
    """The rows by the GTSPLIB folder they were read from: a ``--set`` folder read as GTSPLIB (a
    copy of the library) for its rows, else the library (:func:`gtsp_bench.data.gtsplib.folder`;
    none when it is absent)."""
    from gtsp_bench.data import gtsplib
    from gtsp_bench.data.sets import resolve_set

    copies: dict[str, Path] = {}
    for arg in getattr(settings, "sets", None) or ():
        try:
            s = resolve_set(arg, getattr(settings, "instance_dir", "instances"))
        except InputError:
            continue
        if s.reference_path is None:
            copies[s.name] = Path(s.folder)
    try:
        default: Path | None = gtsplib.folder()
    except InputError:  # no library here, so no row was read from it
        default = None
    out: dict[Path, list[pd.DataFrame]] = {}
    for set_name, g in df.groupby("set", sort=False):
        where = copies.get(str(set_name), default)
        if where is not None:
            out.setdefault(where.resolve(), []).append(g)
    return {where: pd.concat(parts) for where, parts in out.items()}


def best_known_output(bench: Benchmark, df: pd.DataFrame, out_dir: Path, settings: Any,
                      say: Any) -> list[Path]:
    """The output ``best-known``: with ``--update-reference`` (``settings.update_reference``),
    :func:`keep_best_known` into each library the rows were read from, whatever ``out_dir``;
    otherwise nothing. Says one line per kept tour; returns the tables it changed."""
    if not getattr(settings, "update_reference", False):
        return []
    today = dt.datetime.now(dt.UTC).date().isoformat()
    written = []
    for library, rows in libraries(df, settings).items():
        kept = keep_best_known(rows, library, today, bench)
        for name, old, new, source in kept:
            say(f"new best known: {name}: {old:g} -> {new:g} ({source}), tour in {library / 'tours'}")
        if kept:
            written.append(library / "best_known.csv")
    return written


__all__ = ["best_known_output", "finder", "keep_best_known", "keep_hint", "libraries"]

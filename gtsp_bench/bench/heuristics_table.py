"""The table of heuristics and peers: GTSPLIB by size and the committed UAV sets of large K.

``make bench-heuristics-table`` (``python -m gtsp_bench.bench.heuristics_table``) runs every heuristic
and peer (:data:`SOLVERS`) with one time budget per solve on

* GTSPLIB, grouped by size (:data:`GTSPLIB_GROUPS`, the smallest ``--per-group`` instances of each
  group, in the order of ``best_known.csv``), against the best-known value; the asymmetric (AGTSP)
  files are a group of their own, refused by the solvers that handle symmetric costs only;
* the committed UAV sets ``instances/uav-K{K}-N20-s1`` of K = 20, 50, 100, 200 clusters of 20
  nodes (their first ``--uav-instances`` files) at one omega, against the set's ``reference.csv``
  value (a proven optimum or the best known) or, for an instance without one or one that a solver
  beat, the best tour any solver found for it.

It writes one CSV row per solve (``--csv``, default ``benchmarks/heuristics-table.csv``, committed
with the page) and the Markdown table, with the command that made it, into the generated block
``heuristics-table`` of ``docs/solvers/heuristics.md`` (the mechanism of
:func:`gtsp_bench.report.paper.refresh_blocks`); the block's table is what :func:`markdown` makes of the
CSV's rows (:func:`read_rows`), which the tests check. A cell is the mean gap in percent and the median solve
time; ``*`` when a solve stopped at the time limit; ``refused`` or ``failed`` when no solve of
the cell gave an answer (a partly answered cell counts only its answers and says ``n/m``).
Timings are wall-clock, of one run on whatever machine runs it.

The CSV is written after every instance and doubles as the run's progress: a run with the same
time limit, solver seed and omega keeps the rows already there and solves only the missing ones,
so an interrupted run resumes; ``--redo LIST`` solves the named solvers again (e.g. ``--redo lns``
after a change to ``lns``, the other columns kept).
"""

from __future__ import annotations

import argparse
import math
import os
import shlex
import statistics
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import cast

from gtsp_bench.bench.tables import Row, solve, write_csv
from gtsp_bench.checks import check_float, check_int, check_omega, check_seed, parse_ks, parse_names
from gtsp_bench.data.sets import REL_TOL, read_set_file, uav_set
from gtsp_bench.errors import InputError, OneLineParser
from gtsp_bench.instance import Instance

#: The heuristics and peers of the table, in its column order.
SOLVERS = ("greedy", "greedy+ls", "aco", "aco+ls", "lns", "pyvrp", "ortools", "lkh")
#: GTSPLIB groups of symmetric instances: (label, fewest nodes, most nodes).
GTSPLIB_GROUPS = (
    ("GTSPLIB <= 200 nodes", 1, 200),
    ("GTSPLIB 201-500", 201, 500),
    ("GTSPLIB 501-1,100", 501, 1_100),
    ("GTSPLIB 1,101-15,000", 1_101, 15_000),
)
#: The group of the asymmetric GTSPLIB files.
AGTSP_GROUP = "GTSPLIB AGTSP"
#: Cluster counts of the committed UAV sets of the table (20 nodes each).
UAV_KS = (20, 50, 100, 200)
#: The page and the name of the generated block the table goes to.
DOCS_PAGE = Path("docs") / "solvers" / "heuristics.md"
BLOCK = "heuristics-table"
#: The rows of the table in the page (committed with it).
DEFAULT_CSV = Path("benchmarks") / "heuristics-table.csv"
COLUMNS = ("group", "instance", "solver", "status", "objective", "reference", "reference_kind",
           "gap_percent", "runtime_s", "note", "omega", "time_limit", "solver_seed")
_NO_ANSWER = ("failed", "refused")


@dataclass(frozen=True)
class TableConfig:
    """What one run of the table does (see :func:`main` for the options)."""

    solvers: tuple[str, ...] = SOLVERS
    time_limit: float = 10.0
    per_group: int = 3
    uav_ks: tuple[int, ...] = UAV_KS
    uav_instances: int = 3
    omega: float = 0.5
    solver_seed: int = 0
    gtsplib: bool = True
    agtsp: bool = True
    max_nodes: int = 15_000
    csv: Path = DEFAULT_CSV
    docs: Path | None = DOCS_PAGE
    instance_dir: Path = Path("instances")
    redo: tuple[str, ...] = ()


def reference_for(found: Sequence[Row], row_value: float | None, row_status: str | None) -> tuple[float, str]:
    """The value the solves of one UAV instance are measured against, and its kind: the set's
    reference (``optimum`` or ``best known``) unless a solve beat it or there is none; then the
    best tour found (``best found``)."""
    best = min((r.objective for r in found if r.status not in _NO_ANSWER), default=math.nan)
    if row_value is not None and not best < row_value * (1.0 - REL_TOL):
        return row_value, "optimum" if row_status == "optimal" else "best known"
    return best, "best found"


def gtsplib_instances(config: TableConfig) -> list[tuple[str, Instance, float]]:
    """``(group, instance, best known)``: the first ``per_group`` instances of each size group
    (and of the AGTSP files), up to ``max_nodes`` nodes."""
    from gtsp_bench.data import gtsplib

    refs = list(gtsplib.best_known().values())
    out = []
    for label, lo, hi in GTSPLIB_GROUPS:
        picked = [r for r in refs if r.symmetric and lo <= r.nodes <= min(hi, config.max_nodes)]
        out += [(label, r.name, r.value) for r in picked[:config.per_group]]
    if config.agtsp:
        picked = [r for r in refs if not r.symmetric and r.nodes <= config.max_nodes]
        out += [(AGTSP_GROUP, r.name, r.value) for r in picked[:config.per_group]]
    return [(group, gtsplib.read(name), value) for group, name, value in out]


def _say(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


Key = tuple[str, str, str]


def _key(row: Row) -> Key:
    return row.group, row.instance, row.solver


def previous_rows(config: TableConfig) -> dict[Key, Row]:
    """The rows of ``config.csv`` a run with ``config`` keeps: same time limit, solver seed and
    omega, a solver of the run not named in ``redo`` (none when the file is missing or was
    written before the CSV recorded these settings)."""
    if not config.csv.is_file():
        return {}
    kept = {}
    for row, limit, seed in read_table(config.csv):
        if (limit == config.time_limit and seed == config.solver_seed and row.solver in config.solvers
                and row.solver not in config.redo
                and (row.omega is None or row.omega == config.omega)):
            kept[_key(row)] = row
    return kept


def _solve_all(config: TableConfig, group: str, inst: Instance, omega: float | None,
               done: dict[Key, Row]) -> list[Row]:
    rows = []
    for s in config.solvers:
        kept = done.get((group, inst.name, s))
        r = kept or solve(group, inst, omega, s, config.time_limit, config.solver_seed)
        what = r.note if r.status in _NO_ANSWER else f"{r.objective:.6g} in {r.runtime_s:.2f} s"
        _say(f"  {inst.name} {s}: {r.status} {what}" + (" (kept from the CSV)" if kept else ""))
        rows.append(r)
    return rows


def run_table(config: TableConfig) -> list[Row]:
    """Every solver on every instance of the table; each row with its reference. The CSV is
    rewritten after each instance (this run's rows, then the kept rows not reached yet)."""
    done = previous_rows(config)
    if done:
        _say(f"{len(done)} solve(s) kept from {config.csv}")
    rows: list[Row] = []

    def save() -> None:
        seen = {_key(r) for r in rows}
        write_csv_rows(config, rows + [r for k, r in done.items() if k not in seen])

    if config.gtsplib:
        for group, inst, best in gtsplib_instances(config):
            rows += [r.against(best, "best known") for r in _solve_all(config, group, inst, None, done)]
            save()
    for k in config.uav_ks:
        chosen = uav_set(k, config.instance_dir)
        for f in chosen.files[:config.uav_instances]:
            inst = cast(Instance, read_set_file(f)[0])
            found = _solve_all(config, f"UAV K={k}", inst, config.omega, done)
            ref = chosen.references.get((f.stem, config.omega))
            value, kind = reference_for(found, None if ref is None else ref.value,
                                        None if ref is None else ref.status)
            rows += [r.against(value, kind) for r in found]
            save()
    return rows


def cell(rows: Sequence[Row]) -> str:
    """One table cell: mean gap and median time of the answered solves (``*``: a solve stopped
    at the limit; ``n/m``: only n of m solves answered), else why none did."""
    answered = [r for r in rows if r.status not in _NO_ANSWER]
    if not answered:
        return "refused" if all(r.status == "refused" for r in rows) else "failed"
    gap = statistics.fmean(r.gap for r in answered)
    median = statistics.median(r.runtime_s for r in answered)
    star = "*" if any(r.status == "time_limit" for r in answered) else ""
    part = f" ({len(answered)}/{len(rows)})" if len(answered) < len(rows) else ""
    return f"{gap:.2f}% {median:.2f}s{star}{part}"


def markdown(rows: Sequence[Row], solvers: Sequence[str]) -> str:
    """The Markdown table: one line per group, one column per solver."""
    groups: dict[str, list[Row]] = {}
    for r in rows:
        groups.setdefault(r.group, []).append(r)
    lines = ["| group | instances | reference | " + " | ".join(solvers) + " |",
             "|---|---:|---|" + "---:|" * len(solvers)]
    for group, rs in groups.items():
        names = dict.fromkeys(r.instance for r in rs)
        cells = [cell([r for r in rs if r.solver == s]) if any(r.solver == s for r in rs) else "-"
                 for s in solvers]
        kinds = ", ".join(dict.fromkeys(r.reference_kind for r in rs))
        lines.append(f"| {group} | {len(names)} | {kinds} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def block_text(rows: Sequence[Row], config: TableConfig, command: str, wall_s: float) -> str:
    """The generated block: how it was made, the table, and which instances each group holds."""
    groups: dict[str, list[str]] = {}
    for r in rows:
        names = groups.setdefault(r.group, [])
        if r.instance not in names:
            names.append(r.instance)
    listing = "\n".join(f"- {g}: {', '.join(n)}" for g, n in groups.items())
    return (f"Made by `{command}` on {time.strftime('%Y-%m-%d')}: {config.time_limit:g} s per solve, "
            f"solver seed {config.solver_seed}, omega {config.omega:g} on the UAV instances, "
            f"{os.cpu_count()} CPU cores, {wall_s / 60:.0f} min in all.\n\n"
            f"{markdown(rows, config.solvers)}\n\n"
            f"Cells: mean gap to the reference / median solve time; `*`: some solves stopped at the "
            f"time limit; `(n/m)`: only n of m solves answered; `refused`: the solver declines the "
            f"instances by design (asymmetric costs for a symmetric-only solver, a matrix too "
            f"large).\n\n{listing}")


def write_csv_rows(config: TableConfig, rows: Sequence[Row]) -> Path:
    """The CSV of ``rows``, written atomically, with the run's settings on every row; its path."""
    return write_csv(config.csv, COLUMNS, (
        [r.group, r.instance, r.solver, r.status, repr(r.objective), repr(r.reference),
         r.reference_kind, f"{r.gap:.6f}" if math.isfinite(r.gap) else "", f"{r.runtime_s:.4f}",
         r.note, "" if r.omega is None else repr(r.omega), repr(config.time_limit),
         config.solver_seed] for r in rows))


def write_outputs(rows: Sequence[Row], config: TableConfig, command: str, wall_s: float) -> Path:
    """The CSV rows and, when ``config.docs`` is set, the page's generated block; the CSV path."""
    from gtsp_bench.report.paper import refresh_blocks

    path = write_csv_rows(config, rows)
    if config.docs is not None:
        if not config.docs.is_file():
            raise InputError(f"{config.docs}: no such page for the table")
        refresh_blocks(config.docs, {BLOCK: block_text(rows, config, command, wall_s)}, [BLOCK])
    return path


def read_table(path: Path) -> list[tuple[Row, float, int]]:
    """The rows of a CSV that :func:`write_outputs` wrote, in file order, each with the time limit
    and solver seed it was solved with (NaN and -1 in a CSV older than those columns)."""
    import csv

    def number(text: str | None) -> float:
        return float(text) if text else math.nan

    out = []
    try:
        with Path(path).open(newline="") as f:
            for r in csv.DictReader(f):
                row = Row(r["group"], r["instance"], number(r.get("omega")) if r.get("omega") else None,
                          r["solver"], r["status"], number(r["objective"]),
                          runtime_s=number(r["runtime_s"]), note=r["note"], reference=number(r["reference"]),
                          reference_kind=r["reference_kind"])
                out.append((row, number(r.get("time_limit")), int(r.get("solver_seed") or -1)))
    except (KeyError, ValueError, TypeError, csv.Error, UnicodeDecodeError) as e:
        raise InputError(f"{path}: not a CSV of this table ({type(e).__name__}: {e}); "
                         "give another --csv or remove it") from None
    return out


def read_rows(path: Path) -> list[Row]:
    """The rows of a CSV that :func:`write_outputs` wrote, in file order."""
    return [row for row, _, _ in read_table(path)]


def _parser() -> argparse.ArgumentParser:
    p = OneLineParser(
        prog="python -m gtsp_bench.bench.heuristics_table",
        description="Heuristics and peers on GTSPLIB (by size) and on the committed UAV sets of "
                    "large K (instances/uav-K{K}-N20-s1): gap and time per group, into "
                    "docs/solvers/heuristics.md.")
    p.add_argument("--time-limit", "-t", type=float, default=10.0, metavar="S",
                   help="seconds per solve (default: 10)")
    p.add_argument("--per-group", type=int, default=3, metavar="N",
                   help="GTSPLIB instances per size group, smallest first (default: 3)")
    p.add_argument("--uav-instances", type=int, default=3, metavar="N",
                   help="instances per K, the first of the committed set (default: 3)")
    p.add_argument("-K", "--clusters", default=",".join(map(str, UAV_KS)), metavar="LIST",
                   help="UAV cluster counts, each with a committed set uav-K{K}-N20-s1 "
                        "(default: 20,50,100,200)")
    p.add_argument("--solvers", "-s", default=",".join(SOLVERS), metavar="LIST",
                   help=f"solvers, comma-separated (default: {','.join(SOLVERS)})")
    p.add_argument("--omega", type=float, default=0.5,
                   help="omega of the UAV instances (default: 0.5; the sets' references are at 0.3, "
                        "0.5 and 0.6)")
    p.add_argument("--instance-dir", default="instances", metavar="DIR",
                   help="folder of the committed sets (default: instances)")
    p.add_argument("--solver-seed", type=int, default=0, help="seed of every solve (default: 0)")
    p.add_argument("--max-nodes", type=int, default=15_000, metavar="N",
                   help="largest GTSPLIB instance in nodes (default: 15000)")
    p.add_argument("--no-gtsplib", action="store_true", help="the UAV sets only")
    p.add_argument("--no-agtsp", action="store_true", help="leave out the asymmetric GTSPLIB files")
    p.add_argument("--csv", default=str(DEFAULT_CSV), metavar="FILE",
                   help=f"one row per solve (default: {DEFAULT_CSV})")
    p.add_argument("--docs", default=str(DOCS_PAGE), metavar="PAGE",
                   help=f"page whose '{BLOCK}' block gets the table (default: {DOCS_PAGE})")
    p.add_argument("--no-docs", action="store_true", help="leave the documentation alone")
    p.add_argument("--redo", default="", metavar="LIST",
                   help="solvers to solve again although the CSV has their rows for these settings "
                        "(default: none; the CSV's rows of the same time limit, seed and omega are "
                        "kept, so an interrupted run resumes)")
    return p


def make_config(args: argparse.Namespace) -> TableConfig:
    """Check the command line's values."""
    from gtsp_bench.registry import solver_names

    solvers = parse_names(args.solvers, "solver", solver_names())
    if not solvers:
        raise InputError("no solver given")
    return TableConfig(
        solvers=solvers, time_limit=check_float("time limit", args.time_limit, 0.0, math.inf),
        per_group=check_int("--per-group", args.per_group, 0),
        uav_ks=parse_ks(args.clusters) if args.clusters else (),
        uav_instances=check_int("--uav-instances", args.uav_instances, 0),
        omega=check_omega(args.omega), solver_seed=check_seed(args.solver_seed), gtsplib=not args.no_gtsplib,
        agtsp=not args.no_agtsp, max_nodes=check_int("--max-nodes", args.max_nodes, 1),
        csv=Path(args.csv), docs=None if args.no_docs else Path(args.docs),
        instance_dir=Path(args.instance_dir),
        redo=parse_names(args.redo, "solver", solvers) if args.redo else (),
    )


def main(argv: Sequence[str] | None = None) -> int:
    """Run the table; bad input is one ``gtsp-bench: error:`` line and exit code 2."""
    argv = list(sys.argv[1:] if argv is None else argv)
    args = _parser().parse_args(argv)
    try:
        config = make_config(args)
        if config.docs is not None and not config.docs.is_file():
            raise InputError(f"{config.docs}: no such page for the table")
        for k in config.uav_ks:
            uav_set(k, config.instance_dir)  # a K without a committed set fails before any solve
        start = time.perf_counter()
        rows = run_table(config)
        wall = time.perf_counter() - start
        command = "make bench-heuristics-table" + (f" TABLE_ARGS='{shlex.join(argv)}'" if argv else "")
        path = write_outputs(rows, config, command, wall)
    except InputError as e:
        print(f"gtsp-bench: error: {e}", file=sys.stderr)
        return 2
    print(markdown(rows, config.solvers))
    _say(f"rows: {path}; {wall:.0f} s in all" + (f"; table in {config.docs}" if config.docs else ""))
    return 1 if any(r.status == "failed" for r in rows) else 0


if __name__ == "__main__":
    sys.exit(main())

"""The ``gtsp-bench bench`` command: run a named benchmark (:mod:`gtsp_bench.bench.definitions`).

:func:`add_bench_parser` declares the options (the same for every benchmark), and
:func:`run_bench_command` runs one through the engine (:func:`gtsp_bench.bench.engine.run_benchmark`)
or lists them. :mod:`gtsp_bench.cli` wires both into the command line and handles errors.
"""

from __future__ import annotations

import argparse
import datetime as dt
import shlex
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TextIO

from gtsp_bench.checks import arg_float, arg_int, arg_key_value
from gtsp_bench.errors import InputError

DESCRIPTION = """\
Run a named benchmark (gtsp-bench bench --list names them). Every solve runs in a fresh worker
process with a hard time limit (or on Dask workers), and is appended to OUT/tmp/runs.jsonl, so an
interrupted run resumes and a second run re-uses every solve. OUT (default results/NAME, or
results/quick/NAME with --quick) gets rows.csv (one row per solve, with its tour and its gap to the
reference), summary.md (also printed on stdout), manifest.json (commit, packages, machine, command,
budget, instance hashes) and the benchmark's figures and tables. Exit code 1 when a solve failed or a
tour lies below a proven optimum.
"""

EPILOG = """\
examples:
  gtsp-bench bench --list
  gtsp-bench bench paper -K 4..10               # the paper's experiments into results/paper
  gtsp-bench bench heuristics --quick           # a smoke run into results/quick/heuristics
  gtsp-bench bench exact -K 4..7,10 --omegas 0.5 --time-limit 30
  gtsp-bench bench learned -K 4 --instances 20 --solvers drl,am
  gtsp-bench bench sets --set gtsplib --solvers greedy,lns --time-limit 5 --names 11berlin52,40d198
  gtsp-bench bench glns --solvers lns -p remove_fraction=0.15 --seeds 1..3 --out /tmp/rf
  gtsp-bench bench scale --set uav-K50-N20-s1 --omegas 0.2,0.8 --seeds 0..4 --out /tmp/k50
  gtsp-bench bench glns --names 89rbg443 --out /tmp/part --merge-into results/glns
"""


def add_bench_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add the ``bench`` sub-command and its options to the CLI's sub-parsers; its parser."""
    p = sub.add_parser("bench", help="run a named benchmark (the paper's experiments by default)",
                       description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter,
                       epilog=EPILOG)
    p.add_argument("name", nargs="?", default="paper", metavar="NAME",
                   help="the benchmark (default: paper; --list names them all)")
    p.add_argument("--list", action="store_true", help="list the benchmarks: name, rough time, what it does")
    p.add_argument("--quick", action="store_true",
                   help="the benchmark's quick variant: a smoke run, written to results/quick/NAME")
    p.add_argument("--out", "-o", metavar="DIR", help="output folder (default: results/NAME)")
    g = p.add_argument_group("what to run (default: the benchmark's own)")
    g.add_argument("--solvers", "-s", metavar="LIST",
                   help="comma-separated solvers or labels of the benchmark (a prefix picks every "
                        "variant: drl picks 'drl heads=optimal' too), or other registered solvers")
    g.add_argument("--param", "-p", dest="params", type=arg_key_value, action="append", default=[],
                   metavar="KEY=VALUE",
                   help="solver option for every run (repeatable, as solve's -p; over a run's own "
                        "value, and named in its label: -s lns -p effort=fast gives 'lns "
                        "effort=fast'); -p initial=best-known starts each GTSPLIB solve from "
                        "its best-known tour (solvers that take an initial solution: lns, milp, "
                        "lkh, ortools, greedy+ls, gurobi); -p certificate=true has each proof of "
                        "milp write its certificate to OUT/proofs/ and checks it")
    g.add_argument("--clusters", "-K", metavar="K",
                   help="cluster counts to keep: a range 4..10, a list 4,7,10 or a mix 4..7,10")
    g.add_argument("--set", dest="sets", action="append", default=None, metavar="NAME|PATH",
                   help="run on these instance sets instead (repeatable): 'gtsplib', a folder under "
                        "instances/ (uav-K50-N20-s1, ...) or any folder of .json / .gtsp(.gz) files; "
                        "its reference.csv gives the gaps")
    g.add_argument("--names", metavar="LIST", help="instances to keep, by file stem (e.g. 11berlin52)")
    g.add_argument("--instances", type=arg_int, metavar="N", help="instances per K / per set / per group")
    g.add_argument("--nodes", "-n", type=arg_int, metavar="N",
                   help="nodes per cluster of the generated instances (the paper's: 20)")
    g.add_argument("--omegas", metavar="LIST", help="omegas, e.g. 0,0.5,0.9 (ignored for GTSPLIB)")
    g.add_argument("--seeds", metavar="LIST", help="solver seeds, e.g. 0,1,2 or 1..10")
    g.add_argument("--time-limit", "-t", type=arg_float, metavar="S", help="seconds per solve")
    g = p.add_argument_group("how it runs")
    g.add_argument("--jobs", "-j", type=arg_int, metavar="J",
                   help="worker processes (default: the benchmark's, else the number of cores)")
    g.add_argument("--executor", metavar="WHERE", default="local",
                   help="where solves run: 'local' (default: this machine's worker pool), 'dask' "
                   "(a Dask cluster of --jobs workers on this machine) or tcp://HOST:PORT (an "
                   "existing Dask scheduler and its workers; see docs/distributed.md)")
    g.add_argument("--instance-dir", default="instances", metavar="DIR",
                   help="where instance sets are kept (default: instances)")
    g.add_argument("--fresh", action="store_true", help="redo solves already in the task log")
    g.add_argument("--retry-failed", action="store_true",
                   help="also redo solves the log records as failed by the solver's own error "
                   "(failures whose worker died or ran out of memory are always retried)")
    g.add_argument("--update-reference", action="store_true",
                   help="write tours better than a set's best_known value (and values for points "
                        "without one) into its reference.csv, and keep GTSPLIB tours shorter than "
                        "best_known.csv's in the library the run read (tours/NAME.LENGTH.tour.gz; "
                        "any OUT); a proven optimum is never changed")
    g.add_argument("--report-only", action="store_true",
                   help="solve nothing: redraw OUT's summary, tables and figures from OUT/rows.csv")
    g.add_argument("--re-reference", action="store_true",
                   help="solve nothing: measure OUT/rows.csv against today's reference tables "
                        "(the sets' reference.csv, GTSPLIB's best_known.csv) by the benchmark's "
                        "reference rule, rewrite its reference and gap columns, then redraw as "
                        "--report-only does (a reference proven by the run is kept; "
                        "OUT/manifest.json records the command)")
    g.add_argument("--merge-into", metavar="DIR",
                   help="after a run without failures, put its rows in place of the same solves' "
                        "(set, instance, omega, label, seed) in DIR/rows.csv, add the others, and "
                        "redraw DIR's summary, tables and figures from the result, as "
                        "--report-only does (a partial rerun folded into a whole benchmark's "
                        "rows; DIR/manifest.json records the command)")
    g.add_argument("--no-progress", action="store_true", help="no progress bar")
    return p


def list_text() -> str:
    """``--list``: one line per benchmark."""
    from gtsp_bench.bench.definitions import BENCHMARKS

    width = max(map(len, BENCHMARKS))
    time_width = max(len("full run"), *(len(b.rough_time) for b in BENCHMARKS.values()))
    lines = [f"{'name':<{width}}  {'full run':<{time_width}}  what it measures"]
    for b in BENCHMARKS.values():
        lines.append(f"{b.name:<{width}}  {b.rough_time:<{time_width}}  {b.description}")
    return "\n".join(lines) + "\n"


def settings_from(args: argparse.Namespace, argv: Sequence[str] | None = None) -> object:
    """The engine's :class:`~gtsp_bench.bench.engine.Settings` from the parsed options."""
    from gtsp_bench.bench.engine import Settings
    from gtsp_bench.checks import check_time_limit, parse_ks, parse_names, parse_omegas, parse_seeds

    solvers = parse_names(args.solvers, "solver") if args.solvers else None
    if args.solvers is not None and not solvers:
        raise InputError("--solvers: no solver given")
    sets = tuple(dict.fromkeys(s.strip() for s in args.sets if s.strip())) if args.sets else None
    if args.sets is not None and not sets:
        raise InputError("--set: no set given")
    command = "gtsp-bench " + shlex.join(argv if argv is not None else sys.argv[1:])
    return Settings(
        quick=args.quick, out_dir=Path(args.out) if args.out else None, solvers=solvers,
        ks=parse_ks(args.clusters) if args.clusters else None, sets=sets,
        names=parse_names(args.names, "instance") or None if args.names else None,
        instances=args.instances, nodes=args.nodes, omegas=parse_omegas(args.omegas) if args.omegas else None,
        seeds=parse_seeds(args.seeds) if args.seeds else None,
        time_limit=check_time_limit(args.time_limit) if args.time_limit is not None else None,
        jobs=args.jobs, executor=args.executor, instance_dir=Path(args.instance_dir),
        progress=not args.no_progress, fresh=args.fresh, retry_failed=args.retry_failed,
        update_reference=args.update_reference, command=command, params=tuple(args.params),
    )


def report_only(name: str, settings: object) -> tuple[int, str]:
    """Redraw a finished run's outputs from its ``rows.csv`` (the paper: its report)."""
    from gtsp_bench.bench.engine import configure
    from gtsp_bench.bench.outputs import render
    from gtsp_bench.bench.rows import read_rows, summary_markdown, summary_table
    from gtsp_bench.data.io import atomic_write_text

    bench = configure(name, settings)  # type: ignore[arg-type]
    out_dir = Path(bench.output_dir)
    if bench.planner == "paper":
        from gtsp_bench.report.paper import write_report

        if not any(out_dir.glob("*.csv")):
            raise InputError(f"{out_dir}: no experiment CSV files to report on; run bench first")
        from gtsp_bench.bench.runner import shipped_checkpoints

        print(f"wrote {write_report(out_dir, shipped_checkpoints())}", file=sys.stderr)
        return 0, ""
    df = read_rows(out_dir / "rows.csv")
    text = summary_markdown(summary_table(df))
    atomic_write_text(out_dir / "summary.md", f"# {bench.name}\n\n{bench.description}.\n\n{text}")
    written = render(bench, df, out_dir, settings, lambda m: print(m, file=sys.stderr))
    print("wrote " + ", ".join(str(p) for p in [out_dir / "summary.md", *written]), file=sys.stderr)
    return 0, text


def re_reference(name: str, settings: object) -> tuple[int, str]:
    """Measure a finished run's rows against today's reference tables
    (:func:`~gtsp_bench.bench.rereference.rereference`), record it in the manifest and redraw its
    outputs (:func:`report_only`)."""
    from gtsp_bench.bench.engine import configure
    from gtsp_bench.bench.output_kinds import read_manifest
    from gtsp_bench.bench.rereference import Tables, rereference
    from gtsp_bench.bench.rows import read_rows, summary_markdown, summary_table
    from gtsp_bench.data.io import atomic_write_json, atomic_write_text, csv_text

    bench = configure(name, settings)  # type: ignore[arg-type]
    if bench.planner == "paper":
        raise InputError("--re-reference: the paper benchmark writes no rows.csv to measure again")
    out_dir = Path(bench.output_dir)
    old = read_rows(out_dir / "rows.csv")
    manifest = read_manifest(out_dir)
    listed = manifest.get("instances") if isinstance(manifest.get("instances"), dict) else {}
    tables = Tables([Path(settings.instance_dir), out_dir / "instances"], listed)  # type: ignore[attr-defined]
    try:
        done = rereference(bench, old, tables)
    except InputError as e:
        raise InputError(f"{out_dir / 'rows.csv'}: {e}") from None
    for set_name in done.missing:
        print(f"warning: {set_name}: no such set here; its rows keep their references", file=sys.stderr)
    text = csv_text(done.rows)
    if text == (out_dir / "rows.csv").read_text():  # nothing to write or redraw
        print(f"{out_dir / 'rows.csv'}: every row already measured against today's references",
              file=sys.stderr)
        return 0, summary_markdown(summary_table(old))
    merges = manifest.setdefault("merges", [])
    command = settings.command  # type: ignore[attr-defined]
    if not (merges and merges[-1].get("command") == command and "re_referenced" in merges[-1]):
        merges.append({"command": command, "re_referenced": 0, "renamed": 0})
    last = merges[-1]  # the same command again: one entry, the counts added up
    last.update(date=dt.datetime.now(dt.UTC).isoformat(timespec="seconds"),
                re_referenced=last["re_referenced"] + done.changed,
                renamed=last["renamed"] + done.renamed)
    atomic_write_text(out_dir / "rows.csv", text)
    atomic_write_json(out_dir / "manifest.json", manifest)
    print(f"re-referenced {out_dir / 'rows.csv'}: {done.changed} of {len(old)} rows measured "
          f"against a new reference value, {done.renamed} against the same value of a new kind "
          "or source", file=sys.stderr)
    return report_only(name, settings)


def check_merge(name: str, settings: object, target: Path) -> None:
    """Refuse a ``--merge-into`` before anything runs: ``target`` must hold a benchmark's rows,
    other than the run's own output folder."""
    from gtsp_bench.bench.engine import configure
    from gtsp_bench.bench.rows import read_rows

    bench = configure(name, settings)  # type: ignore[arg-type]
    if bench.planner == "paper":
        raise InputError(f"{target}: --merge-into: the paper benchmark writes no rows.csv to merge")
    out_dir = Path(bench.output_dir)
    if out_dir.resolve() == target.resolve():
        raise InputError(f"{target}: --merge-into needs a folder other than the run's --out")
    read_rows(target / "rows.csv")


def merge_into(name: str, settings: object, target: Path) -> tuple[int, str]:
    """Fold a finished run's rows into ``target``'s (:func:`~gtsp_bench.bench.rows.merge_rows`),
    record the command in its manifest and redraw its outputs (:func:`report_only`)."""
    from gtsp_bench.bench.engine import configure
    from gtsp_bench.bench.output_kinds import read_manifest
    from gtsp_bench.bench.rows import merge_rows, read_rows
    from gtsp_bench.data.io import atomic_write_csv, atomic_write_json

    run_dir = Path(configure(name, settings).output_dir)  # type: ignore[arg-type]
    new, old = read_rows(run_dir / "rows.csv"), read_rows(target / "rows.csv")
    try:
        merged, replaced, added = merge_rows(old, new)
    except ValueError as e:
        raise InputError(f"{target / 'rows.csv'}: cannot merge: {e}") from None
    manifest, run = read_manifest(target), read_manifest(run_dir)  # run: its code and machine
    manifest.setdefault("merges", []).append({
        "command": settings.command,  # type: ignore[attr-defined]
        "date": dt.datetime.now(dt.UTC).isoformat(timespec="seconds"),
        **{k: run.get(k) for k in ("git_commit", "git_dirty", "cpu_model")},
        "replaced": replaced, "added": added})
    atomic_write_csv(target / "rows.csv", merged)
    atomic_write_json(target / "manifest.json", manifest)
    print(f"merged into {target / 'rows.csv'}: {replaced} rows replaced, {added} added",
          file=sys.stderr)
    return report_only(name, settings.whole(target))  # type: ignore[attr-defined]


def run_bench_command(args: argparse.Namespace, answer: TextIO, argv: Sequence[str] | None = None) -> int:
    """Run ``gtsp-bench bench``; the summary is the answer on ``answer``; the exit code."""
    if args.list:
        answer.write(list_text())
        return 0
    import matplotlib

    matplotlib.use("Agg")
    from gtsp_bench.bench.engine import run_benchmark

    settings = settings_from(args, argv)
    target = Path(args.merge_into) if args.merge_into else None
    if target is not None:
        if args.report_only:
            raise InputError("--merge-into: give it a run to merge, not --report-only")
        check_merge(args.name, settings, target)
    if args.re_reference and (args.report_only or target is not None or args.update_reference):
        raise InputError("--re-reference: give it alone, not with --report-only, --merge-into or "
                         "--update-reference")
    if args.re_reference:
        code, text = re_reference(args.name, settings)
    elif args.report_only:
        code, text = report_only(args.name, settings)
    else:
        outcome = run_benchmark(args.name, settings)  # type: ignore[arg-type]
        code, text = (1 if outcome.failed or outcome.errors else 0), outcome.answer
        if target is not None and code == 0:
            code, text = merge_into(args.name, settings, target)
        elif target is not None:
            print(f"{target}: not merged (the run had failed solves or errors)", file=sys.stderr)
    if text:
        answer.write(text.rstrip("\n") + "\n")
        answer.flush()
    return code

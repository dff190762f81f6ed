"""The ``gtsp-bench bench`` command: its options and what runs them.

One command, three kinds of run: the paper's experiments (:mod:`gtsp_bench.bench.runner`), a
side-by-side suite (``--suite``, :mod:`gtsp_bench.bench.suites`) or a sweep over instance sets
(``--set``, :mod:`gtsp_bench.bench.sweep`). :func:`add_bench_parser` declares the options,
:func:`run_bench_command` checks that the options given belong to the kind of run asked for and
runs it. :mod:`gtsp_bench.cli` wires both into the command line and handles errors.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import TextIO

from gtsp_bench.checks import arg_float, arg_int, arg_seed
from gtsp_bench.errors import InputError

DESCRIPTION = """\
Run the paper's experiments (ratio-omega, ratio-k, runtime, trajectories, training) over seeded
instance sets in parallel; write OUT/<experiment>.csv and .png and refresh OUT/README.md. Finished
solves are logged in OUT/tmp/runs.jsonl, so an interrupted run resumes.

With --suite, run a side-by-side suite instead: exact (time to proven optimum, GTSPLIB against
best known), heuristics (mean gap and median time) or learned (the learned policies against the
optimum). Its table goes to stdout, one CSV row per solve to OUT/<suite>.csv (default OUT:
benchmarks/out).

With --set, sweep solvers over any instance sets instead (GTSPLIB, the UAV sets under instances/,
a folder of your own): one solve per instance x solver x omega x seed, gaps to each set's
reference.csv ("to optimum" or "to best known"), OUT/sweep.csv, OUT/summary.md (also on stdout),
a performance profile OUT/profile.csv/.png and gap plots (default OUT: benchmarks/out/sets).
"""

EPILOG = """\
suites (--suite NAME) and the options each takes besides -K, --solvers, --instances, --out, --quick:
  exact       --seed --time-limit --omegas --solver-seed --dp-max-k --no-generated
              --gtsplib --names --max-nodes --no-gtsplib
  heuristics  --seed --time-limit --omegas (one) --solver-seed --exact --exact-time-limit
              --gtsplib --names --max-nodes --no-gtsplib
  learned     --repeats --cache
--set NAME|PATH (repeatable) takes -K --solvers --instances --time-limit --out --omegas --seeds
  --names --max-nodes --jobs --instance-dir --fresh --retry-failed --no-progress --update-reference
  --executor

examples:
  gtsp-bench bench -K 4..10                       # the paper's experiments into results/
  gtsp-bench bench --suite exact --quick          # K = 4,7,10, omega 0.5, two GTSPLIB samples
  gtsp-bench bench --suite exact -K 4..7,10 --omegas 0.5 --time-limit 30 --no-gtsplib
  gtsp-bench bench --suite heuristics --quick     # 3 instances per K, 5 s per solve
  gtsp-bench bench --suite learned -K 4 --instances 20 --solvers drl,am
  gtsp-bench bench --set gtsplib --solvers greedy,lns --time-limit 5 --max-nodes 500
  gtsp-bench bench --set uav-K50-N20-s1 --set my/folder --omegas 0.2,0.8 --seeds 0..4
"""



def add_bench_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add the ``bench`` sub-command and its options to the CLI's sub-parsers; its parser."""
    p = sub.add_parser("bench", help="regenerate the paper's tables and figures, or run a suite",
                       description=DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       epilog=EPILOG)
    p.add_argument("--suite", choices=("exact", "heuristics", "learned"), default=None,
                   help="run a benchmark suite instead of the paper's experiments")
    p.add_argument("--clusters", "-K", metavar="K",
                   help="cluster counts: a range 4..10, a list 4,7,10 or a mix 4..7,10 (default: "
                   "4..10; quick: 4,5; suites: their own)")
    p.add_argument("--solvers", "-s", metavar="LIST",
                   help="comma-separated solvers (default: every registered benchmark solver; "
                   "suites: their own; learned: label prefixes, e.g. drl,am)")
    p.add_argument("--instances", type=arg_int, metavar="N",
                   help="instances per K (default: 30; quick: 3; suites: their own)")
    p.add_argument("--seed", type=arg_int, default=None,
                   help="instance-set seed (default: 1; suites exact, heuristics: 0)")
    p.add_argument("--time-limit", "-t", type=arg_float, default=None, metavar="S",
                   help="per-solve time limit in seconds (default: 10; suites: their own)")
    p.add_argument("--quick", action="store_true",
                   help="a smoke run: few instances and small K, written to results/quick "
                   "(suites: their quick preset)")
    p.add_argument("--out", "-o", metavar="DIR",
                   help="output folder (default: results; suites: benchmarks/out)")
    g = p.add_argument_group("instance sets (--set)")
    g.add_argument("--set", dest="sets", action="append", default=None, metavar="NAME|PATH",
                   help="sweep over an instance set, repeatable: 'gtsplib' (the bundled GTSPLIB, "
                   "143 instances, asymmetric ones too), a folder name under instances/ "
                   "(uav-K10-N20-s1, ...), or "
                   "any folder of .json / .gtsp(.gz) files or one such file; its reference.csv "
                   "gives the gaps (--instances: the first N per K; omegas are ignored for GTSPLIB)")
    g.add_argument("--seeds", metavar="LIST",
                   help="solver seeds, e.g. 0,1,2 or 0..4: one solve per seed (default: 0)")
    g.add_argument("--update-reference", action="store_true",
                   help="write a tour strictly better than a set's best_known value into its "
                   "reference.csv (atomically, with the solver and date); a proven optimum is "
                   "never changed, and a tour below it is an error")
    g = p.add_argument_group("the paper's experiments only (--set takes some, see below)")
    g.add_argument("--experiments", "-e", default=None, metavar="LIST",
                   help="comma-separated experiments, or 'all' (default)")
    g.add_argument("--reference", metavar="NAME", default=None,
                   help="exact solver giving the optimum (default: dp up to K=12, else milp)")
    g.add_argument("--nodes", "-n", type=arg_int, default=None, metavar="N",
                   help="nodes per cluster (default: 20)")
    g.add_argument("--jobs", "-j", type=arg_int, metavar="J",
                   help="worker processes (default: the number of cores)")
    g.add_argument("--executor", metavar="WHERE", default=None,
                   help="where solves run: 'local' (default: this machine's worker pool), 'dask' "
                   "(a Dask cluster of --jobs workers on this machine) or tcp://HOST:PORT (an "
                   "existing Dask scheduler and its workers; see docs/distributed.md)")
    g.add_argument("--instance-dir", default=None, metavar="DIR",
                   help="where instance sets are kept (default: instances)")
    g.add_argument("--checkpoints", default=None, metavar="DIR",
                   help="where <model>.train.csv training logs are (default: the shipped "
                        "checkpoints, gtsp_bench/solvers/learned/checkpoints)")
    g.add_argument("--fresh", action="store_true", help="redo solves already in the task log")
    g.add_argument("--retry-failed", action="store_true",
                   help="also redo solves the log records as failed by the solver's own error "
                   "(failures whose worker died or ran out of memory are always retried)")
    g.add_argument("--report-only", action="store_true",
                   help="only refresh OUT/README.md from the CSV files")
    g.add_argument("--no-progress", action="store_true", help="no progress bar")
    g = p.add_argument_group("suites only (--suite); each takes some, and --set some, see below")
    g.add_argument("--omegas", metavar="LIST",
                   help="omegas, e.g. 0,0.5,0.9 (exact: default 0,0.5,0.9, quick 0.5; heuristics: "
                   "one, default 0.5)")
    g.add_argument("--solver-seed", type=arg_seed, metavar="SEED",
                   help="seed given to every solve (default: 0)")
    g.add_argument("--dp-max-k", type=arg_int, metavar="K", help="exact: largest K given to dp (default: 12)")
    g.add_argument("--exact", metavar="LIST",
                   help="heuristics: exact reference solvers, NAME[:MAX_K] in order (default: dp:10,milp)")
    g.add_argument("--exact-time-limit", type=arg_float, metavar="S",
                   help="heuristics: seconds per exact reference solve (default: 120)")
    g.add_argument("--gtsplib", metavar="DIR",
                   help="folder with a best_known.csv in the library's format and the .gtsp(.gz) files "
                   "(default: $GTSP_BENCH_GTSPLIB, else the repository's instances/gtsplib)")
    g.add_argument("--names", metavar="LIST",
                   help="GTSPLIB instances, comma-separated (default: the five samples, or all of "
                        "--gtsplib DIR; quick: a few)")
    g.add_argument("--max-nodes", type=arg_int, metavar="N",
                   help="largest GTSPLIB sample in nodes (exact default: 318; heuristics: no limit)")
    g.add_argument("--no-gtsplib", action="store_true", help="skip the GTSPLIB samples")
    g.add_argument("--no-generated", action="store_true", help="exact: skip the generated instances")
    g.add_argument("--repeats", type=arg_int, metavar="R",
                   help="learned: timed runs per cell, the median is reported (default: 3; quick: 1)")
    g.add_argument("--cache", metavar="FILE",
                   help="learned: cache of exact optima (default: benchmarks/drl_exact.csv)")
    return p


#: ``bench`` options of the paper's experiments only, and of the suites only (argparse dests).
_PAPER_ONLY = ("experiments", "reference", "nodes", "jobs", "instance_dir", "checkpoints", "fresh",
               "retry_failed", "report_only", "no_progress", "executor")
_SUITE_ONLY = ("omegas", "solver_seed", "dp_max_k", "exact", "exact_time_limit", "gtsplib", "names",
               "max_nodes", "no_gtsplib", "no_generated", "repeats", "cache")


def _given(args: argparse.Namespace, dests: Sequence[str]) -> list[str]:
    from gtsp_bench.bench.suites import flag

    return [flag(d) for d in dests if getattr(args, d) is not None and getattr(args, d) is not False]


#: ``bench`` options a sweep (``--set``) takes besides the shared ones (argparse dests).
_SET_OPTIONS = ("omegas", "names", "max_nodes", "jobs", "instance_dir", "fresh", "retry_failed",
                "no_progress", "seeds", "update_reference", "executor")
_SET_ONLY = ("seeds", "update_reference")


def _cmd_sets(args: argparse.Namespace, answer: TextIO) -> int:
    for other in ("suite", "experiments"):
        if getattr(args, other):
            raise InputError(f"--set runs a sweep of its own: it cannot be combined with --{other}")
    stray = _given(args, [d for d in (*_PAPER_ONLY, *_SUITE_ONLY) if d not in _SET_OPTIONS]
                   + ["seed", "quick"])
    if stray:
        hint = "the solver seeds are --seeds" if stray[0] in ("--seed", "--solver-seed") \
            else "see gtsp-bench bench --help"
        raise InputError(f"{stray[0]} is not an option of --set ({hint})")
    import matplotlib

    matplotlib.use("Agg")
    from gtsp_bench.bench.sweep import make_sweep_config, run_sweep

    config = make_sweep_config(
        sets=args.sets, solvers=args.solvers, omegas=args.omegas, seeds=args.seeds,
        time_limit=args.time_limit, n_instances=args.instances, names=args.names,
        max_nodes=args.max_nodes, ks=args.clusters, jobs=args.jobs, out_dir=args.out,
        instance_dir=args.instance_dir, fresh=args.fresh, retry_failed=args.retry_failed,
        progress=not args.no_progress, update_reference=args.update_reference,
        **({"executor": args.executor} if args.executor is not None else {}),
    )
    summary = run_sweep(config)
    answer.write(summary.table.rstrip("\n") + "\n")
    answer.flush()
    return 1 if summary.failed or summary.below_optimum else 0


def run_bench_command(args: argparse.Namespace, answer: TextIO) -> int:
    if args.sets:
        return _cmd_sets(args, answer)
    stray = _given(args, _SET_ONLY)
    if stray:
        raise InputError(f"{stray[0]} is an option of --set (a sweep over instance sets)")
    if args.suite:
        return _cmd_suite(args, answer)
    stray = _given(args, _SUITE_ONLY)
    if stray:
        raise InputError(f"{stray[0]} is an option of the benchmark suites: add --suite "
                         "exact, heuristics or learned")
    import matplotlib

    matplotlib.use("Agg")
    from gtsp_bench.bench.runner import make_config, run_bench
    from gtsp_bench.report.paper import write_report

    # Options left out (None: shared with the suites, whose defaults differ) take make_config's.
    given = {"experiments": args.experiments, "reference": args.reference, "n_nodes": args.nodes,
             "seed": args.seed, "time_limit": args.time_limit, "instance_dir": args.instance_dir,
             "executor": args.executor}
    config = make_config(
        ks=args.clusters, solvers=args.solvers, n_instances=args.instances, jobs=args.jobs,
        quick=args.quick, out_dir=args.out, checkpoint_dir=args.checkpoints, fresh=args.fresh,
        retry_failed=args.retry_failed, progress=not args.no_progress,
        **{k: v for k, v in given.items() if v is not None},
    )
    if args.report_only:
        if not any(config.out_dir.glob("*.csv")):
            raise InputError(f"{config.out_dir}: no experiment CSV files to report on; run bench first")
        print(f"wrote {write_report(config.out_dir, config.checkpoint_dir)}", file=sys.stderr)
        return 0
    summary = run_bench(config)
    return 1 if summary.failed else 0


def _cmd_suite(args: argparse.Namespace, answer: TextIO) -> int:
    from gtsp_bench.bench.suites import make_suite_config, run_suite

    stray = _given(args, _PAPER_ONLY)
    if stray:
        raise InputError(f"{stray[0]} is an option of the paper's experiments, not of --suite")
    options = {d: getattr(args, d) for d in _SUITE_ONLY}
    config = make_suite_config(args.suite, quick=args.quick, out_dir=args.out, ks=args.clusters,
                               solvers=args.solvers, instances=args.instances, seed=args.seed,
                               time_limit=args.time_limit, **options)
    return run_suite(config, answer)  # the table is the answer: the real stdout

"""The ``gtsp-bench`` command line.

Bad input (a file, an option, a solution) prints one line ``gtsp-bench: error: <file>: <problem>``
on stderr and exits with code 2, and so does running out of memory (naming a smaller setting); a
misbehaving solver exits with code 1, and so does ``bench`` when any solve failed.

Standard output carries only the answer (the JSON object of ``--json``, a summary, a listing): for
the whole command file descriptor 1 points at stderr, and the answer is written on a saved copy of
the original stdout, so a banner a native library prints, a warning or a stray ``print`` cannot
corrupt it. Importing this module does not import torch: solvers are loaded only when used.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

from gtsp_bench import __version__
from gtsp_bench.errors import InputError, OneLineParser, SolverError

if TYPE_CHECKING:
    from gtsp_bench.solvers.learned.recipes import TrainConfig

DEFAULT_OMEGA = 0.5
DEFAULT_TIME_LIMIT = 60.0

_EPILOG = """\
examples:
  gtsp-bench generate --clusters 7 --seed 1 -o k7.json
  gtsp-bench solve k7.json --solver greedy --omega 0.3
  gtsp-bench solve k7.json --solver brute --json > sol.json
  gtsp-bench evaluate k7.json --solution sol.json --omega 0.3
  gtsp-bench solve instances/gtsplib/11berlin52.gtsp.gz --solver greedy
  gtsp-bench solvers
  gtsp-bench bench -K 4..10
  gtsp-bench bench --suite exact --quick
"""

_BENCH_DESCRIPTION = """\
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

_BENCH_EPILOG = """\
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


def _float(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None


def _int(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None


def _float_or_none(text: str) -> float | None:
    return None if text.strip().lower() == "none" else _float(text)


def _seed(text: str) -> int:
    from gtsp_bench.checks import check_seed

    try:
        return check_seed(_int(text))
    except InputError as e:
        raise argparse.ArgumentTypeError(f"a {e}") from None


def _key_value(text: str) -> tuple[str, Any]:
    key, sep, raw = text.partition("=")
    if not sep or not key:
        raise argparse.ArgumentTypeError(f"expected KEY=VALUE, got {text!r}")
    try:
        value = json.loads(raw)
    except json.JSONDecodeError:
        value = raw
    return key, value


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``gtsp-bench``."""
    parser = OneLineParser(
        prog="gtsp-bench",
        description=(
            "Benchmark suite and solvers for UAV data collection from IoT clusters as a "
            "generalized TSP (Zhu et al.): pick one cluster head per cluster and a closed tour "
            "from the base station, minimising omega * ground energy + (1 - omega) * UAV energy."
        ),
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=OneLineParser)
    sub.required = True

    p = sub.add_parser("generate", help="write a seeded random UAV instance (paper section VI)",
                       description="Write a seeded random UAV instance as JSON: K clusters of N "
                       "nodes in non-overlapping squares of half-width zeta in the area; the base "
                       "station at (area/2, 0).")
    p.add_argument("--clusters", "-k", type=_int, required=True, metavar="K", help="number of clusters")
    p.add_argument("--nodes", "-n", type=_int, default=20, metavar="N",
                   help="nodes per cluster (default: 20)")
    p.add_argument("--seed", type=_seed, default=0, help="random seed (default: 0)")
    p.add_argument("--zeta", type=_float, default=50.0, metavar="Z",
                   help="cluster half-width in m (default: 50)")
    p.add_argument("--area", type=_float, default=1000.0, metavar="A",
                   help="side of the square area in m (default: 1000)")
    p.add_argument("--name", help="instance name (default: uav-K{K}-N{N}-s{seed})")
    p.add_argument("-o", "--output", required=True, metavar="FILE.json", help="file to write")
    p.set_defaults(handler=_cmd_generate)

    p = sub.add_parser("solve", help="solve an instance with a registered solver",
                       description="Solve a .json (UAV) or .gtsp (GTSPLIB) instance. The result "
                       "is re-checked and re-priced by the shared evaluator.")
    p.add_argument("file", metavar="FILE", help="instance file (.json, .gtsp, or either .gz)")
    p.add_argument("--solver", "-s", required=True, help="solver name (see 'gtsp-bench solvers')")
    p.add_argument("--omega", "-w", type=_float, default=DEFAULT_OMEGA, metavar="W",
                   help=f"weight of the ground energy in [0, 1] (default: {DEFAULT_OMEGA}; "
                   "ignored for .gtsp)")
    p.add_argument("--time-limit", "-t", type=_float, default=DEFAULT_TIME_LIMIT, metavar="S",
                   help=f"time limit in seconds (default: {DEFAULT_TIME_LIMIT:g})")
    p.add_argument("--seed", type=_seed, default=0, help="random seed (default: 0)")
    p.add_argument("--param", "-p", type=_key_value, action="append", default=[],
                   metavar="KEY=VALUE", help="solver option, repeatable (e.g. -p ants=50)")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of a summary")
    p.add_argument("-o", "--output", metavar="SOL.json", help="also write the result JSON here")
    p.set_defaults(handler=_cmd_solve)

    p = sub.add_parser("evaluate", help="re-price a solution file",
                       description="Check and price a solution (a JSON object with 'order' and "
                       "'heads', as 'solve --json' prints) on an instance.")
    p.add_argument("file", metavar="FILE", help="instance file (.json, .gtsp, or either .gz)")
    p.add_argument("--solution", required=True, metavar="SOL.json", help="solution file")
    p.add_argument("--omega", "-w", type=_float, default=DEFAULT_OMEGA, metavar="W",
                   help=f"weight of the ground energy in [0, 1] (default: {DEFAULT_OMEGA})")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of a summary")
    p.set_defaults(handler=_cmd_evaluate)

    p = sub.add_parser("train", help="train a learned policy (drl, am) on generated instances",
                       description="Train a learned policy by REINFORCE on instances drawn fresh "
                       "from the generator, by a named recipe (solvers/learned/recipes.py): drl "
                       "(the shipped drl model's), drl-paper (the paper's plain pointer and "
                       "Algorithm 1), am (the shipped attention model's). Every setting defaults "
                       "to the recipe's; a switch overrides it. Writes CKPT, CKPT.json (with the "
                       "command that repeats the run), CKPT.train.csv and the resume state "
                       "CKPT.state.pt.")
    off = argparse.SUPPRESS  # a switch not given is not in the namespace: the recipe decides
    p.add_argument("--model", default=None, metavar="RECIPE",
                   help="training recipe: drl, drl-paper or am (default: drl)")
    p.add_argument("--clusters", "-k", type=_int, default=off, metavar="K", help="training K")
    p.add_argument("--nodes", "-n", type=_int, default=off, metavar="N", help="nodes per cluster")
    p.add_argument("--steps", type=_int, default=off, help="training steps")
    p.add_argument("--batch", type=_int, default=off, help="instances per step")
    p.add_argument("--lr", type=_float, default=off, help="Adam learning rate")
    p.add_argument("--seed", type=_seed, default=off, help="random seed")
    p.add_argument("--omega", "-w", type=_float_or_none, default=off, metavar="W",
                   help="train for one omega, or 'none': omega uniform in [0, 1] per instance")
    p.add_argument("--heads", choices=("paper", "optimal"), default=off,
                   help="head rule in the reward and validation")
    p.add_argument("--glimpse", choices=("all", "unvisited"), default=off,
                   help="drl: elements the decoder's glimpse attends to: every element (the "
                   "paper's eq. u_k), or only the unvisited ones (generalises better to larger K)")
    p.add_argument("--local", action=argparse.BooleanOptionalAction, default=off,
                   help="drl: add a learned term of the distances from the UAV's location and to "
                   "the base station to the pointer's logits (--no-local drops --energy too)")
    p.add_argument("--energy", action=argparse.BooleanOptionalAction, default=off,
                   help="drl with --local: also feed it the paper rule's energy of entering each "
                   "cluster and where that head is")
    p.add_argument("--direction", action=argparse.BooleanOptionalAction, default=off,
                   help="drl: also price each sampled tour flown backwards and move the odds of "
                   "its first step toward the cheaper direction")
    p.add_argument("--val-every", type=_int, default=off, metavar="S",
                   help="validate and checkpoint every S steps")
    p.add_argument("--val-size", type=_int, default=off, metavar="M", help="validation instances")
    p.add_argument("--threads", type=_int, default=off, help="torch threads")
    p.add_argument("--max-time", type=_float_or_none, default=off, metavar="S",
                   help="stop after S seconds of training wall time ('none': after --steps)")
    p.add_argument("--keep", choices=("best", "last"), default=off,
                   help="policy kept in CKPT: best validation energy or the last")
    p.add_argument("--resume", action="store_true", help="continue from CKPT.state.pt")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("-o", "--output", required=True, metavar="CKPT.pt", help="policy file to write")
    p.set_defaults(handler=_cmd_train)

    p = sub.add_parser("bench", help="regenerate the paper's tables and figures, or run a suite",
                       description=_BENCH_DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       epilog=_BENCH_EPILOG)
    p.add_argument("--suite", choices=("exact", "heuristics", "learned"), default=None,
                   help="run a benchmark suite instead of the paper's experiments")
    p.add_argument("--clusters", "-K", metavar="K",
                   help="cluster counts: a range 4..10, a list 4,7,10 or a mix 4..7,10 (default: "
                   "4..10; quick: 4,5; suites: their own)")
    p.add_argument("--solvers", "-s", metavar="LIST",
                   help="comma-separated solvers (default: every registered benchmark solver; "
                   "suites: their own; learned: label prefixes, e.g. drl,am)")
    p.add_argument("--instances", type=_int, metavar="N",
                   help="instances per K (default: 30; quick: 3; suites: their own)")
    p.add_argument("--seed", type=_int, default=None,
                   help="instance-set seed (default: 1; suites exact, heuristics: 0)")
    p.add_argument("--time-limit", "-t", type=_float, default=None, metavar="S",
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
    g.add_argument("--nodes", "-n", type=_int, default=None, metavar="N",
                   help="nodes per cluster (default: 20)")
    g.add_argument("--jobs", "-j", type=_int, metavar="J",
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
    g.add_argument("--solver-seed", type=_seed, metavar="SEED",
                   help="seed given to every solve (default: 0)")
    g.add_argument("--dp-max-k", type=_int, metavar="K", help="exact: largest K given to dp (default: 12)")
    g.add_argument("--exact", metavar="LIST",
                   help="heuristics: exact reference solvers, NAME[:MAX_K] in order (default: dp:10,milp)")
    g.add_argument("--exact-time-limit", type=_float, metavar="S",
                   help="heuristics: seconds per exact reference solve (default: 120)")
    g.add_argument("--gtsplib", metavar="DIR",
                   help="folder with best_known.csv and the .gtsp(.gz) files (default: "
                   "$GTSP_BENCH_GTSPLIB, else the repository's instances/gtsplib)")
    g.add_argument("--names", metavar="LIST",
                   help="GTSPLIB instances, comma-separated (default: the five samples, or all of "
                        "--gtsplib DIR; quick: a few)")
    g.add_argument("--max-nodes", type=_int, metavar="N",
                   help="largest GTSPLIB sample in nodes (exact default: 318; heuristics: no limit)")
    g.add_argument("--no-gtsplib", action="store_true", help="skip the GTSPLIB samples")
    g.add_argument("--no-generated", action="store_true", help="exact: skip the generated instances")
    g.add_argument("--repeats", type=_int, metavar="R",
                   help="learned: timed runs per cell, the median is reported (default: 3; quick: 1)")
    g.add_argument("--cache", metavar="FILE",
                   help="learned: cache of exact optima (default: benchmarks/drl_exact.csv)")
    p.set_defaults(handler=_cmd_bench)

    p = sub.add_parser("solvers", help="list the registered solvers",
                       description="List the registered solvers, one line each.")
    p.set_defaults(handler=_cmd_solvers)
    return parser


# ---------------------------------------------------------------------- standard output
#: Where a command writes its answer (set by :func:`main` for the command's duration).
_answer: TextIO | None = None


def _say(text: str) -> None:
    """Write the command's answer (one JSON object, a summary or a listing) on the real stdout."""
    stream = _answer if _answer is not None else sys.stdout
    stream.write(text + "\n")
    stream.flush()


@contextmanager
def _stdout_reserved() -> Iterator[TextIO]:
    """Point fd 1 and ``sys.stdout`` at stderr for the duration; yield a stream on the original
    stdout for the answer alone.

    When ``sys.stdout`` is not file descriptor 1 (replaced in-process, e.g. by pytest's capsys),
    the answer goes to it and only fd 1 and ``sys.stdout`` are redirected.
    """
    original = sys.stdout
    with suppress(Exception):
        original.flush()
    try:
        os.fstat(1)
        os.fstat(2)
        saved: int | None = os.dup(1)
    except OSError:  # no fd 1 or 2 (a daemon): nothing to protect
        saved = None
    try:
        on_fd1 = original.fileno() == 1
    except (AttributeError, OSError, ValueError):
        on_fd1 = False
    answer: TextIO = original
    if saved is not None:
        os.dup2(2, 1)
        if on_fd1:
            answer = open(os.dup(saved), "w", encoding=getattr(original, "encoding", None) or "utf-8",  # noqa: SIM115
                          errors=getattr(original, "errors", None) or "strict")
    sys.stdout = sys.stderr
    try:
        yield answer
    finally:
        sys.stdout = original
        if answer is not original:
            with suppress(BrokenPipeError):
                answer.flush()
            with suppress(BrokenPipeError, OSError):
                answer.close()
        if saved is not None:
            os.dup2(saved, 1)
            os.close(saved)


# ---------------------------------------------------------------------- commands
def _cmd_generate(args: argparse.Namespace) -> int:
    from gtsp_bench.generator import generate_instance
    from gtsp_bench.io import write_instance

    out = Path(args.output)
    if out.suffix.lower() != ".json":
        raise InputError(f"{out}: generated instances are written as .json")
    inst = generate_instance(args.clusters, args.nodes, args.seed, zeta=args.zeta,
                             area=args.area, depot=(args.area / 2, 0.0), name=args.name)
    write_instance(inst, out)
    print(f"wrote {out} ({inst.n_clusters} clusters, {inst.n_nodes} nodes)", file=sys.stderr)
    return 0


def _cmd_solve(args: argparse.Namespace) -> int:
    from gtsp_bench.checks import check_omega, check_time_limit
    from gtsp_bench.io import atomic_write_text, read_instance
    from gtsp_bench.registry import get_solver, run_solver

    instance = read_instance(args.file)
    options = dict(args.param)
    solver = get_solver(args.solver, **options)
    if instance.is_uav:
        check_omega(args.omega)  # argument errors first: they are not the file's
    check_time_limit(args.time_limit)
    try:
        result = run_solver(solver, instance, args.omega, time_limit=args.time_limit,
                            seed=args.seed, name=args.solver)
    except InputError as e:  # the solver refuses this instance: say which file
        where = str(args.file)
        raise InputError(str(e) if str(e).startswith(where) else f"{where}: {e}") from None
    text = json.dumps(result.to_dict())
    if args.output:
        atomic_write_text(args.output, text + "\n")
    _say(text if args.json else result.summary())
    return 0


def _cmd_evaluate(args: argparse.Namespace) -> int:
    from gtsp_bench.checks import check_omega
    from gtsp_bench.energy import evaluate
    from gtsp_bench.errors import InfeasibleSolutionError
    from gtsp_bench.io import read_instance, read_solution
    from gtsp_bench.registry import Result

    instance = read_instance(args.file)
    order, heads = read_solution(args.solution)
    omega = check_omega(args.omega) if instance.is_uav else None
    start = time.perf_counter()
    try:
        ev = evaluate(instance, omega, order, heads)
    except InfeasibleSolutionError as e:
        raise InputError(f"{args.solution}: infeasible solution: {e}") from None
    result = Result(
        instance=instance.name, solver=None, omega=omega,
        order=tuple(order), heads=tuple(heads), objective=ev.objective, energy=ev.energy,
        distance=ev.distance, status="feasible", lower_bound=None,
        runtime_s=time.perf_counter() - start,
    )
    _say(json.dumps(result.to_dict()) if args.json else result.summary())
    return 0


#: ``gtsp-bench train`` switches that set a training setting of the same name.
_TRAIN_FIELDS = ("clusters", "nodes", "steps", "batch", "lr", "seed", "omega", "heads", "val_every",
                 "val_size", "threads", "max_time", "keep", "direction")
_DRL_SWITCHES = ("glimpse", "local", "energy", "direction")


def train_config(args: argparse.Namespace) -> TrainConfig:
    """The training settings of a parsed ``gtsp-bench train`` command: the recipe named by
    ``--model``, with the switches given changed (a
    :class:`~gtsp_bench.solvers.learned.recipes.TrainConfig`)."""
    import math

    from gtsp_bench.solvers.learned.recipes import DEFAULT_RECIPE, get_recipe

    given = vars(args)
    base = get_recipe(args.model or DEFAULT_RECIPE)
    if base.model != "drl":
        for name in _DRL_SWITCHES:
            if name in given:
                raise InputError(f"--{name} is an option of the drl model only")
    overrides: dict[str, Any] = {k: given[k] for k in _TRAIN_FIELDS if k in given}
    if "val_every" in given:
        overrides["log_every"] = math.gcd(given["val_every"], base.log_every)
    options = dict(base.model_options)
    if "glimpse" in given:
        options["glimpse"] = given["glimpse"]
    if given.get("local") is True:
        options["local"] = True
    elif given.get("local") is False:
        options.pop("local", None)
        options.pop("energy", None)
    if given.get("energy") is True:
        if not options.get("local"):
            raise InputError("--energy adds features to the --local term: "
                             + ("drop --no-local" if "local" in given else "add --local"))
        options["energy"] = True
    elif given.get("energy") is False:
        options.pop("energy", None)
    if options != base.model_options:
        overrides["model_options"] = options
    return get_recipe(base.recipe, **overrides)


def _cmd_train(args: argparse.Namespace) -> int:
    from gtsp_bench.solvers.learned.train import train

    meta = train(train_config(args), args.output, resume=args.resume, progress=not args.no_progress)
    print(f"wrote {args.output}: step {meta['steps']} of {meta['steps_trained']}, "
          f"validation energy {meta['val_energy']:.2f} J, {meta['wall_s']:.0f} s", file=sys.stderr)
    return 0


#: ``bench`` options of the paper's experiments only, and of the suites only (argparse dests).
_PAPER_ONLY = ("experiments", "reference", "nodes", "jobs", "instance_dir", "checkpoints", "fresh",
               "retry_failed", "report_only", "no_progress", "executor")
_SUITE_ONLY = ("omegas", "solver_seed", "dp_max_k", "exact", "exact_time_limit", "gtsplib", "names",
               "max_nodes", "no_gtsplib", "no_generated", "repeats", "cache")


def _given(args: argparse.Namespace, dests: Sequence[str]) -> list[str]:
    from gtsp_bench.suites import flag

    return [flag(d) for d in dests if getattr(args, d) is not None and getattr(args, d) is not False]


#: ``bench`` options a sweep (``--set``) takes besides the shared ones (argparse dests).
_SET_OPTIONS = ("omegas", "names", "max_nodes", "jobs", "instance_dir", "fresh", "retry_failed",
                "no_progress", "seeds", "update_reference", "executor")
_SET_ONLY = ("seeds", "update_reference")


def _cmd_sets(args: argparse.Namespace) -> int:
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
    from gtsp_bench.sweep import make_sweep_config, run_sweep

    config = make_sweep_config(
        sets=args.sets, solvers=args.solvers, omegas=args.omegas, seeds=args.seeds,
        time_limit=args.time_limit, n_instances=args.instances, names=args.names,
        max_nodes=args.max_nodes, ks=args.clusters, jobs=args.jobs, out_dir=args.out,
        instance_dir=args.instance_dir, fresh=args.fresh, retry_failed=args.retry_failed,
        progress=not args.no_progress, update_reference=args.update_reference,
        **({"executor": args.executor} if args.executor is not None else {}),
    )
    summary = run_sweep(config)
    _say(summary.table.rstrip("\n"))
    return 1 if summary.failed or summary.below_optimum else 0


def _cmd_bench(args: argparse.Namespace) -> int:
    if args.sets:
        return _cmd_sets(args)
    stray = _given(args, _SET_ONLY)
    if stray:
        raise InputError(f"{stray[0]} is an option of --set (a sweep over instance sets)")
    if args.suite:
        return _cmd_suite(args)
    stray = _given(args, _SUITE_ONLY)
    if stray:
        raise InputError(f"{stray[0]} is an option of the benchmark suites: add --suite "
                         "exact, heuristics or learned")
    import matplotlib

    matplotlib.use("Agg")
    from gtsp_bench.report import write_report
    from gtsp_bench.runner import make_config, run_bench

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


def _cmd_suite(args: argparse.Namespace) -> int:
    from gtsp_bench.suites import make_suite_config, run_suite

    stray = _given(args, _PAPER_ONLY)
    if stray:
        raise InputError(f"{stray[0]} is an option of the paper's experiments, not of --suite")
    options = {d: getattr(args, d) for d in _SUITE_ONLY}
    config = make_suite_config(args.suite, quick=args.quick, out_dir=args.out, ks=args.clusters,
                               solvers=args.solvers, instances=args.instances, seed=args.seed,
                               time_limit=args.time_limit, **options)
    return run_suite(config, _answer)  # the table is the answer: the real stdout


def _cmd_solvers(args: argparse.Namespace) -> int:
    from gtsp_bench.registry import solver_specs

    specs = solver_specs()
    width = max(len(s.name) for s in specs)
    for spec in specs:
        _say(f"{spec.name:<{width}}  {spec.description}")
    return 0


# ---------------------------------------------------------------------- entry point
#: A smaller setting to try when a command runs out of memory.
_MEMORY_HINTS = {
    "generate": "use fewer --nodes or --clusters",
    "solve": "try a smaller instance, a solver that needs less memory, or a lower "
             "-p max_memory_gb (dp)",
    "evaluate": "try a smaller instance",
    "train": "use a smaller --batch or --val-size",
    "bench": "use fewer --jobs, a smaller -K or fewer --instances",
    "solvers": "close other programs",
}


def _memory_message(command: str, e: MemoryError) -> str:
    detail = (str(e).splitlines() or [""])[0] or "an allocation failed"
    return f"out of memory ({detail}); {_MEMORY_HINTS.get(command, 'try a smaller setting')}"


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; returns the exit code (0 ok, 1 solver failure or a failed bench solve, 2 bad
    input or out of memory, 130 interrupted)."""
    global _answer
    parser = build_parser()
    args = parser.parse_args(argv)
    with _stdout_reserved() as answer:
        _answer = answer
        try:
            return int(args.handler(args) or 0)
        except InputError as e:
            print(f"gtsp-bench: error: {e}", file=sys.stderr)
            return 2
        except MemoryError as e:
            print(f"gtsp-bench: error: {_memory_message(args.command, e)}", file=sys.stderr)
            return 2
        except SolverError as e:
            print(f"gtsp-bench: solver error: {e}", file=sys.stderr)
            return 1
        except KeyboardInterrupt:
            print("gtsp-bench: interrupted", file=sys.stderr)
            return 130
        except BrokenPipeError:  # e.g. `gtsp-bench solve ... | head`: stop quietly
            with suppress(OSError):
                os.dup2(os.open(os.devnull, os.O_WRONLY), answer.fileno())
            return 141
        finally:
            _answer = None


if __name__ == "__main__":
    sys.exit(main())

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
from gtsp_bench.checks import arg_float, arg_float_or_none, arg_int, arg_key_value, arg_seed
from gtsp_bench.cli.bench import add_bench_parser
from gtsp_bench.cli.proof import add_check_proof_parser, run_check_proof
from gtsp_bench.errors import InputError, OneLineParser, SolverError

if TYPE_CHECKING:
    from gtsp_bench.solver import Result
    from gtsp_bench.solvers.learned.recipes import TrainConfig

DEFAULT_OMEGA = 0.5
DEFAULT_TIME_LIMIT = 60.0

_EPILOG = """\
examples:
  gtsp-bench generate --clusters 7 --seed 1 -o k7.json
  gtsp-bench solve k7.json --solver greedy --omega 0.3
  gtsp-bench solve k7.json --solver brute --json > sol.json
  gtsp-bench evaluate k7.json --solution sol.json --omega 0.3
  gtsp-bench solve k7.json --solver dp --omega 0.3 --tour dp.tour
  gtsp-bench plot k7.json --solution sol.json --solution dp.tour --omega 0.3 -o k7.png
  gtsp-bench solve instances/gtsplib/11berlin52.gtsp.gz --solver greedy
  gtsp-bench solve instances/gtsplib/11berlin52.gtsp.gz --solver milp --certificate b.cert.json.gz
  gtsp-bench check-proof instances/gtsplib/11berlin52.gtsp.gz b.cert.json.gz
  gtsp-bench solvers
  gtsp-bench bench --list
  gtsp-bench bench paper -K 4..10
  gtsp-bench bench heuristics --quick
"""

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
    p.add_argument("--clusters", "-k", type=arg_int, required=True, metavar="K", help="number of clusters")
    p.add_argument("--nodes", "-n", type=arg_int, default=20, metavar="N",
                   help="nodes per cluster (default: 20)")
    p.add_argument("--seed", type=arg_seed, default=0, help="random seed (default: 0)")
    p.add_argument("--zeta", type=arg_float, default=50.0, metavar="Z",
                   help="cluster half-width in m (default: 50)")
    p.add_argument("--area", type=arg_float, default=1000.0, metavar="A",
                   help="side of the square area in m (default: 1000)")
    p.add_argument("--name", help="instance name (default: uav-K{K}-N{N}-s{seed})")
    p.add_argument("-o", "--output", required=True, metavar="FILE.json", help="file to write")
    p.set_defaults(handler=_cmd_generate)

    p = sub.add_parser("solve", help="solve an instance with a registered solver",
                       description="Solve a .json (UAV) or .gtsp (GTSPLIB) instance. The result "
                       "is re-checked and re-priced by the shared evaluator.")
    p.add_argument("file", metavar="FILE", help="instance file (.json, .gtsp, or either .gz)")
    p.add_argument("--solver", "-s", required=True, help="solver name (see 'gtsp-bench solvers')")
    p.add_argument("--omega", "-w", type=arg_float, default=DEFAULT_OMEGA, metavar="W",
                   help=f"weight of the ground energy in [0, 1] (default: {DEFAULT_OMEGA}; "
                   "ignored for .gtsp)")
    p.add_argument("--time-limit", "-t", type=arg_float, default=DEFAULT_TIME_LIMIT, metavar="S",
                   help=f"time limit in seconds (default: {DEFAULT_TIME_LIMIT:g})")
    p.add_argument("--seed", type=arg_seed, default=0, help="random seed (default: 0)")
    p.add_argument("--param", "-p", type=arg_key_value, action="append", default=[],
                   metavar="KEY=VALUE", help="solver option, repeatable (e.g. -p ants=50)")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of a summary")
    p.add_argument("-o", "--output", metavar="SOL.json", help="also write the result JSON here")
    p.add_argument("--tour", metavar="OUT.tour",
                   help="also write the tour as a TSPLIB tour file here (.tour or .tour.gz)")
    p.add_argument("--initial", metavar="SOL",
                   help="warm start from this solution (a JSON file as 'solve --json' prints, whose "
                   "'lower_bound', if any, is taken as claimed, or a .tour file): lns, milp, "
                   "gurobi, greedy+ls, ortools and lkh take one")
    p.add_argument("--progress", action="store_true",
                   help="print each improvement (time, objective, bound, gap) on stderr")
    p.add_argument("--certificate", metavar="CERT.json.gz",
                   help="milp: write a proof certificate here when the solve proves optimality "
                   "(check it with 'gtsp-bench check-proof'); the same as -p certificate=PATH")
    p.set_defaults(handler=_cmd_solve)

    p = sub.add_parser("evaluate", help="re-price a solution file",
                       description="Check and price a solution on an instance: a JSON object with "
                       "'order' and 'heads' (as 'solve --json' prints), or a TSPLIB tour file "
                       "(.tour or .tour.gz, as 'solve --tour' writes).")
    p.add_argument("file", metavar="FILE", help="instance file (.json, .gtsp, or either .gz)")
    p.add_argument("--solution", required=True, metavar="SOL",
                   help="solution file: a TSPLIB tour if named .tour or .tour.gz, else JSON")
    p.add_argument("--omega", "-w", type=arg_float, default=DEFAULT_OMEGA, metavar="W",
                   help=f"weight of the ground energy in [0, 1] (default: {DEFAULT_OMEGA})")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of a summary")
    p.set_defaults(handler=_cmd_evaluate)

    p = sub.add_parser("plot", help="draw an instance and its solutions as a PNG",
                       description="Draw an instance (the base station, each cluster's nodes: its "
                       "candidate heads) and, for each --solution, the chosen heads and the tour in "
                       "a panel of its own, titled with the objective the evaluator gives it. A "
                       "GTSPLIB file is drawn from its coordinates (there is no base station); a file "
                       "of EXPLICIT weights without coordinates is refused.")
    p.add_argument("file", metavar="FILE", help="instance file (.json, .gtsp, or either .gz)")
    p.add_argument("--solution", action="append", default=[], metavar="SOL",
                   help="solution file: a TSPLIB tour if named .tour or .tour.gz, else JSON; "
                   "repeatable, one panel each")
    p.add_argument("--omega", "-w", type=arg_float, default=DEFAULT_OMEGA, metavar="W",
                   help=f"weight of the ground energy in [0, 1] that prices the solutions (default: "
                   f"{DEFAULT_OMEGA}; ignored for .gtsp)")
    p.add_argument("-o", "--output", required=True, metavar="FILE.png", help="PNG file to write")
    p.set_defaults(handler=_cmd_plot)

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
    p.add_argument("--clusters", "-k", type=arg_int, default=off, metavar="K", help="training K")
    p.add_argument("--nodes", "-n", type=arg_int, default=off, metavar="N", help="nodes per cluster")
    p.add_argument("--steps", type=arg_int, default=off, help="training steps")
    p.add_argument("--batch", type=arg_int, default=off, help="instances per step")
    p.add_argument("--lr", type=arg_float, default=off, help="Adam learning rate")
    p.add_argument("--seed", type=arg_seed, default=off, help="random seed")
    p.add_argument("--omega", "-w", type=arg_float_or_none, default=off, metavar="W",
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
    p.add_argument("--val-every", type=arg_int, default=off, metavar="S",
                   help="validate and checkpoint every S steps")
    p.add_argument("--val-size", type=arg_int, default=off, metavar="M", help="validation instances")
    p.add_argument("--threads", type=arg_int, default=off, help="torch threads")
    p.add_argument("--max-time", type=arg_float_or_none, default=off, metavar="S",
                   help="stop after S seconds of training wall time ('none': after --steps)")
    p.add_argument("--keep", choices=("best", "last"), default=off,
                   help="policy kept in CKPT: best validation energy or the last")
    p.add_argument("--resume", action="store_true", help="continue from CKPT.state.pt")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("-o", "--output", required=True, metavar="CKPT.pt", help="policy file to write")
    p.set_defaults(handler=_cmd_train)

    p = add_bench_parser(sub)
    p.set_defaults(handler=_cmd_bench)

    p = add_check_proof_parser(sub)
    p.set_defaults(handler=_cmd_check_proof)

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
    from gtsp_bench.data.io import write_instance
    from gtsp_bench.generator import generate_instance

    out = Path(args.output)
    if out.suffix.lower() != ".json":
        raise InputError(f"{out}: generated instances are written as .json")
    inst = generate_instance(args.clusters, args.nodes, args.seed, zeta=args.zeta,
                             area=args.area, depot=(args.area / 2, 0.0), name=args.name)
    write_instance(inst, out)
    print(f"wrote {out} ({inst.n_clusters} clusters, {inst.n_nodes} nodes)", file=sys.stderr)
    return 0


def _cmd_solve(args: argparse.Namespace) -> int:
    import gzip

    from gtsp_bench.checks import check_omega, check_time_limit, is_number
    from gtsp_bench.data.io import (
        TOUR_SUFFIX,
        atomic_write_text,
        check_tour_name,
        format_suffix,
        read_instance,
        read_solution_file,
        write_tour,
    )
    from gtsp_bench.registry import check_initial, check_warm_start, get_solver, run_solver
    from gtsp_bench.solver import Solution, TrajectoryPoint

    def show(point: TrajectoryPoint) -> None:  # --progress: one line per improvement
        bound = "-" if point.lower_bound is None else f"{point.lower_bound:.6f}"
        gap = "-" if point.gap is None else f"{100 * point.gap:.3f} %"
        print(f"gtsp-bench: progress: {point.time_s:9.3f} s  objective {point.objective:.6f}  "
              f"bound {bound}  gap {gap}", file=sys.stderr, flush=True)

    if args.tour:
        check_tour_name(args.tour)  # before a long solve
    instance = read_instance(args.file)
    options = dict(args.param)
    if args.certificate is not None:
        options["certificate"] = args.certificate
    solver = get_solver(args.solver, **options)
    if instance.is_uav:
        check_omega(args.omega)  # argument errors first: they are not the file's
    check_time_limit(args.time_limit)
    initial = None
    if args.initial is not None:  # checked first; every problem is one line naming the file
        path = args.initial
        try:
            check_warm_start(solver, args.solver)
            order, heads = read_solution_file(path, instance)
            bound = None
            if format_suffix(path) != TOUR_SUFFIX:  # a JSON file may claim a bound
                raw = Path(path).read_bytes()
                bound = json.loads(gzip.decompress(raw) if path.lower().endswith(".gz") else raw
                                   ).get("lower_bound")  # a claim, as the file's writer made it
            if bound is not None and not is_number(bound):
                raise InputError(f"'lower_bound' must be a number or null, not {bound!r}")
            initial = check_initial(instance, args.omega if instance.is_uav else None,
                                    Solution(tuple(order), tuple(heads), float("nan"), lower_bound=bound))
        except InputError as e:
            raise InputError(str(e) if str(e).startswith(f"{path}:") else f"{path}: {e}") from None
    try:
        result = run_solver(solver, instance, args.omega, time_limit=args.time_limit,
                            seed=args.seed, name=args.solver, initial=initial,
                            on_progress=show if args.progress else None)
    except InputError as e:  # the solver refuses this instance: say which file
        where = str(args.file)
        raise InputError(str(e) if str(e).startswith(where) else f"{where}: {e}") from None
    text = json.dumps(result.to_dict())
    if args.output:
        atomic_write_text(args.output, text + "\n")
    if args.tour:
        write_tour(instance, args.tour, result.order, result.heads, _tour_comments(result))
    if "certificate" in options:
        stats = result.stats or {}
        done = stats.get("certificate_bytes")
        print(f"wrote {options['certificate']} ({done} bytes)" if done is not None else
              f"no certificate: {stats.get('certificate', 'not written')}", file=sys.stderr)
    _say(text if args.json else result.summary())
    return 0


def _tour_comments(result: Result) -> list[str]:
    """The COMMENT lines of a tour file: its length (GLKH's first line) or energy, and its solver."""
    if result.energy is None:
        first = f"Length = {result.objective:.12g}"
    else:
        first = (f"Energy = {result.objective:.12g} J at omega = {result.omega:g}, "
                 f"length = {result.distance:.12g} m")
    return [first, f"Found by gtsp-bench solve --solver {result.solver} ({result.status})"]


def _cmd_evaluate(args: argparse.Namespace) -> int:
    from gtsp_bench.checks import check_omega
    from gtsp_bench.data.io import read_instance, read_solution_file
    from gtsp_bench.energy import evaluate
    from gtsp_bench.solver import Result

    instance = read_instance(args.file)
    order, heads = read_solution_file(args.solution, instance)
    omega = check_omega(args.omega) if instance.is_uav else None
    start = time.perf_counter()
    ev = evaluate(instance, omega, order, heads)
    result = Result(
        instance=instance.name, solver=None, omega=omega,
        order=tuple(order), heads=tuple(heads), objective=ev.objective, energy=ev.energy,
        distance=ev.distance, status="feasible", lower_bound=None,
        runtime_s=time.perf_counter() - start,
    )
    _say(json.dumps(result.to_dict()) if args.json else result.summary())
    return 0


def _cmd_plot(args: argparse.Namespace) -> int:
    from gtsp_bench.checks import check_omega
    from gtsp_bench.data.io import read_instance, read_solution_file
    from gtsp_bench.energy import evaluate
    from gtsp_bench.report.figures import save_png, tour_figure
    from gtsp_bench.report.plots import check_drawable

    out = Path(args.output)
    if out.suffix.lower() != ".png":
        raise InputError(f"{out}: plot writes PNG; name the output FILE.png")
    instance = read_instance(args.file)
    omega = check_omega(args.omega) if instance.is_uav else None
    try:
        check_drawable(instance)
    except InputError as e:
        raise InputError(f"{args.file}: {e}") from None
    tours = []
    for path in args.solution:
        order, heads = read_solution_file(path, instance)
        ev = evaluate(instance, omega, order, heads)
        value = (f"{ev.objective:.2f} J (omega = {omega:g})" if omega is not None
                 else f"length {ev.objective:.12g}")
        tours.append((f"{Path(path).name}: {value}", order, heads))
    save_png(tour_figure(instance, tours), out)
    drawn = f"{len(tours)} solution{'' if len(tours) == 1 else 's'}" if tours else "the instance alone"
    print(f"wrote {out} ({drawn})", file=sys.stderr)
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


def _cmd_bench(args: argparse.Namespace) -> int:
    from gtsp_bench.cli.bench import run_bench_command

    return run_bench_command(args, _answer if _answer is not None else sys.stdout, args.argv)


def _cmd_check_proof(args: argparse.Namespace) -> int:
    return run_check_proof(args, _answer if _answer is not None else sys.stdout)


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
    "plot": "try a smaller instance",
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
    args.argv = list(sys.argv[1:] if argv is None else argv)
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


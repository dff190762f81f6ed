"""Exact solvers side by side: time to proven optimum, and the GTSPLIB samples against best known.

Generated instances: ``instance_set(instances, K, set_seed)`` (N = 20 nodes per cluster) for each
K and each omega; every solver in ``--solvers`` runs on every instance with the same time limit.
A cell is the median time to a *proven* optimum over the instances (a solve that is not proven
counts as slower than the limit) and how many were proven. All proven optima of one instance must
agree (relative 1e-6); disagreements are counted and printed.

GTSPLIB (``instances/gtsplib/``): the five samples (``--names``) up to ``--max-nodes`` nodes
(default: up to 64lin318), solved by the solvers that fit; the table gives status, objective,
bound and time, and whether the objective equals the best-known value.

    python benchmarks/exact.py --quick                      # a subset, about a minute
    nice -n 5 python benchmarks/exact.py                    # K = 4..10, 15, 20, 30; all omegas
    python benchmarks/exact.py --k 4,7,10 --omegas 0.5 --time-limit 30 --no-gtsplib

One row per solve goes to ``benchmarks/out/exact.csv`` (``--csv`` to change). Timings are wall-clock
medians of one run on whatever machine runs it (solver time only, as ``run_solver`` measures it).
"""

from __future__ import annotations

import argparse
import csv
import io
import math
import os
import statistics
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
if str(REPO) not in sys.path:  # run as a script from anywhere
    sys.path.insert(0, str(REPO))

from gtsp_bench.errors import InputError, SolverError  # noqa: E402
from gtsp_bench.generator import instance_set  # noqa: E402
from gtsp_bench.gtsplib import SAMPLES  # noqa: E402
from gtsp_bench.instance import Instance  # noqa: E402
from gtsp_bench.io import atomic_write_text, read_instance  # noqa: E402
from gtsp_bench.registry import get_solver, run_solver, solver_names  # noqa: E402

DEFAULT_K = (4, 5, 6, 7, 8, 9, 10, 15, 20, 30)
DEFAULT_GTSPLIB = REPO / "instances" / "gtsplib"
DEFAULT_CSV = REPO / "benchmarks" / "out" / "exact.csv"
#: Relative tolerance between two proven optima of the same instance.
AGREE = 1e-6


@dataclass(frozen=True)
class Run:
    """One solve: the CSV row."""

    group: str
    instance: str
    omega: float | None
    solver: str
    status: str
    objective: float
    lower_bound: float
    runtime_s: float
    note: str = ""


def parse_ints(text: str) -> list[int]:
    """``"4..7,10"`` -> ``[4, 5, 6, 7, 10]``."""
    out: list[int] = []
    for part in filter(None, (p.strip() for p in text.split(","))):
        lo, sep, hi = part.partition("..")
        try:
            out += list(range(int(lo), int(hi) + 1)) if sep else [int(part)]
        except ValueError:
            raise argparse.ArgumentTypeError(f"bad list {text!r} (e.g. 4..10,15)") from None
    return out


def parse_floats(text: str) -> list[float]:
    """``"0,0.5"`` -> ``[0.0, 0.5]``."""
    try:
        return [float(p) for p in text.split(",") if p.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"bad list {text!r} (e.g. 0,0.5,0.9)") from None


def solve(group: str, instance: Instance, omega: float | None, solver: str, time_limit: float) -> Run:
    """One solve through the checked harness; a refusal or failure becomes a row too."""
    try:
        r = run_solver(get_solver(solver), instance, omega, time_limit=time_limit, seed=0)
    except (InputError, SolverError) as e:
        return Run(group, instance.name, omega, solver, "failed", math.nan, math.nan, math.nan,
                   str(e).splitlines()[0][:200])
    lower = math.nan if r.lower_bound is None else r.lower_bound
    return Run(group, instance.name, omega, solver, r.status, r.objective, lower, r.runtime_s)


def disagreements(runs: Sequence[Run]) -> list[str]:
    """Instances (and omegas) whose proven optima differ between solvers."""
    proven: dict[tuple[str, float | None], list[Run]] = {}
    for r in runs:
        if r.status == "optimal":
            proven.setdefault((r.instance, r.omega), []).append(r)
    bad = []
    for (name, omega), rs in proven.items():
        lo, hi = min(r.objective for r in rs), max(r.objective for r in rs)
        if hi - lo > AGREE * max(1.0, abs(lo)):
            bad.append(f"{name} omega={omega}: " + ", ".join(f"{r.solver} {r.objective!r}" for r in rs))
    return bad


def generated_runs(args: argparse.Namespace) -> list[Run]:
    """Every solver on every generated instance and omega (dp only up to ``--dp-max-k``)."""
    runs = []
    for k in args.k:
        instances = instance_set(args.instances, k, args.set_seed)
        for omega in args.omegas:
            for solver in args.solvers:
                if solver == "dp" and k > args.dp_max_k:
                    continue
                for inst in instances:
                    runs.append(solve(f"K={k}", inst, omega, solver, args.time_limit))
            done = [r for r in runs if r.group == f"K={k}" and r.omega == omega]
            print(f"  K={k} omega={omega:g}: {len(done)} solves", file=sys.stderr, flush=True)
    return runs


def gtsplib_runs(args: argparse.Namespace) -> tuple[list[Run], dict[str, tuple[int, int, float, str]]]:
    """The solvers on the GTSPLIB samples; also ``{name: (clusters, nodes, best, status)}``."""
    folder = Path(args.gtsplib)
    table = folder / "best_known.csv"
    if not table.is_file():
        print(f"no {table}: GTSPLIB skipped", file=sys.stderr)
        return [], {}
    with table.open() as f:
        rows = [r for r in csv.DictReader(f) if int(r["nodes"]) <= args.max_nodes
                and (not args.names or r["name"] in args.names)]
    runs, info = [], {}
    for row in rows:
        inst = read_instance(folder / f"{row['name']}.gtsp.gz")
        info[inst.name] = (int(row["clusters"]), int(row["nodes"]), float(row["best_known"]), row["status"])
        for solver in args.solvers:
            if solver == "dp" and inst.n_clusters > args.dp_max_k:
                continue
            runs.append(solve("GTSPLIB", inst, None, solver, args.time_limit))
            print(f"  {inst.name} {solver}: {runs[-1].status} {runs[-1].runtime_s:.2f} s",
                  file=sys.stderr, flush=True)
    return runs, info


def median_time(runs: Sequence[Run], limit: float) -> str:
    """Median time to a proven optimum (unproven solves count as above the limit) and count."""
    times = sorted(r.runtime_s if r.status == "optimal" else math.inf for r in runs)
    proven = sum(math.isfinite(t) for t in times)
    med = statistics.median(times)
    text = f"{med:7.2f}s" if math.isfinite(med) else f">{limit:6.0f}s"
    return f"{text} {proven}/{len(times)}"


def generated_table(runs: Sequence[Run], solvers: Sequence[str], limit: float) -> str:
    """Rows K x omega; cells: median time to proven optimum and how many were proven."""
    head = f"{'K':>4} {'omega':>5}" + "".join(f" | {s:>14}" for s in solvers)
    lines = [head, "-" * len(head)]
    keys = list(dict.fromkeys((r.group, r.omega) for r in runs))
    for group, omega in keys:
        cells = []
        for s in solvers:
            mine = [r for r in runs if r.group == group and r.omega == omega and r.solver == s]
            cells.append(median_time(mine, limit) if mine else f"{'-':>14}")
        lines.append(f"{group[2:]:>4} {omega:>5g}" + "".join(f" | {c:>14}" for c in cells))
    lines.append("cells: median time to proven optimum over the instances / instances proven")
    return "\n".join(lines)


def gtsplib_table(runs: Sequence[Run], info: dict[str, tuple[int, int, float, str]]) -> str:
    """One row per GTSPLIB solve: status, objective vs best known, bound, time."""
    head = (f"{'instance':<11} {'K':>3} {'n':>4} {'solver':<7} {'status':<10} {'objective':>9} "
            f"{'best known':>10} {'(literature)':<12} {'match':>5} {'bound':>10} {'time':>8}")
    lines = [head, "-" * len(head)]
    for r in runs:
        k, n, best, status = info[r.instance]
        match = "yes" if r.objective == best else ("BETTER" if r.objective < best else "no")
        lines.append(f"{r.instance:<11} {k:>3} {n:>4} {r.solver:<7} {r.status:<10} {r.objective:>9.0f} "
                     f"{best:>10.0f} {status:<12} {match:>5} {r.lower_bound:>10.1f} "
                     f"{r.runtime_s:>7.2f}s")
    return "\n".join(lines)


def write_csv(path: str, runs: Sequence[Run]) -> None:
    """One row per solve."""
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(["group", "instance", "omega", "solver", "status", "objective", "lower_bound",
                "runtime_s", "note"])
    for r in runs:
        w.writerow([r.group, r.instance, "" if r.omega is None else r.omega, r.solver, r.status,
                    repr(r.objective), repr(r.lower_bound), f"{r.runtime_s:.4f}", r.note])
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(path, buf.getvalue())


def build_parser() -> argparse.ArgumentParser:
    """The script's options."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true",
                   help="a subset: K = 4, 7, 10, omega 0.5, 11berlin52 and 20kroA100")
    p.add_argument("--k", type=parse_ints, default=None,
                   help="cluster counts, e.g. 4..10,15 (default 4..10,15,20,30)")
    p.add_argument("--omegas", type=parse_floats, default=None, help="omegas (default 0,0.5,0.9)")
    p.add_argument("--instances", type=int, default=5, help="instances per K (default 5)")
    p.add_argument("--set-seed", type=int, default=0, help="seed of the instance sets (default 0)")
    p.add_argument("--solvers", default="milp,dp", help="comma-separated (default milp,dp)")
    p.add_argument("--dp-max-k", type=int, default=12, help="largest K given to dp (default 12)")
    p.add_argument("--time-limit", type=float, default=60.0, help="seconds per solve (default 60)")
    p.add_argument("--gtsplib", default=str(DEFAULT_GTSPLIB), help="folder with best_known.csv")
    p.add_argument("--max-nodes", type=int, default=318,
                   help="largest GTSPLIB sample, in nodes (default 318: up to 64lin318)")
    p.add_argument("--names", default=None,
                   help=f"GTSPLIB instances, comma-separated (default: the samples {','.join(SAMPLES)})")
    p.add_argument("--no-generated", action="store_true", help="skip the generated instances")
    p.add_argument("--no-gtsplib", action="store_true", help="skip GTSPLIB")
    p.add_argument("--csv", default=str(DEFAULT_CSV), help=f"CSV output (default {DEFAULT_CSV})")
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Run the benchmark and print the tables; returns the exit code (1 on a disagreement)."""
    args = build_parser().parse_args(argv)
    if args.quick:
        args.k = args.k or [4, 7, 10]
        args.omegas = args.omegas or [0.5]
        args.names = args.names or "11berlin52,20kroA100"
    args.k = args.k or list(DEFAULT_K)
    args.omegas = args.omegas if args.omegas is not None else [0.0, 0.5, 0.9]
    args.solvers = [s for s in args.solvers.split(",") if s]
    args.names = [s for s in (args.names or ",".join(SAMPLES)).split(",") if s]
    unknown = [s for s in args.solvers if s not in solver_names()]
    if unknown:
        print(f"exact: error: unknown solver {unknown[0]!r} (valid: {', '.join(solver_names())})",
              file=sys.stderr)
        return 2
    runs = [] if args.no_generated else generated_runs(args)
    lib_runs, info = ([], {}) if args.no_gtsplib else gtsplib_runs(args)
    print(f"{args.instances} instances per K (set seed {args.set_seed}, N = 20), time limit "
          f"{args.time_limit:g} s per solve, {os.cpu_count()} CPU cores")
    if runs:
        print(generated_table(runs, args.solvers, args.time_limit))
    if lib_runs:
        print()
        print(gtsplib_table(lib_runs, info))
    bad = disagreements([*runs, *lib_runs])
    print(f"\n{len(bad)} disagreement(s) between proven optima" + "".join(f"\n  {b}" for b in bad))
    write_csv(args.csv, [*runs, *lib_runs])
    print(f"rows: {args.csv}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())

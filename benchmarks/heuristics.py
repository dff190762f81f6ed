"""Heuristics side by side: mean gap to the optimum / best known and median time, in one run.

For seeded generated sets (``instance_set(n, K, seed)``, omega 0.5) and for the five GTSPLIB
samples (``instances/gtsplib/``, ``--names`` for others), every solver runs on every instance with
the same per-solve time limit and seed. The reference of a generated instance is the optimum of an
exact solver picked by K (``--exact``, default ``dp`` up to K = 10, then ``milp``); when that
solver is not registered, fails, or stops without proving optimality, the reference is the best
objective any solver found, and the table says "best found" instead of "optimum". GTSPLIB gaps are
to the best-known values.

    python benchmarks/heuristics.py --quick                  # a few minutes less: a subset
    nice -n 5 python benchmarks/heuristics.py --csv out.csv  # everything, one row per solve in CSV

Timings are wall-clock medians of one run on whatever machine runs it.
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

SOLVERS = ("greedy", "greedy+ls", "aco", "aco+ls", "lns", "pyvrp")
DEFAULT_GTSPLIB = REPO / "instances" / "gtsplib"


@dataclass(frozen=True)
class Run:
    """One solve: the CSV row."""

    group: str
    instance: str
    solver: str
    objective: float
    runtime_s: float
    status: str
    reference: float
    reference_kind: str

    @property
    def gap(self) -> float:
        """Gap in percent to the reference."""
        return 100.0 * (self.objective - self.reference) / self.reference


def parse_exact(text: str) -> list[tuple[str, int | None]]:
    """``"dp:10,milp"`` -> ``[("dp", 10), ("milp", None)]``: exact solvers and their largest K."""
    out: list[tuple[str, int | None]] = []
    for part in filter(None, (p.strip() for p in text.split(","))):
        name, _, k = part.partition(":")
        try:
            out.append((name, int(k) if k else None))
        except ValueError:
            raise InputError(f"--exact: bad entry {part!r} (expected NAME or NAME:MAX_K)") from None
    return out


def exact_optimum(
    instance: Instance, omega: float, exact: list[tuple[str, int | None]], time_limit: float
) -> tuple[float, str] | None:
    """The proven optimum and the exact solver's name, or ``None`` when none proves one."""
    registered = set(solver_names())
    for name, max_k in exact:
        if name not in registered or (max_k is not None and instance.n_clusters > max_k):
            continue
        try:
            r = run_solver(name, instance, omega, time_limit=time_limit)
        except (InputError, SolverError) as e:
            print(f"  {name} failed on {instance.name}: {e}", file=sys.stderr)
            continue
        if r.status == "optimal":
            return r.objective, name
    return None


def solve_all(
    instance: Instance, omega: float | None, solvers: Sequence[str], time_limit: float, seed: int
) -> dict[str, tuple[float, float, str]]:
    """``{solver: (objective, runtime_s, status)}`` for every solver that returns a tour."""
    out = {}
    for name in solvers:
        try:
            r = run_solver(get_solver(name), instance, omega, time_limit=time_limit, seed=seed)
        except (InputError, SolverError) as e:
            print(f"  {name} failed on {instance.name}: {e}", file=sys.stderr)
            continue
        out[name] = (r.objective, r.runtime_s, r.status)
    return out


def generated_runs(args: argparse.Namespace, solvers: Sequence[str]) -> list[Run]:
    """Runs on the generated sets; reference: exact optimum, else best found."""
    exact = parse_exact(args.exact)
    runs = []
    for k in args.k:
        for inst in instance_set(args.instances, k, args.set_seed):
            found = solve_all(inst, args.omega, solvers, args.time_limit, args.seed)
            opt = exact_optimum(inst, args.omega, exact, args.exact_time_limit)
            if opt is not None:
                ref, kind = opt[0], f"optimum ({opt[1]})"
            else:
                ref, kind = min(o for o, _, _ in found.values()), "best found"
            runs += [Run(f"K={k}", inst.name, s, o, t, st, ref, kind) for s, (o, t, st) in found.items()]
            print(f"  {inst.name}: reference {ref:.4f} ({kind})", file=sys.stderr, flush=True)
    return runs


def gtsplib_runs(args: argparse.Namespace, solvers: Sequence[str]) -> list[Run]:
    """Runs on the GTSPLIB samples; reference: best_known.csv."""
    folder = Path(args.gtsplib)
    table = folder / "best_known.csv"
    if not table.is_file():
        print(f"no {table}: GTSPLIB skipped", file=sys.stderr)
        return []
    with table.open() as f:
        rows = [r for r in csv.DictReader(f) if not args.names or r["name"] in args.names]
    runs = []
    for row in rows:
        inst = read_instance(folder / f"{row['name']}.gtsp.gz")
        ref = float(row["best_known"])
        kind = "optimum (literature)" if row["status"] == "optimal" else "best known"
        found = solve_all(inst, None, solvers, args.time_limit, args.seed)
        runs += [Run("GTSPLIB", inst.name, s, o, t, st, ref, kind) for s, (o, t, st) in found.items()]
        print(f"  {inst.name}: done", file=sys.stderr, flush=True)
    return runs


def table(runs: list[Run], solvers: Sequence[str]) -> str:
    """Mean gap and median time per group (and per GTSPLIB instance) and solver."""
    lines = []
    width = 14
    head = f"{'set':<14} {'n':>3}  {'reference':<22}" + "".join(f" | {s:>{width}}" for s in solvers)
    lines += [head, "-" * len(head)]
    groups: dict[str, list[Run]] = {}
    for r in runs:
        groups.setdefault(r.group, []).append(r)
        if r.group == "GTSPLIB":
            groups.setdefault(f"  {r.instance}", []).append(r)
    for group, rs in groups.items():
        kinds = sorted({r.reference_kind for r in rs})
        n = len({r.instance for r in rs})
        cells = []
        for s in solvers:
            mine = [r for r in rs if r.solver == s]
            if not mine:
                cells.append(f"{'-':>{width}}")
                continue
            gap = statistics.fmean(r.gap for r in mine)
            time_ = statistics.median(r.runtime_s for r in mine)
            limit = "*" if any(r.status == "time_limit" for r in mine) else " "
            cells.append(f"{gap:>6.3f}% {time_:>5.2f}s{limit}")
        kind = kinds[0] if len(kinds) == 1 else "mixed"
        lines.append(f"{group:<14} {n:>3}  {kind:<22}" + "".join(f" | {c}" for c in cells))
    lines.append("")
    lines.append("cells: mean gap to the reference / median solve time; * = some solves hit the time limit")
    return "\n".join(lines)


def build_parser() -> argparse.ArgumentParser:
    """The script's options."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true",
                   help="a subset: 3 instances per K, K = 4, 7, 10, 20, time limit 5 s, the three "
                        "smallest GTSPLIB samples")
    p.add_argument("--k", type=int, nargs="+", default=None, help="cluster counts (default 4 7 10 20)")
    p.add_argument("--instances", type=int, default=None, help="instances per K (default 10)")
    p.add_argument("--set-seed", type=int, default=0, help="seed of the instance sets (default 0)")
    p.add_argument("--seed", type=int, default=0, help="solver seed (default 0)")
    p.add_argument("--omega", type=float, default=0.5, help="weight omega (default 0.5)")
    p.add_argument("--time-limit", type=float, default=None, help="seconds per solve (default 10)")
    p.add_argument("--solvers", nargs="+", default=list(SOLVERS), help="solvers to compare")
    p.add_argument("--exact", default="dp:10,milp",
                   help="exact reference solvers, NAME[:MAX_K] in order (default dp:10,milp)")
    p.add_argument("--exact-time-limit", type=float, default=120.0,
                   help="seconds per exact reference solve (default 120)")
    p.add_argument("--gtsplib", default=str(DEFAULT_GTSPLIB), help="folder with best_known.csv")
    p.add_argument("--names", nargs="*", default=None,
                   help=f"GTSPLIB instances (default: the samples {' '.join(SAMPLES)})")
    p.add_argument("--no-gtsplib", action="store_true", help="skip GTSPLIB")
    p.add_argument("--csv", default=None, help="also write one row per solve to this CSV file")
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Run the comparison and print the table; returns the exit code."""
    args = build_parser().parse_args(argv)
    if args.quick:
        args.instances = args.instances or 3
        args.time_limit = args.time_limit or 5.0
        if args.names is None:
            args.names = ["11berlin52", "20kroA100", "40d198"]
    if args.names is None:
        args.names = list(SAMPLES)
    args.k = args.k or [4, 7, 10, 20]
    args.instances = args.instances or 10
    args.time_limit = args.time_limit or 10.0
    try:
        unknown = [s for s in args.solvers if s not in solver_names()]
        if unknown:
            raise InputError(f"unknown solver {unknown[0]!r} (valid: {', '.join(solver_names())})")
        runs = generated_runs(args, args.solvers)
        if not args.no_gtsplib:
            runs += gtsplib_runs(args, args.solvers)
    except InputError as e:
        print(f"heuristics: error: {e}", file=sys.stderr)
        return 2
    print(f"omega {args.omega:g} (generated sets), seed {args.seed}, time limit {args.time_limit:g} s "
          f"per solve, {os.cpu_count()} CPU cores")
    print(table(runs, args.solvers))
    if args.csv:
        buf = io.StringIO()
        writer = csv.writer(buf)
        writer.writerow(["group", "instance", "solver", "objective", "gap_percent", "runtime_s",
                         "status", "reference", "reference_kind"])
        for r in runs:
            writer.writerow([r.group, r.instance, r.solver, repr(r.objective),
                             f"{r.gap:.6f}" if math.isfinite(r.gap) else "", f"{r.runtime_s:.4f}",
                             r.status, repr(r.reference), r.reference_kind])
        atomic_write_text(args.csv, buf.getvalue())
    return 0


if __name__ == "__main__":
    sys.exit(main())

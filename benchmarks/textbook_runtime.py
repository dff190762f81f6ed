"""The textbook MILP (``milp-textbook``: DFJ, MTZ, flow) against ``milp`` and ``dp``, K = 4..10.

For each K, the first ``--instances`` instances of the committed set ``instances/uav-K{K}-N20-s1``
(other ``--nodes``: the generated set of that N) are solved at one omega by ``dp``, ``milp`` and
``milp-textbook`` with each subtour form (HiGHS through cvxpy; ``--backend gurobi`` or ``auto``
for Gurobi where it is licensed for the model's size), each under ``--time-limit`` seconds. It
also solves each textbook model's LP relaxation: its bound against the optimum is the root gap
that explains the search time, shown beside ``milp``'s root bound (after its cuts). Prints a
markdown table (median time to proven optimum, proven count; for the unproven, how far the bound
lies below and the tour above the optimum) and the root gaps, and writes one CSV row per solve
to ``--out``. The table in ``docs/solvers/exact.md`` is

    nice -n 10 python benchmarks/textbook_runtime.py --instances 2 --time-limit 60

Timings are wall-clock, of one run on whatever machine runs it.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

from gtsp_bench.solvers.exact.textbook import MilpTextbook, build

from gtsp_bench.bench.tables import write_csv
from gtsp_bench.checks import parse_ks
from gtsp_bench.data.io import read_instance
from gtsp_bench.errors import SolverError
from gtsp_bench.generator import instance_set
from gtsp_bench.problem import price
from gtsp_bench.registry import run_solver

COLUMNS = ("K", "instance", "omega", "solver", "status", "objective", "lower_bound", "runtime_s",
           "root_bound", "backend")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ks", default="4..10")
    ap.add_argument("--instances", type=int, default=2)
    ap.add_argument("--nodes", type=int, default=20, help="N (20: the committed sets, else generated)")
    ap.add_argument("--omega", type=float, default=0.5)
    ap.add_argument("--time-limit", type=float, default=60.0)
    ap.add_argument("--subtours", default="dfj,mtz,flow")
    ap.add_argument("--backend", default="highs", help="highs, gurobi or auto")
    ap.add_argument("--out", default="benchmarks/out/textbook_runtime.csv")
    args = ap.parse_args(argv)
    import cvxpy as cp

    subtours = args.subtours.split(",")
    solvers = ["dp", "milp", *(f"milp-textbook:{s}" for s in subtours)]
    records: list[list[object]] = []
    lines = []
    for k in parse_ks(args.ks):
        if args.nodes == 20:  # the committed sets
            folder = Path("instances") / f"uav-K{k}-N20-s1"
            instances = [read_instance(f) for f in sorted(folder.glob("*.json"))[: args.instances]]
        else:
            instances = instance_set(args.instances, k, 1, n_nodes=args.nodes)
        # per solver: (status, seconds, bound, objective, optimum)
        runs: dict[str, list[tuple[str, float, float | None, float, float]]] = {s: [] for s in solvers}
        root: dict[str, list[float]] = {s: [] for s in ["milp", *subtours]}
        for inst in instances:
            opt = run_solver("dp", inst, args.omega).objective
            for s in solvers:
                solver = (MilpTextbook(subtour=s.split(":")[1], backend=args.backend)
                          if s.startswith("milp-textbook") else s)
                try:
                    r = run_solver(solver, inst, args.omega, time_limit=args.time_limit, name=s)
                except SolverError as e:  # no tour within the limit
                    records.append([k, inst.name, args.omega, s, "failed", "", "", "", "", str(e)])
                    runs[s].append(("failed", args.time_limit, None, float("nan"), opt))
                    print(f"K={k} {inst.name} {s}: failed ({e})", file=sys.stderr, flush=True)
                    continue
                rb = r.stats.get("root_bound")
                if s == "milp":
                    root["milp"].append(100 * (opt - rb) / opt)
                no_tour = r.stats.get("tour") == "greedy"  # the model found none: greedy's is returned
                records.append([k, inst.name, args.omega, s, r.status, repr(r.objective),
                                repr(r.lower_bound), f"{r.runtime_s:.3f}", "" if rb is None else repr(rb),
                                r.stats.get("backend", "") + (" (no tour: greedy)" if no_tour else "")])
                runs[s].append(("failed" if no_tour else r.status, r.runtime_s, r.lower_bound, r.objective,
                                opt))
                print(f"K={k} {inst.name} {s}: {r.status} {r.objective:.4f} bound {r.lower_bound} "
                      f"{r.runtime_s:.2f} s", file=sys.stderr, flush=True)
            problem = price(inst, args.omega)
            for sub in subtours:
                tm = build(problem, sub, relax=True)
                t = time.perf_counter()
                tm.model.solve(solver=cp.HIGHS)
                lp = float(tm.model.value)
                root[sub].append(100 * (opt - lp) / opt)
                records.append([k, inst.name, args.omega, f"lp-relaxation:{sub}", tm.model.status,
                                "", repr(lp), f"{time.perf_counter() - t:.3f}", repr(lp), "highs"])
        cells = []
        for s in solvers:
            proven = [t for st, t, _, _, _ in runs[s] if st == "optimal"]
            cell = f"{statistics.median(proven):.2f} s" if proven else "-"
            cell += f" ({len(proven)}/{len(runs[s])})"
            failed = sum(st == "failed" for st, *_ in runs[s])
            if failed:
                cell += f", {failed} no tour"
            bounds = [100 * (o - lb) / o for st, _, lb, _, o in runs[s] if st != "optimal" and lb is not None]
            tours = [100 * (obj - o) / o for st, _, _, obj, o in runs[s] if st == "time_limit"]
            if bounds:
                cell += f", bound -{statistics.median(bounds):.1f} %"
            if tours:
                cell += f", tour +{statistics.median(tours):.1f} %"
            cells.append(cell)
        gaps = " | ".join(f"{round(statistics.mean(root[s]), 1) + 0.0:.1f} %" for s in root)
        lines.append(f"| {k} | " + " | ".join(cells) + f" | {gaps} |")
    head = ("| K | " + " | ".join(f"`{s}`" for s in solvers) + " | root gap: "
            + " | ".join(["`milp` (after cuts)", *(f"{s} LP" for s in subtours)]) + " |")
    print(head)
    print("|" + "---|" * (1 + len(solvers) + 1 + len(subtours)))
    print("\n".join(lines))
    print(f"\ncells: median time to proven optimum (proven/solved); of the unproven, the median bound "
          "below and tour above the optimum; "
          f"time limit {args.time_limit:g} s, omega {args.omega:g}; root gap: mean (optimum - bound) / "
          "optimum")
    write_csv(args.out, COLUMNS, records)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Quality and speed of the learned policies against the exact optimum (issue 5's targets).

Test sets: ``instance_set(100, K, seed=TEST_SEED)`` for K = 4, 7, 10 (N = 20), never used in
training (training draws from its own seeded stream; validation has its own seed). For each
omega in 0.3 and 0.6 and each learned solver, all 100 instances are solved in one batch; the
script prints the mean and max gap to the exact optimum (the ``dp`` solver, cached in
``benchmarks/drl_exact.csv``) and the batched wall time per instance (median of ``--repeats``
runs). Every solution is re-priced by the shared evaluator. A first reference row, ``bound:
paper heads``, is the best any visiting order can reach when heads follow the paper's rule
(:func:`gtsp_bench.solvers.learned.oracles.paper_rule_optimum`): no policy using that rule can be below it.

    PYTHONPATH=. .venv/bin/python benchmarks/drl.py [--repeats 3] [--k 4,7,10] [--csv out.csv]

Targets (issue 5, greedy decoding, models trained on K = 4 only): paper's ``drl`` K=4 <= 1.5 %,
K=10 <= 5 %; best learned policy K=4 <= 0.3 %, K=7 <= 1 %, K=10 <= 2 %; <= 5 ms per instance
batched at K = 10.
"""

from __future__ import annotations

import argparse
import csv
import sys
import time
from pathlib import Path

import numpy as np
from gtsp_bench.solvers.learned.env import env_from_instances
from gtsp_bench.solvers.learned.oracles import paper_rule_optimum

from gtsp_bench.energy import evaluate
from gtsp_bench.generator import instance_set
from gtsp_bench.io import atomic_write_text
from gtsp_bench.registry import get_solver, run_solver

TEST_SEED = 5_000
OMEGAS = (0.3, 0.6)
CACHE = Path(__file__).resolve().parent / "drl_exact.csv"
#: (label, registered name, options): every learned solver, plus the greedy baseline for scale.
SOLVERS = (
    ("greedy", "greedy", {}),
    ("drl", "drl", {}),
    ("drl heads=optimal", "drl", {"heads": "optimal"}),
    ("drl reverse=true", "drl", {"reverse": True}),
    ("drl-sample (S=64)", "drl-sample", {}),
    ("drl-sample heads=optimal", "drl-sample", {"heads": "optimal"}),
    ("am", "am", {}),
    ("am heads=paper", "am", {"heads": "paper"}),
    ("am augment=true", "am", {"augment": True}),
)


def exact_optima(instances, ks) -> dict[tuple[str, float], float]:
    """Optimum of each (instance, omega) from the cache, solving the missing ones with dp."""
    known: dict[tuple[str, float], float] = {}
    if CACHE.exists():
        with CACHE.open(newline="") as f:
            for row in csv.DictReader(f):
                known[(row["instance"], float(row["omega"]))] = float(row["optimum"])
    missing = [(inst, w) for k in ks for inst in instances[k] for w in OMEGAS
               if (inst.name, w) not in known]
    for i, (inst, w) in enumerate(missing):
        result = run_solver("dp", inst, w)
        assert result.status == "optimal", result.status
        known[(inst.name, w)] = result.objective
        if (i + 1) % 50 == 0 or i + 1 == len(missing):
            print(f"exact optima: {i + 1}/{len(missing)}", file=sys.stderr)
    if missing:
        lines = ["instance,omega,optimum"] + [f"{n},{w},{v!r}" for (n, w), v in sorted(known.items())]
        atomic_write_text(CACHE, "\n".join(lines) + "\n")
    return known


def run(solver, instances, omega: float) -> tuple[np.ndarray, float]:
    """Objectives (re-priced by the evaluator) and wall time of one batched solve."""
    start = time.perf_counter()
    if hasattr(solver, "solve_batch"):
        sols = solver.solve_batch(instances, [omega] * len(instances))
    else:
        sols = [solver.solve(inst, omega) for inst in instances]
    wall = time.perf_counter() - start
    objs = np.array([evaluate(inst, omega, s.order, s.heads).objective
                     for inst, s in zip(instances, sols, strict=True)])
    return objs, wall


def main(argv: list[str] | None = None) -> int:
    """Print the table; optionally write it as CSV."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--k", default="4,7,10", help="cluster counts (default: 4,7,10)")
    parser.add_argument("--instances", type=int, default=100,
                        help="instances per K, the first ones of each test set (default: 100)")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per cell (median)")
    parser.add_argument("--only", help="comma-separated solver labels' prefixes to run (default: all)")
    parser.add_argument("--csv", help="also write the rows here")
    args = parser.parse_args(argv)
    ks = [int(k) for k in args.k.split(",")]
    if args.instances < 1 or args.repeats < 1:
        parser.error("--instances and --repeats must be >= 1")
    instances = {k: instance_set(args.instances, k, TEST_SEED) for k in ks}
    opt = exact_optima(instances, ks)
    rows = []
    bound = {}
    for k in ks:
        for w in OMEGAS:
            env = env_from_instances(instances[k], [w] * len(instances[k]))
            bound[(k, w)] = np.concatenate([paper_rule_optimum(env.rows(i, i + 20)).numpy()
                                            for i in range(0, len(instances[k]), 20)])
    header = f"{'solver':<26} {'K':>3} {'omega':>5} {'mean gap %':>10} {'max gap %':>9} {'ms/inst':>8}"
    print(header)
    print("-" * len(header))
    for k in ks:
        for w in OMEGAS:
            best = np.array([opt[(inst.name, w)] for inst in instances[k]])
            gap = (bound[(k, w)] / best - 1) * 100
            rows.append({"solver": "bound: paper heads", "K": k, "omega": w,
                         "mean_gap_pct": gap.mean(), "max_gap_pct": gap.max(),
                         "ms_per_instance": float("nan")})
            print(f"{'bound: paper heads':<26} {k:>3} {w:>5g} {gap.mean():>10.3f} {gap.max():>9.3f} "
                  f"{'-':>8}", flush=True)
    chosen = [s for s in SOLVERS if not args.only
              or any(s[0].startswith(p) for p in args.only.split(","))]
    for label, name, options in chosen:
        solver = get_solver(name, **options)
        for k in ks:
            for w in OMEGAS:
                best = np.array([opt[(inst.name, w)] for inst in instances[k]])
                times = []
                for _ in range(args.repeats):
                    objs, wall = run(solver, instances[k], w)
                    times.append(wall)
                gap = (objs / best - 1) * 100
                assert gap.min() > -1e-7, f"{label} below the optimum: a bug"
                ms = 1000 * float(np.median(times)) / len(instances[k])
                rows.append({"solver": label, "K": k, "omega": w, "mean_gap_pct": gap.mean(),
                             "max_gap_pct": gap.max(), "ms_per_instance": ms})
                print(f"{label:<26} {k:>3} {w:>5g} {gap.mean():>10.3f} {gap.max():>9.3f} {ms:>8.2f}",
                      flush=True)
    if args.csv:
        lines = ["solver,K,omega,mean_gap_pct,max_gap_pct,ms_per_instance"] + [
            f"{r['solver']},{r['K']},{r['omega']},{r['mean_gap_pct']:.4f},{r['max_gap_pct']:.4f},"
            f"{r['ms_per_instance']:.3f}" for r in rows]
        atomic_write_text(args.csv, "\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

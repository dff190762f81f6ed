"""The learned policies from K = 4 to 200: mean gap and batched time per instance, per K.

``make bench-learned`` (``python -m gtsp_bench.bench.learned_table``) runs every learned solver
(:data:`SOLVERS`, with the paper's greedy rule as the baseline) with its defaults on

* K = 4, 7, 10: the learned suite's test sets (``instance_set(n, K, 5000)``, N = 20, 1000 m
  area), against the exact optimum (``dp``, cached in ``benchmarks/drl_exact.csv`` as the
  learned suite does);
* K = 20, 50, 100, 200: the committed sets ``instances/uav-K{K}-N20-s1``, against the rows their
  ``reference.csv`` holds (proven optima at K = 20 where ``milp`` proved them, otherwise the
  best tour known); instances without a row at an omega are left out of that cell, and the
  table says how many instances each K used.

Omega 0.3 and 0.6 by default. All instances of one (K, omega) are solved in one batch
(``solve_batch``), and the time per instance is that batch's wall time over its size; every tour
is re-priced by :func:`gtsp_bench.energy.evaluate`. The table goes to stdout (the mean over both
omegas per K), one CSV row per (solver, K, omega) to ``--csv`` (default
``benchmarks/out/learned-table.csv``). Timings are wall-clock, of one run on whatever machine
runs it.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from gtsp_bench.bench.suites import DEFAULT_CACHE, SUITES
from gtsp_bench.bench.tables import median_wall, write_csv
from gtsp_bench.checks import arg_int, check_int, parse_ks, parse_names, parse_omegas
from gtsp_bench.errors import InputError, OneLineParser
from gtsp_bench.generator import instance_set
from gtsp_bench.instance import Instance

#: Solvers of the table, in row order (registered names; greedy is the paper's baseline rule).
SOLVERS = ("greedy", "drl", "am", "local")
#: K of the learned suite's generated test sets (exact optima) and of the committed sets.
SMALL_KS = (4, 7, 10)
LARGE_KS = (20, 50, 100, 200)
#: Instance-set seed of the small test sets: the learned suite's own.
SMALL_SEED = SUITES["learned"].set_seed
DEFAULT_CSV = Path("benchmarks") / "out" / "learned-table.csv"
COLUMNS = ("solver", "K", "omega", "instances", "mean_gap_pct", "max_gap_pct", "ms_per_instance",
           "reference")


@dataclass(frozen=True)
class Cell:
    """The instances of one (K, omega) and their reference objectives."""

    k: int
    omega: float
    instances: tuple[Instance, ...]
    reference: np.ndarray
    kind: str


def small_cells(ks: Sequence[int], n: int, omegas: Sequence[float], cache: Path) -> list[Cell]:
    """Cells of the generated test sets against their exact optima (solved by dp if missing)."""
    from gtsp_bench.bench.suites import exact_optima

    sets = {k: instance_set(n, k, SMALL_SEED) for k in ks}
    opt = exact_optima(cache, sets, omegas)
    return [Cell(k, w, tuple(sets[k]), np.array([opt[(i.name, w)] for i in sets[k]]), "optimum")
            for k in ks for w in omegas]


def large_cells(ks: Sequence[int], omegas: Sequence[float], instance_dir: Path) -> list[Cell]:
    """Cells of the committed sets ``uav-K{K}-N20-s1``: the instances with a reference row."""
    from gtsp_bench.data.sets import read_set_file, uav_set

    cells = []
    for k in ks:
        s = uav_set(k, instance_dir)
        loaded = {f.stem: read_set_file(f)[0] for f in s.files}
        for w in omegas:
            rows = [(loaded[stem], r) for (stem, om), r in sorted(s.references.items())
                    if om is not None and math.isclose(om, w) and stem in loaded]
            if not rows:
                continue
            kinds = {r.status for _, r in rows}
            cells.append(Cell(k, w, tuple(i for i, _ in rows), np.array([r.value for _, r in rows]),
                              "optimum" if kinds == {"optimal"} else "best known"))
    return cells


def run_cell(solver: Any, cell: Cell, repeats: int = 1) -> tuple[np.ndarray, float]:
    """Gaps (%) of one batched solve of the cell, and its wall time per instance (ms)."""
    from gtsp_bench.energy import evaluate

    insts = list(cell.instances)
    sols, wall = median_wall(lambda: solver.solve_batch(insts, [cell.omega] * len(insts))
                             if hasattr(solver, "solve_batch")
                             else [solver.solve(i, cell.omega) for i in insts], repeats)
    objs = np.array([evaluate(i, cell.omega, s.order, s.heads).objective
                     for i, s in zip(insts, sols, strict=True)])
    return (objs / cell.reference - 1) * 100, 1000 * wall / len(insts)


def table(results: dict[tuple[str, int], list[tuple[np.ndarray, float]]], solvers: Sequence[str],
          ks: Sequence[int], counts: dict[int, int]) -> str:
    """The text table: one line per solver, a ``gap % / ms`` cell per K (means over omegas)."""
    width = 18
    head = f"{'solver':<8}" + "".join(f"{f'K={k} (n={counts.get(k, 0)})':>{width}}" for k in ks)
    lines = [head, "-" * len(head)]
    for name in solvers:
        cells = []
        for k in ks:
            got = results.get((name, k))
            if not got:
                cells.append(f"{'-':>{width}}")
                continue
            gap = float(np.mean(np.concatenate([g for g, _ in got])))
            ms = float(np.mean([m for _, m in got]))
            cells.append(f"{f'{gap:.2f}% {ms:.1f}ms':>{width}}")
        lines.append(f"{name:<8}" + "".join(cells))
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m gtsp_bench.bench.learned_table``."""
    p = OneLineParser(prog="python -m gtsp_bench.bench.learned_table",
                                description="learned policies: mean gap and ms per instance, K = 4..200")
    p.add_argument("--solvers", default=",".join(SOLVERS), help="comma-separated registered names")
    p.add_argument("--clusters", "-K", default="4,7,10,20,50,100,200",
                   help=f"K values: {SMALL_KS} use generated sets, {LARGE_KS} the committed ones")
    p.add_argument("--omegas", default="0.3,0.6", help="omega values (default 0.3,0.6)")
    p.add_argument("--instances", type=arg_int, default=100, help="instances per small K (default 100)")
    p.add_argument("--repeats", type=arg_int, default=1, help="batched solves per cell; the median time")
    p.add_argument("--cache", default=str(DEFAULT_CACHE), help="exact optima of the small sets")
    p.add_argument("--instance-dir", default="instances", help="where the committed sets are")
    p.add_argument("--csv", default=str(DEFAULT_CSV), help="CSV of the rows")
    args = p.parse_args(argv)
    try:
        from gtsp_bench.registry import get_solver, solver_names

        solvers = parse_names(args.solvers, "solver", solver_names())
        if not solvers:
            raise InputError("no solver given")
        ks = parse_ks(args.clusters)
        bad = [k for k in ks if k not in SMALL_KS + LARGE_KS]
        if bad:
            raise InputError(f"--clusters: no test set for K = {bad[0]} (valid: {SMALL_KS + LARGE_KS})")
        omegas = parse_omegas(args.omegas)
        n = check_int("--instances", args.instances, 1)
        repeats = check_int("--repeats", args.repeats, 1)
        cells = (small_cells([k for k in ks if k in SMALL_KS], n, omegas, Path(args.cache))
                 + large_cells([k for k in ks if k in LARGE_KS], omegas, Path(args.instance_dir)))
        built = {name: get_solver(name) for name in solvers}
    except InputError as e:
        print(f"gtsp-bench: error: {e}", file=sys.stderr)
        return 2
    counts = {k: max((len(c.instances) for c in cells if c.k == k), default=0) for k in ks}
    results: dict[tuple[str, int], list[tuple[np.ndarray, float]]] = {}
    records = []
    for name, solver in built.items():
        for cell in cells:
            gap, ms = run_cell(solver, cell, repeats)
            results.setdefault((name, cell.k), []).append((gap, ms))
            records.append([name, cell.k, cell.omega, len(gap), f"{gap.mean():.4f}", f"{gap.max():.4f}",
                            f"{ms:.3f}", cell.kind])
            print(f"{name} K={cell.k} omega={cell.omega:g}: {gap.mean():.2f} % ({ms:.1f} ms/inst)",
                  file=sys.stderr, flush=True)
    print("mean gap to the reference (K <= 20 where proven: optimum; else best known) / ms per "
          "instance, omega " + ", ".join(f"{w:g}" for w in omegas))
    print(table(results, solvers, ks, counts))
    write_csv(args.csv, COLUMNS, records)
    print(f"rows: {args.csv}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

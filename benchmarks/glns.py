"""lns against GLNS on GTSPLIB: per-instance gaps, hits and worst runs next to GLNS's.

Default mode: the 45 instances of ``instances/gtsplib/glns-45.csv`` (31-217 clusters, 5 of them
asymmetric), each run
``--seeds`` times with a budget of ``--factor`` times GLNS's (Julia) mean seconds there; prints a
table beside GLNS's numbers and the three target lines (mean gap, instances whose best known was
hit at least once, worst run), and writes one CSV row per run.

``--large``: the symmetric GTSPLIB instances of 1,000 to 15,112 nodes (or ``--names``), ``--time``
seconds each (60 by default), the gap to GLKH's best known tour. Above 400 clusters a
time-limited lns runs on two threads where two cores are free (its default ``workers``); with
``--jobs J`` each run gets ``cores // J`` threads unless ``--set workers=N`` says otherwise, and the
CSV's ``workers`` column says what ran.

Run from the repository root, e.g. ``.venv/bin/python benchmarks/glns.py --seeds 3 --jobs 2``;
``--first-seed 4 --seeds 3 --with benchmarks/out/glns.csv --out other.csv`` adds seeds 4-6 to an
earlier run's summary (``make bench-glns``). The first run on a machine compiles the numba kernels
(about a minute).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import sys
import time
from multiprocessing import get_context
from pathlib import Path

from gtsp_bench.data import gtsplib
from gtsp_bench.registry import get_solver, run_solver

GLNS_CSV = gtsplib.folder() / "glns-45.csv"
COLUMNS = ("instance", "seed", "budget_s", "objective", "best_known", "gap_pct", "runtime_s",
           "status", "iterations", "trials", "best_at", "workers")


def glns_rows() -> dict[str, dict[str, str]]:
    """GLNS's published numbers by instance (``glns-45.csv``)."""
    with open(GLNS_CSV, newline="") as f:
        return {row["instance"]: row for row in csv.DictReader(f)}


def large_names(low: int = 1000, high: int = 15112) -> list[str]:
    """Symmetric GTSPLIB instances of ``low`` to ``high`` nodes, smallest first."""
    refs = [r for r in gtsplib.best_known().values()
            if low <= r.nodes <= high and r.type == "GTSP"]
    return [r.name for r in sorted(refs, key=lambda r: (r.nodes, r.name))]


def parse_option(text: str) -> tuple[str, object]:
    """``KEY=VALUE`` with VALUE as JSON (numbers, true/false), else as a string."""
    key, sep, value = text.partition("=")
    if not sep:
        raise argparse.ArgumentTypeError(f"expected KEY=VALUE, got {text!r}")
    try:
        return key, json.loads(value)
    except json.JSONDecodeError:
        return key, value


def solve(task: tuple[str, int, float, dict]) -> dict[str, object]:
    """One run: (instance name, seed, budget in seconds, solver options) -> a CSV row."""
    name, seed, budget, options = task
    inst = gtsplib.read(name)
    best = gtsplib.best_known()[name].value
    solver = get_solver("lns", **options)  # loads the compiled kernels: not part of the budget
    r = run_solver(solver, inst, None, seed=seed, time_limit=budget)
    return {"instance": name, "seed": seed, "budget_s": round(budget, 3), "objective": r.objective,
            "best_known": best, "gap_pct": 100.0 * (r.objective - best) / best,
            "runtime_s": round(r.runtime_s, 3), "status": r.status,
            "iterations": r.stats.get("iterations"), "trials": r.stats.get("trials"),
            "best_at": r.stats.get("best_at"), "workers": r.stats.get("workers", 1)}


def write_csv(rows: list[dict[str, object]], path: Path) -> None:
    """Write the rows atomically."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(path.suffix + ".tmp")
    with open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        w.writerows(rows)
    os.replace(tmp, path)


def summarise(rows: list[dict[str, object]], names: list[str], glns: dict[str, dict[str, str]] | None,
              seeds: int) -> list[str]:
    """The per-instance table and the target lines."""
    lines = []
    head = f"{'instance':<12} {'budget_s':>8} {'mean_gap%':>9} {'hits':>5} {'worst%':>7}"
    if glns is not None:
        head += f"  {'glns_gap%':>9} {'glns_hits':>9} {'glns_s':>7}"
    lines.append(head)
    means, worsts, hit_any = [], [], 0
    for name in names:
        gaps = [float(r["gap_pct"]) for r in rows if r["instance"] == name]
        if not gaps:
            continue
        hits = sum(g <= 1e-9 for g in gaps)
        hit_any += hits > 0
        mean, worst = sum(gaps) / len(gaps), max(gaps)
        means.append(mean)
        worsts.append(worst)
        budget = next(float(r["budget_s"]) for r in rows if r["instance"] == name)
        line = f"{name:<12} {budget:>8.2f} {mean:>9.4f} {hits:>2}/{len(gaps):<2} {worst:>7.3f}"
        if glns is not None:
            g = glns[name]
            line += (f"  {float(g['glns_julia_mean_gap_pct']):>9.4f} {g['glns_julia_hits10']:>6}/10"
                     f" {float(g['glns_julia_mean_s']):>7.3f}")
        lines.append(line)
    if means:
        lines.append(f"mean gap: {sum(means) / len(means):.4f} % over {len(means)} instances x {seeds} seeds"
                     + (" (GLNS 0.048 %, target <= 0.04 %)" if glns is not None else ""))
        lines.append(f"instances hit: {hit_any} of {len(means)}"
                     + (" (target >= 43 of 45)" if glns is not None else ""))
        lines.append(f"worst run: {max(worsts):.4f} %" + (" (target <= 0.5 %)" if glns is not None else ""))
    return lines


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--factor", type=float, default=2.0,
                   help="budget = FACTOR x GLNS's mean seconds on the instance (default 2)")
    p.add_argument("--seeds", type=int, default=10, help="seeds 1..SEEDS per instance (default 10)")
    p.add_argument("--first-seed", type=int, default=1,
                   help="start the seeds here: FIRST..FIRST+SEEDS-1 (default 1)")
    p.add_argument("--with", dest="earlier", action="append", type=Path, default=[], metavar="CSV",
                   help="rows of an earlier run (e.g. other seeds) to summarise with this one's")
    p.add_argument("--names", help="comma-separated instance names (default: all of the mode)")
    p.add_argument("--jobs", type=int, default=1, help="parallel worker processes (default 1)")
    p.add_argument("--large", action="store_true",
                   help="the 1,000-15,112-node instances, --time seconds each, gap to GLKH's tour")
    p.add_argument("--time", type=float, default=60.0, help="seconds per run with --large (default 60)")
    p.add_argument("--set", dest="options", action="append", type=parse_option, default=[],
                   metavar="KEY=VALUE", help="an lns option (repeatable), e.g. --set remove_fraction=0.2")
    p.add_argument("--out", type=Path, help="CSV of the runs (default benchmarks/out/glns[-large].csv)")
    args = p.parse_args(argv)
    if args.seeds < 1 or args.jobs < 1 or args.first_seed < 0 or args.factor <= 0 or args.time <= 0:
        p.error("--seeds and --jobs must be >= 1, --first-seed >= 0, --factor and --time > 0")
    earlier: list[dict[str, object]] = []
    for path in args.earlier:
        try:
            with open(path, newline="") as f:
                earlier += list(csv.DictReader(f))
        except OSError as e:
            p.error(f"{path}: {e.strerror}")
    glns = None if args.large else glns_rows()
    known = gtsplib.best_known()
    names = args.names.split(",") if args.names else (large_names() if args.large else list(glns))
    for name in names:
        if name not in known or (glns is not None and name not in glns):
            p.error(f"unknown instance {name!r}" + ("" if args.large else " (not in glns-45.csv)"))
    options = dict(args.options)
    if args.jobs > 1:  # jobs x lns threads <= cores (a single job: lns's default, 2 where free)
        options.setdefault("workers", max(1, (os.cpu_count() or 1) // args.jobs))
    get_solver("lns", **options)  # bad options fail here, once
    tasks = []
    for name in names:
        budget = args.time if args.large else args.factor * float(glns[name]["glns_julia_mean_s"])
        tasks += [(name, seed, budget, options)
                  for seed in range(args.first_seed, args.first_seed + args.seeds)]
    out = args.out or Path("benchmarks/out") / ("glns-large.csv" if args.large else "glns.csv")
    rows: list[dict[str, object]] = []
    t0 = time.perf_counter()
    with get_context("spawn").Pool(args.jobs) as pool:
        for row in pool.imap(solve, tasks):
            rows.append(row)
            print(f"{row['instance']:<12} seed {row['seed']:>2} gap {float(row['gap_pct']):7.3f} % "
                  f"({row['iterations']} iterations, {row['runtime_s']} s)", file=sys.stderr, flush=True)
            write_csv(rows, out)
    both = earlier + rows
    runs = max((sum(r["instance"] == n for r in both) for n in names), default=0)
    print("\n".join(summarise(both, names, glns, runs)))
    print(f"{len(rows)} runs in {time.perf_counter() - t0:.0f} s, rows in {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

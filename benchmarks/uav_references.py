"""Generate the committed UAV instance sets and compute their reference values.

Two sub-commands:

``generate``
    Write ``instances/uav-K{K}-N{N}-s{seed}/uav-K{K}-N{N}-s{seed}-{i:03d}.json`` for
    i = 0 .. n-1 from :func:`gtsp_bench.generator.instance_set` (the runner's code path), with the
    area given; files already there must hold exactly what the generator gives (else an error).

``solve``
    Fill ``reference.csv`` in a set folder: one row per (instance, omega), header
    ``instance,omega,value,lower_bound,status,source,date``. Each row's solvers follow a plan
    (by K; see ``PLANS``), every answer goes through the JSON the CLI prints and is re-priced with
    the shared evaluator before it is kept; the best value is kept with its true source, the
    highest lower bound any solver proved with it. ``optimal`` rows are proven (dp, or milp to its
    ``abs_gap``), ``best_known`` rows are not. Rows already present are skipped, and the file is
    rewritten atomically after every row, so the batch can be stopped and resumed.

Examples
--------
``python benchmarks/uav_references.py generate --clusters 50 --area 1500``
``nice -n 10 python benchmarks/uav_references.py solve instances/uav-K50-N20-s1 --first 0 --last 9``
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import math
import re
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from gtsp_bench.data.io import atomic_write_text, read_instance
from gtsp_bench.data.parse import format_json_instance
from gtsp_bench.data.sets import ReferenceRow, read_reference, write_reference
from gtsp_bench.energy import evaluate
from gtsp_bench.errors import InputError
from gtsp_bench.generator import DEFAULT_AREA, DEFAULT_NODES, DEFAULT_ZETA, instance_set
from gtsp_bench.registry import get_solver, run_solver

STATUSES = ("optimal", "best_known")
#: The omegas of the paper's experiments (gtsp_bench.bench.runner): 0.5 at every K, 0 .. 0.9 at 4 and 7.
PAPER_OMEGAS = {k: (0.5,) for k in range(5, 11)} | {
    k: tuple(round(0.1 * i, 1) for i in range(10)) for k in (4, 7)}
LARGE_OMEGAS = (0.3, 0.5, 0.6)
#: Seed of the (seeded, time-limited) heuristic runs.
SEED = 0


@dataclass(frozen=True)
class Step:
    """One solver run of a plan: the solver and its time limit in seconds."""

    solver: str
    time_limit: float

    @property
    def source(self) -> str:
        """What the reference.csv ``source`` column says of a value found by this run."""
        if self.solver == "dp":
            return "dp"
        if self.solver == "lns":
            return f"lns {self.time_limit:g}s seed {SEED}"
        return f"{self.solver} {self.time_limit:g}s"


#: Solver runs per K (K <= 10: dp alone). The best re-priced value of the runs is kept.
PLANS: dict[int, tuple[Step, ...]] = {
    20: (Step("milp", 60), Step("lns", 10)),
    50: (Step("lns", 20), Step("milp", 60)),
    100: (Step("lns", 30),),
    200: (Step("lns", 40),),
}


def plan_for(k: int) -> tuple[Step, ...]:
    """The solver runs for K clusters."""
    if k <= 10:
        return (Step("dp", 3600),)
    if k not in PLANS:
        raise InputError(f"no reference plan for K = {k} (valid: <= 10, {', '.join(map(str, PLANS))})")
    return PLANS[k]


# ---------------------------------------------------------------------- solving
@dataclass(frozen=True)
class Answer:
    """One re-priced solver answer."""

    step: Step
    value: float
    lower_bound: float | None
    proven: bool


def solve_once(instance, omega: float, step: Step) -> Answer:
    """Run one solver as ``gtsp-bench solve --json`` does, then re-price its tour."""
    result = run_solver(get_solver(step.solver), instance, omega, time_limit=step.time_limit,
                        seed=SEED, name=step.solver)
    d = json.loads(json.dumps(result.to_dict()))  # exactly what the CLI prints
    ev = evaluate(instance, omega, d["order"], d["heads"])
    if ev.objective != d["objective"]:
        raise RuntimeError(f"{instance.name} omega {omega}: {step.solver} reports {d['objective']!r}, "
                           f"the evaluator prices its tour at {ev.objective!r}")
    lb = d.get("lower_bound")
    return Answer(step, ev.objective, None if lb is None else float(lb), d["status"] == "optimal")


def reference_row(instance, omega: float, steps: tuple[Step, ...], date: str) -> ReferenceRow:
    """The reference row of one (instance, omega): the best value of the plan's runs."""
    answers = [solve_once(instance, omega, s) for s in steps]
    best = min(answers, key=lambda a: (a.value, not a.proven))
    for a in answers:
        if a.proven and best.value < a.value - 1e-6 * max(1.0, abs(a.value)):
            raise RuntimeError(f"{instance.name} omega {omega}: {best.step.source} found "
                               f"{best.value!r} below {a.step.source}'s proven optimum {a.value!r}")
    bounds = [a.lower_bound for a in answers if a.lower_bound is not None and math.isfinite(a.lower_bound)]
    lb = min(max(bounds), best.value) if bounds else None  # a bound above the value is float noise
    return ReferenceRow(instance.name, float(omega), best.value, lb,
                        "optimal" if best.proven else "best_known", best.step.source, date)


_SET = re.compile(r"uav-K(\d+)-N(\d+)-s(\d+)$")


def cmd_solve(args: argparse.Namespace) -> int:
    folder = Path(args.folder)
    m = _SET.match(folder.name)
    if not m or not folder.is_dir():
        raise InputError(f"{folder}: not a set folder uav-K{{K}}-N{{N}}-s{{seed}}")
    k = int(m.group(1))
    steps = plan_for(k)
    omegas = tuple(args.omega) if args.omega else PAPER_OMEGAS.get(k, LARGE_OMEGAS)
    out = folder / "reference.csv"
    rows = read_reference(out) if out.exists() else {}
    done = set(rows)
    files = sorted(folder.glob(f"{folder.name}-*.json"))
    last = len(files) - 1 if args.last is None else args.last
    todo = [(p, w) for p in files if args.first <= int(p.stem.rsplit("-", 1)[1]) <= last
            for w in omegas if (p.stem, w) not in done]
    date = dt.datetime.now(dt.UTC).date().isoformat()
    print(f"{folder.name}: {len(todo)} rows to compute ({', '.join(s.source for s in steps)})",
          flush=True)
    start = time.perf_counter()
    for path, omega in todo:
        t = time.perf_counter()
        row = reference_row(read_instance(path), omega, steps, date)
        rows[(row.instance, row.omega)] = row
        write_reference(out, sorted(rows.values(), key=lambda r: (r.instance, r.omega)))  # atomic
        lb = "-" if row.lower_bound is None else repr(row.lower_bound)
        print(f"{row.instance} w={row.omega!r}: {row.value!r} {row.status} ({row.source}; lb {lb}) "
              f"{time.perf_counter() - t:.1f}s", flush=True)
    print(f"{folder.name}: done in {time.perf_counter() - start:.0f}s", flush=True)
    return 0


# ---------------------------------------------------------------------- generating
def cmd_generate(args: argparse.Namespace) -> int:
    insts = instance_set(args.instances, args.clusters, args.seed, args.nodes, zeta=args.zeta,
                         area=args.area)
    folder = Path(args.out) / f"uav-K{args.clusters}-N{args.nodes}-s{args.seed}"
    folder.mkdir(parents=True, exist_ok=True)
    for inst in insts:
        path = folder / f"{inst.name}.json"
        text = format_json_instance(inst)
        if path.exists():
            if path.read_text(encoding="utf-8") != text:
                raise InputError(f"{path}: differs from what the generator gives; move it away")
            continue
        atomic_write_text(path, text)
    print(f"{folder}: {len(insts)} instances", flush=True)
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True)
    g = sub.add_parser("generate", help="write a seeded UAV set (gtsp_bench.generator.instance_set)")
    g.add_argument("--clusters", "-k", type=int, required=True, help="K")
    g.add_argument("--area", type=float, default=DEFAULT_AREA, help="side of the square area in m "
                   "(default: %(default)g; the base station is at (area/2, 0))")
    g.add_argument("--instances", type=int, default=20, help="instances 0 .. n-1 (default: 20)")
    g.add_argument("--nodes", type=int, default=DEFAULT_NODES, help="N (default: %(default)s)")
    g.add_argument("--seed", type=int, default=1, help="set seed (default: 1)")
    g.add_argument("--zeta", type=float, default=DEFAULT_ZETA, help="half-width in m (default: 50)")
    g.add_argument("--out", default="instances", help="parent folder (default: instances)")
    g.set_defaults(func=cmd_generate)
    s = sub.add_parser("solve", help="fill FOLDER/reference.csv (resumable)")
    s.add_argument("folder", help="a set folder instances/uav-K{K}-N{N}-s{seed}")
    s.add_argument("--omega", type=float, nargs="+",
                   help="omegas (default: the paper's for K <= 10, else 0.3 0.5 0.6)")
    s.add_argument("--first", type=int, default=0, help="first instance index (default: 0)")
    s.add_argument("--last", type=int, help="last instance index (default: all)")
    s.set_defaults(func=cmd_solve)
    return p


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except InputError as e:
        print(f"uav_references: error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())

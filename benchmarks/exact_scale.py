"""Exact at scale: ``milp`` on GTSPLIB and on large generated UAV instances.

One line per solve, printed as it finishes (instance, proven or not, time, objective, bound, gap),
then a summary per group (proven count and median time to proof) and, with ``--csv``, the rows.

    python benchmarks/exact_scale.py --time-limit 120                     # GTSPLIB <= 442 nodes
    python benchmarks/exact_scale.py --gtsplib none --uav 20,50 --time-limit 600
    python benchmarks/exact_scale.py --gtsplib large --time-limit 3600    # 493-1,084 nodes

GTSPLIB: the symmetric instances (``small``: the 63 with at most 442 nodes, whose optima are
proven in the literature; ``large``: the 20 of 493-1,084 nodes; ``all``; ``none``; or a
comma-separated list of names). UAV: ``gtsp-bench generate``'s instances, N = 20 nodes per
cluster, zeta = 50 m, area 1000 m (2000 m from K = 100 on), depot at the middle of the bottom
edge, seeds ``--seeds``, each at every omega of ``--omegas``.

The gap is ``(objective - bound) / objective``; a proven optimum has gap 0. ``time s`` is the
solve's wall time, ``cpu s`` the process's CPU time over it (on a shared machine the two differ).
For GTSPLIB the best known value is shown and ``match`` says whether the objective equals it
(``BETTER`` below it).

The CSV is rewritten after every solve and doubles as the run's progress: a run with the same
solver, time limit and solver seed keeps the rows already there (``kept`` after the line) and
solves only the missing ones, so a long sweep (``--gtsplib large --time-limit 3600``: up to
20 hours) can be stopped and resumed; ``--redo`` solves everything again.
"""

from __future__ import annotations

import argparse
import csv
import statistics
import sys
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

from gtsp_bench.bench.tables import Row, solve, write_csv
from gtsp_bench.data import gtsplib
from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance
from gtsp_bench.instance import Instance

#: Node counts of the two GTSPLIB groups (symmetric instances only).
SMALL_NODES, LARGE_NODES = 442, 1084
COLUMNS = ("group", "instance", "clusters", "nodes", "omega", "status", "objective", "lower_bound",
           "gap_percent", "runtime_s", "cpu_s", "best_known", "match", "solver", "time_limit_s",
           "solver_seed")
#: A solve's identity in the CSV: group, instance name, omega ("" for GTSPLIB).
Key = tuple[str, str, str]


@dataclass(frozen=True)
class Job:
    """One solve to run: its group, name (GTSPLIB's, not the file's ``NAME``), instance, omega and
    (GTSPLIB) best-known value."""

    group: str
    name: str
    instance: Instance
    omega: float | None
    best: float | None = None


def gtsplib_names(which: str) -> list[str]:
    """Symmetric GTSPLIB instances: ``small``, ``large``, ``all``, ``none`` or a list of names."""
    refs = [r for r in gtsplib.best_known().values() if r.type == "GTSP"]
    refs.sort(key=lambda r: (r.nodes, r.name))
    if which == "none":
        return []
    if which in ("small", "large", "all"):
        lo, hi = {"small": (0, SMALL_NODES), "large": (SMALL_NODES + 1, LARGE_NODES),
                  "all": (0, LARGE_NODES)}[which]
        return [r.name for r in refs if lo <= r.nodes <= hi]
    return [name.strip() for name in which.split(",") if name.strip()]


def uav_instance(k: int, seed: int) -> Instance:
    """The generated UAV instance of K clusters (N = 20) and this seed."""
    area = 1000.0 if k < 100 else 2000.0
    return generate_instance(k, 20, seed, area=area, depot=(area / 2, 0.0))


def jobs(args: argparse.Namespace) -> Iterator[Job]:
    """The solves asked for, GTSPLIB first (by size), then UAV by K, seed and omega."""
    refs = gtsplib.best_known()
    for name in gtsplib_names(args.gtsplib):
        yield Job("GTSPLIB", name, gtsplib.read(name), None, refs[name].value)
    for k in args.uav:
        for seed in args.seeds:
            inst = uav_instance(k, seed)
            for omega in args.omegas:
                yield Job(f"UAV K={k}", inst.name, inst, omega)


def gap_percent(row: Row) -> float:
    """``(objective - bound) / objective`` in percent (``nan`` without a bound)."""
    if row.lower_bound is None or row.objective is None:
        return float("nan")
    return 100.0 * (row.objective - row.lower_bound) / max(abs(row.objective), 1e-12)


def match(row: Row, best: float | None) -> str:
    """``yes``, ``no`` or ``BETTER``: the objective against the best-known value."""
    if best is None:
        return ""
    return "yes" if row.objective == best else ("BETTER" if row.objective < best else "no")


def line(job: Job, row: Row, cpu: float) -> str:
    """One table line (``cpu``: the process's CPU seconds during the solve)."""
    proven = "yes" if row.status == "optimal" else row.status
    omega = "" if job.omega is None else f"{job.omega:g}"
    best = "" if job.best is None else f"{job.best:.0f}"
    return (f"{job.name:<16} {job.instance.n_clusters:>4} {job.instance.n_nodes:>5} {omega:>5} "
            f"{proven:>10} {row.runtime_s:>8.1f} {cpu:>7.1f} {row.objective:>12.2f} {row.lower_bound:>12.2f} "
            f"{gap_percent(row):>7.3f} {best:>8} {match(row, job.best):>6}")


HEADER = (f"{'instance':<16} {'K':>4} {'n':>5} {'omega':>5} {'proven':>10} {'time s':>8} {'cpu s':>7} "
          f"{'objective':>12} {'bound':>12} {'gap %':>7} {'best':>8} {'match':>6}")


def summary(done: Sequence[tuple[Job, Row]]) -> list[str]:
    """Per group: instances, proven, median time to proof, largest gap left."""
    out = []
    for group in dict.fromkeys(j.group for j, _ in done):
        rows = [r for j, r in done if j.group == group]
        proven = [r.runtime_s for r in rows if r.status == "optimal"]
        med = f"{statistics.median(proven):.1f} s" if proven else "-"
        worst = max(gap_percent(r) for r in rows)
        out.append(f"{group}: {len(proven)}/{len(rows)} proven, median time to proof {med}, "
                   f"largest gap {worst:.3f} %")
    return out


def _key(job: Job) -> Key:
    return job.group, job.name, "" if job.omega is None else repr(job.omega)


def record(job: Job, row: Row, cpu: float, args: argparse.Namespace) -> list[object]:
    """The CSV line of one solve (with the settings a resumed run must share)."""
    return [job.group, job.name, job.instance.n_clusters, job.instance.n_nodes,
            "" if job.omega is None else job.omega, row.status, repr(row.objective),
            repr(row.lower_bound), f"{gap_percent(row):.4f}", f"{row.runtime_s:.2f}", f"{cpu:.2f}",
            "" if job.best is None else job.best, match(row, job.best), args.solver,
            repr(float(args.time_limit)), args.solver_seed]


def _settings(args: argparse.Namespace) -> tuple[str, float, int]:
    return args.solver, float(args.time_limit), args.solver_seed


@dataclass(frozen=True)
class Line:
    """One line of a CSV this benchmark wrote: its text fields, and parsed, the solve's key, the
    settings it ran with, the row and its CPU seconds."""

    fields: dict[str, str]
    key: Key
    settings: tuple[str, float, int]
    row: Row
    cpu_s: float


def _line(r: dict[str, str]) -> Line:
    omega = None if r["omega"] == "" else float(r["omega"])
    row = Row(r["group"], r["instance"], omega, r["solver"], r["status"], float(r["objective"]),
              float(r["lower_bound"]), float(r["runtime_s"]))
    key = (r["group"], r["instance"], "" if omega is None else repr(omega))
    return Line(r, key, (r["solver"], float(r["time_limit_s"]), int(r["solver_seed"])), row,
                float(r["cpu_s"]))


def read_table(path: str) -> list[Line]:
    """The lines of a CSV this benchmark wrote (none when the file is missing)."""
    try:
        with open(path, newline="", encoding="utf-8") as f:
            fields = list(csv.DictReader(f))
    except FileNotFoundError:
        return []
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise InputError(f"{path}: cannot read the table: {exc}") from None
    lines = []
    for i, r in enumerate(fields, start=2):
        try:
            lines.append(_line(r))
        except (KeyError, TypeError, ValueError):
            raise InputError(f"{path}: line {i} is not a row of this benchmark's table "
                             f"(columns {', '.join(COLUMNS)})") from None
    return lines


def _floats(text: str) -> list[float]:
    return [float(t) for t in text.split(",") if t.strip()]


def _ints(text: str) -> list[int]:
    return [int(t) for t in text.split(",") if t.strip()]


def main(argv: Sequence[str] | None = None) -> int:
    """Run the benchmark; exit code 1 when a proof disagrees with a proven GTSPLIB optimum, 2 on
    bad input (one line on stderr)."""
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--solver", default="milp")
    p.add_argument("--gtsplib", default="small", help="small, large, all, none or NAME,NAME,...")
    p.add_argument("--uav", type=_ints, default=[], help="K values, e.g. 20,50,100")
    p.add_argument("--seeds", type=_ints, default=[0, 1, 2])
    p.add_argument("--omegas", type=_floats, default=[0.0, 0.5, 0.9])
    p.add_argument("--time-limit", type=float, default=120.0)
    p.add_argument("--solver-seed", type=int, default=0)
    p.add_argument("--csv", default=None,
                   help="write the rows here, after every solve; rows already there for the same "
                        "solver, time limit and solver seed are kept, not solved again")
    p.add_argument("--redo", action="store_true", help="solve again the rows the CSV already has")
    args = p.parse_args(argv)
    try:
        return _run(args)
    except InputError as exc:
        print(f"exact_scale: error: {exc}", file=sys.stderr)
        return 2


def _run(args: argparse.Namespace) -> int:
    refs = gtsplib.best_known()
    lines = read_table(args.csv) if args.csv else []
    settings = _settings(args)
    kept = {} if args.redo else {x.key: (x.row, x.cpu_s) for x in lines if x.settings == settings}
    print(f"{args.solver}, time limit {args.time_limit:g} s per solve", flush=True)
    print(HEADER + "\n" + "-" * len(HEADER), flush=True)
    done: list[tuple[Job, Row]] = []
    cpus: list[float] = []
    bad = 0
    start = time.perf_counter()
    for job in jobs(args):
        found = kept.get(_key(job))
        if found is None:
            cpu = time.process_time()
            row = solve(job.group, job.instance, job.omega, args.solver, args.time_limit, args.solver_seed)
            cpu_s = time.process_time() - cpu
        else:
            row, cpu_s = found
        cpus.append(cpu_s)
        done.append((job, row))
        print(line(job, row, cpu_s) + ("  kept" if found else ""), flush=True)
        ref = refs.get(job.name) if job.group == "GTSPLIB" else None
        proven = ref is not None and ref.status == "optimal" and row.status == "optimal"
        if proven and row.objective != ref.value:
            print(f"  DISAGREES with the proven optimum {ref.value:g}", flush=True)
            bad += 1
        if args.csv:
            ours = {_key(j) for j, _ in done}
            others = [[x.fields[c] for c in COLUMNS] for x in lines
                      if not (x.settings == settings and x.key in ours)]
            write_csv(args.csv, COLUMNS, [record(j, r, c, args) for (j, r), c in zip(done, cpus, strict=True)]
                      + others)
    print(*summary(done), sep="\n")
    print(f"{bad} disagreement(s) with proven optima; {time.perf_counter() - start:.0f} s in all")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())

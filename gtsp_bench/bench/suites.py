"""The benchmark suites beside the paper's experiments: ``gtsp-bench bench --suite NAME``.

``exact``
    exact solvers side by side: time to a *proven* optimum on seeded generated sets
    (``instance_set(instances, K, seed)``, N = 20) for each K and omega, and the GTSPLIB samples
    against their best-known values; every proven optimum of one instance must agree (relative
    1e-6), else the exit code is 1.
``heuristics``
    heuristics side by side: mean gap and median time on generated sets at one omega, against
    the optimum of an exact solver picked by K (``--exact``, default ``dp`` up to K = 10, then
    ``milp``; the best found when none proves one), and on the GTSPLIB samples against their
    best-known values.
``learned``
    the learned policies against the exact optimum (``dp``, cached in ``--cache``) on test sets
    never used in training (``instance_set(n, K, 5000)``); all instances of a K are solved in one
    batch; a first row, ``bound: paper heads``, is the best any order reaches with the paper's
    head rule.

Each suite's defaults, its ``--quick`` preset and the options it takes are one :class:`Suite`
in :data:`SUITES`; :func:`make_suite_config` checks the options, :func:`run_suite` prints the
table on stdout (progress on stderr) and writes one CSV row per solve (learned: per cell)
atomically to ``<out>/<suite>.csv`` (default ``benchmarks/out``). Timings are wall-clock, of one
run on whatever machine runs it.
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO

from gtsp_bench.bench.tables import (
    Row,
    count_failed,
    gap_time_cell,
    grid_header,
    grid_line,
    median_wall,
    solve,
    time_to_proof_cell,
    write_csv,
)
from gtsp_bench.checks import (
    check_choice,
    check_int,
    check_seed,
    check_time_limit,
    parse_ks,
    parse_names,
    parse_omegas,
)
from gtsp_bench.data.gtsplib import SAMPLES, Reference, parse_best_known
from gtsp_bench.data.gtsplib import folder as gtsplib_folder
from gtsp_bench.errors import InputError, SolverError
from gtsp_bench.generator import DEFAULT_ZETA, check_generator_args, instance_set
from gtsp_bench.instance import Instance

SUITE_NAMES = ("exact", "heuristics", "learned")
#: Where the suites write ``<suite>.csv`` (relative to the working directory; git-ignored).
DEFAULT_OUT = Path("benchmarks") / "out"
#: The learned suite's cache of exact optima (committed; missing optima are solved and added).
DEFAULT_CACHE = Path("benchmarks") / "drl_exact.csv"
#: Relative tolerance between two proven optima of the same instance (exact suite).
AGREE = 1e-6
#: The learned suite's rows: (label, registered name, options); the greedy baseline for scale.
LEARNED_SOLVERS: tuple[tuple[str, str, dict[str, Any]], ...] = (
    ("greedy", "greedy", {}),
    ("drl", "drl", {}),
    ("drl heads=optimal", "drl", {"heads": "optimal"}),
    ("drl reverse=true", "drl", {"reverse": True}),
    ("drl-sample (S=64)", "drl-sample", {}),
    ("drl-sample heads=optimal", "drl-sample", {"heads": "optimal"}),
    ("am", "am", {}),
    ("am heads=paper", "am", {"heads": "paper"}),
    ("am augment=true", "am", {"augment": True}),
    ("local", "local", {}),
    ("local heads=paper", "local", {"heads": "paper"}),
    ("local starts=8", "local", {"starts": 8}),
)
_COMMON = ("ks", "solvers", "instances")
_GTSPLIB = ("gtsplib", "names", "max_nodes", "no_gtsplib")


@dataclass(frozen=True)
class Preset:
    """A suite's defaults (full run or ``--quick``); ``names``: GTSPLIB instances (None: the
    five samples of the bundled library, or every symmetric instance of a folder given with
    ``--gtsplib``)."""

    ks: tuple[int, ...]
    instances: int
    omegas: tuple[float, ...]
    time_limit: float | None
    names: tuple[str, ...] | None = None
    repeats: int = 1


@dataclass(frozen=True)
class Suite:
    """One suite: its solvers, instance-set seed, presets and the options it takes (the
    keyword names of :func:`make_suite_config`)."""

    name: str
    description: str
    solvers: tuple[str, ...]
    set_seed: int
    full: Preset
    quick: Preset
    options: tuple[str, ...]
    max_nodes: int | None = None


SUITES: dict[str, Suite] = {
    "exact": Suite(
        "exact", "exact solvers: time to proven optimum; GTSPLIB against best known",
        ("milp", "dp"), 0,
        Preset((*range(4, 11), 15, 20, 30), 5, (0.0, 0.5, 0.9), 60.0),
        Preset((4, 7, 10), 5, (0.5,), 60.0, ("11berlin52", "20kroA100")),
        (*_COMMON, "seed", "time_limit", "omegas", "solver_seed", "dp_max_k", "no_generated", *_GTSPLIB),
        max_nodes=318,
    ),
    "heuristics": Suite(
        "heuristics", "heuristics: mean gap to the optimum / best known and median time",
        ("greedy", "greedy+ls", "aco", "aco+ls", "lns", "pyvrp"), 0,
        Preset((4, 7, 10, 20), 10, (0.5,), 10.0),
        Preset((4, 7, 10, 20), 3, (0.5,), 5.0, ("11berlin52", "20kroA100", "40d198")),
        (*_COMMON, "seed", "time_limit", "omegas", "solver_seed", "exact", "exact_time_limit", *_GTSPLIB),
    ),
    "learned": Suite(
        "learned", "learned policies: gap to the exact optimum and batched time per instance",
        tuple(label for label, _, _ in LEARNED_SOLVERS), 5_000,
        Preset((4, 7, 10), 100, (0.3, 0.6), None, repeats=3),
        Preset((4, 7), 20, (0.3, 0.6), None, repeats=1),
        (*_COMMON, "repeats", "cache"),
    ),
}
#: Command-line spelling of the options whose flag is not ``--`` + the name with dashes.
FLAGS = {"ks": "--clusters", "out_dir": "--out", "seed": "--seed"}


def flag(option: str) -> str:
    """The command-line flag of a :func:`make_suite_config` option."""
    return FLAGS.get(option, "--" + option.replace("_", "-"))


@dataclass(frozen=True)
class SuiteConfig:
    """Everything one suite run needs, checked (see :func:`make_suite_config`)."""

    suite: str
    ks: tuple[int, ...]
    instances: int
    set_seed: int
    solvers: tuple[str, ...]
    omegas: tuple[float, ...]
    time_limit: float | None
    solver_seed: int = 0
    repeats: int = 1
    generated: bool = True
    gtsplib: Path | None = None
    names: tuple[str, ...] | None = None
    max_nodes: int | None = None
    dp_max_k: int = 12
    exact: tuple[tuple[str, int | None], ...] = ()
    exact_time_limit: float = 120.0
    cache: Path = DEFAULT_CACHE
    out_dir: Path = DEFAULT_OUT
    quick: bool = False

    @property
    def csv_path(self) -> Path:
        """``<out>/<suite>.csv``."""
        return self.out_dir / f"{self.suite}.csv"


def parse_exact(text: str) -> tuple[tuple[str, int | None], ...]:
    """``"dp:10,milp"`` -> ``(("dp", 10), ("milp", None))``: exact solvers and their largest K."""
    out: list[tuple[str, int | None]] = []
    for part in filter(None, (p.strip() for p in str(text).split(","))):
        name, _, k = part.partition(":")
        try:
            out.append((name, int(k) if k else None))
        except ValueError:
            raise InputError(f"--exact: bad entry {part!r} (expected NAME or NAME:MAX_K)") from None
    return tuple(out)


def _solvers(suite: Suite, given: str | Sequence[str]) -> tuple[str, ...]:
    """Registered solver names; for ``learned``, the labels starting with one of the given
    prefixes (``drl`` picks every drl variant)."""
    names = parse_names(given, "solver")
    if not names:
        raise InputError("no solver given")
    if suite.name == "learned":
        for p in names:
            if not any(label.startswith(p) for label in suite.solvers):
                raise InputError(f"no learned-suite solver starts with {p!r} "
                                 f"(valid: {', '.join(suite.solvers)})")
        return tuple(s for s in suite.solvers if any(s.startswith(p) for p in names))
    from gtsp_bench.registry import solver_names

    registered = solver_names()
    unknown = [s for s in names if s not in registered]
    if unknown:
        raise InputError(f"unknown solver {unknown[0]!r} (valid: {', '.join(registered)})")
    return names


def make_suite_config(suite: str, *, quick: bool = False, out_dir: str | os.PathLike[str] | None = None,
                      **options: Any) -> SuiteConfig:
    """Check a suite's options (``None`` or ``False``: not given, the preset's value).

    Options: ``ks`` (a K set such as ``4..7,10``, or ints), ``solvers`` (comma-separated),
    ``instances``, ``seed`` (instance sets), ``time_limit``, ``omegas``, ``solver_seed``,
    ``repeats``, ``dp_max_k``, ``exact`` (``NAME[:MAX_K],...``), ``exact_time_limit``,
    ``gtsplib`` (folder), ``names`` (GTSPLIB samples), ``max_nodes``, ``no_gtsplib``,
    ``no_generated``, ``cache``; each suite takes those in its :attr:`Suite.options`.

    Raises
    ------
    InputError
        An unknown suite, an option the suite does not take, or a bad value.
    """
    spec = SUITES[check_choice("suite", suite, SUITE_NAMES)]
    given = {k: v for k, v in options.items() if v is not None and v is not False}
    for key in given:
        if key not in spec.options:
            takes = ", ".join(flag(o) for o in spec.options)
            raise InputError(f"{flag(key)} is not an option of the {suite} suite (it takes {takes})")
    preset = spec.quick if quick else spec.full
    ks = given.get("ks", preset.ks)
    ks = parse_ks(ks if isinstance(ks, str) else ",".join(str(check_int("K", k, 1)) for k in ks))
    for k in (ks[0], ks[-1]):
        check_generator_args(k, 20, DEFAULT_ZETA, 1000.0)
    omegas = given.get("omegas", preset.omegas)
    omegas = parse_omegas(omegas if isinstance(omegas, str) else ",".join(map(repr, omegas)))
    if suite == "heuristics" and len(omegas) != 1:
        raise InputError(f"the heuristics suite takes one omega, got {len(omegas)}")
    time_limit = check_time_limit(given.get("time_limit", preset.time_limit))
    names = given.get("names", preset.names)
    if names is None and not given.get("gtsplib"):
        names = SAMPLES
    gtsplib = None
    if "gtsplib" in spec.options and not given.get("no_gtsplib"):
        gtsplib = Path(given["gtsplib"]) if given.get("gtsplib") else gtsplib_folder()
    max_nodes = given.get("max_nodes", spec.max_nodes)
    return SuiteConfig(
        suite=suite, ks=ks,
        instances=check_int("number of instances", given.get("instances", preset.instances), 1),
        set_seed=check_seed(given.get("seed", spec.set_seed)),
        solvers=_solvers(spec, given.get("solvers", spec.solvers)),
        omegas=omegas, time_limit=time_limit,
        solver_seed=check_seed(given.get("solver_seed", 0)),
        repeats=check_int("repeats", given.get("repeats", preset.repeats), 1),
        generated=not given.get("no_generated"), gtsplib=gtsplib,
        names=None if names is None else parse_names(names, "instance") or None,
        max_nodes=None if max_nodes is None else check_int("max nodes", max_nodes, 1),
        dp_max_k=check_int("dp max K", given.get("dp_max_k", 12), 1),
        exact=parse_exact(given.get("exact", "dp:10,milp")),
        exact_time_limit=check_time_limit(given.get("exact_time_limit", 120.0)),
        cache=Path(given.get("cache", DEFAULT_CACHE)),
        out_dir=Path(out_dir) if out_dir is not None else DEFAULT_OUT, quick=quick,
    )


def _say(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def _gtsplib_samples(config: SuiteConfig) -> list[tuple[Instance, Reference]]:
    """The GTSPLIB samples the config asks for, with their ``best_known.csv`` rows (none, with a
    note on stderr, when the folder has no such table)."""
    from gtsp_bench.data.io import read_instance

    if config.gtsplib is None:
        return []
    table = config.gtsplib / "best_known.csv"
    if not table.is_file():
        _say(f"no {table}: GTSPLIB skipped")
        return []
    try:
        refs = parse_best_known(table.read_text(encoding="utf-8"))
    except InputError as e:
        raise InputError(f"{table}: {e}") from None
    wanted, limit = config.names, config.max_nodes
    picked = [r for r in refs.values() if (limit is None or r.nodes <= limit)
              and (not wanted or r.name in wanted) and r.type != "AGTSP"]

    def file(name: str) -> Path:
        gz = config.gtsplib / f"{name}.gtsp.gz"
        return gz if gz.is_file() else config.gtsplib / f"{name}.gtsp"

    return [(read_instance(file(r.name)), r) for r in picked]


# ---------------------------------------------------------------------- exact
def disagreements(rows: Sequence[Row]) -> list[str]:
    """Instances (and omegas) whose proven optima differ between solvers."""
    proven: dict[tuple[str, float | None], list[Row]] = {}
    for r in rows:
        if r.status == "optimal":
            proven.setdefault((r.instance, r.omega), []).append(r)
    bad = []
    for (name, omega), rs in proven.items():
        lo, hi = min(r.objective for r in rs), max(r.objective for r in rs)
        if hi - lo > AGREE * max(1.0, abs(lo)):
            bad.append(f"{name} omega={omega}: " + ", ".join(f"{r.solver} {r.objective!r}" for r in rs))
    return bad


def _exact_rows(c: SuiteConfig) -> tuple[list[Row], list[Row], dict[str, tuple[int, int, float, str]]]:
    """Generated rows, GTSPLIB rows and ``{sample: (clusters, nodes, best, status)}``."""
    tl = c.time_limit
    rows: list[Row] = []
    for k in c.ks if c.generated else ():
        instances = instance_set(c.instances, k, c.set_seed)
        for omega in c.omegas:
            for solver in c.solvers:
                if solver == "dp" and k > c.dp_max_k:
                    continue
                rows += [solve(f"K={k}", inst, omega, solver, tl, c.solver_seed) for inst in instances]
            done = [r for r in rows if r.group == f"K={k}" and r.omega == omega]
            _say(f"  K={k} omega={omega:g}: {len(done)} solves")
    lib: list[Row] = []
    info = {}
    for inst, row in _gtsplib_samples(c):
        info[inst.name] = (row.clusters, row.nodes, row.value, row.status)
        for solver in c.solvers:
            if solver == "dp" and inst.n_clusters > c.dp_max_k:
                continue
            lib.append(solve("GTSPLIB", inst, None, solver, tl, c.solver_seed))
            _say(f"  {inst.name} {solver}: {lib[-1].status} {lib[-1].runtime_s:.2f} s")
    return rows, lib, info


def exact_table(rows: Sequence[Row], solvers: Sequence[str], limit: float) -> str:
    """Rows K x omega; cells: median time to proven optimum and how many were proven."""
    lines = grid_header(f"{'K':>4} {'omega':>5}", solvers, 14)
    for group, omega in dict.fromkeys((r.group, r.omega) for r in rows):
        cells = []
        for s in solvers:
            mine = [r for r in rows if r.group == group and r.omega == omega and r.solver == s]
            cells.append(time_to_proof_cell(mine, limit) if mine else None)
        lines.append(grid_line(f"{group[2:]:>4} {omega:>5g}", cells, 14))
    lines.append("cells: median time to proven optimum over the instances / instances proven")
    return "\n".join(lines)


def gtsplib_table(rows: Sequence[Row], info: Mapping[str, tuple[int, int, float, str]]) -> str:
    """One line per GTSPLIB solve: status, objective against best known, bound, time."""
    head = (f"{'instance':<11} {'K':>3} {'n':>4} {'solver':<7} {'status':<10} {'objective':>9} "
            f"{'best known':>10} {'(literature)':<12} {'match':>5} {'bound':>10} {'time':>8}")
    lines = [head, "-" * len(head)]
    for r in rows:
        k, n, best, status = info[r.instance]
        match = "yes" if r.objective == best else ("BETTER" if r.objective < best else "no")
        lines.append(f"{r.instance:<11} {k:>3} {n:>4} {r.solver:<7} {r.status:<10} {r.objective:>9.0f} "
                     f"{best:>10.0f} {status:<12} {match:>5} {r.lower_bound:>10.1f} "
                     f"{r.runtime_s:>7.2f}s")
    return "\n".join(lines)


EXACT_COLUMNS = ("group", "instance", "omega", "solver", "status", "objective", "lower_bound",
                 "runtime_s", "note")


def run_exact(c: SuiteConfig, out: TextIO) -> int:
    """The exact suite; exit code 1 when two proven optima disagree or a solve failed."""
    rows, lib, info = _exact_rows(c)
    assert c.time_limit is not None
    print(f"{c.instances} instances per K (set seed {c.set_seed}, N = 20), time limit "
          f"{c.time_limit:g} s per solve, {os.cpu_count()} CPU cores", file=out)
    if rows:
        print(exact_table(rows, c.solvers, c.time_limit), file=out)
    if lib:
        print(file=out)
        print(gtsplib_table(lib, info), file=out)
    bad = disagreements([*rows, *lib])
    print(f"\n{len(bad)} disagreement(s) between proven optima" + "".join(f"\n  {b}" for b in bad), file=out)
    write_csv(c.csv_path, EXACT_COLUMNS, (
        [r.group, r.instance, "" if r.omega is None else r.omega, r.solver, r.status, repr(r.objective),
         repr(r.lower_bound), f"{r.runtime_s:.4f}", r.note] for r in [*rows, *lib]))
    return 1 if bad or count_failed([*rows, *lib]) else 0


# ---------------------------------------------------------------------- heuristics
def exact_optimum(instance: Instance, omega: float, exact: Sequence[tuple[str, int | None]],
                  time_limit: float) -> tuple[float, str] | None:
    """The proven optimum and the exact solver's name, or ``None`` when none proves one."""
    from gtsp_bench.registry import run_solver, solver_names

    registered = set(solver_names())
    for name, max_k in exact:
        if name not in registered or (max_k is not None and instance.n_clusters > max_k):
            continue
        try:
            r = run_solver(name, instance, omega, time_limit=time_limit)
        except (InputError, SolverError) as e:
            _say(f"  {name} failed on {instance.name}: {e}")
            continue
        if r.status == "optimal":
            return r.objective, name
    return None


_NO_ANSWER = ("failed", "refused")


def _solved(c: SuiteConfig, group: str, instance: Instance, omega: float | None) -> list[Row]:
    """Every solver on one instance; a failure or refusal is said on stderr (and kept as a row
    for the CSV; the tables leave it out)."""
    rows = []
    for s in c.solvers:
        r = solve(group, instance, omega, s, c.time_limit, c.solver_seed)
        if r.status in _NO_ANSWER:
            _say(f"  {s} {r.status} on {instance.name}: {r.note}")
        rows.append(r)
    return rows


def _heuristics_rows(c: SuiteConfig) -> list[Row]:
    """Generated sets against the exact optimum (else the best found); GTSPLIB against best known."""
    omega = c.omegas[0]
    out: list[Row] = []
    for k in c.ks:
        for inst in instance_set(c.instances, k, c.set_seed):
            found = _solved(c, f"K={k}", inst, omega)
            opt = exact_optimum(inst, omega, c.exact, c.exact_time_limit)
            if opt is not None:
                ref, kind = opt[0], f"optimum ({opt[1]})"
            else:
                answered = (r.objective for r in found if r.status not in _NO_ANSWER)
                ref, kind = min(answered, default=math.nan), "best found"
            out += [r.against(ref, kind) for r in found]
            _say(f"  {inst.name}: reference {ref:.4f} ({kind})")
    for inst, row in _gtsplib_samples(c):
        kind = "optimum (literature)" if row.status == "optimal" else "best known"
        out += [r.against(row.value, kind) for r in _solved(c, "GTSPLIB", inst, None)]
        _say(f"  {inst.name}: done")
    return out


def heuristics_table(rows: Sequence[Row], solvers: Sequence[str]) -> str:
    """Mean gap and median time per group (and per GTSPLIB sample) and solver; solves without an
    answer (failed, refused) are left out."""
    rows = [r for r in rows if r.status not in _NO_ANSWER]
    lines = grid_header(f"{'set':<14} {'n':>3}  {'reference':<22}", solvers, 14)
    groups: dict[str, list[Row]] = {}
    for r in rows:
        groups.setdefault(r.group, []).append(r)
        if r.group == "GTSPLIB":
            groups.setdefault(f"  {r.instance}", []).append(r)
    for group, rs in groups.items():
        kinds = sorted({r.reference_kind for r in rs})
        cells = []
        for s in solvers:
            mine = [r for r in rs if r.solver == s]
            cells.append(gap_time_cell(mine) if mine else None)
        kind = kinds[0] if len(kinds) == 1 else "mixed"
        lines.append(grid_line(f"{group:<14} {len({r.instance for r in rs}):>3}  {kind:<22}", cells, 14))
    lines.append("")
    lines.append("cells: mean gap to the reference / median solve time; * = some solves hit the time limit")
    return "\n".join(lines)


HEURISTICS_COLUMNS = ("group", "instance", "solver", "objective", "gap_percent", "runtime_s", "status",
                      "reference", "reference_kind")


def run_heuristics(c: SuiteConfig, out: TextIO) -> int:
    """The heuristics suite; exit code 1 when a solve failed."""
    rows = _heuristics_rows(c)
    assert c.time_limit is not None
    print(f"omega {c.omegas[0]:g} (generated sets), seed {c.solver_seed}, time limit {c.time_limit:g} s "
          f"per solve, {os.cpu_count()} CPU cores", file=out)
    print(heuristics_table(rows, c.solvers), file=out)
    write_csv(c.csv_path, HEURISTICS_COLUMNS, (
        [r.group, r.instance, r.solver, repr(r.objective), f"{r.gap:.6f}" if math.isfinite(r.gap) else "",
         f"{r.runtime_s:.4f}", r.status, repr(r.reference), r.reference_kind] for r in rows))
    return 1 if count_failed(rows) else 0


# ---------------------------------------------------------------------- learned
def exact_optima(cache: Path, instances: Mapping[int, Sequence[Instance]],
                 omegas: Sequence[float]) -> dict[tuple[str, float], float]:
    """Optimum of each (instance, omega) from ``cache``, solving the missing ones with dp (and
    adding them to the cache)."""
    import csv

    from gtsp_bench.registry import run_solver

    known: dict[tuple[str, float], float] = {}
    if cache.exists():
        with cache.open(newline="") as f:
            for row in csv.DictReader(f):
                known[(row["instance"], float(row["omega"]))] = float(row["optimum"])
    missing = [(inst, w) for insts in instances.values() for inst in insts for w in omegas
               if (inst.name, w) not in known]
    for i, (inst, w) in enumerate(missing):
        result = run_solver("dp", inst, w)
        if result.status != "optimal":
            raise SolverError(f"dp did not prove the optimum of {inst.name} (omega {w}): {result.status}")
        known[(inst.name, w)] = result.objective
        if (i + 1) % 50 == 0 or i + 1 == len(missing):
            _say(f"exact optima: {i + 1}/{len(missing)}")
    if missing:
        write_csv(cache, ("instance", "omega", "optimum"),
                  ([n, w, v] for (n, w), v in sorted(known.items())))
    return known


def _learned_line(label: str, k: int, w: float, mean: float, worst: float, ms: float) -> str:
    time_ = f"{'-':>8}" if math.isnan(ms) else f"{ms:>8.2f}"
    return f"{label:<26} {k:>3} {w:>5g} {mean:>10.3f} {worst:>9.3f} {time_}"


def _batch(solver: Any, instances: Sequence[Instance], omega: float) -> list[Any]:
    """One batched solve (one by one when the solver has no ``solve_batch``)."""
    if hasattr(solver, "solve_batch"):
        return solver.solve_batch(instances, [omega] * len(instances))
    return [solver.solve(inst, omega) for inst in instances]


def run_learned(c: SuiteConfig, out: TextIO) -> int:
    """The learned suite: the paper-heads bound, then each chosen policy, per K and omega."""
    import numpy as np

    from gtsp_bench.energy import evaluate
    from gtsp_bench.registry import get_solver
    from gtsp_bench.solvers.learned.env import env_from_instances
    from gtsp_bench.solvers.learned.oracles import paper_rule_optimum

    instances = {k: instance_set(c.instances, k, c.set_seed) for k in c.ks}
    opt = exact_optima(c.cache, instances, c.omegas)
    records: list[list[object]] = []

    def record(label: str, k: int, w: float, gap: Any, ms: float) -> None:
        records.append([label, k, w, f"{gap.mean():.4f}", f"{gap.max():.4f}", f"{ms:.3f}"])
        print(_learned_line(label, k, w, gap.mean(), gap.max(), ms), file=out, flush=True)

    header = f"{'solver':<26} {'K':>3} {'omega':>5} {'mean gap %':>10} {'max gap %':>9} {'ms/inst':>8}"
    print(header, file=out)
    print("-" * len(header), file=out)
    for k in c.ks:
        for w in c.omegas:
            env = env_from_instances(instances[k], [w] * len(instances[k]))
            bound = np.concatenate([paper_rule_optimum(env.rows(i, i + 20)).numpy()
                                    for i in range(0, len(instances[k]), 20)])
            best = np.array([opt[(inst.name, w)] for inst in instances[k]])
            record("bound: paper heads", k, w, (bound / best - 1) * 100, math.nan)
    for label, name, options in LEARNED_SOLVERS:
        if label not in c.solvers:
            continue
        solver = get_solver(name, **options)
        for k in c.ks:
            insts = instances[k]
            for w in c.omegas:
                best = np.array([opt[(inst.name, w)] for inst in insts])
                sols, wall = median_wall(lambda s=solver, xs=insts, w=w: _batch(s, xs, w), c.repeats)
                objs = np.array([evaluate(inst, w, s.order, s.heads).objective
                                 for inst, s in zip(insts, sols, strict=True)])
                gap = (objs / best - 1) * 100
                if gap.min() <= -1e-7:
                    raise SolverError(f"{label} is below the exact optimum at K = {k}, omega {w}: a bug")
                record(label, k, w, gap, 1000 * wall / len(insts))
    write_csv(c.csv_path, ("solver", "K", "omega", "mean_gap_pct", "max_gap_pct", "ms_per_instance"),
              records)
    return 0


RUNNERS = {"exact": run_exact, "heuristics": run_heuristics, "learned": run_learned}


def run_suite(config: SuiteConfig, out: TextIO | None = None) -> int:
    """Run a suite: its table on ``out`` (default stdout), progress on stderr, its rows to
    :attr:`SuiteConfig.csv_path` (named on stderr); returns the exit code."""
    code = RUNNERS[config.suite](config, sys.stdout if out is None else out)
    _say(f"rows: {config.csv_path}")
    return code


__all__ = [
    "DEFAULT_CACHE", "DEFAULT_OUT", "LEARNED_SOLVERS", "SUITES", "SUITE_NAMES", "Preset", "Suite",
    "SuiteConfig", "disagreements", "exact_optima", "exact_optimum", "exact_table", "gtsplib_table",
    "heuristics_table", "make_suite_config", "parse_exact", "run_suite",
]

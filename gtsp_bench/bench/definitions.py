"""Every benchmark of the suite as data: one frozen :class:`Benchmark` per name in :data:`BENCHMARKS`.

A definition says *what* is measured; :mod:`gtsp_bench.bench.engine` says *how* (tasks in the
worker pool, the task log, rows, outputs). Its parts:

instance sources
    :class:`Generated` (seeded UAV sets, written once under ``instances/uav-K{K}-N{N}-s{seed}``),
    :class:`Committed` (sets already under ``instances/``, or any folder) and :class:`Gtsplib`
    (the bundled library by name, by size group or as GLNS's list of 45);
solvers
    :class:`Run`: a registered solver with options and a label (``drl heads=optimal``);
omegas, seeds and the budget
    :class:`Budget`: seconds per solve, or a factor of a per-instance reference time (GLNS's);
the reference rule
    :class:`Reference`: proven optima of exact solvers run as tasks beside the others, the set's
    ``reference.csv`` / GTSPLIB's ``best_known.csv``, or the best the benchmark found;
outputs
    always ``rows.csv``, ``summary.md`` and ``manifest.json``; more by name
    (:data:`gtsp_bench.bench.outputs.OUTPUTS`): figures, the paper's experiment tables, generated
    blocks of a documentation page;
``quick``
    the fields a ``--quick`` run replaces (a smoke run in seconds to minutes).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any

from gtsp_bench.errors import InputError

#: The paper's omega sweep and its quick variant.
PAPER_OMEGAS = tuple(round(0.1 * i, 1) for i in range(10))
#: GTSPLIB's five samples, smallest first.
SAMPLES = ("11berlin52", "20kroA100", "40d198", "64lin318", "107att532")
#: GLNS's time on this class of machine, per second of its published (Apple M4 Pro) C++ time.
GLNS_MACHINE_FACTOR = 2.4


@dataclass(frozen=True)
class Generated:
    """Seeded UAV instances: the first ``instances`` of ``instance_set(instances, K, seed, nodes)``
    for each K (written once into ``instances/uav-K{K}-N{nodes}-s{seed}/`` and re-used)."""

    ks: tuple[int, ...]
    instances: int
    seed: int = 1
    nodes: int = 20

    def describe(self) -> str:
        """One line: which sets."""
        return f"generated K={','.join(map(str, self.ks))}, {self.instances} per K, seed {self.seed}"


@dataclass(frozen=True)
class Committed:
    """Committed sets by folder name under ``instances/`` (or any folder path); ``instances``: the
    first N files per set (``None``: all)."""

    sets: tuple[str, ...]
    instances: int | None = None

    def describe(self) -> str:
        """One line: which sets."""
        first = "" if self.instances is None else f", first {self.instances} each"
        return f"sets {', '.join(self.sets)}{first}"


@dataclass(frozen=True)
class Gtsplib:
    """GTSPLIB instances: by ``names``, else by ``group`` (``samples``, ``glns-45``, or every
    file) filtered by ``min_nodes`` / ``max_nodes`` and symmetry; ``per_group``: the smallest N
    of each of ``size_groups`` (``(label, lowest, highest)`` node counts) instead."""

    names: tuple[str, ...] = ()
    group: str = "all"
    min_nodes: int = 1
    max_nodes: int | None = None
    symmetric_only: bool = True
    asymmetric_only: bool = False
    size_groups: tuple[tuple[str, int, int], ...] = ()
    per_group: int | None = None

    def describe(self) -> str:
        """One line: which files."""
        if self.names:
            return f"GTSPLIB {', '.join(self.names)}"
        what = {"all": "GTSPLIB", "samples": "GTSPLIB samples", "glns-45": "GLNS's 45 GTSPLIB files"}
        text = what.get(self.group, self.group)
        if self.max_nodes is not None or self.min_nodes > 1:
            text += f" of {self.min_nodes}-{self.max_nodes or 'any'} nodes"
        if self.per_group is not None:
            text += f", {self.per_group} per size group"
        return text + (" (AGTSP)" if self.asymmetric_only else "")


Source = Generated | Committed | Gtsplib


@dataclass(frozen=True)
class Run:
    """One solver column: a registered ``solver`` with ``options``, shown as ``label`` (default:
    the solver's name); ``max_k``: given instances of at most this many clusters only;
    ``one_seed``: solved with the benchmark's first seed only (a deterministic solver)."""

    solver: str
    options: tuple[tuple[str, Any], ...] = ()
    label: str = ""
    max_k: int | None = None
    one_seed: bool = False

    @property
    def name(self) -> str:
        """The label rows carry."""
        return self.label or self.solver


def run(
    solver: str, label: str = "", max_k: int | None = None, one_seed: bool = False, **options: Any
) -> Run:
    """A :class:`Run` from keyword options (sorted, so that equal runs compare equal)."""
    return Run(solver, tuple(sorted(options.items())), label, max_k, one_seed)


@dataclass(frozen=True)
class Budget:
    """Seconds per solve: ``seconds``, or ``factor`` x the instance's reference time ``of``
    (``glns``: GLNS's C++ mean seconds in ``glns-45.csv`` x :data:`GLNS_MACHINE_FACTOR`).
    ``None`` seconds: the solvers' own stopping rule (learned policies)."""

    seconds: float | None = 10.0
    factor: float | None = None
    of: str | None = None

    def describe(self) -> str:
        """The rule in words (the manifest's ``budget_rule``)."""
        if self.factor is not None:
            return (
                f"{self.factor:g} x GLNS's C++ mean seconds (glns-45.csv) x {GLNS_MACHINE_FACTOR:g} "
                "(GLNS's time on this class of machine)"
            )
        return "no time limit" if self.seconds is None else f"{self.seconds:g} s per solve"


@dataclass(frozen=True)
class Reference:
    """How a solve's gap is measured, in order of preference.

    ``exact``: exact solvers run as tasks beside the others (``(solver, largest K or None)``, the
    first that applies), each given ``exact_time_limit``; their proven optimum is an ``optimal``
    reference. ``table``: the set's ``reference.csv`` (GTSPLIB: ``best_known.csv``), ``optimal``
    or ``best_known``. ``own_proofs``: a proven optimum any solver of the benchmark found.
    Otherwise the best objective the benchmark found (``best_found``). A solve better than a
    ``best_known`` reference turns that reference into ``best_found``.
    """

    exact: tuple[tuple[str, int | None], ...] = ()
    exact_time_limit: float = 120.0
    table: bool = True
    own_proofs: bool = False

    def describe(self) -> str:
        """The rule in words, in the order :func:`gtsp_bench.bench.rows.references` applies it."""
        parts = []
        if self.exact:
            parts.append(
                "proven optimum of "
                + ", then ".join(f"{s}" + (f" (K <= {k})" if k else "") for s, k in self.exact)
            )
        if self.table:
            parts.append("the set's reference.csv / GTSPLIB's best_known.csv")
        if self.own_proofs:
            parts.append("a proven optimum of the benchmark's own solves")
        parts.append("the best found")
        return "; else ".join(parts)


@dataclass(frozen=True)
class Benchmark:
    """One named benchmark (see the module docstring for its parts).

    ``batched``: solvers with ``solve_batch`` solve all instances of one set, K, omega and seed as
    one task, ``repeats`` times (the median wall time over the batch is each instance's time).
    ``planner``: ``grid`` (every source x run x omega x seed) or ``paper`` (the paper's
    experiment cells). ``rough_time``: what ``--list`` says a full run takes on 2 cores.
    """

    name: str
    description: str
    sources: tuple[Source, ...]
    runs: tuple[Run, ...]
    omegas: tuple[float, ...] = (0.5,)
    seeds: tuple[int, ...] = (0,)
    budget: Budget = Budget()
    reference: Reference = Reference()
    batched: bool = False
    repeats: int = 1
    planner: str = "grid"
    outputs: tuple[str, ...] = ()
    out_dir: str = ""
    rough_time: str = ""
    quick: Mapping[str, Any] = field(default_factory=dict)
    jobs: int | None = None

    def quick_variant(self) -> Benchmark:
        """The definition with its ``quick`` fields applied (output in ``results/quick/NAME``)."""
        return replace(self, **{"out_dir": f"results/quick/{self.name}", **self.quick}, quick={})

    @property
    def output_dir(self) -> str:
        """Where its outputs go by default: ``results/NAME``."""
        return self.out_dir or f"results/{self.name}"


_HEURISTICS = ("greedy", "greedy+ls", "aco", "aco+ls", "lns", "pyvrp")
_PEERS_TABLE = (*_HEURISTICS, "ortools", "lkh")
#: The wider local-view policies trained on a GPU (recipes ``local-gpu-l3``, ``local-gpu-l4``,
#: ``local-gpu-l4-tiled``), shipped files.
_L3 = "solvers/learned/checkpoints/local-l3.pt"
_L4 = "solvers/learned/checkpoints/local-l4.pt"
_L4_TILED = "solvers/learned/checkpoints/local-l4-tiled.pt"
#: GTSPLIB's planar (EUC_2D) files of GLNS's 45: the transfer benchmark's distance-only problems.
_GLNS45_PLANAR = (
    "31pr152", "32u159", "39rat195", "40d198", "40kroa200", "40krob200", "45ts225", "45tsp225",
    "46pr226", "53gil262", "53pr264", "56a280", "60pr299", "64lin318", "80rd400", "84fl417",
    "88pr439", "89pcb442", "99d493", "115rat575", "115u574", "131p654", "132d657", "145u724",
    "157rat783", "201pr1002", "212u1060", "217vm1084",
)
_TRANSFER_SETS = ("uav-K50-N10-s1", "uav-K50-N40-s1", "uav-K100-N10-s1", "uav-K100-N40-s1",
                  "uav-K50-N20-a1100-s21", "uav-K50-N20-a3000-s22")
#: lns in a fixed-budget benchmark: it uses the whole time limit (effort ``budget``), as every
#: committed table of such a benchmark was made; its own default stops when its trials are done.
LNS_BUDGET = run("lns", "lns", effort="budget")


def fixed_budget(solver: str) -> Run:
    """The run of ``solver`` in a fixed-budget benchmark: :data:`LNS_BUDGET` for lns, else its
    defaults."""
    return LNS_BUDGET if solver == "lns" else run(solver)

#: The learned benchmark's runs: each policy at every K; its variants (the paper's head rule,
#: reversal, sampling, augmentation, multi-start) at the generated K <= 10 only.
_LEARNED = (
    run("greedy"),
    run("drl"),
    run("drl", "drl heads=optimal", max_k=10, heads="optimal"),
    run("drl", "drl reverse=true", max_k=10, reverse=True),
    run("drl-sample", "drl-sample (S=64)", max_k=10),
    run("drl-sample", "drl-sample heads=optimal", max_k=10, heads="optimal"),
    run("am"),
    run("am", "am heads=paper", max_k=10, heads="paper"),
    run("am", "am augment=true", max_k=10, augment=True),
    run("local"),
    run("local", "local heads=paper", max_k=10, heads="paper"),
    run("local", "local starts=8", max_k=10, starts=8),
    run("local", "local policy=l3", checkpoint=_L3),
    run("local", "local policy=l4", checkpoint=_L4),
    run("local", "local policy=l4-tiled", checkpoint=_L4_TILED),
    run("local-search"),
    run("greedy+ils"),  # local-search's kicks from the greedy tour: what the policy adds
)
_LARGE_UAV = tuple(f"uav-K{k}-N20-s1" for k in (20, 50, 100, 200))
_TABLE_GROUPS = (
    ("GTSPLIB <= 200 nodes", 1, 200),
    ("GTSPLIB 201-500", 201, 500),
    ("GTSPLIB 501-1,100", 501, 1_100),
    ("GTSPLIB 1,101-15,000", 1_101, 15_000),
)

BENCHMARKS: dict[str, Benchmark] = {
    b.name: b
    for b in (
        Benchmark(
            "paper",
            "the paper's experiments: energy ratio to the optimum by omega and K, runtimes, "
            "trajectories, training curves",
            (Generated(tuple(range(4, 11)), 30, seed=1),),
            (),
            omegas=PAPER_OMEGAS,
            budget=Budget(10.0),
            reference=Reference(exact=(("dp", 12), ("milp", None)), table=False),
            planner="paper",
            outputs=("paper",),
            out_dir="results/paper",
            rough_time="2 min",
            quick={"sources": (Generated((4, 5), 3, seed=1),), "omegas": (0.0, 0.5, 0.9)},
        ),
        Benchmark(
            "exact",
            "exact solvers: time to a proven optimum on generated sets; GTSPLIB samples "
            "against the literature",
            (Generated((*range(4, 11), 15, 20, 30), 5, seed=0), Gtsplib(SAMPLES, max_nodes=318)),
            (run("milp"), run("dp", max_k=12)),
            omegas=(0.0, 0.5, 0.9),
            budget=Budget(60.0),
            reference=Reference(own_proofs=True),
            rough_time="25 min",
            quick={
                "sources": (Generated((4, 7, 10), 5, seed=0), Gtsplib(("11berlin52", "20kroA100"))),
                "omegas": (0.5,),
            },
        ),
        Benchmark(
            "heuristics",
            "heuristics side by side: gap to the optimum or best known, median time",
            (Generated((4, 7, 10, 20), 10, seed=0), Gtsplib(SAMPLES)),
            tuple(fixed_budget(s) for s in _HEURISTICS),
            budget=Budget(10.0),
            reference=Reference(exact=(("dp", 10), ("milp", None))),
            outputs=("profile", "anytime"),
            rough_time="40 min",
            quick={
                "sources": (
                    Generated((4, 7, 10, 20), 3, seed=0),
                    Gtsplib(("11berlin52", "20kroA100", "40d198")),
                ),
                "budget": Budget(5.0),
            },
        ),
        Benchmark(
            "heuristics-table",
            "every heuristic and peer on GTSPLIB by size and on the UAV sets of "
            "K = 20-200: the table of the heuristics page",
            (
                Gtsplib(size_groups=_TABLE_GROUPS, per_group=3, max_nodes=15_000),
                Gtsplib(
                    group="AGTSP",
                    symmetric_only=False,
                    asymmetric_only=True,
                    per_group=3,
                    size_groups=(("GTSPLIB AGTSP", 1, 15_000),),
                ),
                Committed(_LARGE_UAV, 3),
            ),
            tuple(fixed_budget(s) for s in _PEERS_TABLE),
            budget=Budget(10.0),
            outputs=("profile", "anytime", "doc-heuristics"),
            rough_time="10 min",
            quick={
                "sources": (Gtsplib(("11berlin52", "20kroA100")), Committed(("uav-K20-N20-s1",), 1)),
                "budget": Budget(2.0),
                "outputs": (),
            },
        ),
        Benchmark(
            "learned",
            "learned policies (and greedy) from K = 4 to 200: gap to the optimum or best "
            "known, batched ms per instance",
            (Generated((4, 7, 10), 100, seed=5000), Committed(_LARGE_UAV)),
            _LEARNED,
            omegas=(0.3, 0.6),
            budget=Budget(None),
            reference=Reference(exact=(("dp", 10),)),
            batched=True,
            repeats=3,
            outputs=("doc-learned",),
            rough_time="30 min",
            quick={"sources": (Generated((4, 7), 20, seed=5000),), "repeats": 1, "outputs": ()},
        ),
        Benchmark(
            "learned-transfer",
            "the local policies off their training distribution (N = 10 and 40 per cluster, "
            "denser and sparser areas, GTSPLIB's planar GLNS files as distance-only problems): "
            "one greedy decode against lns to convergence or GTSPLIB's best known",
            (Committed(_TRANSFER_SETS), Gtsplib(names=_GLNS45_PLANAR)),
            (run("local"), run("local", "local policy=l3", checkpoint=_L3),
             run("local", "local policy=l4", checkpoint=_L4),
             run("local", "local policy=l4-tiled", checkpoint=_L4_TILED),
             run("lns", "lns (reference)", max_k=100, stop_at_convergence=True)),
            omegas=(0.3, 0.6),
            budget=Budget(None),
            batched=True,
            outputs=("doc-learned-transfer",),
            jobs=1,
            rough_time="2 min",
            quick={"sources": (Committed(("uav-K50-N10-s1",), instances=2),
                               Gtsplib(names=("40kroa200",))), "outputs": ()},
        ),
        Benchmark(
            "glns",
            "lns against GLNS on GLNS's 45 GTSPLIB files at half of GLNS's time (10 seeds; lns "
            "on two threads where two cores are free: GLNS's CPU time)",
            (Gtsplib(group="glns-45", symmetric_only=False),),
            (LNS_BUDGET,),
            seeds=tuple(range(1, 11)),
            budget=Budget(factor=0.5, of="glns"),
            outputs=("glns", "doc-glns"),
            jobs=1,
            rough_time="25 min on one core",
            quick={"sources": (Gtsplib(("31pr152", "40d198", "64lin318")),), "seeds": (1,)},
        ),
        Benchmark(
            "glns-large",
            "lns on the 41 symmetric GTSPLIB files of 1,000-15,112 nodes at 60 s (3 seeds), gap to "
            "the best known (GLKH's tours, or a shorter one kept since)",
            (Gtsplib(min_nodes=1_000, max_nodes=15_112),),
            (LNS_BUDGET,),
            seeds=(1, 2, 3),
            budget=Budget(60.0),
            outputs=("anytime", "doc-glns-large"),
            jobs=1,
            rough_time="2 h 10 min on one core",
            quick={"sources": (Gtsplib(("235pcb1173",)),), "budget": Budget(10.0)},
        ),
        Benchmark(
            "lns-effort",
            "lns's effort presets that stop on their own (fast, default, slow) on GLNS's 45 files, "
            "60 s a cap: gap and time to stop",
            (Gtsplib(group="glns-45", symmetric_only=False),),
            tuple(run("lns", f"lns effort={e}", effort=e) for e in ("fast", "default", "slow")),
            seeds=(1,),
            budget=Budget(60.0),
            outputs=(),
            jobs=1,
            rough_time="15 min on one core",
            quick={"sources": (Gtsplib(("11berlin52", "40d198")),)},
        ),
        Benchmark(
            "exact-scale",
            "milp at scale: GTSPLIB to 442 nodes and UAV K = 20, 50, proven or the certified gap",
            (Gtsplib(max_nodes=442), Committed(("uav-K20-N20-s1", "uav-K50-N20-s1"), 3)),
            (run("milp"),),
            omegas=(0.0, 0.5, 0.9),
            budget=Budget(120.0),
            reference=Reference(own_proofs=True),
            outputs=("doc-exact-scale",),
            jobs=1,
            rough_time="10 min",
            quick={
                "sources": (Gtsplib(("11berlin52", "20kroA100", "40d198")),),
                "budget": Budget(30.0),
                "outputs": (),
            },
        ),
        Benchmark(
            "exact-frontier",
            "milp past the published frontier: the symmetric GTSPLIB files of 443-1,084 nodes, "
            "3,600 s each",
            (Gtsplib(min_nodes=443, max_nodes=1084),),
            (run("milp"),),
            budget=Budget(3600.0),
            reference=Reference(own_proofs=True),
            outputs=("doc-exact-frontier",),
            jobs=1,
            rough_time="20 h",
            quick={
                "sources": (Gtsplib(("107si535",)),),
                "budget": Budget(300.0),
            },
        ),
        Benchmark(
            "exact-frontier-uav",
            "milp on the committed UAV sets of K = 100 and 200 (3 instances, omega 0, 0.5, 0.9), "
            "600 s each: proven or the certified gap",
            (Committed(("uav-K100-N20-s1", "uav-K200-N20-s1"), 3),),
            (run("milp"),),
            omegas=(0.0, 0.5, 0.9),
            budget=Budget(600.0),
            reference=Reference(own_proofs=True),
            outputs=("doc-exact-frontier-uav",),
            jobs=1,
            rough_time="3 h",
            quick={
                "sources": (Committed(("uav-K100-N20-s1",), 1),),
                "omegas": (0.9,),
                "outputs": (),
            },
        ),
        Benchmark(
            "textbook",
            "the textbook MILP (DFJ, MTZ, flow rows in cvxpy) against milp and dp, K = 4-10",
            (Committed(tuple(f"uav-K{k}-N20-s1" for k in range(4, 11)), 2),),
            (
                run("dp"),
                run("milp"),
                run("milp-textbook", "textbook dfj", subtour="dfj"),
                run("milp-textbook", "textbook mtz", subtour="mtz"),
                run("milp-textbook", "textbook flow", subtour="flow"),
            ),
            budget=Budget(60.0),
            reference=Reference(exact=(("dp", 12),)),
            outputs=("doc-textbook",),
            jobs=1,
            rough_time="30 min",
            quick={
                "sources": (Committed(("uav-K4-N20-s1", "uav-K5-N20-s1"), 1),),
                "budget": Budget(20.0),
                "outputs": (),
            },
        ),
        Benchmark(
            "scale",
            "the paper's solvers and ours on the committed UAV sets of K = 20-200 against "
            "their reference.csv",
            (Committed(_LARGE_UAV, 10),),
            tuple(fixed_budget(s) for s in ("greedy", "aco", "drl", "am", "local", "lns")),
            budget=Budget(10.0),
            outputs=("profile", "gap-k", "anytime"),
            rough_time="6 min",
            quick={"sources": (Committed(("uav-K20-N20-s1", "uav-K50-N20-s1"), 1),), "budget": Budget(2.0)},
        ),
        Benchmark(
            "references",
            "fill the committed UAV sets' reference.csv: milp's proven optimum or bound, "
            "else the best of lns over seeds",
            (Committed(_LARGE_UAV),),
            (run("milp", one_seed=True), LNS_BUDGET),
            omegas=(0.3, 0.5, 0.6),
            seeds=(0, 1, 2),
            budget=Budget(600.0),
            reference=Reference(own_proofs=True),
            outputs=("update-references",),
            jobs=1,
            rough_time="days (K >= 50)",
            quick={
                "sources": (Committed(("uav-K20-N20-s1",), 1),),
                "seeds": (0,),
                "budget": Budget(10.0),
                "omegas": (0.5,),
                "outputs": (),
            },
        ),
        Benchmark(
            "sets",
            "any solvers over any instance sets (--set NAME|PATH) against their reference.csv",
            (Gtsplib(max_nodes=200, symmetric_only=False),),
            tuple(fixed_budget(s) for s in ("greedy", "lns")),
            budget=Budget(10.0),
            outputs=("profile", "gap-k"),
            out_dir="results/sets",
            rough_time="depends",
            quick={"sources": (Gtsplib(("11berlin52", "20kroA100")),), "budget": Budget(2.0)},
        ),
    )
}


def get_benchmark(name: str) -> Benchmark:
    """The definition named ``name``.

    Raises
    ------
    InputError
        For an unknown name, listing the valid ones.
    """
    if name not in BENCHMARKS:
        raise InputError(f"unknown benchmark {name!r} (valid: {', '.join(BENCHMARKS)})")
    return BENCHMARKS[name]


__all__ = [
    "BENCHMARKS",
    "GLNS_MACHINE_FACTOR",
    "LNS_BUDGET",
    "PAPER_OMEGAS",
    "SAMPLES",
    "Benchmark",
    "Budget",
    "Committed",
    "Generated",
    "Gtsplib",
    "Reference",
    "Run",
    "Source",
    "fixed_budget",
    "get_benchmark",
    "run",
]

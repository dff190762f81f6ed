"""The solver contract: what a solver is, what it returns and what the harness makes of it.

A solver is any class with a ``solve`` method (the :class:`Solver` protocol) returning a
:class:`Solution`; :func:`gtsp_bench.registry.run_solver` checks and re-prices it into a
:class:`Result`. Four optional parts of a solver class are declared here, not guessed:

``asymmetric = True``
    a class attribute: the solver prices a tour in its direction and may be given asymmetric
    instances (:func:`handles_asymmetric`; absent means ``False``);
``capped = True``
    a class attribute: the solver searches until a time limit (or, lns, stops when done, the
    limit a cap); given none, :func:`gtsp_bench.registry.run_solver` gives it the default one,
    :func:`gtsp_bench.checks.default_time_limit` (:func:`is_capped`; absent means ``False``:
    ``None`` reaches the solver);
``revision()``
    a class method returning a short tag of the data the solver's answers depend on besides its
    code (a learned policy's weights); benchmarks put it in their task keys
    (:func:`gtsp_bench.registry.solver_revision`);
``solve_batch(instances, omegas, *, seed=0)``
    many instances in one call (learned policies decode a batch as one tensor program): the
    :class:`BatchSolver` protocol, tested by :func:`solves_batches`.

Two optional keywords of ``solve`` are declared the same way, by naming them in its signature
(:func:`takes_keyword`); the harness passes them only to a solver that does:

``progress``
    a :class:`Progress` callable the solver calls with each better objective it finds (and, for
    an exact solver, each better lower bound); the harness turns the calls into the result's
    :attr:`Result.trajectory`. A solver that does not declare it reports its one answer.
``initial``
    a warm start: a :class:`Solution` already checked and priced by the evaluator (its
    ``lower_bound`` is whatever the caller claimed, unchecked). A solver without it refuses a
    warm start with one :class:`~gtsp_bench.errors.InputError` line.

A solver that runs threads of its own may run as many as :data:`SOLVE_THREADS_VAR` says where it
is set (a benchmark's worker processes set it), at most :func:`usable_cores`
(:func:`allowed_threads`).
"""

from __future__ import annotations

import inspect
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np

from gtsp_bench.energy import Energy
from gtsp_bench.instance import Instance

#: Statuses a solution may have.
STATUSES = ("optimal", "feasible", "time_limit", "failed")
#: Relative tolerance between a solver's claimed objective and the evaluator's.
REL_TOL = 1e-6


@dataclass(frozen=True)
class Solution:
    """What a solver returns; :func:`run_solver` checks and re-prices it.

    Attributes
    ----------
    order
        Cluster indices in visiting order (depot excluded), each cluster once.
    heads
        ``heads[k]``: index of cluster k's head inside cluster k.
    objective
        The objective the solver believes this solution has; a mismatch with the evaluator
        (relative 1e-6) is a :class:`SolverError`.
    status
        ``"optimal"`` (proven), ``"feasible"``, ``"time_limit"`` (stopped by the limit; the best
        solution found) or ``"failed"``.
    lower_bound
        A proven lower bound on the optimum, if the solver has one.
    stats
        Free-form solver statistics (iterations, nodes, gap, ...).
    """

    order: tuple[int, ...]
    heads: tuple[int, ...]
    objective: float
    status: str = "feasible"
    lower_bound: float | None = None
    stats: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class TrajectoryPoint:
    """One point of a solve's trajectory: the best objective and bound known at a time.

    Attributes
    ----------
    time_s
        Seconds since the harness started the solve.
    objective
        The best objective found by then (never increases along a trajectory).
    lower_bound
        The best proven lower bound by then, if the solver has one (never decreases).
    """

    time_s: float
    objective: float
    lower_bound: float | None = None

    @property
    def gap(self) -> float | None:
        """``(objective - lower_bound) / |objective|``, or ``None`` without a bound."""
        if self.lower_bound is None:
            return None
        return max(0.0, self.objective - self.lower_bound) / max(abs(self.objective), 1e-300)

    def to_dict(self) -> dict[str, float | None]:
        """The JSON object of one point in ``gtsp-bench solve --json``."""
        return {"time_s": self.time_s, "objective": self.objective, "lower_bound": self.lower_bound}


class Progress(Protocol):
    """What a solver that declares ``progress`` is given: call it with each better objective
    (the exact cost of a tour it holds) and, for an exact solver, each better lower bound.

    Either may be left out (``None``); calls that improve neither are ignored, so a solver may
    call it freely. It is cheap, thread-safe and never raises: what a solver reports wrongly
    (a non-number, an objective below its final answer) surfaces as a
    :class:`~gtsp_bench.errors.SolverError` after the solve.
    """

    def __call__(self, objective: float | None = None, lower_bound: float | None = None) -> None:
        """Report an objective and/or a lower bound."""
        ...


def no_progress(objective: float | None = None, lower_bound: float | None = None) -> None:
    """A :class:`Progress` that ignores everything (a solver's default)."""


def takes_keyword(solver: object, name: str) -> bool:
    """Whether a solver's (object's or class's) ``solve`` declares the keyword ``name``
    (``"progress"``, ``"initial"``); a bare ``**kwargs`` does not count."""
    solve = getattr(solver, "solve", None)
    if not callable(solve):
        return False
    try:
        params = inspect.signature(solve).parameters
    except (TypeError, ValueError):
        return False
    param = params.get(name)
    return param is not None and param.kind in (inspect.Parameter.KEYWORD_ONLY,
                                                inspect.Parameter.POSITIONAL_OR_KEYWORD)


@runtime_checkable
class Solver(Protocol):
    """The solver interface: one method.

    ``time_limit`` is in seconds (``None``: the solver's own default); ``seed`` makes a randomised
    solver reproducible. ``omega`` is ``None`` for distance-only instances. A class attribute
    ``asymmetric = True`` (not part of the protocol; absent means ``False``) declares that the
    solver prices a tour in its direction and so may be given asymmetric instances (on the class
    itself: :func:`handles_asymmetric`).
    """

    def solve(
        self, instance: Instance, omega: float | None, *, time_limit: float | None, seed: int
    ) -> Solution:
        """Solve ``instance`` for weight ``omega``."""
        ...


@runtime_checkable
class BatchSolver(Solver, Protocol):
    """A solver that also solves many instances in one call (declared by defining
    ``solve_batch``); the benchmarks time such a batch as one task."""

    def solve_batch(self, instances: Sequence[Instance], omegas: Sequence[float | None], *,
                    seed: int = 0) -> list[Solution]:
        """One solution per instance, in order."""
        ...


def plain(value: Any) -> Any:
    """``value`` in JSON's types: numpy scalars and arrays as numbers and lists, tuples as
    lists, mapping keys as strings, a float that is not finite as ``None``, anything else as its
    ``str``."""
    if isinstance(value, Mapping):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [plain(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if value is None or isinstance(value, (bool, int, str)):
        return value
    return str(value)


def solves_batches(solver: object) -> bool:
    """Whether a solver (object or class) defines ``solve_batch``."""
    return callable(getattr(solver, "solve_batch", None))


@dataclass(frozen=True)
class Result:
    """A checked, re-priced solution: what the CLI prints and the runner stores."""

    instance: str
    solver: str | None
    omega: float | None
    order: tuple[int, ...]
    heads: tuple[int, ...]
    objective: float
    energy: Energy | None
    distance: float
    status: str
    lower_bound: float | None
    runtime_s: float
    stats: Mapping[str, Any] = field(default_factory=dict)
    #: Each improvement, in time order; the last point is the answer (empty: not solved here).
    trajectory: tuple[TrajectoryPoint, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """The JSON object of ``gtsp-bench solve --json``."""
        energy = None
        if self.energy is not None:
            energy = {k: getattr(self.energy, k) for k in ("total", "ground", "flight", "hover")}
        return {
            "instance": self.instance,
            "solver": self.solver,
            "omega": self.omega,
            "order": list(self.order),
            "heads": list(self.heads),
            "objective": self.objective,
            "energy": energy,
            "distance": self.distance,
            "status": self.status,
            "lower_bound": self.lower_bound,
            "runtime_s": self.runtime_s,
            "trajectory": [p.to_dict() for p in self.trajectory],
            "stats": plain(self.stats),
        }

    def summary(self) -> str:
        """A few readable lines."""
        unit = " J" if self.energy is not None else ""
        lines = [
            f"instance   {self.instance}",
            f"solver     {self.solver or '(evaluated solution)'}"
            + (f"  (omega = {self.omega:g})" if self.omega is not None else ""),
            f"status     {self.status}",
            f"objective  {self.objective:.6f}{unit}",
        ]
        if self.lower_bound is not None:
            lines.append(f"bound      {self.lower_bound:.6f}{unit}")
        if self.energy is not None:
            e = self.energy
            lines.append(
                f"energy     ground {e.ground:.3f} J, flight {e.flight:.3f} J, hover {e.hover:.3f} J"
            )
        lines.append(f"distance   {self.distance:.3f}")
        lines.append("tour       " + " -> ".join(
            (["depot"] if self.energy is not None else [])
            + [f"{c}[{self.heads[c]}]" for c in self.order]
            + (["depot"] if self.energy is not None else [])
        ))
        lines.append(f"runtime    {self.runtime_s:.3f} s")
        return "\n".join(lines)


def handles_asymmetric(solver: object) -> bool:
    """Whether a solver (object or class) declares ``asymmetric = True``: it takes asymmetric
    costs (``edge_cost[i, j] != edge_cost[j, i]``) and prices every tour in its direction.

    The class must declare it itself: the claim is not inherited, so a subclass that adds a step
    (``greedy+ls`` over ``greedy``, whose 2-opt reversals assume symmetric costs) is refused
    until it says ``asymmetric = True`` too.
    """
    cls = solver if inspect.isclass(solver) else type(solver)
    return vars(cls).get("asymmetric", False) is True


def is_capped(solver: object) -> bool:
    """Whether a solver (object or class) declares ``capped = True``: given no time limit, it is
    given :func:`gtsp_bench.checks.default_time_limit`."""
    cls = solver if inspect.isclass(solver) else type(solver)
    return getattr(cls, "capped", False) is True


#: The environment variable by which a benchmark's worker process tells a solver how many threads
#: one solve may run of its own (the cores over the workers: ``gtsp_bench.bench.pool``).
SOLVE_THREADS_VAR = "GTSP_BENCH_SOLVE_THREADS"


def usable_cores() -> int:
    """The cores this process may run on (its CPU affinity where the platform has one), >= 1."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return max(1, cores or 1)


def allowed_threads(limit: int, environ: Mapping[str, str] | None = None,
                    cores: int | None = None) -> int:
    """Threads a solve may run of its own: at most ``limit`` and the cores this process may run
    on (``cores``, default :func:`usable_cores`), and at most what :data:`SOLVE_THREADS_VAR` says
    where it is set (a benchmark's worker processes get the cores over the workers: with
    ``--jobs 1`` on two cores, 2), else ``OMP_NUM_THREADS`` (a setting that is not a number is
    ignored); at least 1."""
    env = os.environ if environ is None else environ
    top = max(1, min(limit, usable_cores() if cores is None else cores))
    for var in (SOLVE_THREADS_VAR, "OMP_NUM_THREADS"):
        text = env.get(var, "").strip()
        if text.isdigit() and int(text) >= 1:
            return min(top, int(text))
    return top


__all__ = [
    "REL_TOL", "SOLVE_THREADS_VAR", "STATUSES", "BatchSolver", "Progress", "Result", "Solution", "Solver",
    "TrajectoryPoint", "allowed_threads", "handles_asymmetric", "is_capped", "no_progress", "solves_batches",
    "takes_keyword", "usable_cores",
]

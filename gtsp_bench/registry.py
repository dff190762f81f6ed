"""Solver interface, registry and the checked harness every solve goes through.

A solver is any class with a ``solve`` method (the :class:`Solver` protocol) returning a
:class:`Solution`. It is registered under a name with :func:`register_solver`, by its class or by a
``"module:Class"`` string so that heavy imports (torch, ortools, ...) happen only when it is used.
:func:`run_solver` times a solve, then re-checks and re-prices the solution with the one evaluator
(:func:`gtsp_bench.energy.evaluate`): a solver never reports its own number unchecked.

Asymmetric costs (a GTSPLIB ``AGTSP`` file, ``Instance.symmetric`` false) are part of the problem
model, but a solver takes them only when its class says so with ``asymmetric = True``
(:func:`handles_asymmetric`; absent means ``False``): :func:`run_solver` refuses an asymmetric
instance for any other solver with one :class:`InputError` line, before it runs.

A solver whose ``solve`` declares ``progress`` reports each improvement to a :class:`Recorder`
(the result's ``trajectory``; ``on_progress`` sees each point as it comes), and one that declares
``initial`` takes a warm start, checked by the evaluator first (:func:`check_initial`).
"""

from __future__ import annotations

import importlib
import inspect
import math
import statistics
import sys
import threading
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, replace
from importlib.metadata import entry_points
from typing import Any

from gtsp_bench.checks import check_omega, check_seed, check_time_limit, default_time_limit, is_number
from gtsp_bench.energy import evaluate
from gtsp_bench.errors import InfeasibleSolutionError, InputError, SolverError
from gtsp_bench.instance import Instance
from gtsp_bench.solver import (
    REL_TOL,
    STATUSES,
    Result,
    Solution,
    Solver,
    TrajectoryPoint,
    handles_asymmetric,
    is_capped,
    solves_batches,
    takes_keyword,
)

#: A warm start: a :class:`Solution`, a :class:`Result` or ``(order, heads)``.
Initial = Solution | Result | tuple[Sequence[int], Sequence[int]]


# ---------------------------------------------------------------------- registry
@dataclass(frozen=True)
class SolverSpec:
    """A registered solver: its name, where its class lives and one line describing it.

    ``plugin`` is the distribution (or, without one, the entry point) a plug-in solver comes from,
    ``None`` for a built-in or a solver registered by :func:`register_solver`.
    """

    name: str
    target: str | type
    description: str
    bench: bool = True
    plugin: str | None = None

    def import_path(self) -> str | None:
        """``"module:Class"`` by which a fresh process (a runner worker) can import the class.

        ``None`` for a class that only exists in this process: one defined in ``__main__``,
        inside a function, or by ``exec``.
        """
        if isinstance(self.target, str):
            return self.target
        module = getattr(self.target, "__module__", None)
        qualname = getattr(self.target, "__qualname__", "")
        if not module or module == "__main__" or "." in qualname:
            return None
        if getattr(sys.modules.get(module), qualname, None) is not self.target:
            return None  # e.g. a class made by exec(): its module does not hold it
        return f"{module}:{qualname}"

    def load(self) -> type:
        """Import and return the solver class.

        Raises
        ------
        InputError
            When its module cannot be imported, lacks the class, or the object is no solver class;
            for a plug-in, also whatever else its import raises.
        """
        if not isinstance(self.target, str):
            return self.target
        module_name, _, attr = self.target.partition(":")
        try:
            obj: Any = importlib.import_module(module_name)
            for part in attr.split(".") if attr else ():
                obj = getattr(obj, part)
        except ImportError as e:
            raise InputError(f"solver {self.name!r} is not available: {e}") from None
        except AttributeError:
            raise InputError(f"solver {self.name!r}: module {module_name!r} has no {attr!r}") from None
        except Exception as e:
            if self.plugin is None:
                raise
            raise InputError(f"solver {self.name!r} (plug-in {self.target}) cannot be loaded: "
                             f"{type(e).__name__}: {e}") from None
        if not inspect.isclass(obj) or not callable(getattr(obj, "solve", None)):
            raise InputError(f"solver {self.name!r}: {self.target} is not a solver class "
                             "(a class with a solve method)")
        return obj


_REGISTRY: dict[str, SolverSpec] = {}
_builtins_loaded = False
#: Plug-ins registered from entry points whose class has not been imported to describe it yet.
_UNDESCRIBED: set[str] = set()


def register_solver(
    name: str, target: str | type, description: str, *, bench: bool = True, replace: bool = False
) -> None:
    """Register a solver class under ``name``.

    Parameters
    ----------
    name
        The name used by ``--solver`` and the runner.
    target
        The class, or ``"module:Class"`` to import it only when used.
    description
        One line for ``gtsp-bench solvers``.
    bench
        Whether the runner uses it by default (``False`` for test oracles and duplicates).
    replace
        Allow re-registering an existing name.
    """
    if not replace and name in _REGISTRY and _REGISTRY[name].target != target:
        raise ValueError(f"a solver named {name!r} is already registered")
    _REGISTRY[name] = SolverSpec(name, target, description, bench)


#: Entry-point group through which other packages register solvers.
ENTRY_POINT_GROUP = "gtsp_bench.solvers"


def _warn(message: str) -> None:
    print(f"gtsp-bench: warning: {message}", file=sys.stderr)


def _load_entry_points() -> None:
    """Register the solvers other installed packages declare in :data:`ENTRY_POINT_GROUP`.

    An entry point ``name = "package.module:Class"`` registers ``Class`` under ``name``; the class
    is imported only when used or listed (:func:`solver_specs`). A name that is already taken (a
    built-in's, or an earlier plug-in's) is skipped with a warning.
    """
    try:
        found = list(entry_points(group=ENTRY_POINT_GROUP))
    except Exception as e:  # a broken installed distribution must not break the built-ins
        _warn(f"cannot read the {ENTRY_POINT_GROUP!r} entry points ({type(e).__name__}: {e}); "
              "plug-in solvers skipped")
        return
    for ep in found:
        if ep.name in _REGISTRY:
            _warn(f"solver {ep.name!r} from entry point {ep.value!r} is already registered; skipped")
            continue
        dist = getattr(ep, "dist", None)
        origin = dist.name if dist is not None else ep.value
        _REGISTRY[ep.name] = SolverSpec(ep.name, ep.value, f"plug-in {ep.value} (from {origin})",
                                        plugin=origin)
        _UNDESCRIBED.add(ep.name)


def _describe_plugins(registry: dict[str, SolverSpec]) -> None:
    """Import each plug-in not yet described: its description becomes its class docstring's first
    line. One that cannot be loaded is dropped from the registry with a warning, so that listing
    and default benchmark runs go on with the others."""
    for name in sorted(_UNDESCRIBED):
        _UNDESCRIBED.discard(name)
        spec = registry.get(name)
        if spec is None or spec.plugin is None:
            continue
        try:
            cls = spec.load()
        except InputError as e:
            _warn(f"{e}; skipped")
            del registry[name]
            continue
        doc = (inspect.getdoc(cls) or "").strip().splitlines()
        first = doc[0].strip() if doc else spec.target
        registry[name] = replace(spec, description=f"{first} (plug-in from {spec.plugin})")


def _registry() -> dict[str, SolverSpec]:
    global _builtins_loaded
    if not _builtins_loaded:
        _builtins_loaded = True
        # Plain data (no import of this module back), then the installed plug-ins.
        for b in importlib.import_module("gtsp_bench.solvers").BUILTIN:
            _REGISTRY.setdefault(b.name, SolverSpec(b.name, b.target, b.description, b.bench))
        _load_entry_points()
    return _REGISTRY


def solver_specs() -> list[SolverSpec]:
    """All registered solvers, sorted by name (plug-ins imported to describe them; one that
    cannot be loaded is left out with a warning)."""
    registry = _registry()
    _describe_plugins(registry)
    return sorted(registry.values(), key=lambda s: s.name)


def solver_names() -> list[str]:
    """Names of all registered solvers, sorted (nothing is imported)."""
    return sorted(_registry())


def solver_revision(name: str) -> str:
    """What the solver's optional ``revision()`` class method returns, else ``""``.

    A solver whose default results depend on data besides its code (a learned policy's shipped
    weights) returns a short tag of that data; the runner puts it in its task keys, so results
    solved with other data are solved again rather than re-used.
    """
    registry = _registry()
    if name not in registry:
        raise InputError(f"unknown solver {name!r} (valid: {', '.join(solver_names())})")
    revision = getattr(registry[name].load(), "revision", None)
    return str(revision()) if callable(revision) else ""


def get_solver(name: str, **options: Any) -> Solver:
    """Instantiate a registered solver with keyword options.

    Raises
    ------
    InputError
        For an unknown name (listing the valid ones) or an option the solver does not take.
    """
    cls = _solver_class(name)
    if options:
        _check_names(name, option_names(cls), options)
    return cls(**options)


def _solver_class(name: str) -> type:
    registry = _registry()
    if name not in registry:
        raise InputError(f"unknown solver {name!r} (valid: {', '.join(solver_names())})")
    return registry[name].load()


def option_names(solver: str | type) -> tuple[str, ...] | None:
    """The keyword options a registered solver (by name, or its class) takes, in order; ``None``
    when it takes any (``**kwargs``)."""
    cls = _solver_class(solver) if isinstance(solver, str) else solver
    params = inspect.signature(cls).parameters
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values()):
        return None
    return tuple(params)


def can_warm_start(name: str) -> bool:
    """Whether the registered solver ``name`` can start from an initial solution (its ``solve``
    declares ``initial``)."""
    return takes_keyword(_solver_class(name), "initial")


def check_option_names(name: str, options: Iterable[str]) -> None:
    """:class:`InputError` (one line, listing the valid ones) when the registered solver ``name``
    does not take one of ``options`` (keyword names); the values are the solver's to check."""
    given = list(options)
    if given:
        _check_names(name, option_names(name), given)


def _check_names(name: str, valid: tuple[str, ...] | None, given: Iterable[str]) -> None:
    unknown = [] if valid is None else [k for k in given if k not in valid]
    if unknown:
        raise InputError(f"solver {name!r} has no option {unknown[0]!r} "
                         f"(options: {', '.join(valid or ()) or 'none'})")


# ---------------------------------------------------------------------- harness
def check_capability(solver: object, name: str, instance: Instance) -> None:
    """:class:`InputError` (one line) when ``instance`` is asymmetric and the solver does not
    declare that it handles asymmetric costs."""
    if not instance.symmetric and not handles_asymmetric(solver):
        raise InputError(f"{name} handles symmetric costs only (this instance is asymmetric)")


def check_initial(instance: Instance, omega: float | None, initial: Initial) -> Solution:
    """A warm start checked and priced by the evaluator, as a :class:`Solution` with status
    ``feasible`` (its ``lower_bound`` kept as claimed, when not above its objective).

    Raises
    ------
    InputError
        One line: not a Solution, a Result nor ``(order, heads)``, an infeasible solution, or a claimed
        lower bound that is not a number or lies above the objective.
    """
    bound: object = None
    if isinstance(initial, (Solution, Result)):
        order, heads, bound = initial.order, initial.heads, initial.lower_bound
    elif isinstance(initial, (tuple, list)) and len(initial) == 2:
        order, heads = initial
    else:
        raise InputError("an initial solution is a Solution, a Result or (order, heads), "
                         f"not {type(initial).__name__}")
    w = check_omega(omega) if instance.is_uav else None
    try:
        ev = evaluate(instance, w, order, heads)
    except InfeasibleSolutionError as e:
        raise InputError(f"infeasible initial solution: {e}") from None
    if bound is not None:
        tol = REL_TOL * max(1.0, abs(ev.objective))
        if not is_number(bound) or not math.isfinite(bound):  # type: ignore[arg-type]
            raise InputError(f"the initial solution's lower bound {bound!r} is not a finite number")
        if bound > ev.objective + tol:
            raise InputError(f"the initial solution's lower bound {bound!r} is above its "
                             f"objective {ev.objective!r}")
    return Solution(tuple(int(c) for c in order), tuple(int(h) for h in heads), ev.objective,
                    "feasible", None if bound is None else float(bound))


def check_warm_start(solver: object, name: str) -> None:
    """:class:`InputError` (one line) when the solver cannot start from an initial solution
    (its ``solve`` does not declare ``initial``)."""
    if not takes_keyword(solver, "initial"):
        raise InputError(f"solver {name!r} cannot start from an initial solution")


class Recorder:
    """The :class:`~gtsp_bench.solver.Progress` the harness hands a solver: it keeps each
    improvement as a :class:`TrajectoryPoint` (objectives never rise, bounds never fall).

    Parameters
    ----------
    start
        The :func:`time.perf_counter` reading the points' times count from.
    listener
        Called with each new point as it is recorded (``gtsp-bench solve --progress``).
    """

    def __init__(self, start: float, listener: Callable[[TrajectoryPoint], None] | None = None) -> None:
        self.start = start
        self.listener = listener
        self.points: list[TrajectoryPoint] = []
        self.best = math.inf
        self.bound = -math.inf
        self.error: str | None = None  #: the first bad report, raised after the solve
        self._lock = threading.Lock()

    def __call__(self, objective: float | None = None, lower_bound: float | None = None) -> None:
        """Record ``objective`` and/or ``lower_bound`` when either improves."""
        now = time.perf_counter() - self.start
        with self._lock:
            better = False
            for kind, value in (("objective", objective), ("lower bound", lower_bound)):
                if value is None:
                    continue
                try:
                    x = float(value)
                except (TypeError, ValueError):
                    x = math.nan
                if not math.isfinite(x):
                    self.error = self.error or f"reported {kind} {value!r}, not a finite number"
                elif kind == "objective" and x < self.best:
                    self.best, better = x, True
                elif kind == "lower bound" and x > self.bound:
                    self.bound, better = x, True
            if better and math.isfinite(self.best):
                point = TrajectoryPoint(now, self.best, self.bound if math.isfinite(self.bound) else None)
                self.points.append(point)
                if self.listener is not None:
                    self.listener(point)

    def finish(self, runtime: float, objective: float, lower_bound: float | None, tol: float
               ) -> tuple[TrajectoryPoint, ...]:
        """The trajectory ending at the answer (``objective``, ``lower_bound``) at ``runtime``.

        A reported objective within ``tol`` below the answer (rounding) counts as the answer; the
        answer is appended when the last point is not it (a solver that reports nothing gets
        one point). Raises :class:`SolverError` for a bad report, an objective reported below the
        answer by more than ``tol`` or a bound above it.
        """
        with self._lock:
            if self.error is not None:
                raise SolverError(self.error)
            if self.best < objective - tol:
                raise SolverError(f"reported objective {self.best!r} below its answer's {objective!r}")
            if self.bound > objective + tol:
                raise SolverError(f"reported lower bound {self.bound!r} above its answer's {objective!r}")
            points = [replace(p, objective=max(p.objective, objective)) for p in self.points]
            bound = max((b for b in (lower_bound, self.bound) if b is not None and math.isfinite(b)),
                        default=None)
            if not points or (points[-1].objective, points[-1].lower_bound) != (objective, bound):
                point = TrajectoryPoint(max(runtime, points[-1].time_s if points else 0.0), objective,
                                        bound)
                points.append(point)
                if self.listener is not None:
                    self.listener(point)
            return tuple(points)


def run_solver(
    solver: Solver | str,
    instance: Instance,
    omega: float | None = 0.5,
    *,
    time_limit: float | None = None,
    seed: int = 0,
    name: str | None = None,
    initial: Initial | None = None,
    on_progress: Callable[[TrajectoryPoint], None] | None = None,
) -> Result:
    """Solve, time, check and re-price.

    Parameters
    ----------
    solver
        A solver object or a registered name.
    instance
        The instance.
    omega
        Weight of the ground energy in [0, 1] (ignored for distance-only instances).
    time_limit
        Seconds (``None``: :func:`gtsp_bench.checks.default_time_limit` for a solver that declares
        ``capped = True``, else the solver's own rule).
    seed
        Random seed.
    name
        Name recorded in the result (default: the registered name or the class name).
    initial
        A warm start, a :class:`Solution`, a :class:`Result` or ``(order, heads)``, checked by
        :func:`check_initial`; only for a solver whose ``solve`` declares ``initial``.
    on_progress
        Called with each point of the trajectory as it is recorded (the last one: the answer).

    Raises
    ------
    InputError
        Bad omega, time limit or seed, an unknown solver name, an asymmetric instance for a
        solver that handles symmetric costs only (:func:`check_capability`), or a warm start
        that is infeasible or given to a solver that takes none.
    SolverError
        The solver failed, or returned an infeasible solution, an unknown status, a claimed
        objective the evaluator does not confirm, or a lower bound above the objective; or it
        reported a trajectory its answer contradicts (:meth:`Recorder.finish`).
    """
    if isinstance(solver, str):
        name = name or solver
        solver = get_solver(solver)
    name = name or type(solver).__name__
    w = check_omega(omega) if instance.is_uav else None
    time_limit = check_time_limit(time_limit)
    if time_limit is None and is_capped(solver):
        time_limit = default_time_limit(instance.n_clusters)
    check_seed(seed)
    check_capability(solver, name, instance)
    extra: dict[str, Any] = {}
    if initial is not None:
        check_warm_start(solver, name)
        extra["initial"] = check_initial(instance, w, initial)
    start = time.perf_counter()
    recorder = Recorder(start, on_progress)
    if takes_keyword(solver, "progress"):
        extra["progress"] = recorder
    sol = solver.solve(instance, w, time_limit=time_limit, seed=seed, **extra)
    return checked_result(sol, instance, w, name, time.perf_counter() - start, recorder)


def checked_result(sol: object, instance: Instance, omega: float | None, name: str, runtime: float,
                   recorder: Recorder | None = None) -> Result:
    """Check a solver's answer on ``instance`` and re-price it with the evaluator; its trajectory
    is what ``recorder`` heard, ending at the answer (one point without a recorder).

    Raises
    ------
    SolverError
        Not a :class:`Solution`, an unknown or ``failed`` status, an infeasible tour, a claimed
        objective the evaluator does not confirm, a lower bound above the objective, or a
        trajectory the answer contradicts.
    """
    w = omega
    recorder = recorder or Recorder(0.0, None)
    if not isinstance(sol, Solution):
        raise SolverError(f"solver {name!r} returned {type(sol).__name__}, not a Solution")
    if sol.status not in STATUSES:
        raise SolverError(f"solver {name!r} returned unknown status {sol.status!r}")
    if sol.status == "failed":
        raise SolverError(f"solver {name!r} failed on {instance.name}")
    try:
        ev = evaluate(instance, w, sol.order, sol.heads)
    except InfeasibleSolutionError as e:
        raise SolverError(f"solver {name!r} returned an infeasible solution: {e}") from None
    tol = REL_TOL * max(1.0, abs(ev.objective))
    if not math.isfinite(sol.objective) or abs(sol.objective - ev.objective) > tol:
        raise SolverError(
            f"solver {name!r} claims objective {sol.objective!r} but the evaluator finds "
            f"{ev.objective!r} on {instance.name}"
        )
    if sol.lower_bound is not None and sol.lower_bound > ev.objective + tol:
        raise SolverError(
            f"solver {name!r} claims lower bound {sol.lower_bound!r} above its objective "
            f"{ev.objective!r} on {instance.name}"
        )
    lower = None if sol.lower_bound is None else float(sol.lower_bound)
    try:
        trajectory = recorder.finish(runtime, ev.objective, lower, tol)
    except SolverError as e:
        raise SolverError(f"solver {name!r} {e} on {instance.name}") from None
    return Result(
        instance=instance.name,
        solver=name,
        omega=w,
        order=tuple(int(c) for c in sol.order),
        heads=tuple(int(h) for h in sol.heads),
        objective=ev.objective,
        energy=ev.energy,
        distance=ev.distance,
        status=sol.status,
        lower_bound=lower,
        runtime_s=runtime,
        stats=dict(sol.stats),
        trajectory=trajectory,
    )


def run_solver_batch(
    solver: Solver | str, instances: Sequence[Instance], omega: float | None = 0.5, *, seed: int = 0,
    name: str | None = None, repeats: int = 1,
) -> tuple[list[Result], float]:
    """Solve ``instances`` in one call of the solver's ``solve_batch`` (one by one through
    ``solve`` when it has none), ``repeats`` times; check and re-price every answer of the last
    call. Returns the results and the median wall time of a whole batch in seconds (each
    result's ``runtime_s`` is that time over the batch's size).

    Raises
    ------
    InputError, SolverError
        As :func:`run_solver`.
    """
    if isinstance(solver, str):
        name = name or solver
        solver = get_solver(solver)
    name = name or type(solver).__name__
    check_seed(seed)
    omegas = [check_omega(omega) if inst.is_uav else None for inst in instances]
    for inst in instances:
        check_capability(solver, name, inst)
    walls, sols = [], []
    for _ in range(max(1, int(repeats))):
        start = time.perf_counter()
        if solves_batches(solver):
            sols = list(solver.solve_batch(list(instances), omegas, seed=seed))
        else:
            sols = [solver.solve(i, w, time_limit=None, seed=seed)
                    for i, w in zip(instances, omegas, strict=True)]
        walls.append(time.perf_counter() - start)
    if len(sols) != len(instances):
        raise SolverError(f"solver {name!r} returned {len(sols)} solutions for {len(instances)} instances")
    wall = statistics.median(walls)
    each = wall / max(1, len(instances))
    results = [checked_result(s, i, w, name, each) for s, i, w in zip(sols, instances, omegas, strict=True)]
    return results, wall

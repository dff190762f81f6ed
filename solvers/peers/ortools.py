"""OR-Tools' vehicle routing solver (first solution + local search metaheuristic) as an outside peer.

The GTSP becomes a one-vehicle routing problem: every node is a visit, the nodes of each cluster
form one **mandatory disjunction** of cardinality 1 (OR-Tools' way to say *exactly one of these*:
a disjunction without a penalty must be served, so no penalty has to be chosen large enough and
no penalty can overflow). Node costs are folded into the arc costs, half of each end's node cost on
every arc, and scaled to integers as for the pyvrp peer (:mod:`.scaling`: whole-number costs as
they are, else the largest about ``resolution`` units; costs whose tours could overflow int64 sums
or could not be told apart are refused with one :class:`InputError` line). The matrix is handed
over with ``RegisterTransitMatrix``, so the search never calls back into Python. The tour found is
mapped back and priced exactly (:meth:`~gtsp_bench.problem.Problem.tour_cost`).

OR-Tools needs a depot. A UAV instance has one. A ``.gtsp`` file has none: as in the pyvrp peer, a
node of its smallest cluster is made the depot and the other clusters become disjunctions; when that
cluster has several nodes OR-Tools runs once per node (the time limit shared among the runs) and the
best tour is kept. (GTSPLIB files all have a one-node cluster: a single run.)

The search (``first_solution``, then ``metaheuristic``) runs until the time limit, unless
``solution_limit`` stops it first or a metaheuristic without escape (``GREEDY_DESCENT``) reaches a
local optimum. Guided local search never stops on its own: it runs to the limit and reports status
``time_limit``, as the other time-limited solvers do.

Seeding: ``seed`` reseeds OR-Tools' constraint solver (``Solver.ReSeed``), the random source of its
randomised operators. OR-Tools' default routing operators and guided local search are
deterministic, so in practice the seed does not change a run; and a run stopped by its time limit
depends on the machine's speed whatever the seed. A run stopped by ``solution_limit`` is
reproducible.

OR-Tools never loads into the caller's process: the ortools and highspy wheels each bundle a
``libhighs.so.1`` of a different version, and in one process whichever loads second fails on a
missing symbol (so ``milp`` and ``ortools`` could not both run in a script, a notebook or pytest).
The first solve starts a worker process (``python -m gtsp_bench.solvers.peers.ortools``) that
imports OR-Tools and serves this process's later solves; it ends when this process does. Its
start-up (about half a second) is not charged to the time limit. The registry and a listing import
nothing of OR-Tools.
"""

from __future__ import annotations

import atexit
import contextlib
import math
import os
import pickle
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from gtsp_bench.solvers.peers.depots import best_of_runs, depot_candidates, run_nodes
from gtsp_bench.solvers.peers.scaling import MAX_EXACT, RESOLUTION, folded_costs

from gtsp_bench.checks import (
    check_choice,
    check_float,
    check_int,
    check_seed,
    time_limit_or_default,
)
from gtsp_bench.errors import InputError, SolverError
from gtsp_bench.instance import Instance
from gtsp_bench.problem import Problem, price
from gtsp_bench.solver import Progress, Solution, no_progress

#: First solution strategies (names of OR-Tools' ``FirstSolutionStrategy``) that build a tour of
#: this model; ``EVALUATOR_STRATEGY`` (needs a callback), ``SWEEP`` (needs coordinates),
#: ``BEST_INSERTION`` (finds no tour here) and ``ALL_UNPERFORMED`` (leaves the mandatory clusters
#: out) are not offered.
FIRST_SOLUTIONS = (
    "AUTOMATIC", "PATH_CHEAPEST_ARC", "PATH_MOST_CONSTRAINED_ARC", "SAVINGS", "PARALLEL_SAVINGS",
    "CHRISTOFIDES", "PARALLEL_CHEAPEST_INSERTION", "SEQUENTIAL_CHEAPEST_INSERTION",
    "LOCAL_CHEAPEST_INSERTION", "LOCAL_CHEAPEST_COST_INSERTION", "GLOBAL_CHEAPEST_ARC",
    "LOCAL_CHEAPEST_ARC", "FIRST_UNBOUND_MIN_VALUE",
)
#: Local search metaheuristics (names of OR-Tools' ``LocalSearchMetaheuristic``).
METAHEURISTICS = (
    "GUIDED_LOCAL_SEARCH", "GREEDY_DESCENT", "SIMULATED_ANNEALING", "TABU_SEARCH",
    "GENERIC_TABU_SEARCH", "AUTOMATIC",
)
#: OR-Tools' search statuses that say the time limit stopped the search (a metaheuristic stopped by
#: it reports ``ROUTING_SUCCESS``: the run's duration tells that case).
_TIMED_OUT = ("ROUTING_PARTIAL_SUCCESS_LOCAL_OPTIMUM_NOT_REACHED", "ROUTING_FAIL_TIMEOUT")
#: Shortest run handed to OR-Tools (seconds): a run owes a tour even when the budget is spent.
_MIN_RUN = 1e-3
#: Seconds allowed for the first tour alone when the limit ran out before it.
_FIRST_TOUR_S = 60


def _import_ortools():
    """OR-Tools' routing modules, or one :class:`InputError` line saying why they cannot load."""
    try:
        from ortools.constraint_solver import pywrapcp, routing_enums_pb2
    except ImportError as e:  # a required dependency: only a broken install gets here
        raise InputError(f"solver 'ortools' needs the package ortools ({e}); "
                         "install it with pip install ortools") from None
    return pywrapcp, routing_enums_pb2


def route(
    cost: np.ndarray, sizes: list[int], first_solution: str, metaheuristic: str, seconds: float,
    solution_limit: int | None, seed: int, initial: list[int] | None = None,
    report: Callable[[list[int]], None] | None = None,
) -> dict[str, Any]:
    """One OR-Tools run (in the worker process): node 0 is the depot, then groups of ``sizes``
    nodes, each a mandatory disjunction of cardinality 1; ``cost`` is the integer arc matrix.

    ``initial`` (the route's nodes after the depot) is the first solution when given, instead of
    ``first_solution``'s; ``report`` is called with the route of each solution cheaper than the
    ones before (from OR-Tools' solution callback).

    Returns ``visits`` (the route's nodes from the depot), ``solutions`` (found by the search),
    ``status`` (OR-Tools' name) and ``timed_out`` (the limit stopped the search).
    """
    pywrapcp, enums = _import_ortools()
    manager = pywrapcp.RoutingIndexManager(len(cost), 1, 0)
    routing = pywrapcp.RoutingModel(manager)
    routing.solver().ReSeed(seed)
    arcs = routing.RegisterTransitMatrix(cost.tolist())
    routing.SetArcCostEvaluatorOfAllVehicles(arcs)
    first = 1
    for size in sizes:  # no penalty: the disjunction is mandatory, exactly one node visited
        routing.AddDisjunction([manager.NodeToIndex(i) for i in range(first, first + size)])
        first += size
    params = pywrapcp.DefaultRoutingSearchParameters()
    params.first_solution_strategy = getattr(enums.FirstSolutionStrategy, first_solution)
    params.local_search_metaheuristic = getattr(enums.LocalSearchMetaheuristic, metaheuristic)
    params.time_limit.FromNanoseconds(max(int(seconds * 1e9), int(_MIN_RUN * 1e9)))
    if solution_limit is not None:
        params.solution_limit = solution_limit
    params.log_search = False

    def visits_now() -> list[int]:
        out, index = [], routing.Start(0)
        while not routing.IsEnd(index):
            out.append(manager.IndexToNode(index))
            index = routing.NextVar(index).Value()
        return out

    best = [math.inf]

    def on_solution() -> None:  # (the assignment being accepted; its cost is CostVar's value)
        value = routing.CostVar().Value()
        if value < best[0]:
            best[0] = value
            report(visits_now())  # type: ignore[misc]

    if report is not None:
        routing.AddAtSolutionCallback(on_solution)
    began = time.perf_counter()
    if initial is not None:
        start = routing.ReadAssignmentFromRoutes([initial], True)
        if start is None:
            raise SolverError("OR-Tools did not accept the initial route")
        assignment = routing.SolveFromAssignmentWithParameters(start, params)
    else:
        assignment = routing.SolveWithParameters(params)
    took = time.perf_counter() - began
    status = enums.RoutingSearchStatus.Value.Name(routing.status())
    if assignment is None and status == "ROUTING_FAIL_TIMEOUT":
        # The limit ran out before the first tour: take the first solution alone, as every
        # solver returns its best tour when stopped by its limit.
        params.solution_limit = 1
        params.time_limit.FromSeconds(_FIRST_TOUR_S)
        assignment = routing.SolveWithParameters(params)
        took = time.perf_counter() - began
        status = enums.RoutingSearchStatus.Value.Name(routing.status())
        seconds = 0.0  # the limit is spent: the answer is marked as stopped by it
    if assignment is None:
        raise SolverError(f"OR-Tools found no tour ({status}, first solution {first_solution})")
    visits, index = [], routing.Start(0)
    while not routing.IsEnd(index):
        visits.append(manager.IndexToNode(index))
        index = assignment.Value(routing.NextVar(index))
    # A metaheuristic stopped by the limit reports plain success: the clock tells.
    return {"visits": visits, "solutions": int(routing.solver().Solutions()), "status": status,
            "timed_out": status in _TIMED_OUT or took >= 0.99 * seconds}


class _Worker:
    """The process OR-Tools runs in: ``python -m gtsp_bench.solvers.peers.ortools``, started on
    the first solve and kept for the next ones; requests and answers are pickles on its stdin and
    stdout. It ends when its stdin closes (this process ended or dropped it)."""

    def __init__(self) -> None:
        self.pid = os.getpid()
        # The worker finds this package as this process did (its sys.path), and -P keeps the
        # current folder off its path (a file named ortools.py there would hide OR-Tools).
        path = [os.path.abspath(p) for p in sys.path if p]
        env = {**os.environ, "PYTHONPATH": os.pathsep.join(dict.fromkeys(path))}
        self.proc = subprocess.Popen(
            [sys.executable, "-P", "-m", __name__], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL, env=env,
        )

    def call(self, request: dict[str, Any] | None,
             on_route: Callable[[list[int]], None] | None = None) -> Any:
        """Send ``request`` (``None``: only read the handshake) and return the answer; a lost
        worker is a :class:`SolverError`. Routes the worker sends before its answer (each better
        solution, when the request asks for them) go to ``on_route`` as they come."""
        try:
            if request is not None:
                pickle.dump(request, self.proc.stdin, protocol=pickle.HIGHEST_PROTOCOL)
                self.proc.stdin.flush()
            kind, value = pickle.load(self.proc.stdout)
            while kind == "route":
                if on_route is not None:
                    on_route(value)
                kind, value = pickle.load(self.proc.stdout)
        except (EOFError, OSError, pickle.UnpicklingError):
            code = self.proc.poll()
            raise SolverError(f"the OR-Tools worker process ended (exit code {code})") from None
        if kind == "ok":
            return value
        raise (InputError if kind == "InputError" else SolverError)(value)

    def close(self) -> None:
        """End the worker: close its stdin, then kill it if it lingers."""
        with contextlib.suppress(OSError):
            self.proc.stdin.close()
        try:
            self.proc.wait(timeout=1.0)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


_WORKER: _Worker | None = None
_LOCK = threading.Lock()


def _call_worker(request: dict[str, Any] | None,
                 on_route: Callable[[list[int]], None] | None = None) -> Any:
    """Run ``request`` in this process's OR-Tools worker (started if needed; ``None``: just start
    it), passing the routes it reports on the way to ``on_route``. A request that does not come
    back whole (an error, an interrupt) drops the worker, so a late answer can never be read as
    the next one's."""
    global _WORKER
    with _LOCK:
        if _WORKER is None or _WORKER.pid != os.getpid() or _WORKER.proc.poll() is not None:
            _WORKER = _Worker()  # (a forked child never shares its parent's worker)
            try:
                _WORKER.call(None)
            except BaseException:
                _WORKER.close()
                _WORKER = None
                raise
            atexit.register(_WORKER.close)
        if request is None:
            return None
        try:
            return _WORKER.call(request, on_route)
        except SolverError:
            if _WORKER.proc.poll() is None:
                raise  # OR-Tools' own error: the worker is fine
            _WORKER = None
            raise
        except BaseException:
            _WORKER.close()
            _WORKER = None
            raise


def _serve() -> None:
    """The worker's loop: import OR-Tools, answer each pickled request until stdin closes."""
    out = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)  # anything printed by a library goes to stderr, never into the answers
    source = sys.stdin.buffer

    def answer(kind: str, value: Any) -> None:
        pickle.dump((kind, value), out, protocol=pickle.HIGHEST_PROTOCOL)
        out.flush()

    try:
        _import_ortools()
    except InputError as e:
        answer("InputError", str(e))
        return
    answer("ok", None)
    while True:
        try:
            request = pickle.load(source)
        except EOFError:
            return
        report = None
        if request.pop("report", False):
            def report(visits: list[int]) -> None:
                answer("route", visits)
        try:
            result = ("ok", route(**request, report=report))
        except Exception as e:  # sent back whole: the caller raises it
            result = (type(e).__name__, str(e))
        try:
            answer(*result)
        except (BrokenPipeError, OSError):
            return


class OrToolsPeer:
    """OR-Tools routing on the GTSP with one mandatory disjunction per cluster (see the module
    docstring).

    Parameters
    ----------
    first_solution
        OR-Tools first solution strategy, one of :data:`FIRST_SOLUTIONS`.
    metaheuristic
        OR-Tools local search metaheuristic, one of :data:`METAHEURISTICS`.
    resolution
        The largest folded arc cost becomes about this many integer units (> 0), unless the costs
        are already whole numbers.
    solution_limit
        Stop each run after this many solutions (>= 1; ``None``: only the time limit stops
        guided local search). A run stopped this way is reproducible.
    """

    #: The transit matrix is directed (row = from, column = to).
    asymmetric = True
    capped = True  #: given no time limit, run_solver gives it the default one

    def __init__(
        self, first_solution: str = "PATH_CHEAPEST_ARC", metaheuristic: str = "GUIDED_LOCAL_SEARCH",
        resolution: float = RESOLUTION, solution_limit: int | None = None,
    ) -> None:
        self.first_solution = check_choice("first_solution", first_solution, FIRST_SOLUTIONS)
        self.metaheuristic = check_choice("metaheuristic", metaheuristic, METAHEURISTICS)
        self.resolution = check_float("resolution", resolution, 0.0, float(MAX_EXACT))
        self.solution_limit = (None if solution_limit is None
                               else check_int("solution_limit", solution_limit, 1))

    def solve(
        self, instance: Instance, omega: float | None, *, time_limit: float | None = None,
        seed: int = 0, initial: Solution | None = None, progress: Progress = no_progress,
    ) -> Solution:
        """Run OR-Tools (once per node of the smallest cluster when there is no depot), from the
        warm start ``initial`` if given (its route read in as the first solution; without a
        depot, in the run from its head in the smallest cluster), reporting each better tour."""
        time_limit = time_limit_or_default(time_limit, instance.n_clusters)
        seed = check_seed(seed)
        problem = price(instance, omega)
        cost, scale = folded_costs(problem, self.resolution, solver="ortools", library="OR-Tools")
        _call_worker(None)  # started (OR-Tools imported) outside the time limit, as imports are
        start = time.perf_counter()
        depots = depot_candidates(problem)
        tour = None if initial is None else problem.to_tour(initial.order, initial.heads)
        best, best_cost, timed_out, solutions = best_of_runs(
            problem, depots, time_limit, start,
            lambda depot, budget: self._run(problem, cost, depot, budget, seed, tour, progress),
            _MIN_RUN)
        order, heads = problem.to_solution(best)
        stats = {"solutions": solutions, "scale": scale, "runs": len(depots)}
        if initial is not None:
            stats["warm_start"] = True
        return Solution(order, heads, objective=best_cost,
                        status="time_limit" if timed_out else "feasible", stats=stats)

    def _run(
        self, problem: Problem, cost: np.ndarray, depot: int, seconds: float, seed: int,
        initial: np.ndarray | None = None, progress: Progress = no_progress,
    ) -> tuple[np.ndarray, int, bool]:
        """One OR-Tools run with ``depot`` as the depot: (tour, solutions, stopped by time); from
        the tour ``initial`` (node ids) when it passes through ``depot``."""
        nodes, others = run_nodes(problem, depot)
        if not others:  # a single cluster and no depot: the tour is the node itself
            progress(problem.tour_cost([depot]))
            return np.array([depot]), 0, False
        route = None
        if initial is not None and depot in initial:
            local = {int(v): i for i, v in enumerate(nodes)}
            at = int(np.flatnonzero(initial == depot)[0])
            route = [local[int(v)] for v in np.roll(initial, -at)[1:]]
        try:
            out = _call_worker({
                "cost": np.ascontiguousarray(cost[np.ix_(nodes, nodes)]),
                "sizes": [len(problem.clusters[c]) for c in others],
                "first_solution": self.first_solution, "metaheuristic": self.metaheuristic,
                "seconds": seconds, "solution_limit": self.solution_limit, "seed": seed,
                "initial": route, "report": progress is not no_progress,
            }, lambda visits: progress(problem.tour_cost(nodes[visits])))
        except SolverError as e:
            raise SolverError(f"{problem.instance.name}: {e}") from None
        return nodes[out["visits"]], out["solutions"], out["timed_out"]


if __name__ == "__main__":
    _serve()

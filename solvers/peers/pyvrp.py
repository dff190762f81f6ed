"""PyVRP (hybrid genetic search / iterated local search for VRPs) as an outside peer.

The GTSP becomes a one-vehicle VRP with **mutually exclusive client groups**: every node is an
optional client, the nodes of a cluster form one required group (PyVRP visits exactly one client
of each required group). Node costs are folded into the edges, half of each end's node cost on
every edge (a tour uses two edges at every node, so its folded length is exactly its cost), and
the folded costs are scaled to integers: by 1 when they are all whole numbers (GTSPLIB), else so
that the largest is about ``resolution``. The answer is mapped back and priced exactly.

PyVRP needs a depot. A UAV instance has one. A ``.gtsp`` file has none: one node of its smallest
cluster is made the depot and the other clusters become groups; when that cluster has several nodes
PyVRP runs once per node (the time limit shared among the runs) and the best tour is kept, so the
model stays exact. (GTSPLIB files all have a one-node cluster: a single run.)

Each better tour PyVRP's iterated local search finds (its ``on_best`` callback) is mapped back,
priced exactly and reported as it comes.

PyVRP is an optional extra (``make install`` installs it); without it this solver raises a clear
:class:`InputError`. It imports fine in one process together with highspy or ortools.
"""

from __future__ import annotations

import time

import numpy as np
from gtsp_bench.solvers.peers.depots import best_of_runs, depot_candidates, run_nodes
from gtsp_bench.solvers.peers.scaling import MAX_EXACT, RESOLUTION, folded_costs

from gtsp_bench.checks import (
    check_float,
    check_int,
    time_limit_or_default,
)
from gtsp_bench.errors import InputError, SolverError
from gtsp_bench.instance import Instance
from gtsp_bench.problem import Problem, price
from gtsp_bench.solver import Progress, Solution, no_progress


def _import_pyvrp():
    try:
        import pyvrp
        import pyvrp.stop
    except ImportError as e:
        raise InputError(
            f"solver 'pyvrp' needs the optional package pyvrp ({e}); install it with "
            "'make install' or pip install 'gtsp-bench[pyvrp]'"
        ) from None
    return pyvrp


class PyVRPPeer:
    """PyVRP on the GTSP as a one-vehicle VRP with client groups (see the module docstring).

    Parameters
    ----------
    no_improvement
        Stop after this many PyVRP iterations without a better solution (>= 1); the time limit
        stops it too (status ``time_limit``).
    resolution
        The largest folded edge cost becomes about this many integer units (> 0), unless the
        costs are already whole numbers.
    """

    #: PyVRP's distance matrix is directed (row = from, column = to).
    asymmetric = True
    capped = True  #: given no time limit, run_solver gives it the default one

    def __init__(self, no_improvement: int = 2_000, resolution: float = RESOLUTION) -> None:
        self.no_improvement = check_int("no_improvement", no_improvement, 1)
        self.resolution = check_float("resolution", resolution, 0.0, float(MAX_EXACT))

    def solve(
        self, instance: Instance, omega: float | None, *, time_limit: float | None = None,
        seed: int = 0, progress: Progress = no_progress,
    ) -> Solution:
        """Run PyVRP (once per node of the smallest cluster when there is no depot), reporting
        each better tour to ``progress``."""
        pyvrp = _import_pyvrp()
        time_limit = time_limit_or_default(time_limit, instance.n_clusters)
        start = time.perf_counter()
        problem = price(instance, omega)
        cost, scale = folded_costs(problem, self.resolution, solver="pyvrp", library="PyVRP")
        depots = depot_candidates(problem)
        best, best_cost, timed_out, iterations = best_of_runs(
            problem, depots, time_limit, start,
            lambda depot, budget: self._run(pyvrp, problem, cost, depot, budget, seed, progress),
            1e-3)
        order, heads = problem.to_solution(best)
        return Solution(order, heads, objective=best_cost,
                        status="time_limit" if timed_out else "feasible",
                        stats={"iterations": iterations, "scale": scale, "runs": len(depots)})

    def _run(
        self, pyvrp, problem: Problem, cost: np.ndarray, depot: int, seconds: float, seed: int,
        progress: Progress = no_progress,
    ) -> tuple[np.ndarray, int, bool]:
        """One PyVRP run with ``depot`` as the depot: (tour, iterations, stopped by time)."""
        nodes, others = run_nodes(problem, depot)

        def tour_of(solution) -> np.ndarray | None:
            """The tour of a PyVRP solution (node ids), ``None`` unless it is one feasible route."""
            if not solution.is_feasible() or len(solution.routes()) != 1:
                return None
            visits = [1 + a.idx for a in solution.routes()[0] if a.type == pyvrp.ActivityType.CLIENT]
            return nodes[[0, *visits]]

        class Report(pyvrp.IteratedLocalSearchCallbacks):
            """Each new best solution (and the first), priced exactly, to ``progress``."""

            def on_start(self, ils) -> None:
                self.on_best(ils.initial_solution)

            def on_best(self, best) -> None:
                tour = tour_of(best)
                if tour is not None:
                    progress(problem.tour_cost(tour))

        if not others:  # a single cluster and no depot: the tour is the node itself
            return np.array([depot]), 0, False
        locations = [pyvrp.Location(0.0, 0.0) for _ in nodes]  # coordinates unused: matrix given
        clients, groups = [], []
        for g, c in enumerate(others):
            first = len(clients)
            clients += [pyvrp.Client(location=first + i + 1, required=False, group=g)
                        for i in range(len(problem.clusters[c]))]
            groups.append(pyvrp.ClientGroup(list(range(first, len(clients))), required=True))
        distances = np.ascontiguousarray(cost[np.ix_(nodes, nodes)])
        data = pyvrp.ProblemData(
            locations, clients, [pyvrp.Depot(location=0)], [pyvrp.VehicleType(1)],
            [distances], [np.zeros_like(distances)], groups,
        )
        stop = pyvrp.stop.MultipleCriteria([
            pyvrp.stop.MaxRuntime(seconds), pyvrp.stop.NoImprovement(self.no_improvement),
        ])
        params = pyvrp.SolveParams()
        if progress is not no_progress:
            params = pyvrp.SolveParams(ils=pyvrp.IteratedLocalSearchParams(callbacks=Report()))
        result = pyvrp.solve(data, stop, seed=seed, collect_stats=False, display=False, params=params)
        tour = tour_of(result.best)
        if tour is None:
            raise SolverError(f"PyVRP found no feasible tour on {problem.instance.name}")
        return tour, int(result.num_iterations), result.runtime >= seconds * 0.99

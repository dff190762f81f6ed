"""``greedy+ils``: the paper's greedy tour, then an iterated local search until its budget ends.

The iterated local search (:func:`kick`) is the one Lin-Kernighan solvers run: a double-bridge
kick (three far-apart edges of the cycle changed at once, no run reversed), then ``lns``'s compiled
local search (2-opt, or-opt, move, re-opt of the heads) from the clusters at its cuts; the kicked
tour is kept when it costs no more. ``local-search`` (the learned search) spends the end of its
budget on it; ``greedy+ils`` is the same search from a tour no policy made, in the same budget,
so that the learned benchmark shows what the policy adds (its control).
"""

from __future__ import annotations

import time

import numpy as np
from gtsp_bench.solvers.heuristics import lns_kernels as kernels
from gtsp_bench.solvers.heuristics.greedy import best_greedy_tour
from gtsp_bench.solvers.heuristics.lns_costs import cluster_arrays, kernel_costs
from gtsp_bench.solvers.heuristics.lns_settings import LnsSettings

from gtsp_bench.checks import check_float
from gtsp_bench.instance import Instance
from gtsp_bench.problem import Problem, price
from gtsp_bench.solver import Progress, Solution, no_progress

#: Kicks per call of the compiled search, between looks at the clock.
KICK_CHUNK = 64
#: Fewest clusters (the depot's included) of a cycle that a double-bridge kick changes.
KICK_MIN = 8
#: Share of the budget kept back for what follows the search (the final pricing; in the learned
#: ``local-search``, also its last round's local search when it has no kicks), so that a solve
#: ends within its budget.
MARGIN = 0.03


def kick(problem: Problem, tour: np.ndarray, deadline: float, seed: int) -> tuple[np.ndarray, float, int]:
    """Iterated local search from ``tour`` (node ids, one per cluster) until ``deadline`` (a
    :func:`time.perf_counter` value): the compiled local search, then double-bridge kicks in
    calls of :data:`KICK_CHUNK` (:func:`~gtsp_bench.solvers.heuristics.lns_local.kick_search`),
    a kicked tour kept when it costs no more; below :data:`KICK_MIN` clusters the local search
    only. Returns the tour, its cost and the kicks done."""
    edge = kernel_costs(problem, False)
    node, start, cluster_of = cluster_arrays(problem)
    symmetric = bool(problem.symmetric)
    near = kernels.neighbours(edge, start, LnsSettings().neighbours_for(problem.n_clusters, symmetric))
    t = np.array(tour, dtype=np.int64)
    tol = kernels.REL_TOL * max(1.0, abs(kernels.tour_cost(t, edge, node)))
    kernels.seed(seed)
    cost = kernels.local_search(t, edge, node, start, near, cluster_of, tol,
                                np.ones(problem.n_clusters, dtype=np.bool_), symmetric)
    done = 0
    while problem.n_clusters >= KICK_MIN and time.perf_counter() < deadline:
        cost = kernels.kick_search(t, cost, KICK_CHUNK, edge, node, start, near, cluster_of, tol,
                                   symmetric)
        done += KICK_CHUNK
    return t, cost, done


class GreedyILS:
    """The paper's greedy tour, then :func:`kick` for ``seconds_per_cluster`` x K seconds
    (default 0.01: 1 s at K = 100, ``local-search``'s budget), or the time limit where smaller."""

    asymmetric = True

    def __init__(self, seconds_per_cluster: float = 0.01) -> None:
        self.seconds_per_cluster = check_float("seconds_per_cluster", seconds_per_cluster, 0.0,
                                               float("inf"))
        kernels.warm_up()  # compiled or loaded here, not in a solve's clock

    def solve(self, instance: Instance, omega: float | None, *, time_limit: float | None = None,
              seed: int = 0, progress: Progress = no_progress) -> Solution:
        """The greedy tour, then kicks until the budget ends, each better tour reported."""
        begin = time.perf_counter()
        budget = self.seconds_per_cluster * instance.n_clusters
        if time_limit is not None:
            budget = min(budget, float(time_limit))
        problem = price(instance, omega)
        first, first_cost = best_greedy_tour(problem)
        progress(first_cost)
        tour, cost, kicks = kick(problem, first, begin + budget * (1.0 - MARGIN), seed)
        progress(cost)
        order, heads = problem.to_solution(tour)
        return Solution(order, heads, objective=cost, status="feasible",
                        stats={"kicks": kicks, "budget_s": budget})

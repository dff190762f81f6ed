"""The paper's greedy baseline (section VI-1).

From the current head (the depot first), go to the (cluster, node) pair that adds the least
weighted energy: the flight from the current head plus that node's weighted cost; after the last
cluster, return to the depot. Without a depot (GTSPLIB), every node of the smallest cluster is
tried as the start and the best tour is kept.
"""

from __future__ import annotations

import numpy as np

from gtsp_bench.instance import Instance
from gtsp_bench.problem import Problem, price
from gtsp_bench.solver import Solution


def greedy_tour(problem: Problem, start: int) -> np.ndarray:
    """Greedy tour (node ids) from node ``start``, one node per cluster."""
    cluster_of = problem.cluster_of
    alive = cluster_of != cluster_of[start]
    tour = [start]
    current = start
    for _ in range(problem.n_clusters - 1):
        score = np.where(alive, problem.edge_row(current) + problem.node_cost, np.inf)
        current = int(np.argmin(score))
        tour.append(current)
        alive &= cluster_of != cluster_of[current]
    return np.array(tour)


def greedy_starts(problem: Problem) -> list[int]:
    """Where the greedy tours start: the depot, else every node of the smallest cluster."""
    if problem.depot is not None:
        return [int(problem.depot)]
    return [int(v) for v in min(problem.clusters, key=len)]


def best_greedy_tour(problem: Problem) -> tuple[np.ndarray, float]:
    """The cheapest of the greedy tours from :func:`greedy_starts`, and its cost (the first such
    start on a tie)."""
    tours = [greedy_tour(problem, s) for s in greedy_starts(problem)]
    costs = [problem.tour_cost(t) for t in tours]
    best = int(np.argmin(costs))
    return tours[best], costs[best]


class Greedy:
    """Nearest (cluster, head) pair by weighted energy, step by step."""

    #: Each step takes the cheapest arc *from* the current node: asymmetric costs work as they are.
    asymmetric = True

    def solve(
        self, instance: Instance, omega: float | None, *, time_limit: float | None = None,
        seed: int = 0,
    ) -> Solution:
        """Build the greedy tour (``time_limit`` and ``seed`` are not used)."""
        problem = price(instance, omega)
        tour, cost = best_greedy_tour(problem)
        order, heads = problem.to_solution(tour)
        return Solution(order, heads, objective=cost, status="feasible")

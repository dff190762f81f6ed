"""Peers built for vehicle routing need a depot. A UAV instance has one (the base station); a
GTSPLIB file has none, so such a peer is run once from each node of the smallest cluster, the
runs sharing what is left of the time limit, and the cheapest tour is kept."""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from gtsp_bench.problem import Problem

#: One run from a depot node with a time budget: (tour of node ids, solutions or iterations, whether
#: the budget stopped it).
Run = Callable[[int, float], tuple[np.ndarray, int, bool]]


def depot_candidates(problem: Problem) -> list[int]:
    """The base station, or every node of the smallest cluster when there is none."""
    if problem.depot is not None:
        return [problem.depot]
    return [int(v) for v in min(problem.clusters, key=len)]


def run_nodes(problem: Problem, depot: int) -> tuple[np.ndarray, list[int]]:
    """The nodes of one run from ``depot``: the depot first, then every node of the other
    clusters in cluster order; and those other clusters (none: the depot's cluster is the only
    one, and the tour is the depot alone)."""
    depot_cluster = int(problem.cluster_of[depot])
    others = [c for c in range(problem.n_clusters) if c != depot_cluster]
    nodes = np.concatenate([[depot], *(problem.clusters[c] for c in others)]).astype(np.int64)
    return nodes, others


def best_of_runs(problem: Problem, depots: list[int], time_limit: float, start: float, run: Run,
                 min_run: float) -> tuple[np.ndarray, float, bool, int]:
    """Run from each depot in turn, each with an equal share of the time left since ``start``
    (a ``time.perf_counter()`` reading).

    Returns
    -------
    tour, cost, timed_out, count
        The cheapest tour and its exact cost, whether the limit stopped a run or left depots
        untried, and the runs' solutions (or iterations) added up. When not even the first run
        fits in the limit, one run of ``min_run`` seconds still gives a tour.
    """
    best, best_cost, timed_out, count = None, np.inf, False, 0
    for n_done, depot in enumerate(depots):
        budget = (time_limit - (time.perf_counter() - start)) / (len(depots) - n_done)
        if budget <= 0:
            timed_out = True
            break
        tour, found, hit = run(depot, budget)
        count += found
        timed_out |= hit
        cost = problem.tour_cost(tour)
        if cost < best_cost:
            best, best_cost = tour, cost
    if best is None:  # not even one run fitted: a tour is still owed
        best = run(depots[0], min_run)[0]
        best_cost = problem.tour_cost(best)
    return best, float(best_cost), timed_out, count

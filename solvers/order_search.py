"""A small, fast local search over tours: the exact solvers' first upper bound.

A tour is an array of node ids, one per GTSP cluster (the depot included). Three moves are
repeated until none improves:

* 2-opt on the node sequence (best improvement, all pairs at once with numpy);
* cluster reinsertion: take one cluster out and put it back at the best position with its best
  node (heads change here);
* optimal heads for the current cluster order (:func:`solvers.heads.optimal_heads`).

:func:`search_tour` starts from the greedy tour and then perturbs the best tour a few times,
seeded (ruin and recreate: a few random clusters out, then back in at their cheapest). It is not
meant to compete with the heuristic solvers; it only gives the MILP a good cutoff quickly.
"""

from __future__ import annotations

import time

import numpy as np

from gtsp_bench.problem import Problem
from solvers.greedy import greedy_tour
from solvers.heads import optimal_heads

#: Improvements smaller than this (relative to the tour cost) are ignored.
_EPS = 1e-10


def _two_opt(edge: np.ndarray, tour: np.ndarray, eps: float) -> bool:
    """Apply the best improving 2-opt move in place; False if there is none."""
    m = len(tour)
    nxt = np.roll(tour, -1)
    # reversing tour[i+1..j] replaces edges (t_i, t_i+1), (t_j, t_j+1) by (t_i, t_j), (t_i+1, t_j+1)
    delta = (edge[np.ix_(tour, tour)] + edge[np.ix_(nxt, nxt)]
             - edge[tour, nxt][:, None] - edge[tour, nxt][None, :])
    delta = np.triu(delta, 2)  # i < j - 1 (adjacent edges share a node)
    delta[0, m - 1] = 0.0  # the first and the last edge are adjacent too
    i, j = np.unravel_index(int(np.argmin(delta)), delta.shape)
    if delta[i, j] >= -eps:
        return False
    tour[i + 1:j + 1] = tour[i + 1:j + 1][::-1].copy()
    return True


def _insertion(problem: Problem, tour: np.ndarray, cluster: int) -> tuple[float, int, int]:
    """Cheapest way to insert ``cluster`` into ``tour``: (added cost, node id, position)."""
    edge, node = problem.edge_cost, problem.node_cost
    a, b = tour, np.roll(tour, -1)
    cand = problem.clusters[cluster]
    # cost[w, q]: node w between tour[q] and tour[q + 1]
    cost = node[cand][:, None] + edge[np.ix_(cand, a)] + edge[np.ix_(cand, b)] - edge[a, b][None, :]
    w, q = np.unravel_index(int(np.argmin(cost)), cost.shape)
    return float(cost[w, q]), int(cand[w]), int(q) + 1


def _reinsert(problem: Problem, tour: np.ndarray, eps: float) -> bool:
    """Move clusters, with their best node, to their best position; False if none improves."""
    edge, node, cluster_of = problem.edge_cost, problem.node_cost, problem.cluster_of
    m = len(tour)
    if m < 4:
        return False
    improved = False
    for p in range(m):
        v = tour[p]
        prev, nxt = tour[p - 1], tour[(p + 1) % m]
        gain = node[v] + edge[prev, v] + edge[v, nxt] - edge[prev, nxt]
        rest = np.delete(tour, p)
        cost, w, q = _insertion(problem, rest, int(cluster_of[v]))
        if cost < gain - eps:
            tour[:] = np.insert(rest, q, w)
            improved = True
    return improved


def _order(problem: Problem, tour: np.ndarray) -> list[int]:
    """Instance cluster order of a tour (depot dropped)."""
    order, _ = problem.to_solution(tour)
    return list(order)


def local_search(problem: Problem, tour: np.ndarray, deadline: float | None = None) -> np.ndarray:
    """Improve ``tour`` with 2-opt, cluster reinsertion and optimal heads until none helps.

    Parameters
    ----------
    problem
        The priced problem (symmetric edge costs).
    tour
        Node ids, one per GTSP cluster.
    deadline
        ``time.perf_counter()`` value after which it stops early.

    Returns
    -------
    numpy.ndarray
        A tour no worse than ``tour``.
    """
    tour = np.array(tour, dtype=np.int64)
    eps = _EPS * max(1.0, abs(problem.tour_cost(tour)))
    while deadline is None or time.perf_counter() < deadline:
        while _two_opt(problem.edge_cost, tour, eps):
            pass
        moved = _reinsert(problem, tour, eps)
        best, cost = optimal_heads(problem, _order(problem, tour))
        if cost < problem.tour_cost(tour) - eps:
            tour, moved = best, True
        if not moved:
            break
    return tour


def _ruin_recreate(problem: Problem, tour: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Remove a few random clusters (never the depot), then insert each back at its cheapest."""
    movable = np.flatnonzero(tour != problem.depot) if problem.depot is not None else np.arange(len(tour))
    n_out = min(len(movable) - 2, max(2, len(tour) // 8))
    out = rng.choice(movable, size=n_out, replace=False)
    rest = np.delete(tour, out)
    for cluster in problem.cluster_of[tour[out]]:
        _, w, q = _insertion(problem, rest, int(cluster))
        rest = np.insert(rest, q, w)
    return rest


def search_tour(
    problem: Problem, *, restarts: int = 10, seed: int = 0, deadline: float | None = None
) -> tuple[np.ndarray, float]:
    """A good tour: greedy, local search, then ``restarts`` ruin-and-recreate rounds on the best.

    Parameters
    ----------
    problem
        The priced problem (symmetric edge costs).
    restarts
        Number of perturbations (ruin and recreate, then local search).
    seed
        Seed of the perturbations.
    deadline
        ``time.perf_counter()`` value after which it returns the best tour so far.

    Returns
    -------
    tour : numpy.ndarray
        Node ids of the best tour found.
    cost : float
        Its cost (:meth:`Problem.tour_cost`).
    """
    start = problem.depot if problem.depot is not None else int(problem.clusters[0][0])
    best = local_search(problem, greedy_tour(problem, start), deadline)
    best_cost = problem.tour_cost(best)
    if problem.n_clusters < 5:
        return best, best_cost
    rng = np.random.default_rng(seed)
    for _ in range(restarts):
        if deadline is not None and time.perf_counter() >= deadline:
            break
        tour = local_search(problem, _ruin_recreate(problem, best, rng), deadline)
        cost = problem.tour_cost(tour)
        if cost <= best_cost:  # sideways moves too: they help to leave a plateau
            best, best_cost = tour, cost
    return best, best_cost

"""A macro first tour for :mod:`gtsp_bench.solvers.heuristics.lns` on large planar instances.

On a large clustered instance the first trial of lns decides the basin, and from the greedy
tour (nearest node next) it keeps a wrong order of the point groups: the long edges between the
groups carry most of the excess over the best known tours. The macro tour starts from a good order
instead:

1. each cluster is represented by the centre of its points (:func:`cluster_centres`);
2. a short tour through the centres (:func:`centre_order`): a plain TSP, solved with lns's own
   kernels on a one-node-per-cluster instance (random insertion, local search, then one annealing
   trial of ``iterations`` iterations, seeded by the kernels' generator);
3. the heads for that cluster order, chosen optimally by the kernels' exact re-opt
   (:func:`macro_tour`).

The caller then improves it by the local search and starts the usual trials from it.
"""

from __future__ import annotations

import math

import numpy as np
from gtsp_bench.solvers.heuristics import lns_kernels as kernels

#: The centre tour's neighbour lists: the 2 nearest centres in each quadrant and the nearest.
CENTRE_NEIGHBOURS = 10
#: Iterations of the centre tour's trial between two looks at the deadline.
CENTRE_CHUNK = 2000


def cluster_centres(xy: np.ndarray, start: np.ndarray) -> np.ndarray:
    """``(k, 2)``: the mean of each cluster's points (the nodes of cluster ``c`` are ``start[c] ..
    start[c + 1] - 1``, ``xy`` their coordinates)."""
    return np.add.reduceat(xy[: start[-1]], start[:-1], axis=0) / np.diff(start)[:, None]


def centre_order(centre: np.ndarray, iterations: int, large: int,
                 deadline: float | None = None) -> np.ndarray:
    """A short closed tour through the points ``centre``: the cluster order, each index once.

    Random insertion and the local search of lns, then (with ``iterations`` > 0 and at least 5
    points) one lns trial of ``iterations`` iterations on the one-node-per-cluster instance,
    annealed from the tour's mean edge down to 0.003 of it, with the large-cycle path of
    :mod:`gtsp_bench.solvers.heuristics.lns_window` above ``large`` points. Random numbers come
    from the kernels' generator (:func:`gtsp_bench.solvers.heuristics.lns_kernels.seed`), so the
    order is reproducible for a seed; a ``deadline`` that passes cuts the trial (its best so far).
    """
    k = len(centre)
    if k <= 3:
        return np.arange(k, dtype=np.int64)
    xy = np.ascontiguousarray(centre, dtype=np.float64)
    xy.setflags(write=False)  # typed as lns_costs.points_of leaves points: the cached kernels apply
    costs = (xy, 1, 1.0)  # EUCLIDEAN, unrounded
    node = np.zeros(k)
    node.setflags(write=False)
    start = np.arange(k + 1, dtype=np.int64)
    cluster_of = np.arange(k, dtype=np.int64)
    near = kernels.neighbours(costs, start, CENTRE_NEIGHBOURS, xy)
    t = kernels.random_insertion_tour(costs, node, start, near, cluster_of)
    tol = kernels.REL_TOL * max(1.0, kernels.tour_cost(t, costs, node))
    awake = np.ones(k, dtype=np.bool_)
    cost = kernels.local_search(t, costs, node, start, near, cluster_of, tol, awake, True)
    if iterations <= 0 or k < 5:
        return t
    mean_edge = cost / k
    settings = kernels.trial_settings(iterations, iterations, mean_edge, 0.003 * mean_edge,
                                      min(25, math.ceil(0.3 * k)), 0.1 * mean_edge, 0.1,
                                      4 if k > large else 0)
    return kernels.one_trial(t, cost, settings, CENTRE_CHUNK, costs, node, start, near, cluster_of,
                             True, deadline)[0]


def macro_tour(order: np.ndarray, edge: np.ndarray | tuple, node: np.ndarray, start: np.ndarray,
               cluster_of: np.ndarray) -> np.ndarray:
    """The tour (node ids) visiting the clusters in ``order`` with optimal heads for it (the
    kernels' exact re-opt; ``edge``, ``node``, ``start``, ``cluster_of`` as the kernels take them)."""
    t = np.ascontiguousarray(start[np.asarray(order, dtype=np.int64)], dtype=np.int64)
    kernels.reopt(t, edge, node, start, cluster_of)
    return t

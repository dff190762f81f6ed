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

On a clustered instance the centres fall into **groups** (:func:`centre_groups`: centres closer
than a few times the typical distance between neighbouring centres belong together), and the best
known tours cross each group about once: on 2000C10k.0, 35 crossings between its 34 groups, where
a plain tour through the centres made 40-43. With ``groups`` the centre tour pays a penalty for
each edge between two groups, larger than any edge, so it enters every group exactly once and
follows an order of the groups solved first (:func:`group_order`: a short tour through the
groups, two groups as far apart as their nearest centres), from a first tour that already
follows it (:func:`group_chain`). The penalty alone, from a random-insertion tour, left
2000C10k.0's groups in orders 9-33 % longer than the group tour (seeds 1-3): moving a group
takes several edges at once, and each edge alone costs a penalty. Where one group holds half the
centres or more (the uniform, road and city files) nothing changes.

The caller then improves it by the local search and starts the usual trials from it.
"""

from __future__ import annotations

import math

import numpy as np
from gtsp_bench.solvers.heuristics import lns_kernels as kernels
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree
from scipy.spatial.distance import cdist

#: The centre tour's neighbour lists: the 2 nearest centres in each quadrant and the nearest.
CENTRE_NEIGHBOURS = 10
#: Iterations of the centre tour's trial between two looks at the deadline.
CENTRE_CHUNK = 2000
#: Up to this many centres a grouped centre tour is solved on a dense matrix (the penalties);
#: beyond it the centre tour ignores the groups (200 MB at 5,000).
GROUPED_MAX = 5000
#: The groups apply where no group holds this share of the centres (a clustered instance): one
#: large group and a few outlying ones, as on the road and city files, change nothing.
GROUPED_LARGEST = 0.5
#: Up to this many groups their order is solved first (:func:`group_order`) and the centre tour
#: follows it; above, the penalty alone orders them.
GROUP_ORDER_MAX = 300


def cluster_centres(xy: np.ndarray, start: np.ndarray) -> np.ndarray:
    """``(k, 2)``: the mean of each cluster's points (the nodes of cluster ``c`` are ``start[c] ..
    start[c + 1] - 1``, ``xy`` their coordinates)."""
    return np.add.reduceat(xy[: start[-1]], start[:-1], axis=0) / np.diff(start)[:, None]


def centre_groups(centre: np.ndarray, factor: float) -> np.ndarray:
    """``(k,)`` group labels ``0 .. g - 1`` of the points ``centre``: the connected components of
    the graph joining two centres at most ``factor`` times the median distance from a centre to
    its nearest other centre apart (``factor`` > 0). Where that median is 0 (most centres
    repeated), one group."""
    k = len(centre)
    if k < 2:
        return np.zeros(k, dtype=np.int64)
    tree = cKDTree(centre)
    nearest = np.median(tree.query(centre, 2)[0][:, 1])
    if not nearest > 0.0:
        return np.zeros(k, dtype=np.int64)
    pairs = tree.query_pairs(factor * nearest, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(k, k))
    return connected_components(graph, directed=False)[1].astype(np.int64)


def group_distances(centre: np.ndarray, groups: np.ndarray) -> np.ndarray:
    """``(g, g)``: the least distance between a centre of one group and a centre of another (0 on
    the diagonal); ``groups`` are labels ``0 .. g - 1``."""
    count = int(groups.max()) + 1
    by_group = np.argsort(groups, kind="stable")
    firsts = np.searchsorted(groups[by_group], np.arange(count))
    dist = np.zeros((count, count))
    for h in range(count):
        nearest = cKDTree(centre[groups == h]).query(centre[by_group])[0]
        dist[:, h] = np.minimum.reduceat(nearest, firsts)  # symmetric: the same nearest pair
    np.fill_diagonal(dist, 0.0)
    return dist


def _short_tour(costs: np.ndarray | tuple, xy: np.ndarray | None, iterations: int, large: int,
                deadline: float | None, penalised: bool = False,
                first: np.ndarray | None = None) -> np.ndarray:
    """A short closed tour of the one-node-per-cluster instance ``costs`` (a read-only matrix, or
    points as :mod:`gtsp_bench.solvers.heuristics.lns_costs` takes them): random insertion and
    lns's local search, then (with ``iterations`` > 0 and at least 5 nodes) one trial of
    ``iterations`` iterations, annealed from the tour's mean edge down to 0.003 of it, with the
    large-cycle path above ``large`` nodes. ``xy`` (a point per node) adds quadrant neighbours;
    with ``penalised`` (costs that add penalties to the distances between the points ``xy``) the
    mean edge is the plain distances' mean."""
    node = np.zeros(len(xy) if xy is not None else costs.shape[0])
    k = len(node)
    node.setflags(write=False)
    start = np.arange(k + 1, dtype=np.int64)
    cluster_of = np.arange(k, dtype=np.int64)
    near = kernels.neighbours(costs, start, CENTRE_NEIGHBOURS, xy)
    if first is None:
        t = kernels.random_insertion_tour(costs, node, start, near, cluster_of)
    else:
        t = np.array(first, dtype=np.int64)
    tol = kernels.REL_TOL * max(1.0, kernels.tour_cost(t, costs, node))
    awake = np.ones(k, dtype=np.bool_)
    cost = kernels.local_search(t, costs, node, start, near, cluster_of, tol, awake, True)
    if iterations <= 0 or k < 5:
        return t
    if penalised and xy is not None:
        mean_edge = float(np.mean(np.hypot(*(xy[t] - xy[np.roll(t, -1)]).T)))
    else:
        mean_edge = cost / k
    settings = kernels.trial_settings(iterations, iterations, mean_edge, 0.003 * mean_edge,
                                      min(25, math.ceil(0.3 * k)), 0.1 * mean_edge, 0.1,
                                      4 if k > large else 0)
    return kernels.one_trial(t, cost, settings, CENTRE_CHUNK, costs, node, start, near, cluster_of,
                             True, deadline)[0]


def group_order(centre: np.ndarray, groups: np.ndarray, large: int,
                deadline: float | None = None) -> np.ndarray:
    """The order in which a tour visits the groups (labels ``0 .. g - 1``): a short tour through
    them, two groups as far apart as their nearest centres (:func:`group_distances`), by
    :func:`_short_tour` with ``25 g`` iterations."""
    dist = group_distances(centre, groups)
    if len(dist) <= 3:
        return np.arange(len(dist), dtype=np.int64)
    dist.setflags(write=False)  # typed as lns_costs leaves a matrix: the cached kernels apply
    return _short_tour(dist, None, 25 * len(dist), large, deadline)


def group_chain(centre: np.ndarray, groups: np.ndarray, order: np.ndarray) -> np.ndarray:
    """A tour through the points ``centre`` that visits the groups in ``order``, each once: it
    leaves a group at its centre nearest the next group, enters the next at its centre nearest
    that one, and goes through each group nearest centre next."""
    members = [np.flatnonzero(groups == g) for g in order]
    tour: list[int] = []
    entry = int(members[0][0])
    for j, inside in enumerate(members):
        after = members[(j + 1) % len(members)]
        pts = centre[inside]
        first = int(np.flatnonzero(inside == entry)[0])  # positions within the group
        last = int(np.argmin(cKDTree(centre[after]).query(pts)[0]))
        left = np.ones(len(inside), dtype=bool)
        left[[first, last]] = False  # where last == first, the chain ends where it ends
        chain = [first]
        while left.any():
            free = np.flatnonzero(left)
            at = int(free[np.argmin(np.hypot(*(pts[free] - pts[chain[-1]]).T))])
            left[at] = False
            chain.append(at)
        if last != first:
            chain.append(last)
        tour.extend(inside[chain].tolist())
        entry = int(after[np.argmin(np.hypot(*(centre[after] - pts[chain[-1]]).T))])
    return np.array(tour, dtype=np.int64)


def grouped_costs(centre: np.ndarray, groups: np.ndarray,
                  order: np.ndarray | None = None) -> np.ndarray:
    """``(k, k)``: the distances between the centres plus, between two groups, the diagonal of
    their bounding box (more than any edge); with ``order`` (of the groups, :func:`group_order`),
    three diagonals between two groups not next to each other in it, so that the cheapest tours
    enter each group once and follow ``order``."""
    cost = cdist(centre, centre)
    span = centre.max(axis=0) - centre.min(axis=0)
    diagonal = float(np.hypot(span[0], span[1]))
    penalty = (groups[:, None] != groups[None, :]).astype(np.float64)
    if order is not None and len(order) > 2:
        rank = np.empty(len(order), dtype=np.int64)
        rank[order] = np.arange(len(order))
        apart = (rank[groups][:, None] - rank[groups][None, :]) % len(order)
        penalty += 2.0 * ((apart > 1) & (apart < len(order) - 1))
    cost += diagonal * penalty
    cost.setflags(write=False)  # typed as lns_costs leaves a matrix: the cached kernels apply
    return cost


def centre_order(centre: np.ndarray, iterations: int, large: int,
                 deadline: float | None = None, groups: np.ndarray | None = None) -> np.ndarray:
    """A short closed tour through the points ``centre``: the cluster order, each index once.

    Random insertion and the local search of lns, then (with ``iterations`` > 0 and at least 5
    points) one lns trial of ``iterations`` iterations on the one-node-per-cluster instance,
    annealed from the tour's mean edge down to 0.003 of it, with the large-cycle path of
    :mod:`gtsp_bench.solvers.heuristics.lns_window` above ``large`` points. Random numbers come
    from the kernels' generator (:func:`gtsp_bench.solvers.heuristics.lns_kernels.seed`), so the
    order is reproducible for a seed; a ``deadline`` that passes cuts the trial (its best so far).
    With ``groups`` (labels, :func:`centre_groups`) none of which holds
    :data:`GROUPED_LARGEST` of the points, and at most :data:`GROUPED_MAX` points, each edge
    between two groups costs a penalty more than any edge (:func:`grouped_costs`): the tour
    enters each group once. Up to :data:`GROUP_ORDER_MAX` groups their order is solved first
    (:func:`group_order`), the centre tour starts from :func:`group_chain` instead of random
    insertion, and an edge between two groups not next to each other in that order costs three
    penalties: the tour keeps the group order. The trial's temperatures come from the plain
    distances either way.
    """
    k = len(centre)
    if k <= 3:
        return np.arange(k, dtype=np.int64)
    xy = np.ascontiguousarray(centre, dtype=np.float64)
    xy.setflags(write=False)  # typed as lns_costs.points_of leaves points: the cached kernels apply
    grouped = (groups is not None and k <= GROUPED_MAX
               and np.bincount(groups).max() < GROUPED_LARGEST * k)
    if not grouped:
        return _short_tour((xy, 1, 1.0), xy, iterations, large, deadline)  # EUCLIDEAN, unrounded
    assert groups is not None
    few = int(groups.max()) + 1 <= GROUP_ORDER_MAX  # labels 0 .. g - 1
    order = group_order(xy, groups, large, deadline) if few else None
    first = None if order is None else group_chain(xy, groups, order)
    return _short_tour(grouped_costs(xy, groups, order), xy, iterations, large, deadline,
                       penalised=True, first=first)


def macro_tour(order: np.ndarray, edge: np.ndarray | tuple, node: np.ndarray, start: np.ndarray,
               cluster_of: np.ndarray) -> np.ndarray:
    """The tour (node ids) visiting the clusters in ``order`` with optimal heads for it (the
    kernels' exact re-opt; ``edge``, ``node``, ``start``, ``cluster_of`` as the kernels take them).
    An ``order`` that does not visit every cluster exactly once is a :class:`ValueError` (the
    kernels assume a permutation: given a repeated cluster, their trials do not end)."""
    if not np.array_equal(np.sort(order), np.arange(len(start) - 1)):
        raise ValueError("the macro tour's order must visit every cluster exactly once")
    t = np.ascontiguousarray(start[np.asarray(order, dtype=np.int64)], dtype=np.int64)
    kernels.reopt(t, edge, node, start, cluster_of)
    return t

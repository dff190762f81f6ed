"""Exact pair-dominance pruning of candidate heads.

In any tour through at least three clusters, the head ``v`` of cluster ``C`` sits between two
neighbours ``a`` and ``b`` of two other, different clusters, and contributes
``node_cost[v] + edge_cost[a, v] + edge_cost[v, b]``. Replacing ``v`` by the node of ``C``
minimising that sum for the same ``(a, b)`` gives a tour that is no worse. So a node that is not
the cheapest head (the first one, on ties) for *any* pair of possible neighbours is never needed:
some optimal tour avoids it. Applying the rule again with the remaining nodes as neighbours stays
exact (replace the heads of an optimal tour over the remaining nodes one cluster at a time; each
new head is the cheapest for neighbours that remain, so it is kept). The rule is iterated until
nothing changes.

Each kept node remembers one pair of neighbours it is the cheapest head for (its witness). A node
whose witness is still there stays the cheapest for it (its cluster only loses nodes that are the
cheapest for no pair), so a later pass scans a cluster only when some node lost its witness, and
stops once each such node has a new one; the nodes kept are those of a full scan.

Cost: O(K^3 N^3) for the first pass (K clusters of N nodes), in a compiled kernel (numba,
``cache=True``; numpy blocks took 10-15 s a solve at K = 50, N = 20). At UAV K = 200 full scans
in every pass used all of the 34 s they were allowed in a 170 s solve; with witnesses the
fixpoint took 10 s. Keeping only convex-hull nodes is *not* exact, with or without node costs,
and is not done.
"""

from __future__ import annotations

import time

import numpy as np
from numba import njit

from gtsp_bench.problem import Problem


@njit(cache=True)
def _witness_kernel(
    to_neigh: np.ndarray, node: np.ndarray, neigh_cluster: np.ndarray, pending: np.ndarray
) -> np.ndarray:
    """A witness pair of each row of ``to_neigh`` ``(n, A)``: neighbours ``a < b`` of different
    clusters for which the row is the first cheapest head (cost ``node[v] + to_neigh[v, a] +
    to_neigh[v, b]``), ``(-1, -1)`` for none; the pairs are tried in order and the search stops
    once every ``pending`` row has one (rows not pending may then be left without)."""
    n, a_count = to_neigh.shape
    witness = np.full((n, 2), -1, dtype=np.int64)
    left = 0
    for v in range(n):
        if pending[v]:
            left += 1
    if left == 0:
        return witness
    t = np.ascontiguousarray(to_neigh.T)  # (A, n): one neighbour's column in a row
    base = np.empty(n)
    for a in range(a_count):
        for v in range(n):
            base[v] = node[v] + t[a, v]
        ca = neigh_cluster[a]
        for b in range(a + 1, a_count):
            if neigh_cluster[b] == ca:
                continue
            best = 0
            cost = base[0] + t[b, 0]
            for v in range(1, n):
                c = base[v] + t[b, v]
                if c < cost:
                    best, cost = v, c
            if witness[best, 0] < 0:
                witness[best, 0] = a
                witness[best, 1] = b
                if pending[best]:
                    left -= 1
                    if left == 0:
                        return witness
    return witness


def _witnesses(
    problem: Problem, cand: np.ndarray, neigh: np.ndarray, neigh_cluster: np.ndarray,
    pending: np.ndarray,
) -> np.ndarray:
    """``(len(cand), 2)`` node ids of a neighbour pair for which each node of ``cand`` is the
    cheapest head (the first, on ties), -1 for none; searched until every ``pending`` node has
    one."""
    to_neigh = np.ascontiguousarray(problem.edge_cost[np.ix_(cand, neigh)], dtype=np.float64)
    node = np.ascontiguousarray(problem.node_cost[cand], dtype=np.float64)
    found = _witness_kernel(to_neigh, node, np.ascontiguousarray(neigh_cluster, dtype=np.int64),
                            np.ascontiguousarray(pending, dtype=np.bool_))
    return np.where(found >= 0, neigh[np.maximum(found, 0)], -1)


def warm_up() -> None:
    """Compile (first use on a machine) or load (from numba's cache) the kernel on a tiny input,
    so that a solve's clock does not pay for it."""
    _witness_kernel(np.zeros((2, 3)), np.zeros(2), np.arange(3, dtype=np.int64), np.ones(2, dtype=np.bool_))


def prune_heads(
    problem: Problem, *, max_passes: int | None = None, deadline: float | None = None
) -> tuple[np.ndarray, ...]:
    """Candidate heads of each GTSP cluster that survive pair-dominance pruning.

    Parameters
    ----------
    problem
        The priced problem; its edge costs must be symmetric.
    max_passes
        Stop after this many passes over all clusters (``None``: until nothing changes). Any
        number of passes is exact; more passes prune more.
    deadline
        ``time.perf_counter()`` value after which it stops early (still exact).

    Returns
    -------
    tuple of numpy.ndarray
        Node ids kept in each cluster of ``problem.clusters`` (the depot's cluster unchanged).
        Some optimal tour uses only kept nodes. With fewer than three clusters nothing is pruned.
    """
    kept = [np.asarray(c, dtype=np.int64) for c in problem.clusters]
    m = len(kept)
    if m < 3:
        return tuple(kept)
    alive = np.zeros(problem.n_nodes, dtype=bool)
    alive[np.concatenate(kept)] = True
    # a pair of neighbours for which each kept node is the cheapest head, -1 before the first scan
    witness = [np.full((len(k), 2), -1, dtype=np.int64) for k in kept]
    passes = 0
    changed = True
    while changed and (max_passes is None or passes < max_passes):
        changed = False
        passes += 1
        for c in range(m):
            if deadline is not None and time.perf_counter() > deadline:
                return tuple(kept)
            if len(kept[c]) == 1:
                continue
            w = witness[c]
            pending = (w[:, 0] < 0) | ~alive[np.maximum(w, 0)].all(axis=1)
            if not pending.any():  # every node keeps a pair of neighbours still there
                continue
            others = [j for j in range(m) if j != c]
            neigh = np.concatenate([kept[j] for j in others])
            neigh_cluster = np.repeat(others, [len(kept[j]) for j in others])
            found = _witnesses(problem, kept[c], neigh, neigh_cluster, pending)
            keep = ~pending | (found[:, 0] >= 0)
            w = np.where(found >= 0, found, w)
            if not keep.all():
                alive[kept[c][~keep]] = False
                kept[c] = kept[c][keep]
                w = w[keep]
                changed = True
            witness[c] = w
    return tuple(kept)

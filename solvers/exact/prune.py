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

Cost: O(K^3 N^3) for the first pass (K clusters of N nodes). Keeping only convex-hull nodes is
*not* exact, with or without node costs, and is not done.
"""

from __future__ import annotations

import time

import numpy as np

from gtsp_bench.problem import Problem

#: Largest (cluster size x neighbours x neighbours) block evaluated at once (memory bound).
_BLOCK = 4_000_000


def _cheapest_heads(
    problem: Problem, cand: np.ndarray, neigh: np.ndarray, neigh_cluster: np.ndarray
) -> np.ndarray:
    """Mask over ``cand``: which nodes are the cheapest head for some neighbour pair."""
    edge = problem.edge_cost
    to_neigh = edge[np.ix_(cand, neigh)]  # (n, A)
    node = problem.node_cost[cand][:, None, None]
    keep = np.zeros(len(cand), dtype=bool)
    chunk = max(1, _BLOCK // max(1, len(cand) * len(neigh)))
    for lo in range(0, len(neigh), chunk):
        hi = min(lo + chunk, len(neigh))
        # cost[v, a, b] = node[v] + edge[a, v] + edge[v, b] for a in [lo, hi), b >= lo (the
        # pair (b, a) costs the same); only pairs of different clusters are possible neighbours.
        cost = node + to_neigh[:, lo:hi, None] + to_neigh[:, None, lo:]
        best = cost.argmin(axis=0)  # the first cheapest head of each pair
        valid = neigh_cluster[lo:hi, None] != neigh_cluster[None, lo:]
        keep[np.unique(best[valid])] = True
    return keep


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
            others = [j for j in range(m) if j != c]
            neigh = np.concatenate([kept[j] for j in others])
            neigh_cluster = np.repeat(others, [len(kept[j]) for j in others])
            keep = _cheapest_heads(problem, kept[c], neigh, neigh_cluster)
            if not keep.all():
                kept[c] = kept[c][keep]
                changed = True
    return tuple(kept)

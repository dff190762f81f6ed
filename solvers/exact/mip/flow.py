"""Compiled kernels of the separation (numba, ``cache=True``): maximum flow and residual
reachability for the subtour rows, the blossom violation of a handle, and the cuts' dual weights
on edges (for pricing).

The separation of :mod:`gtsp_bench.solvers.exact.mip.separation` runs one max-flow per cluster
on a support graph of at most a few hundred nodes. scipy's ``maximum_flow`` spends almost all
of such a call validating and converting its sparse input (about 2 ms a call, 90 % of a branch
and cut's time on 31pr152); these kernels work on the network's CSR arrays directly.

The network is laid out once (:class:`gtsp_bench.solvers.exact.mip.separation._Network`): CSR
``indptr``/``indices`` with every arc's reverse present, ``row`` the tail of each arc and ``rev``
the position of its reverse. Flows are antisymmetric (``flow[rev[p]] == -flow[p]``), so the
residual capacity of arc ``p`` is ``cap[p] - flow[p]``.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def max_flow(indptr: np.ndarray, indices: np.ndarray, row: np.ndarray, rev: np.ndarray,
             cap: np.ndarray, source: int, sink: int) -> tuple[int, np.ndarray]:
    """Dinic's maximum flow on integer capacities ``cap`` (per CSR position).

    Returns
    -------
    tuple
        The flow value and the antisymmetric flow per CSR position.
    """
    n = len(indptr) - 1
    flow = np.zeros(len(cap), dtype=np.int64)
    level = np.empty(n, dtype=np.int64)
    cursor = np.empty(n, dtype=np.int64)
    queue = np.empty(n, dtype=np.int64)
    path = np.empty(n, dtype=np.int64)
    total = 0
    while True:
        _levels(indptr, indices, rev, cap - flow, source, False, level, queue)
        if level[sink] < 0:
            return total, flow
        for u in range(n):
            cursor[u] = indptr[u]
        while True:  # augmenting paths in the level graph (blocking flow)
            depth = 0
            u = source
            while u != sink:
                advanced = False
                while cursor[u] < indptr[u + 1]:
                    p = cursor[u]
                    v = indices[p]
                    if level[v] == level[u] + 1 and cap[p] - flow[p] > 0:
                        path[depth] = p
                        depth += 1
                        u = v
                        advanced = True
                        break
                    cursor[u] += 1
                if not advanced:
                    if depth == 0:
                        break
                    level[u] = -1  # a dead end for the rest of the phase
                    depth -= 1
                    u = row[path[depth]]
                    cursor[u] += 1
            if u != sink:
                break
            push = cap[path[0]] - flow[path[0]]
            for k in range(1, depth):
                push = min(push, cap[path[k]] - flow[path[k]])
            for k in range(depth):
                flow[path[k]] += push
                flow[rev[path[k]]] -= push
            total += push


@njit(cache=True)
def _levels(indptr: np.ndarray, indices: np.ndarray, rev: np.ndarray, residual: np.ndarray,
            start: int, backward: bool, level: np.ndarray, queue: np.ndarray) -> None:
    """Breadth-first distances from ``start`` along arcs of positive ``residual`` (``backward``:
    along the reverse arcs, i.e. to ``start``) into ``level``, -1 where unreached; ``queue`` is
    scratch space of the node count."""
    level[:] = -1
    level[start] = 0
    queue[0] = start
    first, last = 0, 1
    while first < last:
        u = queue[first]
        first += 1
        for p in range(indptr[u], indptr[u + 1]):
            v = indices[p]
            if level[v] < 0 and (residual[rev[p]] if backward else residual[p]) > 0:
                level[v] = level[u] + 1
                queue[last] = v
                last += 1


@njit(cache=True)
def reach(indptr: np.ndarray, indices: np.ndarray, rev: np.ndarray, residual: np.ndarray,
          start: int, backward: bool) -> np.ndarray:
    """Nodes reachable from ``start`` along arcs of positive ``residual`` (``backward``: nodes
    from which ``start`` is reachable)."""
    n = len(indptr) - 1
    level = np.empty(n, dtype=np.int64)
    _levels(indptr, indices, rev, residual, start, backward, level, np.empty(n, dtype=np.int64))
    return level >= 0


@njit(cache=True)
def teeth_violation(z: np.ndarray, handle: np.ndarray) -> tuple[float, int, int]:
    """The violation of the most violated blossom with this handle (clusters) over the cluster
    tour ``z`` (``(m, m)``, symmetric), and the edge ``(i, j)`` that mends the teeth's parity
    (``(-1, -1)`` when they are odd already): teeth are the edges leaving the handle with
    ``z > 1/2``, parity mended by the edge whose ``z`` is closest to 1/2 (the first in row-major
    order of inner, outer clusters). :func:`gtsp_bench.solvers.exact.mip.separation._best_teeth`
    gives the teeth."""
    m = len(handle)
    slack = 0.0
    teeth = 0
    closest = np.inf
    mend_i, mend_j = -1, -1
    for i in range(m):
        if not handle[i]:
            continue
        for j in range(m):
            if handle[j]:
                continue
            c = z[i, j]
            if c > 0.5:
                teeth += 1
                slack += 1 - c
            else:
                slack += c
            d = abs(1 - 2 * c)
            if d < closest:
                closest, mend_i, mend_j = d, i, j
    if teeth % 2 == 0:
        return 1 - (slack + closest), mend_i, mend_j
    return 1 - slack, -1, -1


@njit(cache=True)
def edge_weights(edges: np.ndarray, tail: np.ndarray, head: np.ndarray, cluster: np.ndarray,
                 pair: np.ndarray, node_cluster: np.ndarray, extra: np.ndarray) -> np.ndarray:
    """Per edge ``e = (t, h)`` of ``edges``: ``pair[C_t, C_h] + node_cluster[h, C_t] +
    node_cluster[t, C_h]``, plus ``extra[e]`` when ``extra`` is not empty (``C_i`` the cluster of
    node ``i``; :meth:`gtsp_bench.solvers.exact.mip.separation.Cuts.dual_weights`). One pass over
    the edges: numpy's gathers and temporaries took about 1 s a call over 6.6 million edges."""
    out = np.empty(len(edges))
    with_extra = len(extra) > 0
    for k in range(len(edges)):
        e = edges[k]
        t, h = tail[e], head[e]
        ct, ch = cluster[t], cluster[h]
        w = pair[ct, ch] + node_cluster[h, ct] + node_cluster[t, ch]
        if with_extra:
            w += extra[e]
        out[k] = w
    return out


def warm_up() -> None:
    """Compile (first use on a machine) or load (from numba's cache) the kernels on a tiny
    network, so that a solve's clock does not pay for it."""
    indptr = np.array([0, 1, 3, 4], dtype=np.int64)
    indices = np.array([1, 0, 2, 1], dtype=np.int64)
    row = np.array([0, 1, 1, 2], dtype=np.int64)
    rev = np.array([1, 0, 3, 2], dtype=np.int64)
    cap = np.array([1, 0, 1, 0], dtype=np.int64)
    _, flow = max_flow(indptr, indices, row, rev, cap, 0, 2)
    reach(indptr, indices, rev, cap - flow, 0, False)
    reach(indptr, indices, rev, cap - flow, 2, True)
    teeth_violation(np.full((3, 3), 0.5), np.array([True, False, False]))
    ends = np.array([0, 1], dtype=np.int64)
    edge_weights(np.zeros(1, dtype=np.int64), ends[:1], ends[1:], ends, np.zeros((2, 2)), np.zeros((2, 2)),
                 np.zeros(0))

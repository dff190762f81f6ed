"""Compiled kernels of the separation (numba, ``cache=True``): maximum flow and residual
reachability for the subtour rows, the blossom violation of a handle, the cuts' dual weights
on edges (for pricing), and the cut rows' entries over the LP's columns.

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


@njit(cache=True)
def edge_reduced_costs(edges: np.ndarray, cost: np.ndarray, tail: np.ndarray, head: np.ndarray,
                       pi_deg: np.ndarray, on_edge: np.ndarray) -> np.ndarray:
    """Per edge ``e = (t, h)`` of ``edges``: ``cost[e] - pi_deg[t] - pi_deg[h] - on_edge[k]``
    (``k`` its position; the sums in that order), in one pass: numpy's gathers and temporaries
    took about 0.3 s a call over 7 million edges."""
    out = np.empty(len(edges))
    for k in range(len(edges)):
        e = edges[k]
        out[k] = cost[e] - pi_deg[tail[e]] - pi_deg[head[e]] - on_edge[k]
    return out


@njit(cache=True)
def cut_rows(side: np.ndarray, row: np.ndarray, cross: np.ndarray, ycoef: np.ndarray,
             cols: np.ndarray, tail: np.ndarray, head: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """CSR arrays ``(indptr, indices, data)`` of cut rows over model columns ``cols`` (the
    entries that are not zero, by position in ``cols``): row ``r`` is ``ycoef[r]`` on the y
    columns, and on edge ``(t, h)`` the sum over its sides ``k`` (``row[k] = r``) of 1 when both
    ends are in ``side[k]``, or with ``cross[k]``, -1/2 when one end is
    (:class:`gtsp_bench.solvers.exact.mip.separation.Cuts`).

    A side visits only the edges at its own nodes (the columns' edges laid out per node once):
    the dense form over every column took about 0.4 s a round at UAV K = 200."""
    n_rows, n_nodes, n_cols = ycoef.shape[0], ycoef.shape[1], len(cols)
    first = np.zeros(n_rows + 1, dtype=np.int64)  # the sides of row r: order[first[r]:first[r + 1]]
    for k in range(len(row)):
        first[row[k] + 1] += 1
    for r in range(n_rows):
        first[r + 1] += first[r]
    order = np.argsort(row, kind="mergesort")
    ys = np.empty(n_cols, dtype=np.int64)  # positions of the y columns
    at = np.zeros(n_nodes + 1, dtype=np.int64)  # the edge positions at node u: inc[at[u]:at[u + 1]]
    n_ys = 0
    for j in range(n_cols):
        c = cols[j]
        if c < n_nodes:
            ys[n_ys] = j
            n_ys += 1
        else:
            at[tail[c - n_nodes] + 1] += 1
            at[head[c - n_nodes] + 1] += 1
    for u in range(n_nodes):
        at[u + 1] += at[u]
    inc = np.empty(at[n_nodes], dtype=np.int64)
    fill = at[:-1].copy()
    for j in range(n_cols):
        c = cols[j]
        if c >= n_nodes:
            for u in (tail[c - n_nodes], head[c - n_nodes]):
                inc[fill[u]] = j
                fill[u] += 1
    acc = np.zeros(n_cols)
    seen = np.zeros(n_cols, dtype=np.bool_)
    touched = np.empty(n_cols, dtype=np.int64)
    indptr = np.zeros(n_rows + 1, dtype=np.int64)
    indices = np.empty(max(16, 64 * n_rows), dtype=np.int64)
    data = np.empty(len(indices))
    filled = 0
    for r in range(n_rows):
        n_touched = 0
        for q in range(n_ys):
            j = ys[q]
            v = ycoef[r, cols[j]]
            if v != 0.0:
                acc[j] = v
                seen[j] = True
                touched[n_touched] = j
                n_touched += 1
        for q in range(first[r], first[r + 1]):
            k = order[q]
            for u in range(n_nodes):
                if not side[k, u]:
                    continue
                for p in range(at[u], at[u + 1]):
                    j = inc[p]
                    e = cols[j] - n_nodes
                    w = head[e] if tail[e] == u else tail[e]
                    if cross[k]:
                        if side[k, w]:
                            continue
                        acc[j] -= 0.5
                    elif side[k, w] and u < w:
                        acc[j] += 1.0
                    else:
                        continue
                    if not seen[j]:
                        seen[j] = True
                        touched[n_touched] = j
                        n_touched += 1
        done = np.sort(touched[:n_touched])
        for j in done:
            if acc[j] != 0.0:
                if filled == len(indices):  # grow
                    indices = np.concatenate((indices, np.empty(len(indices), dtype=np.int64)))
                    data = np.concatenate((data, np.empty(len(data))))
                indices[filled] = j
                data[filled] = acc[j]
                filled += 1
            acc[j] = 0.0
            seen[j] = False
        indptr[r + 1] = filled
    return indptr, indices[:filled].copy(), data[:filled].copy()


@njit(cache=True)
def loose_nodes(sides: np.ndarray, whole: np.ndarray, cluster: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """CSR ``(indptr, indices)`` of ``sides & ~whole[:, cluster]``: per side, its nodes whose
    cluster it does not hold whole (few; numpy's dense mask and its scan took 0.2 s a call at
    UAV K = 200)."""
    indptr = np.zeros(sides.shape[0] + 1, dtype=np.int64)
    for k in range(sides.shape[0]):
        count = 0
        for u in range(sides.shape[1]):
            if sides[k, u] and not whole[k, cluster[u]]:
                count += 1
        indptr[k + 1] = indptr[k] + count
    indices = np.empty(indptr[-1], dtype=np.int64)
    for k in range(sides.shape[0]):
        p = indptr[k]
        for u in range(sides.shape[1]):
            if sides[k, u] and not whole[k, cluster[u]]:
                indices[p] = u
                p += 1
    return indptr, indices


@njit(cache=True)
def side_edges(side: np.ndarray, tails: np.ndarray, heads: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per side (row of ``side``): how many of the edges ``(tails, heads)`` have both ends in it,
    and how many one end."""
    inside = np.zeros(side.shape[0], dtype=np.int64)
    crossing = np.zeros(side.shape[0], dtype=np.int64)
    for k in range(side.shape[0]):
        for e in range(len(tails)):
            a, b = side[k, tails[e]], side[k, heads[e]]
            if a and b:
                inside[k] += 1
            elif a != b:
                crossing[k] += 1
    return inside, crossing


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
    side = np.ones((1, 2), dtype=bool)
    cut_rows(side, np.zeros(1, dtype=np.int64), np.zeros(1, dtype=bool), np.zeros((1, 2)),
             np.array([0, 2], dtype=np.int64), ends[:1], ends[1:])
    side_edges(side, ends[:1], ends[1:])
    loose_nodes(side, np.zeros((1, 2), dtype=bool), ends)
    edge_reduced_costs(np.zeros(1, dtype=np.int64), np.zeros(1), ends[:1], ends[1:], np.zeros(2),
                       np.zeros(1))

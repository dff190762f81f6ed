"""The local search of :mod:`gtsp_bench.solvers.heuristics.lns` on large cycles (numba, ``cache=True``).

The same moves as :func:`gtsp_bench.solvers.heuristics.lns_local.local_search` (2-opt, or-opt,
move; the or-opt here also puts a run back reversed on symmetric costs), but the re-opt is
**windowed**: instead of a shortest path through all the clusters (a full
pass over the cycle, about 1.6 ms per call on 3,023 clusters of 5 nodes), only the positions
within ``half`` places of a cluster that changed since the last re-opt get new heads, by a
shortest path between the fixed heads just outside each window (:func:`reopt_window`). A cluster
"changed" when a move woke it (a fourth row of don't-look bits, set with the other three). When the
windows cover nearly the whole cycle (the first local search, from a new tour) the full re-opt
runs instead. An iteration's cost then grows with the clusters it removed, not with the cycle.

The removals (:func:`remove_near`) likewise look at about ``8 k`` clusters for ``k`` removals, not
at all of them.
"""

from __future__ import annotations

import numpy as np
from gtsp_bench.solvers.heuristics.lns_costs import ec
from gtsp_bench.solvers.heuristics.lns_local import (
    _touch,
    move_round,
    reopt,
    search_state,
    tour_cost,
)
from numba import njit


@njit(cache=True, nogil=True)
def reopt_window(t: np.ndarray, lo: int, length: int, edge: np.ndarray, node: np.ndarray,
                 start: np.ndarray, cluster_of: np.ndarray, tol: float) -> float:
    """Optimal heads for the ``length`` positions ``lo .. lo + length - 1`` (cyclic) of ``t``, the
    heads before and after them kept (``length <= len(t) - 1``); changes ``t`` in place only when
    that saves more than ``tol``. Returns the saving (0 when nothing changed)."""
    n = len(t)
    a, b = t[(lo - 1) % n], t[(lo + length) % n]
    cap = 0
    for x in range(length):
        c = cluster_of[t[(lo + x) % n]]
        cap = max(cap, start[c + 1] - start[c])
    back = np.empty((length, cap), dtype=np.int64)
    cur = np.empty(cap)
    new = np.empty(cap)
    old = ec(edge, t[(lo + length - 1) % n], b)
    prev_lo, prev_hi = a, a + 1
    for x in range(length):
        u0 = t[(lo + x) % n]
        old += ec(edge, t[(lo + x - 1) % n], u0) + node[u0]
        c = cluster_of[u0]
        c_lo, c_hi = start[c], start[c + 1]
        for v in range(c_lo, c_hi):
            bv, bu = np.inf, -1
            for u in range(prev_lo, prev_hi):
                d = (cur[u - prev_lo] if x > 0 else 0.0) + ec(edge, u, v)
                if d < bv:
                    bv, bu = d, u
            new[v - c_lo] = bv + node[v]
            back[x, v - c_lo] = bu
        for v in range(c_hi - c_lo):
            cur[v] = new[v]
        prev_lo, prev_hi = c_lo, c_hi
    best, best_v = np.inf, -1
    for v in range(prev_lo, prev_hi):
        d = cur[v - prev_lo] + ec(edge, v, b)
        if d < best:
            best, best_v = d, v
    if best >= old - tol:
        return 0.0
    v = best_v
    for x in range(length - 1, -1, -1):
        t[(lo + x) % n] = v
        c = cluster_of[v]
        v = back[x, v - start[c]]
    return old - best


@njit(cache=True, nogil=True)
def reopt_changed(t: np.ndarray, edge: np.ndarray, node: np.ndarray, start: np.ndarray,
                  cluster_of: np.ndarray, tol: float, active: np.ndarray, half: int) -> float:
    """Re-opt the windows of ``half`` positions either side of each cluster marked in
    ``active[3]`` (the marks are cleared; positions whose head changed wake), or the whole cycle
    when the windows leave fewer than 2 positions out. Returns the saving (0: none)."""
    n = len(t)
    cover = np.zeros(n, dtype=np.bool_)
    covered = 0
    for i in range(n):
        if active[3, cluster_of[t[i]]]:
            for x in range(i - half, i + half + 1):
                q = x % n
                if not cover[q]:
                    cover[q] = True
                    covered += 1
    active[3, :] = False
    if covered == 0:
        return 0.0
    saved = t.copy()
    gain = 0.0
    if covered >= n - 1:
        before = tour_cost(t, edge, node)
        after = reopt(t, edge, node, start, cluster_of)
        if after >= before - tol:
            t[:] = saved
            return 0.0
        gain = before - after
        cover[:] = True
    else:
        s = 0
        while cover[s]:  # an uncovered position: windows start after one
            s += 1
        x = 1
        while x < n:
            i = (s + x) % n
            if not cover[i]:
                x += 1
                continue
            length = 0
            while cover[(i + length) % n]:
                length += 1
            gain += reopt_window(t, i, length, edge, node, start, cluster_of, tol)
            x += length
    if gain <= 0.0:
        return 0.0
    for i in range(n):
        if cover[i] and t[i] != saved[i]:
            _touch(active, cluster_of, t, i)
    return gain


@njit(cache=True, nogil=True)
def runs_cost(t: np.ndarray, marked: np.ndarray, edge: np.ndarray, node: np.ndarray) -> float:
    """What the marked positions of the cycle ``t`` (not all of them) add to its cost: for each
    maximal run of them, its nodes and the edges into, along and out of it, less the edge that
    would join its two sides. Taking them out saves this; putting them in costs it."""
    n = len(t)
    total = 0.0
    for i in range(n):
        if not marked[i]:
            continue
        total += node[t[i]] + ec(edge, t[(i - 1) % n], t[i])
        after = (i + 1) % n
        if not marked[after]:  # the run ends here: its edge out, less the edge joining its sides
            j = i
            while marked[(j - 1) % n]:
                j = (j - 1) % n
            total += ec(edge, t[i], t[after]) - ec(edge, t[(j - 1) % n], t[after])
    return total


@njit(cache=True, nogil=True)
def local_search_window(t: np.ndarray, edge: np.ndarray, node: np.ndarray, start: np.ndarray,
                        near: np.ndarray, cluster_of: np.ndarray, tol: float, awake: np.ndarray,
                        symmetric: bool, half: int, cost: float) -> float:
    """:func:`gtsp_bench.solvers.heuristics.lns_local.local_search` with the windowed re-opt
    (:func:`reopt_changed`, ``half`` positions either side of a changed cluster); in place,
    returns the cost. Given the tour's ``cost`` (not ``nan``), it counts the cost from there by the moves'
    savings (no pass over the tour; equal up to rounding); else it prices the tour at the start
    and at the end."""
    pos, active = search_state(t, cluster_of, awake, 4)
    exact = np.isnan(cost)
    if exact:
        cost = tour_cost(t, edge, node)
    while True:  # costs by the moves' savings
        moved, new_cost = move_round(t, pos, edge, node, start, near, cluster_of, tol, active, symmetric,
                                     True, cost)
        if moved and new_cost < cost - tol:
            cost = new_cost
            continue
        cost = new_cost
        gain = reopt_changed(t, edge, node, start, cluster_of, tol, active, half)
        if gain > tol:
            cost -= gain
            continue
        return tour_cost(t, edge, node) if exact else cost


@njit(cache=True, nogil=True)
def _distinct_positions(n: int, count: int, mark: np.ndarray) -> np.ndarray:
    """``count`` distinct random positions below ``n`` (``count`` well below ``n``), marked."""
    out = np.empty(count, dtype=np.int64)
    got = 0
    while got < count:
        i = np.random.randint(0, n)
        if not mark[i]:
            mark[i] = True
            out[got] = i
            got += 1
    return out


@njit(cache=True, nogil=True)
def remove_near(t: np.ndarray, k: int, how: int, edge: np.ndarray, node: np.ndarray,
                near: np.ndarray, cluster_of: np.ndarray) -> np.ndarray:
    """The removals of :func:`gtsp_bench.solvers.heuristics.lns_kernels.remove` on a large cycle
    (``8 k < len(t)``), without a pass over all of it: **random** positions drawn one by one;
    **worst** among ``8 k`` random positions (the same randomised saving); a **segment**; and
    **distance**: the heads nearest a random one among its neighbour clusters and theirs (when
    they are fewer than ``k``, the nearest of all). A mask of the positions to take out."""
    n = len(t)
    drop = np.zeros(n, dtype=np.bool_)
    if how == 0:  # random
        _distinct_positions(n, k, drop)
    elif how == 1:  # worst: largest saving, each scaled by a random factor in [0.5, 1.5)
        mark = np.zeros(n, dtype=np.bool_)
        cand = _distinct_positions(n, min(n, 8 * k), mark)
        key = np.empty(len(cand))
        for x in range(len(cand)):
            i = cand[x]
            a, u, b = t[(i - 1) % n], t[i], t[(i + 1) % n]
            key[x] = -(ec(edge, a, u) + node[u] + ec(edge, u, b)
                       - ec(edge, a, b)) * (0.5 + np.random.random())
        order = np.argsort(key)
        for x in range(k):
            drop[cand[order[x]]] = True
    elif how == 2:  # segment
        s = np.random.randint(0, n)
        for i in range(k):
            drop[(s + i) % n] = True
    else:  # distance: the heads nearest a random one, among its neighbours and theirs
        s = np.random.randint(0, n)
        pos = np.empty(n, dtype=np.int64)
        for i in range(n):
            pos[cluster_of[t[i]]] = i
        mark = np.zeros(n, dtype=np.bool_)
        mark[s] = True
        cand = np.empty(near.shape[1] * (near.shape[1] + 1), dtype=np.int64)
        got = 0
        c = cluster_of[t[s]]
        for w in range(near.shape[1]):
            d = near[c, w]
            for e in range(-1, near.shape[1]):
                q = pos[d] if e < 0 else pos[near[d, e]]
                if not mark[q]:
                    mark[q] = True
                    cand[got] = q
                    got += 1
        if got < k:
            got = 0
            cand = np.empty(n - 1, dtype=np.int64)
            for i in range(n):
                if i != s:
                    cand[got] = i
                    got += 1
        key = np.empty(got)
        for x in range(got):
            key[x] = ec(edge, t[s], t[cand[x]])
        order = np.argsort(key)
        for x in range(k):
            drop[cand[order[x]]] = True
    return drop

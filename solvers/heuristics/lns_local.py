"""The local search of :mod:`gtsp_bench.solvers.heuristics.lns` (numba, ``cache=True``).

Tours and problems as in :mod:`gtsp_bench.solvers.heuristics.lns_kernels`. :func:`local_search`
repeats, until none improves:

* **2-opt** on the cycle with the heads kept (first improvement; symmetric costs only);
* **segment swap** (or-3opt; directed costs only, in 2-opt's place): two consecutive runs of any
  length trade places, neither reversed;
* **or-opt**: a run of 2 or 3 consecutive clusters, heads and direction kept (or reversed, in the
  large-cycle search of :mod:`gtsp_bench.solvers.heuristics.lns_window`), moved next to a
  neighbour of its first or last cluster;
* **move** (GLNS's "moveopt"): each cluster in turn is taken out and put back at its cheapest
  position and head, when that is cheaper than where it is;
* **re-opt** (GLNS's "reopt"): optimal heads for the cluster order, a shortest path through the
  layers from each node of the smallest cluster.

Don't-look bits (one row per move kind) keep each move to the clusters near where the tour last
changed.
"""

from __future__ import annotations

import numpy as np
from gtsp_bench.solvers.heuristics.lns_costs import ec
from numba import njit


@njit(cache=True, nogil=True)
def tour_cost(t: np.ndarray, edge: np.ndarray, node: np.ndarray) -> float:
    """Node costs plus edge costs of the closed tour ``t``."""
    n = len(t)
    total = 0.0
    for i in range(n):
        total += node[t[i]] + ec(edge, t[i], t[(i + 1) % n])
    return total


# ---------------------------------------------------------------------- local search
@njit(cache=True, nogil=True)
def _reverse(t: np.ndarray, pos: np.ndarray, cluster_of: np.ndarray, lo: int, hi: int) -> None:
    """Reverse the cyclic run of positions ``lo .. hi`` (or, the same cycle, its complement when
    that is shorter), keeping ``pos`` (the position of each cluster) in step."""
    n = len(t)
    length = (hi - lo) % n + 1
    if 2 * length > n:
        lo, hi, length = (hi + 1) % n, (lo - 1) % n, n - length
    for x in range(length // 2):
        p, q = (lo + x) % n, (hi - x) % n
        t[p], t[q] = t[q], t[p]
        pos[cluster_of[t[p]]] = p
        pos[cluster_of[t[q]]] = q


@njit(cache=True, nogil=True)
def _touch(active: np.ndarray, cluster_of: np.ndarray, t: np.ndarray, i: int) -> None:
    """Wake (every don't-look bit of) the cluster at position ``i`` and its two tour neighbours."""
    n = len(t)
    for q in (i - 1, i, i + 1):
        c = cluster_of[t[q % n]]
        for r in range(active.shape[0]):
            active[r, c] = True


@njit(cache=True, nogil=True)
def two_opt(t: np.ndarray, pos: np.ndarray, edge: np.ndarray, near: np.ndarray,
            cluster_of: np.ndarray, tol: float, active: np.ndarray) -> float:
    """2-opt with fixed heads over neighbour lists and don't-look bits, first improvement, in place.

    For each awake head ``a`` (``active[0]`` of its cluster) and each cluster ``c`` in
    ``near[cluster of a]``, the two exchanges that make ``a`` adjacent to ``c``'s head are tried; a
    head where none improves goes to sleep, the ends of a changed edge wake. Returns the saving (0:
    nothing improved).
    """
    n = len(t)
    if n < 5:
        return 0.0
    gained = 0.0
    improved = True
    while improved:
        improved = False
        for i in range(n):
            if not active[0, cluster_of[t[i]]]:
                continue
            found = False
            for w in range(near.shape[1]):
                a, b, p = t[i], t[(i + 1) % n], t[(i - 1) % n]
                j = pos[near[cluster_of[a], w]]
                c, d, e = t[j], t[(j + 1) % n], t[(j - 1) % n]
                if c != b and d != a:  # a -> c ... b -> d: reverse i + 1 .. j
                    delta = ec(edge, a, c) + ec(edge, b, d) - ec(edge, a, b) - ec(edge, c, d)
                    if delta < -tol:
                        gained -= delta
                        _reverse(t, pos, cluster_of, (i + 1) % n, j)
                        for x in (a, b, c, d):
                            _touch(active, cluster_of, t, pos[cluster_of[x]])
                        improved = found = True
                        continue
                if c != p and e != a:  # p -> e ... a -> c: reverse i .. j - 1
                    delta = ec(edge, a, c) + ec(edge, p, e) - ec(edge, p, a) - ec(edge, e, c)
                    if delta < -tol:
                        gained -= delta
                        _reverse(t, pos, cluster_of, i, (j - 1) % n)
                        for x in (a, p, c, e):
                            _touch(active, cluster_of, t, pos[cluster_of[x]])
                        improved = found = True
            if not found:
                active[0, cluster_of[t[i]]] = False
    return gained


@njit(cache=True, nogil=True)
def move_opt(t: np.ndarray, pos: np.ndarray, edge: np.ndarray, node: np.ndarray,
             start: np.ndarray, near: np.ndarray, cluster_of: np.ndarray, tol: float,
             active: np.ndarray, symmetric: bool = False, awake_only: bool = False) -> float:
    """Each awake cluster (``active[1]``) in turn to its cheapest place and head (GLNS's
    moveopt), in place, in a random order of all the clusters (or, with ``awake_only``, of those
    awake at the start: on a long cycle, shuffling all of them cost more than the moves).

    The places tried are its own and the edges on either side of the heads of its neighbour
    clusters ``near[c]``. A cluster that stays goes to sleep; one that moves wakes its old and new
    neighbours. Returns the saving (0: nothing improved). On ``symmetric`` costs ``ec(edge, v, y)`` is read
    as ``ec(edge, y, v)`` (the same number; a cluster's nodes are then one run of one row).
    """
    n = len(t)
    if n < 3:
        return 0.0
    gained = 0.0
    if awake_only:
        order = np.empty(n, dtype=np.int64)
        m = 0
        for c in range(n):
            if active[1, c]:
                order[m] = c
                m += 1
        for x in range(m - 1, 0, -1):
            y = np.random.randint(0, x + 1)
            order[x], order[y] = order[y], order[x]
        order = order[:m]
    else:
        order = np.random.permutation(n)
    for c in order:
        if not active[1, c]:
            continue
        i = pos[c]
        u = t[i]
        a, b = t[(i - 1) % n], t[(i + 1) % n]
        base = -ec(edge, a, b)
        saving = ec(edge, a, u) + node[u] + ec(edge, u, b) + base  # what taking u out saves
        best, best_j, best_v = saving - tol, -1, -1
        for v in range(start[c], start[c + 1]):  # the same place with another head
            d = base + ec(edge, a, v) + (ec(edge, b, v) if symmetric else ec(edge, v, b)) + node[v]
            if d < best:
                best, best_j, best_v = d, -2, v
        for w in range(near.shape[1]):
            j0 = pos[near[c, w]]
            for j in ((j0 - 1) % n, j0):  # the edge t[j] -> t[j + 1]
                if j == i or (j + 1) % n == i:
                    continue
                x, y = t[j], t[(j + 1) % n]
                base = -ec(edge, x, y)
                for v in range(start[c], start[c + 1]):
                    d = base + ec(edge, x, v) + (ec(edge, y, v) if symmetric else ec(edge, v, y)) + node[v]
                    if d < best:
                        best, best_j, best_v = d, j, v
        if best_j == -1:
            active[1, c] = False
            continue
        gained += saving - best
        if best_j == -2:
            t[i] = best_v
            _touch(active, cluster_of, t, i)
            continue
        _touch(active, cluster_of, t, i)  # the old neighbours (and c)
        # remove position i, insert best_v after position best_j (indices before removal)
        if best_j > i:
            for q in range(i, best_j):
                t[q] = t[q + 1]
                pos[cluster_of[t[q]]] = q
            t[best_j] = best_v
            pos[c] = best_j
        else:
            for q in range(i, best_j + 1, -1):
                t[q] = t[q - 1]
                pos[cluster_of[t[q]]] = q
            t[best_j + 1] = best_v
            pos[c] = best_j + 1
        _touch(active, cluster_of, t, pos[c])  # the new neighbours
    return gained


@njit(cache=True, nogil=True)
def or_opt(t: np.ndarray, pos: np.ndarray, edge: np.ndarray, near: np.ndarray,
           cluster_of: np.ndarray, tol: float, active: np.ndarray, reverse: bool = False) -> float:
    """Or-opt with fixed heads, first improvement, in place: the run of 2 or 3 clusters starting
    at an awake cluster (``active[2]``) moves, in its direction (or, with ``reverse``, for
    symmetric costs, reversed if that is cheaper), to just after the head of a neighbour of its
    first cluster or just before the head of a neighbour of its last one. Each arc is priced in
    its direction, so this is exact on asymmetric costs too. A cluster whose runs do not move goes
    to sleep; the ends of changed edges wake. Returns the saving (0: nothing improved).
    """
    n = len(t)
    if n < 6:
        return 0.0
    gained = 0.0
    for i in range(n):
        c = cluster_of[t[i]]
        if not active[2, c]:
            continue
        found = False
        for length in (2, 3):
            a, b = t[i], t[(i + length - 1) % n]
            p, q = t[(i - 1) % n], t[(i + length) % n]
            gain = ec(edge, p, a) + ec(edge, b, q) - ec(edge, p, q)  # what taking the run out saves
            if gain <= tol:
                continue
            best, best_j, flip = gain - tol, -1, False
            for w in range(near.shape[1]):
                for j in (pos[near[cluster_of[a], w]], (pos[near[cluster_of[b], w]] - 1) % n):
                    if (j - i + 1) % n <= length:  # the edge t[j] -> t[j + 1] touches the run
                        continue
                    x, y = t[j], t[(j + 1) % n]
                    d = ec(edge, x, a) + ec(edge, b, y) - ec(edge, x, y)
                    if d < best:
                        best, best_j, flip = d, j, False
                    if reverse:  # x -> b ... a -> y
                        d = ec(edge, x, b) + ec(edge, a, y) - ec(edge, x, y)
                        if d < best:
                            best, best_j, flip = d, j, True
            if best_j < 0:
                continue
            gained += gain - best
            x, y = t[best_j], t[(best_j + 1) % n]
            run = np.empty(length, dtype=np.int64)
            for r in range(length):
                run[length - 1 - r if flip else r] = t[(i + r) % n]
            out = np.empty(n, dtype=np.int64)
            k = 0
            for r in range(n - length):
                v = t[(i + length + r) % n]
                out[k] = v
                k += 1
                if v == x:
                    for u in range(length):
                        out[k] = run[u]
                        k += 1
            for r in range(n):
                t[r] = out[r]
                pos[cluster_of[out[r]]] = r
            for z in (p, q, a, b, x, y):
                _touch(active, cluster_of, t, pos[cluster_of[z]])
            found = True
            break
        if not found:
            active[2, c] = False
    return gained


@njit(cache=True, nogil=True)
def segment_swap(t: np.ndarray, pos: np.ndarray, edge: np.ndarray, near: np.ndarray,
                 cluster_of: np.ndarray, tol: float, active: np.ndarray, width: int = 10) -> float:
    """Or-3opt with fixed heads (directed costs), first improvement, in place: two consecutive
    runs of the cycle, of any lengths, trade places, neither reversed (``a a' .. b b' .. c c'`` to
    ``a b' .. c a' .. b c'``).

    For each awake head ``a`` (``active[0]``: 2-opt's row, unused on directed costs), ``b'`` is the
    head of one of the first ``width`` neighbours of ``a``'s cluster and ``c`` of ``a'``'s, so both
    new edges into the moved runs are short; the partial gain must stay positive after the second
    edge (Lin and Kernighan's rule). On directed costs the neighbour lists hold every cluster,
    so ``width`` keeps a pass near ``n * width ** 2`` tries, not ``n ** 3``. Every arc is priced
    in its direction. A head where none improves goes to sleep; the ends of changed edges wake.
    Returns the saving (0: nothing improved).
    """
    n = len(t)
    if n < 5:
        return 0.0
    gained = 0.0
    for i in range(n):
        if not active[0, cluster_of[t[i]]]:
            continue
        a, a1 = t[i], t[(i + 1) % n]
        found = False
        for w in range(min(width, near.shape[1])):
            j = pos[near[cluster_of[a], w]]
            k = (j - i) % n  # b' at i + k, b just before it
            if k < 2:
                continue
            b, b1 = t[(j - 1) % n], t[j]
            g2 = ec(edge, a, a1) + ec(edge, b, b1) - ec(edge, a, b1)
            if g2 <= tol:
                continue
            for v in range(min(width, near.shape[1])):
                m = pos[near[cluster_of[a1], v]]
                if (m - i) % n < k:  # c must lie in b' .. a's predecessor
                    continue
                c, c1 = t[m], t[(m + 1) % n]
                gain = g2 + ec(edge, c, c1) - ec(edge, c, a1) - ec(edge, b, c1)
                if gain <= tol:
                    continue
                gained += gain
                length = (m - i) % n  # a, then b' .. c, then a' .. b, then the rest
                out = np.empty(n, dtype=np.int64)
                out[0] = a
                x = 1
                for r in range(k, length + 1):
                    out[x] = t[(i + r) % n]
                    x += 1
                for r in range(1, k):
                    out[x] = t[(i + r) % n]
                    x += 1
                for r in range(length + 1, n):
                    out[x] = t[(i + r) % n]
                    x += 1
                for r in range(n):  # a keeps its place
                    t[(i + r) % n] = out[r]
                    pos[cluster_of[out[r]]] = (i + r) % n
                for z in (a, a1, b, b1, c, c1):
                    _touch(active, cluster_of, t, pos[cluster_of[z]])
                found = True
                break
            if found:
                break
        if not found:
            active[0, cluster_of[a]] = False
    return gained


@njit(cache=True, nogil=True)
def reopt(t: np.ndarray, edge: np.ndarray, node: np.ndarray, start: np.ndarray,
          cluster_of: np.ndarray) -> float:
    """Optimal heads for the cluster order of ``t`` (in place); returns the tour's new cost."""
    n = len(t)
    first, size = 0, 1 << 62
    for i in range(n):
        c = cluster_of[t[i]]
        if start[c + 1] - start[c] < size:
            first, size = i, start[c + 1] - start[c]
    cap = 0
    for c in range(len(start) - 1):
        cap = max(cap, start[c + 1] - start[c])
    back = np.empty((n, cap), dtype=np.int64)
    cur = np.empty(cap)
    new = np.empty(cap)
    best_total, best_path = np.inf, t.copy()
    path = np.empty(n, dtype=np.int64)
    c0 = cluster_of[t[first]]
    for s in range(start[c0], start[c0 + 1]):
        cur[0] = node[s]
        prev_lo, prev_hi = s, s + 1
        for step in range(1, n):
            c = cluster_of[t[(first + step) % n]]
            lo, hi = start[c], start[c + 1]
            for v in range(lo, hi):
                bv, bu = np.inf, -1
                for u in range(prev_lo, prev_hi):
                    d = cur[u - prev_lo] + ec(edge, u, v)
                    if d < bv:
                        bv, bu = d, u
                new[v - lo] = bv + node[v]
                back[step, v - lo] = bu
            for v in range(hi - lo):
                cur[v] = new[v]
            prev_lo, prev_hi = lo, hi
        for v in range(prev_lo, prev_hi):
            total = cur[v - prev_lo] + ec(edge, v, s)
            if total < best_total:
                best_total = total
                path[n - 1] = v
                for step in range(n - 1, 0, -1):
                    c = cluster_of[t[(first + step) % n]]
                    path[step - 1] = back[step, path[step] - start[c]]
                for step in range(n):
                    best_path[(first + step) % n] = path[step]
    if n == 1:
        best_total = np.inf
        for v in range(start[c0], start[c0 + 1]):
            if node[v] < best_total:
                best_total = node[v]
                best_path[0] = v
    for i in range(n):
        t[i] = best_path[i]
    return best_total


@njit(cache=True, nogil=True)
def search_state(t: np.ndarray, cluster_of: np.ndarray, awake: np.ndarray,
                 rows: int) -> tuple[np.ndarray, np.ndarray]:
    """A local search's start: each cluster's position in ``t`` and ``rows`` rows of don't-look
    bits, awake at the ``awake`` clusters and their tour neighbours."""
    n = len(t)
    pos = np.empty(n, dtype=np.int64)
    for i in range(n):
        pos[cluster_of[t[i]]] = i
    active = np.zeros((rows, n), dtype=np.bool_)
    for i in range(n):
        if awake[cluster_of[t[i]]]:
            _touch(active, cluster_of, t, i)
    return pos, active


@njit(cache=True, nogil=True)
def move_round(t: np.ndarray, pos: np.ndarray, edge: np.ndarray, node: np.ndarray, start: np.ndarray,
               near: np.ndarray, cluster_of: np.ndarray, tol: float, active: np.ndarray,
               symmetric: bool, large: bool = False, cost: float = 0.0) -> tuple[bool, float]:
    """One round of 2-opt (symmetric costs) or segment swap (directed costs), or-opt and move on
    ``t`` (in place): whether segment swap, or-opt or move changed it, and its cost after the
    round. ``large`` is the large-cycle path: or-opt also reverses runs (on symmetric costs), move
    shuffles only the awake clusters, and the cost after the round is ``cost`` (the cost before
    it) less the moves' savings, not a pass over the tour."""
    if symmetric:
        saved, swapped = two_opt(t, pos, edge, near, cluster_of, tol, active), 0.0
    else:
        saved, swapped = 0.0, segment_swap(t, pos, edge, near, cluster_of, tol, active)
    moved = or_opt(t, pos, edge, near, cluster_of, tol, active, large and symmetric)
    shifted = move_opt(t, pos, edge, node, start, near, cluster_of, tol, active, symmetric, large)
    changed = moved > 0.0 or shifted > 0.0 or swapped > 0.0
    if large:
        return changed, cost - (saved + swapped + moved + shifted)
    return changed, tour_cost(t, edge, node)


@njit(cache=True, nogil=True)
def local_search(t: np.ndarray, edge: np.ndarray, node: np.ndarray, start: np.ndarray,
                 near: np.ndarray, cluster_of: np.ndarray, tol: float, awake: np.ndarray,
                 symmetric: bool) -> float:
    """2-opt, or-opt, move and re-opt on ``t`` (in place) until none improves; returns the cost.

    ``awake`` marks the clusters to look at first (with their tour neighbours): those just
    inserted, or all of them. Without ``symmetric`` (directed costs) there is no 2-opt: it reverses
    part of the tour, priced as if each edge cost the same both ways; segment swap takes its place,
    and it, or-opt, move and re-opt price every edge in its direction.
    """
    n = len(t)
    pos, active = search_state(t, cluster_of, awake, 3)
    cost = tour_cost(t, edge, node)
    while True:
        moved, new_cost = move_round(t, pos, edge, node, start, near, cluster_of, tol, active, symmetric)
        if moved and new_cost < cost - tol:
            cost = new_cost
            continue
        cost = new_cost
        saved = t.copy()
        dp = reopt(t, edge, node, start, cluster_of)
        if dp < cost - tol:
            cost = dp
            for i in range(n):
                if t[i] != saved[i]:
                    _touch(active, cluster_of, t, i)
            continue
        for i in range(n):
            t[i] = saved[i]
        return cost


@njit(cache=True, nogil=True)
def kick_search(t: np.ndarray, cost: float, count: int, edge: np.ndarray, node: np.ndarray,
                start: np.ndarray, near: np.ndarray, cluster_of: np.ndarray, tol: float,
                symmetric: bool) -> float:
    """``count`` double-bridge kicks of ``t`` (in place), each followed by :func:`local_search`
    from the clusters at its cuts; a kicked tour that costs no more than ``t`` (within ``tol``)
    replaces it: the iterated local search of Lin-Kernighan solvers. Returns the cost of ``t``.

    A kick cuts the cycle at three random places and swaps the two middle runs (``A B C D`` to
    ``A C B D``): three edges, far apart, change at once, whether or not that pays, and no run is
    reversed (directed costs keep their direction); the local search from there reaches tours
    that no chain of improving 2-opt, or-opt and move steps reaches. Cycles of fewer than 8
    clusters are left as they are.
    """
    n = len(t)
    if n < 8:
        return cost
    u = np.empty_like(t)
    awake = np.zeros(n, dtype=np.bool_)
    for _ in range(count):
        cuts = np.sort(np.random.choice(n - 1, 3, replace=False) + 1)
        i, j, k = cuts[0], cuts[1], cuts[2]
        u[:i] = t[:i]
        u[i:i + k - j] = t[j:k]
        u[i + k - j:k] = t[i:j]
        u[k:] = t[k:]
        awake[:] = False
        for p in (i - 1, i, i + k - j - 1, i + k - j, k - 1, k % n):
            awake[cluster_of[u[p]]] = True
        c = local_search(u, edge, node, start, near, cluster_of, tol, awake, symmetric)
        if c <= cost + tol:
            t[:] = u
            cost = c
    return cost

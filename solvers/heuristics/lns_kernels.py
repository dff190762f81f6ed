"""Compiled inner loops of :mod:`gtsp_bench.solvers.heuristics.lns` (numba, ``cache=True``).

A tour is an ``int64`` array of node ids, one per GTSP cluster, in cycle order. The problem is
given as ``edge`` (``(m, m)`` float64, ``edge[i, j]`` from i to j), ``node`` (``(m,)``) and
``start`` (``(k + 1,)``: the nodes of cluster ``c`` are ``start[c] .. start[c + 1] - 1``, as
:func:`gtsp_bench.problem.price` numbers them). One iteration of the search, :func:`iterate`, is
one call: remove clusters, insert them back, then the local search

* **2-opt** on the cycle with the heads kept (first improvement; symmetric costs only);
* **move** (GLNS's "moveopt"): each cluster in turn is taken out and put back at its cheapest
  position and head, when that is cheaper than where it is;
* **re-opt** (GLNS's "reopt"): optimal heads for the cluster order, a shortest path through the
  layers from each node of the smallest cluster;

repeated until none of the three improves. Random numbers come from numba's own generator, seeded
by :func:`seed` (with ``NUMBA_DISABLE_JIT=1`` the same code runs as plain Python on numpy's
global generator: same answers, much slower).
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: Removal operators, by index.
REMOVALS = ("random", "worst", "segment", "distance")
#: Insertion operators, by index: which pending cluster goes in next.
INSERTIONS = ("cheapest", "farthest", "randomised")


@njit(cache=True)
def seed(value: int) -> None:
    """Seed the generator the kernels draw from."""
    np.random.seed(value)


@njit(cache=True)
def tour_cost(t: np.ndarray, edge: np.ndarray, node: np.ndarray) -> float:
    """Node costs plus edge costs of the closed tour ``t``."""
    n = len(t)
    total = 0.0
    for i in range(n):
        total += node[t[i]] + edge[t[i], t[(i + 1) % n]]
    return total


# ---------------------------------------------------------------------- removal
@njit(cache=True)
def remove(t: np.ndarray, k: int, how: int, edge: np.ndarray, node: np.ndarray) -> np.ndarray:
    """A mask of the ``k`` positions of ``t`` to take out (``how`` indexes :data:`REMOVALS`)."""
    n = len(t)
    drop = np.zeros(n, dtype=np.bool_)
    if how == 0:  # random
        perm = np.random.permutation(n)
        for i in range(k):
            drop[perm[i]] = True
    elif how == 1:  # worst: largest saving, each scaled by a random factor in [0.5, 1.5)
        key = np.empty(n)
        for i in range(n):
            a, u, b = t[(i - 1) % n], t[i], t[(i + 1) % n]
            key[i] = -(edge[a, u] + node[u] + edge[u, b] - edge[a, b]) * (0.5 + np.random.random())
        order = np.argsort(key)
        for i in range(k):
            drop[order[i]] = True
    elif how == 2:  # segment
        s = np.random.randint(0, n)
        for i in range(k):
            drop[(s + i) % n] = True
    else:  # distance: the heads nearest a random one
        s = np.random.randint(0, n)
        key = np.empty(n)
        for i in range(n):
            key[i] = edge[t[s], t[i]]
        key[s] = -1.0
        order = np.argsort(key)
        for i in range(k):
            drop[order[i]] = True
    return drop


# ---------------------------------------------------------------------- insertion
@njit(cache=True)
def _price_edge(c: int, e: int, at: np.ndarray, nxt: np.ndarray, edge: np.ndarray, node: np.ndarray,
                start: np.ndarray, noise: float, best: float, best_s: int,
                best_v: int) -> tuple[float, int, int]:
    """``(best, best_s, best_v)`` improved by putting cluster ``c`` on the edge from slot ``e``."""
    a, b = at[e], at[nxt[e]]
    base = -edge[a, b]
    for v in range(start[c], start[c + 1]):
        d = base + edge[a, v] + edge[v, b] + node[v]
        if noise > 0.0:
            d += noise * np.random.random()
        if d < best:
            best, best_s, best_v = d, e, v
    return best, best_s, best_v


@njit(cache=True)
def _best_place(c: int, n_slots: int, at: np.ndarray, nxt: np.ndarray, prv: np.ndarray,
                slot_of: np.ndarray, near: np.ndarray, edge: np.ndarray, node: np.ndarray,
                start: np.ndarray, noise: float) -> tuple[float, int, int]:
    """Cheapest (cost, slot, node) to put cluster ``c`` on an edge of the linked cycle: the edges
    beside its neighbour clusters' heads when the cycle is long (``4 * len(near[c]) < n_slots``)
    and one of them is in it, else every edge."""
    best, best_s, best_v = np.inf, -1, -1
    if 4 * near.shape[1] < n_slots:
        for w in range(near.shape[1]):
            sl = slot_of[near[c, w]]
            if sl >= 0:
                best, best_s, best_v = _price_edge(c, prv[sl], at, nxt, edge, node, start, noise,
                                                   best, best_s, best_v)
                best, best_s, best_v = _price_edge(c, sl, at, nxt, edge, node, start, noise,
                                                   best, best_s, best_v)
        if best_s >= 0:
            return best, best_s, best_v
    for e in range(n_slots):
        best, best_s, best_v = _price_edge(c, e, at, nxt, edge, node, start, noise, best, best_s, best_v)
    return best, best_s, best_v


@njit(cache=True)
def insert(partial: np.ndarray, clusters: np.ndarray, how: int, noise: float, edge: np.ndarray,
           node: np.ndarray, start: np.ndarray, near: np.ndarray, cluster_of: np.ndarray) -> np.ndarray:
    """Put ``clusters`` back into the cycle ``partial``, each at a cheapest place and head.

    ``how`` (:data:`INSERTIONS`) picks the next cluster: the one cheapest to insert, the one
    dearest to insert, or a random one; ``noise`` adds up to that much to every price. Prices are
    kept per pending cluster and re-computed only when its best edge was the one split; on a long
    cycle only the edges beside its ``near`` clusters are priced (:func:`_best_place`).
    """
    r = len(clusters)
    n = len(partial) + r
    at = np.empty(n, dtype=np.int64)  # node in each slot
    nxt = np.empty(n, dtype=np.int64)  # slot after each slot
    prv = np.empty(n, dtype=np.int64)  # slot before each slot
    slot_of = np.full(len(start) - 1, -1, dtype=np.int64)  # slot of each cluster in the cycle
    p = len(partial)
    for i in range(p):
        at[i] = partial[i]
        nxt[i] = (i + 1) % p
        prv[i] = (i - 1) % p
        slot_of[cluster_of[partial[i]]] = i
    cost = np.empty(r)
    slot = np.empty(r, dtype=np.int64)
    head = np.empty(r, dtype=np.int64)
    for j in range(r):
        cost[j], slot[j], head[j] = _best_place(clusters[j], p, at, nxt, prv, slot_of, near, edge,
                                                node, start, noise)
    pending = np.ones(r, dtype=np.bool_)
    order = np.random.permutation(r)
    for step in range(r):
        if how == 2:
            j = order[step]
        else:
            j = -1
            for q in range(r):
                if pending[q] and (j < 0 or (cost[q] < cost[j] if how == 0 else cost[q] > cost[j])):
                    j = q
        pending[j] = False
        s, new = slot[j], p
        at[new] = head[j]
        nxt[new] = nxt[s]
        prv[new] = s
        prv[nxt[s]] = new
        nxt[s] = new
        slot_of[clusters[j]] = new
        p += 1
        for q in range(r):
            if not pending[q]:
                continue
            if slot[q] == s:  # its best edge is gone: price it again
                cost[q], slot[q], head[q] = _best_place(clusters[q], p, at, nxt, prv, slot_of, near,
                                                        edge, node, start, noise)
                continue
            for e in (s, new):  # the two new edges
                cost[q], slot[q], head[q] = _price_edge(clusters[q], e, at, nxt, edge, node, start,
                                                        noise, cost[q], slot[q], head[q])
    out = np.empty(n, dtype=np.int64)
    s = 0
    for i in range(n):
        out[i] = at[s]
        s = nxt[s]
    return out


# ---------------------------------------------------------------------- local search
@njit(cache=True)
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


@njit(cache=True)
def _touch(active: np.ndarray, cluster_of: np.ndarray, t: np.ndarray, i: int) -> None:
    """Wake (both don't-look bits of) the cluster at position ``i`` and its two tour neighbours."""
    n = len(t)
    for q in (i - 1, i, i + 1):
        c = cluster_of[t[q % n]]
        active[0, c] = True
        active[1, c] = True


@njit(cache=True)
def two_opt(t: np.ndarray, pos: np.ndarray, edge: np.ndarray, near: np.ndarray,
            cluster_of: np.ndarray, tol: float, active: np.ndarray) -> bool:
    """2-opt with fixed heads over neighbour lists and don't-look bits, first improvement, in place.

    For each awake head ``a`` (``active[0]`` of its cluster) and each cluster ``c`` in
    ``near[cluster of a]``, the two exchanges that make ``a`` adjacent to ``c``'s head are tried; a
    head where none improves goes to sleep, the ends of a changed edge wake. Returns whether
    anything improved.
    """
    n = len(t)
    if n < 5:
        return False
    any_gain = False
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
                    delta = edge[a, c] + edge[b, d] - edge[a, b] - edge[c, d]
                    if delta < -tol:
                        _reverse(t, pos, cluster_of, (i + 1) % n, j)
                        for x in (a, b, c, d):
                            _touch(active, cluster_of, t, pos[cluster_of[x]])
                        improved = found = True
                        continue
                if c != p and e != a:  # p -> e ... a -> c: reverse i .. j - 1
                    delta = edge[a, c] + edge[p, e] - edge[p, a] - edge[e, c]
                    if delta < -tol:
                        _reverse(t, pos, cluster_of, i, (j - 1) % n)
                        for x in (a, p, c, e):
                            _touch(active, cluster_of, t, pos[cluster_of[x]])
                        improved = found = True
            if found:
                any_gain = True
            else:
                active[0, cluster_of[t[i]]] = False
    return any_gain


@njit(cache=True)
def move_opt(t: np.ndarray, pos: np.ndarray, edge: np.ndarray, node: np.ndarray,
             start: np.ndarray, near: np.ndarray, cluster_of: np.ndarray, tol: float,
             active: np.ndarray) -> bool:
    """Each awake cluster (``active[1]``) in turn to its cheapest place and head (GLNS's
    moveopt), in place.

    The places tried are its own and the edges on either side of the heads of its neighbour
    clusters ``near[c]``. A cluster that stays goes to sleep; one that moves wakes its old and new
    neighbours. Returns whether anything improved.
    """
    n = len(t)
    if n < 3:
        return False
    any_gain = False
    for c in np.random.permutation(n):
        if not active[1, c]:
            continue
        i = pos[c]
        u = t[i]
        a, b = t[(i - 1) % n], t[(i + 1) % n]
        base = -edge[a, b]
        saving = edge[a, u] + node[u] + edge[u, b] + base  # what taking u out saves
        best, best_j, best_v = saving - tol, -1, -1
        for v in range(start[c], start[c + 1]):  # the same place with another head
            d = base + edge[a, v] + edge[v, b] + node[v]
            if d < best:
                best, best_j, best_v = d, -2, v
        for w in range(near.shape[1]):
            j0 = pos[near[c, w]]
            for j in ((j0 - 1) % n, j0):  # the edge t[j] -> t[j + 1]
                if j == i or (j + 1) % n == i:
                    continue
                x, y = t[j], t[(j + 1) % n]
                base = -edge[x, y]
                for v in range(start[c], start[c + 1]):
                    d = base + edge[x, v] + edge[v, y] + node[v]
                    if d < best:
                        best, best_j, best_v = d, j, v
        if best_j == -1:
            active[1, c] = False
            continue
        any_gain = True
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
    return any_gain


@njit(cache=True)
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
                    d = cur[u - prev_lo] + edge[u, v]
                    if d < bv:
                        bv, bu = d, u
                new[v - lo] = bv + node[v]
                back[step, v - lo] = bu
            for v in range(hi - lo):
                cur[v] = new[v]
            prev_lo, prev_hi = lo, hi
        for v in range(prev_lo, prev_hi):
            total = cur[v - prev_lo] + edge[v, s]
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


@njit(cache=True)
def local_search(t: np.ndarray, edge: np.ndarray, node: np.ndarray, start: np.ndarray,
                 near: np.ndarray, cluster_of: np.ndarray, tol: float, awake: np.ndarray,
                 symmetric: bool) -> float:
    """2-opt, move and re-opt on ``t`` (in place) until none improves; returns the cost.

    ``awake`` marks the clusters to look at first (with their tour neighbours): those just
    inserted, or all of them. Without ``symmetric`` (directed costs) there is no 2-opt: it reverses
    part of the tour, priced as if each edge cost the same both ways; move and re-opt price every
    edge in its direction.
    """
    n = len(t)
    pos = np.empty(n, dtype=np.int64)
    for i in range(n):
        pos[cluster_of[t[i]]] = i
    active = np.zeros((2, n), dtype=np.bool_)
    for i in range(n):
        if awake[cluster_of[t[i]]]:
            _touch(active, cluster_of, t, i)
    cost = tour_cost(t, edge, node)
    while True:
        if symmetric:
            two_opt(t, pos, edge, near, cluster_of, tol, active)
        moved = move_opt(t, pos, edge, node, start, near, cluster_of, tol, active)
        new_cost = tour_cost(t, edge, node)
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


@njit(cache=True)
def iterate(t: np.ndarray, k: int, removal: int, insertion: int, noise: float, edge: np.ndarray,
            node: np.ndarray, start: np.ndarray, near: np.ndarray, cluster_of: np.ndarray,
            tol: float, symmetric: bool) -> tuple[np.ndarray, float]:
    """One LNS iteration on a copy of ``t``: remove ``k`` clusters, insert them, local search
    (waking the inserted clusters)."""
    drop = remove(t, k, removal, edge, node)
    partial = t[~drop]
    clusters = cluster_of[t[drop]]
    new = insert(partial, clusters, insertion, noise, edge, node, start, near, cluster_of)
    awake = np.zeros(len(t), dtype=np.bool_)
    awake[clusters] = True
    cost = local_search(new, edge, node, start, near, cluster_of, tol, awake, symmetric)
    return new, cost


#: Scores of an iteration's operators: new best, better than current, accepted, rejected.
SCORES = (3.0, 2.0, 1.0, 0.0)
#: No operator weight falls below this (each keeps being tried).
MIN_WEIGHT = 0.1
#: Improvements smaller than this share of the tour cost are ignored (rounding noise).
REL_TOL = 1e-9


@njit(cache=True)
def _roulette(w: np.ndarray) -> int:
    """An index drawn with probability proportional to ``w``."""
    x = np.random.random() * w.sum()
    for i in range(len(w) - 1):
        x -= w[i]
        if x < 0.0:
            return i
    return len(w) - 1


@njit(cache=True)
def run_trial(cur: np.ndarray, best: np.ndarray, costs: np.ndarray, counts: np.ndarray,
              weights_r: np.ndarray, weights_i: np.ndarray, settings: np.ndarray, steps: int,
              edge: np.ndarray, node: np.ndarray, start: np.ndarray, near: np.ndarray,
              cluster_of: np.ndarray, symmetric: bool) -> bool:
    """Up to ``steps`` iterations of a trial; whether the trial has ended.

    State, updated in place: ``cur`` and ``best`` (tours), ``costs`` = (current, best, trial best),
    ``counts`` = (iteration in the trial, iterations since a new trial best, iterations done,
    iteration of the best), the operator weights. ``settings`` = (iterations, patience, start
    temperature, end temperature, largest removal, noise, reaction), temperatures and noise in
    cost units. Iterations are scored, accepted (simulated annealing) and rewarded as the module
    :mod:`gtsp_bench.solvers.heuristics.lns` describes; chunks of any size give the same run.
    """
    iterations, patience = int(settings[0]), int(settings[1])
    t0, t1, max_remove, noise, reaction = settings[2], settings[3], int(settings[4]), settings[5], settings[6]
    for _ in range(steps):
        it = counts[0]
        if it >= iterations or counts[1] >= patience:
            return True
        temp = t0 * (t1 / t0) ** (it / max(1, iterations - 1)) if t0 > 0.0 and t1 > 0.0 else t0
        r_op, i_op = _roulette(weights_r), _roulette(weights_i)
        k = np.random.randint(1, max_remove + 1)
        level = noise if np.random.random() < 0.5 else 0.0
        cur_cost, best_cost = costs[0], costs[1]
        tol = REL_TOL * max(1.0, abs(cur_cost))
        new, new_cost = iterate(cur, k, r_op, i_op, level, edge, node, start, near, cluster_of, tol,
                                symmetric)
        counts[2] += 1
        counts[0] += 1
        if new_cost < best_cost - tol:
            score = SCORES[0]
        elif new_cost < cur_cost - tol:
            score = SCORES[1]
        elif new_cost > cur_cost + tol and temp > 0.0 and \
                np.random.random() < np.exp(-(new_cost - cur_cost) / temp):
            score = SCORES[2]
        else:
            score = SCORES[3]
        if score > SCORES[3]:
            cur[:] = new
            costs[0] = new_cost
        if new_cost < best_cost - tol:
            best[:] = new
            costs[1] = new_cost
            counts[3] = counts[2]
        if new_cost < costs[2] - tol:
            costs[2] = new_cost
            counts[1] = 0
        else:
            counts[1] += 1
        weights_r[r_op] = max(MIN_WEIGHT, (1.0 - reaction) * weights_r[r_op] + reaction * score)
        weights_i[i_op] = max(MIN_WEIGHT, (1.0 - reaction) * weights_i[i_op] + reaction * score)
    return counts[0] >= iterations or counts[1] >= patience


@njit(cache=True)
def cluster_distances(edge: np.ndarray, start: np.ndarray) -> np.ndarray:
    """``(k, k)``: the least ``edge[i, j]`` from a node of each cluster to a node of each other
    (one pass over the matrix, row by row)."""
    k = len(start) - 1
    dist = np.full((k, k), np.inf)
    for c in range(k):
        for i in range(start[c], start[c + 1]):
            for d in range(k):
                low = dist[c, d]
                for j in range(start[d], start[d + 1]):
                    if edge[i, j] < low:
                        low = edge[i, j]
                dist[c, d] = low
    return dist


def neighbours(edge: np.ndarray, start: np.ndarray, count: int) -> np.ndarray:
    """``(k, min(count, k - 1))``: for each cluster, the clusters nearest it (least edge cost
    between any of their nodes, in either direction), nearest first."""
    k = len(start) - 1
    count = min(count, k - 1)
    if count <= 0:
        return np.zeros((k, 0), dtype=np.int64)
    dist = cluster_distances(edge, start)
    dist = np.minimum(dist, dist.T)
    np.fill_diagonal(dist, np.inf)
    near = np.argpartition(dist, count - 1, axis=1)[:, :count]
    rows = np.arange(k)[:, None]
    order = np.argsort(dist[rows, near], axis=1, kind="stable")
    return np.ascontiguousarray(near[rows, order], dtype=np.int64)


def warm_up() -> None:
    """Compile (first use on a machine) or load (later, from numba's cache) every kernel, on a
    tiny problem, so that a solver's clock does not pay for it."""
    xy = np.arange(12.0)
    edge = np.abs(xy[:, None] - xy[None, :])
    node = np.zeros(12)
    start = np.arange(0, 13, 2, dtype=np.int64)
    cluster_of = np.repeat(np.arange(6), 2).astype(np.int64)
    edge.setflags(write=False)  # as gtsp_bench.problem.price leaves them: numba types them apart
    node.setflags(write=False)
    near = neighbours(edge, start, 3)
    t = np.arange(0, 12, 2, dtype=np.int64)
    for how in range(len(REMOVALS)):
        iterate(t, 2, how, how % len(INSERTIONS), 0.1, edge, node, start, near, cluster_of, 1e-9, True)
    cur = t.copy()
    run_trial(cur, cur.copy(), np.full(3, tour_cost(t, edge, node)), np.zeros(4, dtype=np.int64),
              np.ones(len(REMOVALS)), np.ones(len(INSERTIONS)), np.array([4.0, 4, 1, 0.1, 2, 0.1, 0.1]),
              4, edge, node, start, near, cluster_of, True)
    local_search(t.copy(), edge, node, start, near, cluster_of, 1e-9, np.ones(6, dtype=np.bool_), True)
    tour_cost(t, edge, node)
    seed(0)

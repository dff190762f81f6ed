"""Compiled inner loops of :mod:`gtsp_bench.solvers.heuristics.lns` (numba, ``cache=True``).

A tour is an ``int64`` array of node ids, one per GTSP cluster, in cycle order. The problem is
given as ``edge`` (the edge costs: a ``(m, m)`` float64 matrix or points, read as ``ec(edge, i, j)``
from i to j: :mod:`gtsp_bench.solvers.heuristics.lns_costs`), ``node`` (``(m,)``) and
``start`` (``(k + 1,)``: the nodes of cluster ``c`` are ``start[c] .. start[c + 1] - 1``, as
:func:`gtsp_bench.problem.price` numbers them). One iteration of the search, :func:`iterate`, is
one call: remove clusters, insert them back, then the local search of
:mod:`gtsp_bench.solvers.heuristics.lns_local` (2-opt, or-opt, GLNS's "moveopt" and "reopt").
Random numbers come from numba's own generator, seeded by :func:`seed` (with
``NUMBA_DISABLE_JIT=1`` the same code runs as plain Python on numpy's global generator: same
answers, much slower).
"""

from __future__ import annotations

import numpy as np
from gtsp_bench.solvers.heuristics.lns_costs import ec, ec_key, ec_of_key
from gtsp_bench.solvers.heuristics.lns_local import (  # noqa: F401 (re-exported for callers)
    kick_search,
    local_search,
    move_opt,
    or_opt,
    reopt,
    tour_cost,
    two_opt,
)
from gtsp_bench.solvers.heuristics.lns_window import local_search_window, remove_near, runs_cost
from gtsp_bench.solvers.heuristics.local_search import is_past
from numba import njit

#: Removal operators, by index.
REMOVALS = ("random", "worst", "segment", "distance")
#: Insertion operators, by index: which pending cluster goes in next.
INSERTIONS = ("cheapest", "farthest", "randomised")
#: On a cycle longer than this, a cluster none of whose neighbours is in the cycle is priced beside
#: its neighbours' neighbours before every edge is (each edge is a cache miss on a large matrix:
#: on 3,023 clusters the full scans were most of an iteration's insertion time).
WIDE_INSERT = 400


@njit(cache=True, nogil=True)
def seed(value: int) -> None:
    """Seed the generator the kernels draw from."""
    np.random.seed(value)


# ---------------------------------------------------------------------- removal
@njit(cache=True, nogil=True)
def scaled_savings(t: np.ndarray, edge: np.ndarray, node: np.ndarray) -> np.ndarray:
    """Per position of ``t``, what taking its cluster out saves (its two edges and its node cost,
    less the edge that closes the gap), times a random factor in [0.5, 1.5): the ``worst``
    removal's key, and where a regional restart centres."""
    n = len(t)
    key = np.empty(n)
    for i in range(n):
        a, u, b = t[(i - 1) % n], t[i], t[(i + 1) % n]
        key[i] = (ec(edge, a, u) + node[u] + ec(edge, u, b) - ec(edge, a, b)) * (0.5 + np.random.random())
    return key


@njit(cache=True, nogil=True)
def remove(t: np.ndarray, k: int, how: int, edge: np.ndarray, node: np.ndarray) -> np.ndarray:
    """A mask of the ``k`` positions of ``t`` to take out (``how`` indexes :data:`REMOVALS`)."""
    n = len(t)
    drop = np.zeros(n, dtype=np.bool_)
    if how == 0:  # random
        perm = np.random.permutation(n)
        for i in range(k):
            drop[perm[i]] = True
    elif how == 1:  # worst: largest saving, each scaled by a random factor in [0.5, 1.5)
        order = np.argsort(-scaled_savings(t, edge, node))
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
            key[i] = ec(edge, t[s], t[i])
        key[s] = -1.0
        order = np.argsort(key)
        for i in range(k):
            drop[order[i]] = True
    return drop


# ---------------------------------------------------------------------- insertion
@njit(cache=True, nogil=True)
def _price_edge(c: int, e: int, at: np.ndarray, nxt: np.ndarray, edge: np.ndarray, node: np.ndarray,
                start: np.ndarray, noise: float, best: float, best_s: int,
                best_v: int, symmetric: bool) -> tuple[float, int, int]:
    """``(best, best_s, best_v)`` improved by putting cluster ``c`` on the edge from slot ``e``
    (on ``symmetric`` costs ``ec(edge, v, b)`` is read as ``ec(edge, b, v)``, the same number: the cluster's
    nodes are then one run of a row, not a row each, which on a large matrix is a cache miss each)."""
    a, b = at[e], at[nxt[e]]
    base = -ec(edge, a, b)
    for v in range(start[c], start[c + 1]):
        d = base + ec(edge, a, v) + (ec(edge, b, v) if symmetric else ec(edge, v, b)) + node[v]
        if noise > 0.0:
            d += noise * np.random.random()
        if d < best:
            best, best_s, best_v = d, e, v
    return best, best_s, best_v


@njit(cache=True, nogil=True)
def _price_beside(c: int, sl: int, at: np.ndarray, nxt: np.ndarray, prv: np.ndarray, edge: np.ndarray,
                  node: np.ndarray, start: np.ndarray, noise: float, best: float, best_s: int,
                  best_v: int, symmetric: bool) -> tuple[float, int, int]:
    """:func:`_price_edge` on the two edges beside slot ``sl`` (the one into it first)."""
    best, best_s, best_v = _price_edge(c, prv[sl], at, nxt, edge, node, start, noise, best, best_s, best_v,
                                       symmetric)
    return _price_edge(c, sl, at, nxt, edge, node, start, noise, best, best_s, best_v, symmetric)


@njit(cache=True, nogil=True)
def _best_place(c: int, n_slots: int, at: np.ndarray, nxt: np.ndarray, prv: np.ndarray,
                slot_of: np.ndarray, near: np.ndarray, edge: np.ndarray, node: np.ndarray,
                start: np.ndarray, noise: float, symmetric: bool) -> tuple[float, int, int]:
    """Cheapest (cost, slot, node) to put cluster ``c`` on an edge of the linked cycle: the edges
    beside its neighbour clusters' heads when the cycle is long (``4 * len(near[c]) < n_slots``)
    and one of them is in it; on a cycle of more than ``WIDE_INSERT`` slots, failing those, the
    edges beside its neighbours' neighbours; else every edge."""
    best, best_s, best_v = np.inf, -1, -1
    m = near.shape[1]
    if 4 * m < n_slots:
        for w in range(m):
            sl = slot_of[near[c, w]]
            if sl >= 0:
                best, best_s, best_v = _price_beside(c, sl, at, nxt, prv, edge, node, start, noise,
                                                     best, best_s, best_v, symmetric)
        if best_s >= 0:
            return best, best_s, best_v
        if n_slots > WIDE_INSERT:
            for w in range(m):
                for x in range(m):
                    sl = slot_of[near[near[c, w], x]]
                    if sl >= 0:
                        best, best_s, best_v = _price_beside(c, sl, at, nxt, prv, edge, node, start,
                                                             noise, best, best_s, best_v, symmetric)
            if best_s >= 0:
                return best, best_s, best_v
    for e in range(n_slots):
        best, best_s, best_v = _price_edge(c, e, at, nxt, edge, node, start, noise, best, best_s, best_v,
                                           symmetric)
    return best, best_s, best_v


@njit(cache=True, nogil=True)
def insert(partial: np.ndarray, clusters: np.ndarray, how: int, noise: float, edge: np.ndarray,
           node: np.ndarray, start: np.ndarray, near: np.ndarray, cluster_of: np.ndarray,
           symmetric: bool = False) -> np.ndarray:
    """Put ``clusters`` back into the cycle ``partial``, each at a cheapest place and head.

    ``how`` (:data:`INSERTIONS`) picks the next cluster: the one cheapest to insert, the one
    dearest to insert, or a random one; ``noise`` adds up to that much to every price. Prices are
    kept per pending cluster and re-computed only when its best edge was the one split; on a long
    cycle only the edges beside its ``near`` clusters are priced (:func:`_best_place`).
    ``symmetric`` (costs equal to their transpose) only changes how the matrix is read.
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
                                                node, start, noise, symmetric)
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
                                                        edge, node, start, noise, symmetric)
                continue
            for e in (s, new):  # the two new edges
                cost[q], slot[q], head[q] = _price_edge(clusters[q], e, at, nxt, edge, node, start,
                                                        noise, cost[q], slot[q], head[q], symmetric)
    out = np.empty(n, dtype=np.int64)
    s = 0
    for i in range(n):
        out[i] = at[s]
        s = nxt[s]
    return out


@njit(cache=True, nogil=True)
def iterate(t: np.ndarray, k: int, removal: int, insertion: int, noise: float, edge: np.ndarray,
            node: np.ndarray, start: np.ndarray, near: np.ndarray, cluster_of: np.ndarray,
            tol: float, symmetric: bool, half: int, cost: float) -> tuple[np.ndarray, float]:
    """One LNS iteration on a copy of ``t``: remove ``k`` clusters, insert them, local search
    (waking the inserted clusters). With ``half`` > 0, the large-cycle path of
    :mod:`gtsp_bench.solvers.heuristics.lns_window`: its removals (when ``8 k`` is below the
    cycle's length) and its windowed re-opt, and given ``t``'s ``cost`` (not ``nan``), the new cost
    counted from it by what each step changed (equal up to rounding) instead of pricing the whole
    tour; else the full re-opt. (``cost`` has no default: numba's cache keys a default ``nan`` by
    a value unequal to itself, so such a kernel was compiled again in every process.)"""
    if half > 0 and 8 * k < len(t):
        drop = remove_near(t, k, removal, edge, node, near, cluster_of)
    else:
        drop = remove(t, k, removal, edge, node)
    partial = t[~drop]
    clusters = cluster_of[t[drop]]
    new = insert(partial, clusters, insertion, noise, edge, node, start, near, cluster_of, symmetric)
    awake = np.zeros(len(t), dtype=np.bool_)
    awake[clusters] = True
    if half > 0:
        if not np.isnan(cost):
            cost += runs_cost(new, awake[cluster_of[new]], edge, node) - runs_cost(t, drop, edge, node)
        cost = local_search_window(new, edge, node, start, near, cluster_of, tol, awake, symmetric, half,
                                   cost)
    else:
        cost = local_search(new, edge, node, start, near, cluster_of, tol, awake, symmetric)
    return new, cost


#: Scores of an iteration's operators: new best, better than current, accepted, rejected.
SCORES = (3.0, 2.0, 1.0, 0.0)
#: No operator weight falls below this (each keeps being tried).
MIN_WEIGHT = 0.1
#: Improvements smaller than this share of the tour cost are ignored (rounding noise).
REL_TOL = 1e-9


@njit(cache=True, nogil=True)
def _roulette(w: np.ndarray) -> int:
    """An index drawn with probability proportional to ``w``."""
    x = np.random.random() * w.sum()
    for i in range(len(w) - 1):
        x -= w[i]
        if x < 0.0:
            return i
    return len(w) - 1


def one_trial(t: np.ndarray, cost: float, settings: np.ndarray, chunk: int, edge: np.ndarray,
              node: np.ndarray, start: np.ndarray, near: np.ndarray, cluster_of: np.ndarray,
              symmetric: bool, deadline: float | None
              ) -> tuple[np.ndarray, float, np.ndarray, np.ndarray, int]:
    """One :func:`run_trial` from tour ``t`` (of cost ``cost``) with fresh operator weights, run in
    chunks of ``chunk`` iterations until it ends or ``deadline`` passes (a look after each chunk).

    Returns
    -------
    tuple
        The trial's best tour and its cost, the removal and insertion weights it ended with, and
        the iterations done.
    """
    cur, best, trial_best = t.copy(), t.copy(), t.copy()
    costs = np.array([cost, cost, cost])
    counts = np.zeros(4, dtype=np.int64)
    weights_r, weights_i = np.ones(len(REMOVALS)), np.ones(len(INSERTIONS))
    while not run_trial(cur, best, trial_best, costs, counts, weights_r, weights_i, settings, chunk,
                        edge, node, start, near, cluster_of, symmetric):
        if is_past(deadline):
            break
    return best, float(costs[1]), weights_r, weights_i, int(counts[2])


def trial_settings(iterations: int, patience: int, start_temperature: float, end_temperature: float,
                   max_remove: int, noise: float, reaction: float, window: int,
                   plateau: bool = False) -> np.ndarray:
    """The ``settings`` array of :func:`run_trial`, in its order (temperatures and noise in cost
    units; ``window``: the re-opt window's half-width, 0 for the full re-opt; ``plateau``: a tour
    that costs the same as the current one replaces it)."""
    return np.array([iterations, patience, start_temperature, end_temperature, max_remove, noise,
                     reaction, window, float(plateau)], dtype=np.float64)


@njit(cache=True, nogil=True)
def run_trial(cur: np.ndarray, best: np.ndarray, trial_best: np.ndarray, costs: np.ndarray,
              counts: np.ndarray, weights_r: np.ndarray, weights_i: np.ndarray, settings: np.ndarray,
              steps: int, edge: np.ndarray, node: np.ndarray, start: np.ndarray, near: np.ndarray,
              cluster_of: np.ndarray, symmetric: bool) -> bool:
    """Up to ``steps`` iterations of a trial; whether the trial has ended.

    State, updated in place: ``cur``, ``best`` and ``trial_best`` (tours), ``costs`` = (current,
    best, trial best),
    ``counts`` = (iteration in the trial, iterations since a new trial best, iterations done,
    iteration of the best), the operator weights. ``settings`` = (iterations, patience, start
    temperature, end temperature, largest removal, noise, reaction, re-opt window half-width (0:
    full re-opt), plateau (1: a new tour that costs the same as the current one replaces it, as
    annealing's rule ``exp(0) = 1`` would have it; 0: it is rejected)), temperatures and noise in
    cost units. On the windowed path the current cost is
    counted by changes (:func:`iterate`) and a new trial best is priced from scratch. Iterations
    are scored, accepted (simulated
    annealing) and rewarded as the module :mod:`gtsp_bench.solvers.heuristics.lns` describes;
    chunks of any size give the same run.
    """
    iterations, patience = int(settings[0]), int(settings[1])
    t0, t1, max_remove, noise, reaction = settings[2], settings[3], int(settings[4]), settings[5], settings[6]
    half = int(settings[7])
    plateau = settings[8] > 0.0
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
                                symmetric, half, cur_cost if half > 0 else np.nan)
        if half > 0 and new_cost < costs[2] - tol:
            new_cost = tour_cost(new, edge, node)  # counted by changes: a new trial best is priced
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
        if score > SCORES[3] or (plateau and new_cost <= cur_cost + tol):
            cur[:] = new
            costs[0] = new_cost
        if new_cost < best_cost - tol:
            best[:] = new
            costs[1] = new_cost
            counts[3] = counts[2]
        if new_cost < costs[2] - tol:
            trial_best[:] = new
            costs[2] = new_cost
            counts[1] = 0
        else:
            counts[1] += 1
        weights_r[r_op] = max(MIN_WEIGHT, (1.0 - reaction) * weights_r[r_op] + reaction * score)
        weights_i[i_op] = max(MIN_WEIGHT, (1.0 - reaction) * weights_i[i_op] + reaction * score)
    return counts[0] >= iterations or counts[1] >= patience


@njit(cache=True, nogil=True)
def random_insertion_tour(edge: np.ndarray, node: np.ndarray, start: np.ndarray, near: np.ndarray,
                          cluster_of: np.ndarray) -> np.ndarray:
    """A fresh tour (GLNS's cold start): a random node of a random cluster, then the other
    clusters in random order, each at its cheapest place and head."""
    k = len(start) - 1
    order = np.random.permutation(k)
    first = np.empty(1, dtype=np.int64)
    first[0] = np.random.randint(start[order[0]], start[order[0] + 1])
    return insert(first, order[1:].astype(np.int64), 2, 0.0, edge, node, start, near, cluster_of)


@njit(cache=True, nogil=True)
def regional_tour(t: np.ndarray, k: int, edge: np.ndarray, node: np.ndarray, start: np.ndarray,
                  near: np.ndarray, cluster_of: np.ndarray, symmetric: bool) -> np.ndarray:
    """A regional restart's tour from ``t``: the cluster with the largest removal saving (each
    saving scaled by a random factor in [0.5, 1.5), as the ``worst`` removal does) and the
    ``k - 1`` clusters whose heads are nearest its head (either direction) taken out, then put
    back in random order, each at its cheapest place and head (random insertion, no noise).

    On a tour whose one costly crossing (a far cluster, such as a pole) holds the clusters around
    it in a poor order, this re-plans that region while keeping the rest of the tour.
    """
    n = len(t)
    k = max(1, min(k, n - 1))
    s = int(np.argmax(scaled_savings(t, edge, node)))
    key = np.empty(n)
    for i in range(n):
        key[i] = min(ec(edge, t[s], t[i]), ec(edge, t[i], t[s]))
    key[s] = -1.0
    order = np.argsort(key, kind="mergesort")
    drop = np.zeros(n, dtype=np.bool_)
    for i in range(k):
        drop[order[i]] = True
    return insert(t[~drop], cluster_of[t[drop]], 2, 0.0, edge, node, start, near, cluster_of, symmetric)


@njit(cache=True, nogil=True)
def cluster_distances(edge: np.ndarray, start: np.ndarray) -> np.ndarray:
    """``(k, k)``: the least ``ec(edge, i, j)`` from a node of each cluster to a node of each other
    (one pass over the matrix, row by row; on points, over squared distances, rounded once per
    pair of clusters: :func:`~gtsp_bench.solvers.heuristics.lns_costs.ec_key`)."""
    k = len(start) - 1
    dist = np.full((k, k), np.inf)
    for c in range(k):
        for i in range(start[c], start[c + 1]):
            for d in range(k):
                low = dist[c, d]
                for j in range(start[d], start[d + 1]):
                    key = ec_key(edge, i, j)
                    if key < low:
                        low = key
                dist[c, d] = low
    for c in range(k):
        for d in range(k):
            dist[c, d] = ec_of_key(edge, dist[c, d])
    return dist


@njit(cache=True, nogil=True)
def _nearest_first(row: np.ndarray, at_least: int) -> np.ndarray:
    """The start of ``np.argsort(row, kind="mergesort")`` (ascending, ties by index), at least
    ``at_least`` long, without sorting the whole row."""
    if at_least >= len(row):
        return np.argsort(row, kind="mergesort")
    bound = _kth_value(row, at_least)
    part = np.flatnonzero(row <= bound)  # every entry up to the bound, ties included, by index
    return part[np.argsort(row[part], kind="mergesort")]


@njit(cache=True, nogil=True)
def _kth_value(row: np.ndarray, k: int) -> float:
    """``np.partition(row, k)[k]``, the value of rank ``k`` (0-based; no NaN in ``row``), by
    Hoare's selection on a copy: numba compiles ``np.partition`` for about 10 s, this in about one."""
    a = row.copy()
    lo, hi = 0, len(a) - 1
    while lo < hi:
        pivot = a[(lo + hi) // 2]
        i, j = lo, hi
        while i <= j:
            while a[i] < pivot:
                i += 1
            while a[j] > pivot:
                j -= 1
            if i <= j:
                a[i], a[j] = a[j], a[i]
                i += 1
                j -= 1
        if k <= j:
            hi = j
        elif k >= i:
            lo = i
        else:
            return a[k]
    return a[k]


@njit(cache=True, nogil=True)
def _quadrant_rows(dist: np.ndarray, centre: np.ndarray, count: int, per_quadrant: int) -> np.ndarray:
    """The rows of :func:`neighbours` with centres (``dist`` with an infinite diagonal)."""
    k = len(dist)
    near = np.empty((k, count), dtype=np.int64)
    for c in range(k):
        # the per_quadrant nearest in each quadrant around c's centre, by an insertion sort each
        best = np.full((4, per_quadrant), -1, dtype=np.int64)
        for d in range(k):
            if d == c:
                continue
            q = 2 * (centre[d, 0] >= centre[c, 0]) + (centre[d, 1] >= centre[c, 1])
            x = per_quadrant
            while x > 0 and (best[q, x - 1] < 0 or dist[c, d] < dist[c, best[q, x - 1]]):
                x -= 1
            if x < per_quadrant:
                for y in range(per_quadrant - 1, x, -1):
                    best[q, y] = best[q, y - 1]
                best[q, x] = d
        taken = np.zeros(k, dtype=np.bool_)
        got = 0
        for q in range(4):
            for x in range(per_quadrant):
                if best[q, x] >= 0 and got < count:
                    taken[best[q, x]] = True
                    near[c, got] = best[q, x]
                    got += 1
        if got < count:  # the rest: the nearest not taken yet (ties by index)
            order = _nearest_first(dist[c], count + got)
            x = 0
            while got < count:
                if not taken[order[x]] and order[x] != c:
                    near[c, got] = order[x]
                    got += 1
                x += 1
        row = near[c].copy()
        key = np.empty(count)
        for x in range(count):
            key[x] = dist[c, row[x]]
        rank = np.argsort(key, kind="mergesort")
        for x in range(count):
            near[c, x] = row[rank[x]]
    return near


def neighbours(edge: np.ndarray, start: np.ndarray, count: int,
               centre: np.ndarray | None = None) -> np.ndarray:
    """``(k, min(count, k - 1))``: for each cluster, the clusters nearest it (least edge cost
    between any of their nodes, in either direction), nearest first.

    With ``centre`` (a point per cluster), the ``count // 4`` nearest clusters in each quadrant
    around ``centre[c]`` are among them, the rest the nearest of all: on clustered instances the
    nearest clusters all lie in one group, and a move that joins two groups would never be tried
    (Johnson and McGeoch's quadrant neighbours).
    """
    k = len(start) - 1
    count = min(count, k - 1)
    if count <= 0:
        return np.zeros((k, 0), dtype=np.int64)
    dist = cluster_distances(edge, start)
    dist = np.minimum(dist, dist.T)
    np.fill_diagonal(dist, np.inf)
    if centre is not None:
        return _quadrant_rows(dist, np.ascontiguousarray(centre, dtype=np.float64), count, count // 4)
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
    points = np.column_stack([xy, np.zeros(12)])
    points.setflags(write=False)  # as lns_costs.points_of leaves them
    for costs in (edge, (points, 1, 1.0)):  # the two kinds of lns_costs
        near = neighbours(costs, start, 3)
        neighbours(costs, start, 4, np.column_stack([xy[::2], xy[1::2]]))
        t = np.arange(0, 12, 2, dtype=np.int64)
        for how in range(len(REMOVALS)):
            for half in (0, 1):
                iterate(t, 2, how, how % len(INSERTIONS), 0.1, costs, node, start, near, cluster_of, 1e-9,
                        True, half, np.nan)
        for how in range(len(REMOVALS)):
            remove_near(t, 1, how, costs, node, near, cluster_of)
        cur = t.copy()
        run_trial(cur, cur.copy(), cur.copy(), np.full(3, tour_cost(t, costs, node)),
                  np.zeros(4, dtype=np.int64), np.ones(len(REMOVALS)), np.ones(len(INSERTIONS)),
                  np.array([4.0, 4, 1, 0.1, 2, 0.1, 0.1, 1, 1]), 4, costs, node, start, near, cluster_of,
                  True)
        local_search(t.copy(), costs, node, start, near, cluster_of, 1e-9, np.ones(6, dtype=np.bool_), True)
        kick_search(t.copy(), tour_cost(t, costs, node), 1, costs, node, start, near, cluster_of, 1e-9,
                    True)
        tour_cost(t, costs, node)
        random_insertion_tour(costs, node, start, near, cluster_of)
        regional_tour(t, 3, costs, node, start, near, cluster_of, True)
    seed(0)

"""Region re-solves for :mod:`gtsp_bench.solvers.heuristics.lns` on large cycles (POPMUSIC-style).

A **region** is a set of a tour's clusters. The tour crosses it in one or more paths; the parts of
the tour outside it keep their nodes and their order. Which node of each region cluster, and how
the paths run through the region, is then a small symmetric GTSP, which :func:`improve_region`
solves with lns's own kernels as a cycle: each of the ``s`` outside parts is an edge of cost 0
between its two end nodes (two singleton clusters), and every other edge at an end node costs
``M`` more (``M`` = the cost of the region's current paths). A cycle that keeps every outside part
costs its paths plus ``2 s M``, any other at least ``(2 s + 2) M``, so the search, starting from
the current paths, never drops a part; putting the parts back in place of their edges, forwards or
backwards, gives a tour. The sub-problem is re-solved by a local search and one annealing trial
(temperatures from the paths' mean edge), and replaces the paths when cheaper.

:func:`region_passes` re-solves regions of the ``size`` clusters nearest a random cluster
(:class:`Regions`) until a deadline. On the drilling files (2370rl11849, 3023d15112) lns's tours
are order-optimal for their heads and head-optimal for their order, and no run of up to 11
consecutive clusters re-solved exactly improves them; their excess over GLKH's tours lies in how
the strands through small areas are joined, which a region re-solve reorders and a run of
consecutive clusters (a single path) cannot (docs/notes/lns-vs-glns.md, 2026-11-27).
"""

from __future__ import annotations

import math
import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from gtsp_bench.solvers.heuristics import lns_kernels as kernels
from gtsp_bench.solvers.heuristics.local_search import is_past
from scipy.spatial import cKDTree

from gtsp_bench.problem import Problem
from gtsp_bench.solver import Progress, no_progress

#: Neighbour-list length inside a region's sub-problem (lns's default on symmetric costs).
NEIGHBOURS = 10
#: Where a region's annealing trial ends, as a multiple of its paths' mean edge.
END_TEMPERATURE = 0.003


def path_cost(problem: Problem, nodes: np.ndarray) -> float:
    """Cost of the open path through ``nodes``: node costs of the inner nodes, every edge."""
    return float(problem.node_cost[nodes[1:-1]].sum()
                 + problem.edge_costs(nodes[:-1], nodes[1:]).sum())


def crossings(inside: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """A cycle's positions as (outside part, inside run) pairs in cycle order, ``inside`` marking
    the region's positions; an outside part shorter than two positions joins the region
    (``inside`` is changed in place). Empty when the region takes the whole cycle."""
    n = len(inside)
    while not inside.all():
        first = int(np.flatnonzero(~inside & np.roll(inside, 1))[0])  # an outside part starts here
        cycle = (first + np.arange(n)) % n
        flags = inside[cycle]
        runs = np.split(cycle, np.flatnonzero(flags[1:] != flags[:-1]) + 1)
        short = [part for part in runs[0::2] if len(part) < 2]
        if not short:
            return list(zip(runs[0::2], runs[1::2], strict=True))
        inside[np.concatenate(short)] = True
    return []


def improve_region(problem: Problem, tour: np.ndarray, positions: np.ndarray, iterations: int,
                   temperature: float = 1.0) -> float:
    """Re-solve the region at ``positions`` of the cycle ``tour`` (node ids, one per cluster; an
    outside part shorter than two clusters joins the region); ``tour`` is changed in place when
    that saves anything (beyond a relative 1e-9), the first outside part keeping its positions.
    Needs symmetric, non-negative costs; a region of more than ``len(tour) - 2`` clusters is left
    alone.

    Parameters
    ----------
    iterations
        Iterations per cluster of the annealing trial (0: the local search only).
    temperature
        The trial's start temperature as a multiple of the paths' mean edge (it ends at
        ``END_TEMPERATURE`` times).

    Returns
    -------
    float
        The saving (0.0 when nothing changed).
    """
    n = len(tour)
    inside = np.zeros(n, dtype=np.bool_)
    inside[positions] = True
    pairs = crossings(inside) if inside.sum() <= n - 2 else []
    if not pairs:
        return 0.0
    s = len(pairs)
    old = sum(path_cost(problem, np.concatenate([[tour[part[-1]]], tour[run],
                                                 [tour[pairs[(k + 1) % s][0][0]]]]))
              for k, (part, run) in enumerate(pairs))
    if not old > 0.0:
        return 0.0
    ends = np.array([[tour[part[0]], tour[part[-1]]] for part, _ in pairs], dtype=np.int64).ravel()
    xs = tour[np.concatenate([run for _, run in pairs])]
    groups = [np.asarray(problem.clusters[c], dtype=np.int64) for c in problem.cluster_of[xs]]
    nodes = np.concatenate([ends, *groups])
    sizes = np.array([1] * (2 * s) + [len(g) for g in groups], dtype=np.int64)
    start = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    cluster_of = np.repeat(np.arange(len(sizes), dtype=np.int64), sizes)
    e = 2 * s
    edge = problem.edge_block(nodes)
    np.fill_diagonal(edge, 0.0)
    big = old  # a cycle without some outside part costs >= (2 s + 2) big > 2 s big + old
    edge[:e, :] += big
    edge[:, :e] += big
    edge[np.arange(0, e, 2), np.arange(1, e, 2)] = 0.0
    edge[np.arange(1, e, 2), np.arange(0, e, 2)] = 0.0
    edge = np.ascontiguousarray(edge)
    edge.setflags(write=False)  # as lns's own matrices: one compiled kind
    node = np.array(problem.node_cost[nodes], dtype=np.float64)
    node[:e] = 0.0
    node.setflags(write=False)
    index = {int(v): j for j, v in enumerate(nodes[e:], start=e)}  # one cluster each: distinct
    t = np.array([j for k, (_, run) in enumerate(pairs)
                  for j in (2 * k, 2 * k + 1, *(index[int(v)] for v in tour[run]))], dtype=np.int64)
    k = len(sizes)
    near = kernels.neighbours(edge, start, NEIGHBOURS)
    tol = kernels.REL_TOL * (old + e * big)
    cost = kernels.local_search(t, edge, node, start, near, cluster_of, tol,
                                np.ones(k, dtype=np.bool_), True)
    if iterations > 0:
        mean = old / (len(xs) + s)
        count = max(100, iterations * k)
        settings = kernels.trial_settings(count, count, temperature * mean, END_TEMPERATURE * mean,
                                          max(1, min(k - 2, 100, math.ceil(0.3 * k))),
                                          0.1 * mean, 0.1, 0)
        best, best_cost, _, _, _ = kernels.one_trial(t, cost, settings, count, edge, node, start,
                                                     near, cluster_of, True, None)
        if best_cost < cost:
            t, cost = best, best_cost
    if not cost - e * big < old - 1e-9 * old:
        return 0.0
    new = _spliced(list(t), pairs, nodes, tour)
    saved = problem.tour_cost(tour) - problem.tour_cost(new)
    if not saved > 1e-9 * old:
        return 0.0
    tour[:] = np.roll(new, int(pairs[0][0][0]))  # the first outside part back at its positions
    return saved


def _spliced(cycle: list[int], pairs: list[tuple[np.ndarray, np.ndarray]], nodes: np.ndarray,
             tour: np.ndarray) -> np.ndarray:
    """The tour of a sub-problem ``cycle`` (indices into ``nodes``) that keeps every outside part:
    each part's two end indices replaced by the part, forwards or backwards; it starts with the
    first part, forwards."""
    z = cycle.index(0)
    cycle = cycle[z:] + cycle[:z]
    if cycle[1] != 1:  # 0 -> its partner 1 backwards round the cycle
        cycle = [0, *cycle[1:][::-1]]
    out, i, e = [], 0, 2 * len(pairs)
    while i < len(cycle):
        j = cycle[i]
        if j < e:
            assert cycle[i + 1] == j ^ 1, "an outside part came apart"
            part = tour[pairs[j // 2][0]]
            out.extend(part if j % 2 == 0 else part[::-1])
            i += 2
        else:
            out.append(int(nodes[j]))
            i += 1
    return np.array(out, dtype=np.int64)


class Regions:
    """Regions of a cycle's clusters: the ``size`` clusters nearest a cluster, by the distance
    between their centres (a k-d tree) where ``centre`` is given, else in breadth-first order over
    the neighbour lists ``near`` (fewer where those do not reach ``size`` clusters)."""

    def __init__(self, near: np.ndarray, centre: np.ndarray | None = None) -> None:
        self.near = near
        self.centre = centre
        self.tree = None if centre is None else cKDTree(centre)

    def around(self, c: int, size: int) -> np.ndarray:
        """The clusters of the region round cluster ``c`` (``c`` among them)."""
        size = min(size, len(self.near))
        if self.tree is not None:
            return np.atleast_1d(self.tree.query(self.centre[c], k=size)[1])
        seen, queue, head = {c}, [c], 0
        while len(queue) < size and head < len(queue):
            for x in self.near[queue[head]]:
                if int(x) not in seen:
                    seen.add(int(x))
                    queue.append(int(x))
            head += 1
        return np.array(queue[:size], dtype=np.int64)


def random_region(problem: Problem, tour: np.ndarray, regions: Regions, size: int,
                  iterations: int, temperature: float, rng: np.random.Generator,
                  pos: np.ndarray) -> float:
    """:func:`improve_region` of the ``size`` clusters round a random cluster of ``tour``
    (changed in place), ``pos`` a scratch array of ``len(tour)`` positions; returns the saving."""
    n = len(tour)
    pos[problem.cluster_of[tour]] = np.arange(n)
    around = regions.around(int(rng.integers(n)), size)
    return improve_region(problem, tour, pos[around], iterations, temperature)


def region_passes(problem: Problem, tour: np.ndarray, regions: Regions, size: int,
                  iterations: int, deadline: float | None, rng: np.random.Generator,
                  passes: int | None = None, progress: Progress = no_progress,
                  temperature: float = 1.0) -> tuple[float, int]:
    """Re-solve regions of ``size`` clusters (at most ``len(tour) - 2``) round random clusters of
    ``tour`` (changed in place; :func:`improve_region`) until ``deadline`` (checked before each
    region) or ``passes`` passes of ``ceil(2 n / size)`` regions (no deadline and no ``passes``:
    one pass), telling ``progress`` the tour's cost after each region that saved something;
    ``temperature`` is :func:`improve_region`'s. Returns (the saving, the regions solved)."""
    n = len(tour)
    size = min(size, n - 2)
    if size < 2:
        return 0.0, 0
    if passes is None and deadline is None:
        passes = 1
    count = None if passes is None else passes * math.ceil(2 * n / size)
    saved, done = 0.0, 0
    pos = np.empty(n, dtype=np.int64)
    while (count is None or done < count) and not is_past(deadline):
        gain = random_region(problem, tour, regions, size, iterations, temperature, rng, pos)
        if gain > 0.0:
            saved += gain
            progress(problem.tour_cost(tour))
        done += 1
    return saved, done


def _edges(tour: np.ndarray, base: int) -> np.ndarray:
    """A cycle's undirected edges as sorted codes ``low * base + high`` (node ids below ``base``)."""
    nxt = np.roll(tour, -1)
    return np.sort(np.minimum(tour, nxt) * base + np.maximum(tour, nxt))


def merged_tour(current: np.ndarray, before: np.ndarray, after: np.ndarray,
                base: int) -> np.ndarray | None:
    """``current`` with the change from ``before`` to ``after`` made in it: the edges that
    ``after`` dropped from ``before`` taken out of ``current``, those it added put in (cycles of
    node ids below ``base``, one per cluster, ``before`` and ``after`` of the same clusters).
    ``None`` where that is not one cycle through all of ``current``'s clusters: a dropped edge is
    no longer in ``current`` (another change took it), or the edges left and added close a
    shorter cycle. Where it is one cycle its cost is ``current``'s minus the change's saving (the
    same edges and heads go and come)."""
    old, new = _edges(before, base), _edges(after, base)
    gone, came = np.setdiff1d(old, new), np.setdiff1d(new, old)
    if not np.isin(gone, _edges(current, base)).all():
        return None
    links: dict[int, list[int]] = {}
    for a, b in zip(current, np.roll(current, -1), strict=True):
        links.setdefault(int(a), []).append(int(b))
        links.setdefault(int(b), []).append(int(a))
    for code in gone:
        a, b = divmod(int(code), base)
        links[a].remove(b)
        links[b].remove(a)
    for code in came:
        a, b = divmod(int(code), base)
        links.setdefault(a, []).append(b)
        links.setdefault(b, []).append(a)
    n = len(current)
    out, prev, at = [int(after[0])], -1, int(after[0])
    for _ in range(n):
        ends = links.get(at, [])
        if len(ends) != 2:
            return None
        nxt = ends[1] if ends[0] == prev else ends[0]
        if nxt == out[0]:
            break
        prev, at = at, nxt
        out.append(at)
    tour = np.array(out, dtype=np.int64)
    return tour if len(tour) == n and all(len(v) in (0, 2) for v in links.values()) else None


def shared_region_passes(problem: Problem, tour: np.ndarray, regions: Regions, size: int,
                         iterations: int, deadline: float, rngs: list[np.random.Generator],
                         progress: Progress = no_progress, temperature: float = 1.0
                         ) -> tuple[float, int]:
    """:func:`region_passes` on one tour by ``len(rngs)`` threads at once, until ``deadline``.

    Each thread re-solves a region of a copy of the tour as it was when the thread began
    (:func:`improve_region` runs without the GIL most of its time), and a saving is put into the
    shared ``tour`` (changed in place) under a lock: as it is where no other change came in
    between, else by :func:`merged_tour` (dropped where the two changes clash). Returns (the
    saving, the regions solved)."""
    n = len(tour)
    size = min(size, n - 2)
    if size < 2:
        return 0.0, 0
    lock = threading.Lock()
    base = problem.n_nodes
    state = {"version": 0, "saved": 0.0, "done": 0}

    def work(rng: np.random.Generator) -> None:
        pos = np.empty(n, dtype=np.int64)
        while not is_past(deadline):
            with lock:
                before, seen = tour.copy(), state["version"]
            after = before.copy()
            gain = random_region(problem, after, regions, size, iterations, temperature, rng, pos)
            with lock:
                state["done"] += 1
                if gain <= 0.0:
                    continue
                new = after if state["version"] == seen else merged_tour(tour, before, after, base)
                if new is None or len(np.unique(problem.cluster_of[new])) != n:
                    continue
                tour[:] = new
                state["version"] += 1
                state["saved"] += gain
                progress(problem.tour_cost(tour))

    with ThreadPoolExecutor(max_workers=len(rngs), thread_name_prefix="lns-regions") as pool:
        list(pool.map(work, rngs))
    return float(state["saved"]), int(state["done"])

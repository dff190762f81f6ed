"""Sub-path re-solves for :mod:`gtsp_bench.solvers.heuristics.lns` on large cycles (POPMUSIC-style).

A run of ``r`` consecutive clusters of a tour, between the fixed nodes ``a`` just before it and
``b`` just after it, is a small path-GTSP: which node of each cluster, in which order, from ``a``
to ``b``. :func:`improve_path` solves it with lns's own kernels as a small symmetric GTSP cycle:
``a`` and ``b`` become two singleton clusters joined by an edge of cost 0, every other edge at
``a`` or ``b`` costs ``M`` more (``M`` = the current path's cost). A cycle with ``a`` and ``b``
adjacent then costs its path plus ``2 M``, any other at least ``4 M`` (costs are not negative),
so the search, starting from the current path, never leaves the adjacent cycles' side. The
sub-path is re-solved by a local search and one annealing trial (temperatures from the path's
mean edge), and replaces the run when cheaper. :func:`path_passes` sweeps half-overlapping
windows from random offsets over the tour until a deadline.

On the large files lns's tours are order-optimal for their heads within a few tenths of a point,
but a joint re-choice of heads and order over 100-200 consecutive clusters still finds savings
that more trials of the whole tour do not (docs/notes/lns-vs-glns.md, eighth session).
"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from gtsp_bench.solvers.heuristics import lns_kernels as kernels
from gtsp_bench.solvers.heuristics.local_search import is_past

from gtsp_bench.problem import Problem

#: Neighbour-list length inside a sub-path problem (lns's default on symmetric costs).
NEIGHBOURS = 10


def path_cost(problem: Problem, nodes: np.ndarray) -> float:
    """Cost of the open path through ``nodes``: node costs of the inner nodes, every edge."""
    return float(problem.node_cost[nodes[1:-1]].sum()
                 + problem.edge_costs(nodes[:-1], nodes[1:]).sum())


def improve_path(problem: Problem, tour: np.ndarray, lo: int, length: int, iterations: int,
                 temperature: float = 1.0) -> float:
    """Re-solve the run of ``length`` clusters at positions ``lo, lo + 1, ...`` (cyclic) of the
    cycle ``tour`` (node ids, one per cluster) between its fixed neighbours; ``tour`` is changed in
    place when that saves anything (beyond a relative 1e-9). Needs symmetric, non-negative costs
    and ``length <= len(tour) - 2``.

    Parameters
    ----------
    iterations
        Iterations per cluster of the annealing trial (0: the local search only).
    temperature
        The trial's start temperature as a multiple of the path's mean edge (ends at 0.003 times).

    Returns
    -------
    float
        The saving (0.0 when nothing changed).
    """
    n = len(tour)
    pos = (lo + np.arange(length)) % n
    a, b = int(tour[(lo - 1) % n]), int(tour[(lo + length) % n])
    xs = tour[pos]
    old = path_cost(problem, np.concatenate([[a], xs, [b]]))
    if not old > 0.0:
        return 0.0
    groups = [np.asarray(problem.clusters[c], dtype=np.int64) for c in problem.cluster_of[xs]]
    nodes = np.concatenate([np.array([a, b], dtype=np.int64), *groups])
    sizes = np.array([1, 1] + [len(g) for g in groups], dtype=np.int64)
    start = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    cluster_of = np.repeat(np.arange(len(sizes), dtype=np.int64), sizes)
    m = len(nodes)
    edge = problem.edge_costs(np.repeat(nodes, m), np.tile(nodes, m)).reshape(m, m)
    np.fill_diagonal(edge, 0.0)
    big = old  # a cycle with a, b apart costs >= 4 big > 2 big + old
    edge[:2, :] += big
    edge[:, :2] += big
    edge[0, 0] = edge[1, 1] = edge[0, 1] = edge[1, 0] = 0.0
    edge = np.ascontiguousarray(edge)
    edge.setflags(write=False)  # as lns's own matrices: one compiled kind
    node = np.array(problem.node_cost[nodes], dtype=np.float64)
    node[:2] = 0.0
    node.setflags(write=False)
    index = {int(v): j for j, v in enumerate(nodes)}  # nodes are distinct: one cluster each
    t = np.array([0] + [index[int(v)] for v in xs] + [1], dtype=np.int64)
    k = len(sizes)
    near = kernels.neighbours(edge, start, NEIGHBOURS)
    tol = kernels.REL_TOL * (old + 2 * big)
    cost = kernels.local_search(t, edge, node, start, near, cluster_of, tol,
                                np.ones(k, dtype=np.bool_), True)
    if iterations > 0:
        mean = old / (length + 1)
        count = max(100, iterations * k)
        settings = kernels.trial_settings(count, count, temperature * mean, 0.003 * mean,
                                          max(1, min(k - 2, 100, math.ceil(0.3 * k))),
                                          0.1 * mean, 0.1, 0)
        best, best_cost, _, _, _ = kernels.one_trial(t, cost, settings, count, edge, node, start,
                                                     near, cluster_of, True, None)
        if best_cost < cost:
            t, cost = best, best_cost
    new = cost - 2 * big
    if not new < old - 1e-9 * old:
        return 0.0
    cyc = list(t)
    z = cyc.index(0)
    cyc = cyc[z:] + cyc[:z]
    if cyc[1] == 1:  # 0 -> 1 -> path backwards -> 0
        cyc = [0, *cyc[1:][::-1]]
    assert cyc[-1] == 1, "the fixed ends came apart"
    path = nodes[np.array(cyc[1:-1], dtype=np.int64)]
    saved = old - path_cost(problem, np.concatenate([[a], path, [b]]))
    if not saved > 1e-9 * old:
        return 0.0
    tour[pos] = path
    return saved


def path_passes(problem: Problem, tour: np.ndarray, length: int, iterations: int,
                deadline: float | None, rng: np.random.Generator, passes: int | None = None
                ) -> tuple[float, int]:
    """Sweep :func:`improve_path` over ``tour`` (changed in place): windows of ``length`` clusters
    (at most ``len(tour) - 2``) every ``length // 2`` positions from a random offset, a new offset
    each pass, until ``deadline`` (checked before each window) or ``passes`` passes. Returns (the
    saving, the windows solved)."""
    n = len(tour)
    length = min(length, n - 2)
    if length < 2:
        return 0.0, 0
    step = max(1, length // 2)
    saved, done, sweeps = 0.0, 0, 0
    while passes is None or sweeps < passes:
        offset = int(rng.integers(n))
        for w in range(0, n, step):
            if is_past(deadline):
                return saved, done
            saved += improve_path(problem, tour, offset + w, length, iterations)
            done += 1
        sweeps += 1
        if deadline is None and passes is None:
            break
    return saved, done


def region_windows(lo: int, size: int, length: int) -> list[tuple[int, int]]:
    """Windows ``(first position, clusters)`` that sweep the region of ``size`` positions from
    ``lo`` (cyclic) and stay off its last position, which the next region's windows take as their
    fixed start: ``length`` clusters every ``length // 2`` positions, the last one shortened."""
    room = size - 1
    if room < 2:
        return []
    length = min(length, room)
    step = max(1, length // 2)
    out = []
    for w in range(0, room, step):
        out.append((lo + w, min(length, room - w)))
        if w + length >= room:
            break
    return [(first, count) for first, count in out if count >= 2]


def split_path_passes(problem: Problem, tour: np.ndarray, length: int, iterations: int,
                      deadline: float, rng: np.random.Generator, workers: int
                      ) -> tuple[float, int]:
    """:func:`path_passes` on ``workers`` threads: each pass cuts the tour at a random offset into
    ``workers`` regions of consecutive positions and each thread sweeps the windows of its own
    region (:func:`region_windows`). A region's windows never touch its last position, so no window
    changes a fixed end of another's, and the threads write disjoint positions of ``tour``. Passes
    go on until ``deadline``; returns (the saving, the windows solved)."""
    n = len(tour)
    seeds = rng.integers(2**31 - 1, size=workers)
    totals = np.zeros((workers, 2))

    def sweep(j: int, windows: list[tuple[int, int]], first: bool) -> None:
        if first:
            kernels.seed(int(seeds[j]))  # numba's random state is the thread's own
        for lo, count in windows:
            if is_past(deadline):
                return
            totals[j, 0] += improve_path(problem, tour, lo % n, count, iterations)
            totals[j, 1] += 1

    with ThreadPoolExecutor(max_workers=workers, thread_name_prefix="lns-paths") as pool:
        first = True
        while not is_past(deadline):
            offset = int(rng.integers(n))
            cuts = [offset + (n * j) // workers for j in range(workers + 1)]
            jobs = [pool.submit(sweep, j, region_windows(cuts[j], cuts[j + 1] - cuts[j], length),
                                first) for j in range(workers)]
            for job in jobs:
                job.result()
            first = False
    return float(totals[:, 0].sum()), int(totals[:, 1].sum())

"""Held-Karp dynamic programming over clusters: exact, and fast for small K.

``cost[S, v]`` is the cheapest path that starts at the depot, visits exactly the clusters in the
set ``S`` (one head each) and ends at node ``v``; node costs are included. Sets are bit masks, so
``S | bit`` is always larger than ``S`` and a plain loop over ``S`` = 1, 2, ... visits every set
after all of its predecessors. Each state is reached from exactly one smaller set, so one
vectorised minimum per set fills the table: O(2^K K^2 N^2) time and O(2^K K N) memory.

Without a depot (GTSPLIB) the cycle is anchored at the smallest cluster and the DP runs once per
node of that cluster.
"""

from __future__ import annotations

import math
import time

import numpy as np

from gtsp_bench.checks import check_float
from gtsp_bench.errors import InputError
from gtsp_bench.instance import Instance
from gtsp_bench.problem import Problem, price
from gtsp_bench.solver import Solution

#: Bytes per table entry: a float64 cost and an int32 parent.
_BYTES_PER_STATE = 12


def table_bytes(instance: Instance) -> int:
    """Memory the DP table needs for ``instance`` (bytes)."""
    k = instance.n_clusters if instance.depot is not None else instance.n_clusters - 1
    n = instance.n_nodes if instance.depot is not None else instance.n_nodes - int(instance.sizes.min())
    return (2**k) * max(n, 1) * _BYTES_PER_STATE


class _TimeoutError(Exception):
    pass


def _held_karp(
    problem: Problem, start: int, clusters: list[np.ndarray], deadline: float | None
) -> tuple[float, list[int]]:
    """Cheapest cycle from ``start`` through one node of each cluster in ``clusters``."""
    edge, node_cost = problem.edge_cost, problem.node_cost
    k = len(clusters)
    nodes = np.concatenate(clusters) if clusters else np.zeros(0, dtype=np.int64)
    if k == 0:
        return float(node_cost[start]), [start]
    bit = np.concatenate([np.full(len(c), 1 << i, dtype=np.int64) for i, c in enumerate(clusters)])
    e_local = edge[np.ix_(nodes, nodes)]
    n_local = node_cost[nodes]
    full = (1 << k) - 1
    cost = np.full((full + 1, len(nodes)), np.inf)
    parent = np.full((full + 1, len(nodes)), -1, dtype=np.int32)
    cost[bit, np.arange(len(nodes))] = node_cost[start] + edge[start, nodes] + n_local
    for s in range(1, full):
        if deadline is not None and s % 64 == 0 and time.perf_counter() > deadline:
            raise _TimeoutError
        inside = (bit & s) != 0
        outside = ~inside
        if not outside.any():
            continue
        idx_in = np.flatnonzero(inside)
        trans = cost[s, idx_in][:, None] + e_local[np.ix_(idx_in, np.flatnonzero(outside))]
        arg = trans.argmin(axis=0)
        targets = s | bit[outside]
        out_idx = np.flatnonzero(outside)
        cost[targets, out_idx] = trans[arg, np.arange(len(out_idx))] + n_local[outside]
        parent[targets, out_idx] = idx_in[arg]
    closing = cost[full] + edge[nodes, start]
    v = int(np.argmin(closing))
    best = float(closing[v])
    path, s = [], full
    while v >= 0:
        path.append(int(nodes[v]))
        v, s = int(parent[s, v]), s & ~int(bit[v])
    path.append(start)
    return best, path[::-1]


class DynamicProgramming:
    """Exact Held-Karp DP over (set of visited clusters, last node).

    Parameters
    ----------
    max_memory_gb
        Refuse instances whose table needs more memory than this (GiB).
    """

    #: Directed transitions ``edge[last, next]`` and closing ``edge[last, start]``: asymmetric costs.
    asymmetric = True

    def __init__(self, max_memory_gb: float = 2.0) -> None:
        self.max_memory_gb = check_float("max_memory_gb", max_memory_gb, 0.0, math.inf)

    def solve(
        self, instance: Instance, omega: float | None, *, time_limit: float | None = None,
        seed: int = 0,
    ) -> Solution:
        """Solve exactly; at the time limit, fall back to greedy with optimal heads."""
        need = table_bytes(instance)
        if need > self.max_memory_gb * 2**30:
            raise InputError(
                f"dp needs {need / 2**30:.3g} GiB for {instance.name} (K = {instance.n_clusters}, "
                f"{instance.n_nodes} nodes), above its limit of {self.max_memory_gb:g} GiB; "
                f"use 'milp', or raise -p max_memory_gb"
            )
        deadline = None if time_limit is None else time.perf_counter() + time_limit
        problem = price(instance, omega)
        k = instance.n_clusters
        try:
            if problem.depot is not None:
                best, tour = _held_karp(problem, problem.depot, list(problem.clusters[:k]), deadline)
            else:
                anchor = int(np.argmin(instance.sizes))
                others = [problem.clusters[c] for c in range(k) if c != anchor]
                best, tour = math.inf, []
                for s in problem.clusters[anchor]:
                    cost, path = _held_karp(problem, int(s), others, deadline)
                    if cost < best:
                        best, tour = cost, path
        except _TimeoutError:
            return self._fallback(problem)
        except MemoryError:  # the table fits max_memory_gb but not this machine (or ulimit -v)
            raise MemoryError(f"dp's {need / 2**30:.3g} GiB table for {instance.name} does not fit; "
                              f"set -p max_memory_gb below {need / 2**30:.3g} to refuse it, or "
                              f"use 'milp'") from None
        order, heads = problem.to_solution(tour)
        objective = problem.tour_cost(tour)
        return Solution(order, heads, objective=objective, status="optimal",
                        lower_bound=objective, stats={"table_bytes": need})

    @staticmethod
    def _fallback(problem: Problem) -> Solution:
        from gtsp_bench.solvers.heads import optimal_heads
        from gtsp_bench.solvers.heuristics.greedy import Greedy

        greedy = Greedy().solve(problem.instance, problem.omega)
        tour, _ = optimal_heads(problem, greedy.order)
        order, heads = problem.to_solution(tour)
        return Solution(order, heads, objective=problem.tour_cost(tour), status="time_limit")

"""Exhaustive search over every cluster order and every choice of heads: the test oracle.

It refuses instances with more than ``max_tours`` candidate tours with a clear error.
"""

from __future__ import annotations

import itertools
import math
import time

import numpy as np

from gtsp_bench.checks import check_int
from gtsp_bench.errors import InputError
from gtsp_bench.instance import Instance
from gtsp_bench.problem import price
from gtsp_bench.solver import Solution

#: Default limit on the number of (order, heads) combinations enumerated.
MAX_TOURS = 20_000_000


def count_tours(instance: Instance) -> int:
    """Number of (order, heads) combinations brute force enumerates."""
    k = instance.n_clusters
    orders = math.factorial(k if instance.depot is not None else k - 1)
    return orders * math.prod(int(s) for s in instance.sizes)


class Brute:
    """Enumerate all tours; exact, for tiny instances only.

    Parameters
    ----------
    max_tours
        Refuse instances with more candidate tours than this.
    """

    #: Prices every tour in its direction (see :func:`gtsp_bench.solver.handles_asymmetric`).
    asymmetric = True

    def __init__(self, max_tours: int = MAX_TOURS) -> None:
        self.max_tours = check_int("max_tours", max_tours, 1)

    def solve(
        self, instance: Instance, omega: float | None, *, time_limit: float | None = None,
        seed: int = 0,
    ) -> Solution:
        """Enumerate; stop with status ``time_limit`` (best so far) if the limit passes."""
        n_tours = count_tours(instance)
        if n_tours > self.max_tours:
            raise InputError(
                f"brute force would enumerate {n_tours:.3g} tours on {instance.name}, above its "
                f"limit of {self.max_tours:.3g}; use 'dp' or 'milp' for instances this size"
            )
        deadline = None if time_limit is None else time.perf_counter() + time_limit
        problem = price(instance, omega)
        k = instance.n_clusters
        heads = np.array(list(itertools.product(*problem.clusters[:k])), dtype=np.int64)  # (M, K)
        node_total = problem.node_cost[heads].sum(axis=1)
        edge = problem.edge_cost
        rest = range(k) if problem.depot is not None else range(1, k)
        fixed = [] if problem.depot is not None else [0]
        best_cost, best_tour, status = math.inf, None, "optimal"
        for perm in itertools.permutations(rest):
            seq = heads[:, fixed + list(perm)]
            cost = node_total + edge[seq[:, :-1], seq[:, 1:]].sum(axis=1)
            if problem.depot is not None:
                cost = cost + edge[problem.depot, seq[:, 0]] + edge[seq[:, -1], problem.depot]
            else:
                cost = cost + edge[seq[:, -1], seq[:, 0]]
            i = int(np.argmin(cost))
            if cost[i] < best_cost:
                best_cost, best_tour = float(cost[i]), seq[i]
            if deadline is not None and time.perf_counter() > deadline:
                status = "time_limit"
                break
        tour = best_tour if problem.depot is None else np.concatenate([[problem.depot], best_tour])
        order, head_idx = problem.to_solution(tour)
        return Solution(
            order, head_idx, objective=problem.tour_cost(tour), status=status,
            lower_bound=problem.tour_cost(tour) if status == "optimal" else None,
            stats={"tours": n_tours},
        )

"""Optimal heads for a fixed order equal brute force over heads."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from gtsp_bench.solvers.heads import optimal_heads

from gtsp_bench.generator import generate_instance
from gtsp_bench.instance import Instance
from gtsp_bench.problem import price


def _best_over_heads(problem, order):
    return min(
        problem.tour_cost(problem.to_tour(order, list(heads)))
        for heads in itertools.product(*(range(s) for s in problem.instance.sizes))
    )


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("depot", [True, False])
def test_equals_brute_force_over_heads(seed, depot):
    """For random orders, omegas and cluster sizes (some of one node) the DP is optimal."""
    rng = np.random.default_rng(seed)
    k = int(rng.integers(1, 6))
    base = generate_instance(k, 4, seed=seed)
    sizes = rng.integers(1, 5, size=k)
    inst = Instance(name="h", clusters=tuple(c[:s] for c, s in zip(base.clusters, sizes, strict=True)),
                    depot=base.depot if depot else None)
    problem = price(inst, float(rng.uniform()))
    order = rng.permutation(k).tolist()
    tour, cost = optimal_heads(problem, order)
    assert cost == pytest.approx(problem.tour_cost(tour), rel=1e-12)
    assert cost == pytest.approx(_best_over_heads(problem, order), rel=1e-12)
    got_order, _ = problem.to_solution(tour)
    if depot:
        assert list(got_order) == order
    else:  # a cycle: the same cyclic sequence
        assert set(got_order) == set(order)

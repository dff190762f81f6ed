"""greedy+ils and its kicks: tours at their true price, cheaper than where they started, never
below a proven optimum, within the budget, directed costs kept in their direction, bad options
refused."""

from __future__ import annotations

import time

import numpy as np
import pytest
from gtsp_bench.solvers.heuristics import lns_kernels as kernels
from gtsp_bench.solvers.heuristics.ils import KICK_CHUNK, GreedyILS, kick

from gtsp_bench.energy import evaluate
from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance, instance_set
from gtsp_bench.problem import price
from gtsp_bench.registry import get_solver, run_solver
from tests.tiny_cases import not_below, tiny_asymmetric_case


def test_kicks_return_a_cheaper_tour_at_its_true_price():
    """From a random tour: one node of every cluster, the cost the problem prices it at, below
    the start's, kicks until the deadline; a cycle under 8 clusters gets no kick."""
    kernels.warm_up()  # compiled first (as the solver does), not in the deadline
    inst = instance_set(1, 40, 4_343, 6)[0]
    problem = price(inst, 0.3)
    rng = np.random.default_rng(3)
    tour = problem.to_tour(rng.permutation(40), [int(rng.integers(len(c))) for c in inst.clusters])
    before = problem.tour_cost(tour)
    out, cost, done = kick(problem, tour, time.perf_counter() + 0.5, seed=1)
    assert sorted(problem.cluster_of[out].tolist()) == list(range(problem.n_clusters))
    assert cost == pytest.approx(problem.tour_cost(out), rel=1e-9)
    assert cost < before and done >= KICK_CHUNK
    small = price(instance_set(1, 5, 4_343, 6)[0], 0.3)  # 6 clusters with the depot's
    _, _, none = kick(small, small.to_tour(list(range(5)), [0] * 5), time.perf_counter() + 10.0, 1)
    assert none == 0


def test_kicks_on_directed_costs_price_each_arc_its_way():
    """On an asymmetric file the kicked tour's cost is its price in its own direction."""
    kernels.warm_up()
    inst, optimum = tiny_asymmetric_case(2)
    problem = price(inst, None)
    out, cost, _ = kick(problem, np.array([c[0] for c in problem.clusters]), time.perf_counter() + 0.02, 0)
    assert cost == pytest.approx(problem.tour_cost(out), rel=1e-9)
    assert not_below(cost, optimum)


@pytest.mark.parametrize("seed", range(3))
def test_greedy_ils_never_below_the_optimum_nor_above_greedy(seed):
    """K = 9 (10 clusters with the depot's, so kicks run): never below dp's optimum, never above
    greedy's tour, priced by the evaluator, within its budget."""
    inst = generate_instance(9, 3, seed=seed)
    optimum = run_solver("dp", inst, 0.5).objective
    greedy = run_solver("greedy", inst, 0.5).objective
    start = time.perf_counter()
    r = run_solver(get_solver("greedy+ils", seconds_per_cluster=0.005), inst, 0.5, seed=seed)
    assert time.perf_counter() - start < 2.0
    assert not_below(r.objective, optimum) and r.objective <= greedy + 1e-9
    assert r.objective == pytest.approx(evaluate(inst, 0.5, r.order, r.heads).objective, rel=1e-12)
    assert r.stats["kicks"] > 0 and r.stats["budget_s"] == pytest.approx(0.045)  # 0.005 s x K = 9


def test_time_limit_caps_the_budget_and_bad_options_are_refused():
    inst = generate_instance(9, 3, seed=1)
    r = GreedyILS().solve(inst, 0.5, time_limit=1e-6)
    assert r.stats["budget_s"] == 1e-6 and r.stats["kicks"] == 0
    for bad in (0, -1.0, "x"):
        with pytest.raises(InputError, match="seconds_per_cluster"):
            GreedyILS(seconds_per_cluster=bad)

"""Sub-path re-solves of lns: the path between fixed ends, exact on small runs, passes, the option."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from gtsp_bench.solvers.heuristics import lns_kernels as kernels
from gtsp_bench.solvers.heuristics.greedy import greedy_tour
from gtsp_bench.solvers.heuristics.lns import LARGE, LnsSettings
from gtsp_bench.solvers.heuristics.lns_paths import improve_path, path_cost, path_passes
from gtsp_bench.solvers.heuristics.local_search import anchor_node

from gtsp_bench.energy import evaluate
from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance
from gtsp_bench.problem import Problem, price
from gtsp_bench.registry import get_solver, run_solver


def _problem(k: int, seed: int) -> tuple[Problem, np.ndarray]:
    """A UAV problem of ``k`` clusters of 3 nodes (node costs, a depot cluster) and its greedy
    tour (node ids, one per cluster)."""
    problem = price(generate_instance(k, 3, seed=seed), 0.5)
    return problem, np.array(greedy_tour(problem, anchor_node(problem)), dtype=np.int64)


def _best_path(problem: Problem, a: int, clusters: list[int], b: int) -> float:
    """Brute force: the cheapest path from ``a`` through one node of each of ``clusters`` to ``b``."""
    best = np.inf
    for order in itertools.permutations(clusters):
        for heads in itertools.product(*(problem.clusters[c] for c in order)):
            best = min(best, path_cost(problem, np.array([a, *heads, b])))
    return best


def _valid(problem: Problem, tour: np.ndarray) -> bool:
    return sorted(problem.cluster_of[tour].tolist()) == list(range(problem.n_clusters))


@pytest.mark.parametrize("seed", range(4))
def test_a_short_path_is_solved_exactly(seed):
    """Four clusters between fixed ends (UAV costs, node costs included): the re-solved path is
    the brute-force optimum, never below it; only those positions change; the saving is exact."""
    problem, tour = _problem(9, seed)
    n, lo, length = len(tour), 3, 4
    a, b = int(tour[lo - 1]), int(tour[lo + length])
    clusters = problem.cluster_of[tour[lo:lo + length]].tolist()
    optimum = _best_path(problem, a, clusters, b)
    before, cost = tour.copy(), problem.tour_cost(tour)
    kernels.seed(seed)
    saved = improve_path(problem, tour, lo, length, 5)
    assert _valid(problem, tour)
    assert path_cost(problem, tour[lo - 1:lo + length + 1]) == pytest.approx(optimum, rel=1e-9)
    assert problem.tour_cost(tour) == pytest.approx(cost - saved, rel=1e-9)
    outside = np.r_[0:lo, lo + length:n]
    assert np.array_equal(tour[outside], before[outside])


def test_a_window_across_the_end_of_the_array():
    """A run that wraps round the end of the tour array is re-solved in place, cyclically."""
    problem, tour = _problem(12, 7)
    n = len(tour)
    cost = problem.tour_cost(tour)
    kernels.seed(1)
    saved = improve_path(problem, tour, n - 3, 6, 0)
    assert _valid(problem, tour)
    assert saved >= 0.0
    assert problem.tour_cost(tour) == pytest.approx(cost - saved, rel=1e-9)


def test_passes_never_make_the_tour_worse():
    """Two passes of half-overlapping windows over a greedy tour: valid, cheaper or the same, never
    below the DP's proven optimum, and the saving is what the tour lost."""
    inst = generate_instance(11, 3, seed=4)
    optimum = run_solver("dp", inst, 0.5).objective
    problem = price(inst, 0.5)
    tour = np.array(greedy_tour(problem, anchor_node(problem)), dtype=np.int64)
    cost = problem.tour_cost(tour)
    kernels.seed(2)
    saved, windows = path_passes(problem, tour, 6, 5, None, np.random.default_rng(0), passes=2)
    assert windows == 2 * len(range(0, len(tour), 3))
    assert _valid(problem, tour)
    assert problem.tour_cost(tour) == pytest.approx(cost - saved, rel=1e-9)
    assert problem.tour_cost(tour) >= optimum - 1e-9 * optimum


def test_default_run_ends_with_sub_paths_above_large():
    """By default a time-limited run above LARGE clusters keeps the end of its budget for sub-path
    re-solves (windows counted in the stats, a valid tour priced as the evaluator prices it);
    with ``stop_at_convergence`` it stops after its trials, without them; ``fail_passes`` is off."""
    assert LnsSettings().fail_passes == 0
    n = LARGE + 20
    inst = generate_instance(n, 2, seed=3, zeta=10.0, area=4000.0)
    r = run_solver("lns", inst, 0.5, seed=1, time_limit=3.0)
    assert sorted(r.order) == list(range(n))
    assert r.objective == pytest.approx(evaluate(inst, 0.5, r.order, r.heads).objective, rel=1e-9)
    assert r.stats["windows"] > 0
    r = run_solver(get_solver("lns", iterations=200, trials=1, stop_at_convergence=True), inst, 0.5,
                   seed=1, time_limit=30.0)
    assert "windows" not in r.stats


@pytest.mark.parametrize("n, symmetric, options, timed, share", [
    (LARGE + 1, True, {}, True, 0.15),
    (LARGE + 1, True, {"paths": 0.3}, True, 0.3),
    (LARGE, True, {}, True, 0.0),  # up to LARGE clusters: never
    (LARGE + 1, False, {}, True, 0.0),  # directed costs: never
    (LARGE + 1, True, {}, False, 0.0),  # no time limit
    (LARGE + 1, True, {"stop_at_convergence": True}, True, 0.0),
    (LARGE + 1, True, {"paths": 0.0}, True, 0.0),
])
def test_share_of_the_budget_for_sub_paths(n, symmetric, options, timed, share):
    """The end phase's share: ``paths`` (default 0.15) above LARGE clusters on symmetric costs in
    a time-limited run that does not stop at convergence, else none."""
    assert LnsSettings(**options).path_share_for(n, symmetric, timed) == share


def test_paths_option_on_a_large_cycle():
    """Above LARGE clusters with paths=0.5 the end of the budget re-solves sub-paths: a valid
    tour, priced as the evaluator prices it, and the windows counted in the stats."""
    n = LARGE + 20
    inst = generate_instance(n, 2, seed=3, zeta=10.0, area=4000.0)
    r = run_solver(get_solver("lns", paths=0.5, path_clusters=40, path_iterations=1), inst, 0.5,
                   seed=1, time_limit=3.0)
    assert sorted(r.order) == list(range(n))
    assert r.objective == pytest.approx(evaluate(inst, 0.5, r.order, r.heads).objective, rel=1e-9)
    assert r.stats["windows"] > 0


def test_fail_passes_on_a_large_cycle():
    """Above LARGE clusters with fail_passes=1 a trial that did not improve its base is followed
    by a pass of sub-path re-solves over the base: a valid tour, priced as the evaluator prices
    it, and the windows counted in the stats (short trials, so that some fail)."""
    n = LARGE + 20
    inst = generate_instance(n, 2, seed=3, zeta=10.0, area=4000.0)
    r = run_solver(get_solver("lns", fail_passes=1, path_clusters=40, path_iterations=1,
                              iterations=100, trials=6, stop_at_convergence=True), inst, 0.5, seed=1)
    assert sorted(r.order) == list(range(n))
    assert r.objective == pytest.approx(evaluate(inst, 0.5, r.order, r.heads).objective, rel=1e-9)
    assert r.stats["windows"] > 0


def test_paths_leave_small_instances_alone():
    """Up to LARGE clusters paths has no effect: the same run as without, never below the DP's
    proven optimum."""
    inst = generate_instance(12, 3, seed=8)
    runs = [run_solver(get_solver("lns", paths=share, stop_at_convergence=True), inst, 0.5, seed=3)
            for share in (0.0, 0.5)]
    assert all("windows" not in r.stats for r in runs)
    assert len({(r.order, r.heads, r.objective, r.stats["iterations"]) for r in runs}) == 1
    optimum = run_solver("dp", inst, 0.5).objective
    assert runs[0].objective >= optimum - 1e-9 * optimum


@pytest.mark.parametrize("options, message", [
    ({"paths": 1.5}, "paths must be a number in"),
    ({"path_clusters": 1}, "path_clusters must be an integer >= 2"),
    ({"path_iterations": -1}, "path_iterations must be an integer >= 0"),
    ({"fail_passes": -1}, "fail_passes must be an integer >= 0"),
])
def test_bad_options_rejected(options, message):
    """Invalid sub-path settings raise InputError naming the setting."""
    with pytest.raises(InputError, match=message):
        get_solver("lns", **options)

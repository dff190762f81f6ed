"""Region re-solves of lns: one path and two strands solved exactly, regions, passes, the option."""

from __future__ import annotations

import itertools
import time

import numpy as np
import pytest
from gtsp_bench.solvers.heuristics import lns_kernels as kernels
from gtsp_bench.solvers.heuristics.greedy import greedy_tour
from gtsp_bench.solvers.heuristics.lns import LARGE, LnsSettings, _Search
from gtsp_bench.solvers.heuristics.lns_paths import (
    Regions,
    crossings,
    improve_region,
    merged_tour,
    path_cost,
    region_passes,
    shared_region_passes,
)
from gtsp_bench.solvers.heuristics.lns_settings import FAIL_FROM, FAIL_TO, PATHS, PATHS_ABOVE_FAIL_TO
from gtsp_bench.solvers.heuristics.local_search import anchor_node

from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance
from gtsp_bench.problem import Problem, price
from gtsp_bench.registry import get_solver, run_solver
from tests.tiny_cases import not_below


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
    """A region of four consecutive clusters (UAV costs, node costs included) is one path between
    fixed ends: re-solved to the brute-force optimum, never below it; only those positions change;
    the saving is exact."""
    problem, tour = _problem(9, seed)
    n, lo, length = len(tour), 3, 4
    a, b = int(tour[lo - 1]), int(tour[lo + length])
    clusters = problem.cluster_of[tour[lo:lo + length]].tolist()
    optimum = _best_path(problem, a, clusters, b)
    before, cost = tour.copy(), problem.tour_cost(tour)
    kernels.seed(seed)
    saved = improve_region(problem, tour, np.arange(lo, lo + length), 5)
    assert _valid(problem, tour)
    assert path_cost(problem, tour[lo - 1:lo + length + 1]) == pytest.approx(optimum, rel=1e-9)
    assert problem.tour_cost(tour) == pytest.approx(cost - saved, rel=1e-9)
    outside = np.r_[0:lo, lo + length:n]
    assert np.array_equal(tour[outside], before[outside])


def test_a_region_across_the_end_of_the_array():
    """A run that wraps round the end of the tour array is re-solved cyclically."""
    problem, tour = _problem(12, 7)
    n = len(tour)
    cost = problem.tour_cost(tour)
    kernels.seed(1)
    saved = improve_region(problem, tour, np.arange(n - 3, n + 3) % n, 0)
    assert _valid(problem, tour)
    assert saved >= 0.0
    assert problem.tour_cost(tour) == pytest.approx(cost - saved, rel=1e-9)


def _best_with_parts(problem: Problem, parts: list[np.ndarray], clusters: list[int]) -> float:
    """Brute force: the cheapest tour that keeps each of ``parts`` (node ids) in one piece,
    forwards or backwards, and visits one node of each of ``clusters`` in any order."""
    items = [("part", k) for k in range(1, len(parts))] + [("cluster", c) for c in clusters]
    best = np.inf
    for order in itertools.permutations(items):
        for flips in itertools.product((False, True), repeat=len(parts) - 1):
            for heads in itertools.product(*(problem.clusters[c] for c in clusters)):
                chosen = dict(zip(clusters, heads, strict=True))
                seq = list(parts[0])
                for kind, x in order:
                    if kind == "part":
                        seq.extend(parts[x][::-1] if flips[x - 1] else parts[x])
                    else:
                        seq.append(chosen[x])
                best = min(best, problem.tour_cost(np.array(seq)))
    return best


def _pieces(tour: np.ndarray, part: np.ndarray) -> bool:
    """Whether ``part`` (node ids) lies in ``tour`` in one piece, forwards or backwards."""
    n, k = len(tour), len(part)
    at = int(np.flatnonzero(tour == part[0])[0])
    ahead = tour[(at + np.arange(k)) % n]
    behind = tour[(at - np.arange(k)) % n]
    return bool(np.array_equal(ahead, part) or np.array_equal(behind, part))


@pytest.mark.parametrize("seed", range(4))
def test_a_region_of_two_strands_is_solved_exactly(seed):
    """A region the tour crosses twice (positions 2-3 and 6-7 of 10): its four clusters, and how
    the two strands join the two outside parts, re-solved to the brute-force optimum over every
    tour that keeps those parts in one piece; the parts stay whole; the saving is exact."""
    problem, tour = _problem(9, seed)
    assert len(tour) == 10  # nine clusters and the depot's
    parts = [tour[[4, 5]].copy(), tour[[8, 9, 0, 1]].copy()]
    clusters = problem.cluster_of[tour[[2, 3, 6, 7]]].tolist()
    optimum = _best_with_parts(problem, parts, clusters)
    cost = problem.tour_cost(tour)
    kernels.seed(seed)
    saved = improve_region(problem, tour, np.array([2, 3, 6, 7]), 5)
    assert _valid(problem, tour)
    assert problem.tour_cost(tour) == pytest.approx(optimum, rel=1e-9)
    assert problem.tour_cost(tour) == pytest.approx(cost - saved, rel=1e-9)
    assert all(_pieces(tour, part) for part in parts)
    assert np.array_equal(tour[[4, 5]], parts[0])  # the first outside part keeps its positions


def test_crossings_alternate_and_absorb_short_parts():
    """Outside parts and inside runs alternate in cycle order from an outside part; a part of one
    position joins the region; a region of the whole cycle has none."""
    inside = np.zeros(12, dtype=np.bool_)
    inside[[0, 1, 5, 7, 8]] = True
    pairs = crossings(inside)
    assert [(p.tolist(), r.tolist()) for p, r in pairs] == [([2, 3, 4], [5, 6, 7, 8]),
                                                            ([9, 10, 11], [0, 1])]
    assert inside[6]  # the one-position part between 5 and 7 joined the region
    assert crossings(np.ones(5, dtype=np.bool_)) == []
    almost = np.ones(6, dtype=np.bool_)
    almost[3] = False  # one outside position: it joins, nothing is left outside
    assert crossings(almost) == []


def test_regions_by_centres_and_by_neighbour_lists():
    """With centres a region is the clusters nearest the cluster's centre; without, the
    clusters met breadth-first over the neighbour lists; never more than there are."""
    rng = np.random.default_rng(3)
    centre = rng.random((30, 2))
    near = np.array([np.argsort(np.hypot(*(centre - centre[c]).T))[1:5] for c in range(30)])
    by_centre = Regions(near, centre).around(7, 6)
    assert sorted(by_centre.tolist()) == sorted(np.argsort(np.hypot(*(centre - centre[7]).T))[:6].tolist())
    ring = np.array([[(c + 1) % 10, (c - 1) % 10] for c in range(10)])
    assert Regions(ring).around(0, 5).tolist() == [0, 1, 9, 2, 8]
    assert sorted(Regions(ring).around(4, 50).tolist()) == list(range(10))


def test_region_passes_never_make_the_tour_worse():
    """Two passes of regions over a greedy tour: ``2 x ceil(2 n / size)`` regions, a valid tour,
    cheaper or the same, never below the DP's proven optimum, and the saving is what the tour
    lost; ``progress`` is told the cost after each region that saved something."""
    inst = generate_instance(11, 3, seed=4)
    optimum = run_solver("dp", inst, 0.5).objective
    problem = price(inst, 0.5)
    tour = np.array(greedy_tour(problem, anchor_node(problem)), dtype=np.int64)
    cost = problem.tour_cost(tour)
    kernels.seed(2)
    near = _Search(problem, LnsSettings(neighbours=4), np.random.default_rng(0)).near
    told: list[float] = []
    saved, regions = region_passes(problem, tour, Regions(near), 6, 5, None,
                                   np.random.default_rng(0), passes=2, progress=told.append)
    assert regions == 2 * 4  # ceil(2 * 12 / 6) regions a pass
    assert _valid(problem, tour)
    assert problem.tour_cost(tour) == pytest.approx(cost - saved, rel=1e-9)
    assert not_below(problem.tour_cost(tour), optimum)
    # progress hears each region that saved something: falling costs, the last the tour's
    assert saved > 0.0 and told and told == sorted(told, reverse=True)
    assert told[-1] == problem.tour_cost(tour) and told[0] < cost


def _two_opt(tour: list[int], i: int, j: int) -> np.ndarray:
    """``tour`` with positions ``i..j`` reversed."""
    return np.array(tour[:i] + tour[i:j + 1][::-1] + tour[j + 1:], dtype=np.int64)


def _edge_set(tour: np.ndarray) -> set[frozenset[int]]:
    return {frozenset((int(a), int(b))) for a, b in zip(tour, np.roll(tour, -1), strict=True)}


def test_merged_tour_makes_a_change_in_a_tour_that_moved_on():
    """Two changes found on the same tour: the second, made in the tour the first left, keeps
    both (its edges are the first's plus the second's, minus what each dropped); where another
    change took an edge it dropped, or the two together close a shorter cycle, there is none."""
    before = list(range(12))
    first, second = _two_opt(before, 2, 4), _two_opt(before, 7, 9)
    merged = merged_tour(first, np.array(before), second, 100)
    assert merged is not None and sorted(merged.tolist()) == before
    assert _edge_set(merged) == (_edge_set(first) | _edge_set(second)) - (
        _edge_set(np.array(before)) - _edge_set(first)) - (
        _edge_set(np.array(before)) - _edge_set(second))
    # a new head (node 20 in place of 8) comes with its edges
    head = np.array([*before[:8], 20, *before[9:]], dtype=np.int64)
    merged = merged_tour(first, np.array(before), head, 100)
    assert merged is not None and _edge_set(merged) == (_edge_set(first) - {
        frozenset((7, 8)), frozenset((8, 9))}) | {frozenset((7, 20)), frozenset((20, 9))}
    # both drop the edge (4, 5): the second's edge is no longer there
    assert merged_tour(first, np.array(before), _two_opt(before, 5, 8), 100) is None
    # crossing reversals: each alone a tour, together two cycles (0-1-4-8-..-11, 2-3-7-6-5)
    assert merged_tour(_two_opt(before, 2, 4), np.array(before), _two_opt(before, 4, 7),
                       100) is None


def test_shared_region_passes_on_one_tour():
    """Two threads re-solving regions of one tour: a valid tour, its cost the old one less the
    saving, never below the DP's proven optimum, every region counted; ``progress`` hears each
    saving, falling."""
    inst = generate_instance(11, 3, seed=4)
    optimum = run_solver("dp", inst, 0.5).objective
    problem = price(inst, 0.5)
    tour = np.array(greedy_tour(problem, anchor_node(problem)), dtype=np.int64)
    cost = problem.tour_cost(tour)
    near = _Search(problem, LnsSettings(neighbours=4), np.random.default_rng(0)).near
    told: list[float] = []
    rngs = np.random.default_rng(0).spawn(2)
    saved, regions = shared_region_passes(problem, tour, Regions(near), 6, 5,
                                          time.perf_counter() + 0.5, rngs, told.append)
    assert regions > 2
    assert _valid(problem, tour)
    assert problem.tour_cost(tour) == pytest.approx(cost - saved, rel=1e-9)
    assert not_below(problem.tour_cost(tour), optimum)
    assert saved > 0.0 and told == sorted(told, reverse=True)
    assert told[-1] == pytest.approx(problem.tour_cost(tour), rel=1e-12)


def test_default_run_ends_with_regions_above_large():
    """With effort ``budget`` a time-limited run above LARGE clusters keeps the end of its budget for region
    re-solves (windows counted in the stats, a valid tour priced as the evaluator prices it
    (run_solver refuses any other claim));
    with ``stop_at_convergence`` it stops after its trials, without them. ``fail_passes`` is set
    to 0 so that the windows counted are the end phase's."""
    n = LARGE + 20
    inst = generate_instance(n, 2, seed=3, zeta=10.0, area=4000.0)
    r = run_solver(get_solver("lns", effort="budget", fail_passes=0), inst, 0.5, seed=1,
                   time_limit=3.0)
    assert sorted(r.order) == list(range(n))
    assert r.stats["windows"] > 0
    r = run_solver(get_solver("lns", iterations=200, trials=1, stop_at_convergence=True), inst, 0.5,
                   seed=1, time_limit=30.0)
    assert "windows" not in r.stats


@pytest.mark.parametrize("n, symmetric, options, timed, share", [
    (LARGE + 1, True, {"effort": "budget"}, True, PATHS),
    (FAIL_TO, True, {"effort": "budget"}, True, PATHS),
    (FAIL_TO + 1, True, {"effort": "budget"}, True, PATHS_ABOVE_FAIL_TO),  # no passes between trials
    (FAIL_TO + 1, True, {"paths": 0.3, "effort": "budget"}, True, 0.3),
    (FAIL_TO + 1, True, {"effort": "default"}, True, 0.0),
    (LARGE + 1, True, {"paths": 0.15, "effort": "budget"}, True, 0.15),
    (LARGE + 1, True, {}, True, 0.0),  # the default effort stops after its trials
    (LARGE, True, {}, True, 0.0),  # up to LARGE clusters: never
    (LARGE + 1, False, {}, True, 0.0),  # directed costs: never
    (LARGE + 1, True, {}, False, 0.0),  # no time limit
    (LARGE + 1, True, {"stop_at_convergence": True}, True, 0.0),
    (LARGE + 1, True, {"paths": 0.0}, True, 0.0),
])
def test_share_of_the_budget_for_regions(n, symmetric, options, timed, share):
    """The end phase's share: ``paths`` (default PATHS, PATHS_ABOVE_FAIL_TO above FAIL_TO) above LARGE
    clusters on symmetric costs in a time-limited run with effort ``budget``, else none."""
    assert LnsSettings(**options).path_share_for(n, symmetric, timed) == share


@pytest.mark.parametrize("n, symmetric, options, passes", [
    (FAIL_FROM, True, {"effort": "budget"}, 1),
    (LARGE, True, {"effort": "budget"}, 1),
    (LARGE + 1, True, {"effort": "budget"}, 1),  # beside the end phase above LARGE
    (FAIL_TO, True, {"effort": "budget"}, 1),
    (FAIL_FROM - 1, True, {"effort": "budget"}, 0),  # below FAIL_FROM: off by default
    (FAIL_TO + 1, True, {"effort": "budget"}, 0),  # above FAIL_TO: off by default
    (FAIL_FROM, True, {}, 0),  # the default effort stops after its trials: off
    (FAIL_FROM, True, {"effort": "slow"}, 0),
    (FAIL_FROM, True, {"stop_at_convergence": False}, 1),  # effort budget by its old name
    (FAIL_FROM, False, {"effort": "budget"}, 0),  # directed costs: never
    (FAIL_FROM, False, {"fail_passes": 2}, 0),
    (12, True, {"fail_passes": 2}, 2),  # given: at any size on symmetric costs
    (FAIL_FROM, True, {"effort": "budget", "fail_passes": 0}, 0),
])
def test_fail_passes_by_size(n, symmetric, options, passes):
    """Region passes after a failed trial: ``fail_passes`` on symmetric costs, by default 1 from
    FAIL_FROM to FAIL_TO clusters with effort ``budget``, else 0."""
    assert LnsSettings(**options).fail_passes_for(n, symmetric) == passes


@pytest.mark.parametrize("n, passes", [(FAIL_FROM - 2, False), (FAIL_FROM - 1, True)])
def test_budget_runs_fail_passes_from_fail_from(n, passes):
    """A budget run on a cycle of FAIL_FROM clusters (K = FAIL_FROM - 1 and the base station)
    re-solves regions after its failed trials by default (windows counted in its stats), one of
    a cluster fewer does not; both give a valid tour priced as the evaluator prices it
    (run_solver refuses any other claim). Short trials, so that some fail; no kicks, which come
    first after a failed trial and on a loaded machine could spend the budget before a pass."""
    inst = generate_instance(n, 2, seed=3, zeta=10.0, area=4000.0)
    r = run_solver(get_solver("lns", effort="budget", iterations=100, path_clusters=40,
                              path_iterations=1, kicks=0), inst, 0.5, seed=1, time_limit=1.5)
    assert ("windows" in r.stats and r.stats["windows"] > 0) == passes
    assert sorted(r.order) == list(range(n))


def test_paths_option_on_a_large_cycle():
    """Above LARGE clusters with paths=0.5 the end of the budget re-solves regions: a valid
    tour, priced as the evaluator prices it
    (run_solver refuses any other claim), and the windows counted in the stats."""
    n = LARGE + 20
    inst = generate_instance(n, 2, seed=3, zeta=10.0, area=4000.0)
    solver = get_solver("lns", paths=0.5, path_clusters=40, path_iterations=1, effort="budget")
    r = run_solver(solver, inst, 0.5, seed=1, time_limit=3.0)
    assert sorted(r.order) == list(range(n))
    assert r.stats["windows"] > 0


def test_fail_passes_on_a_large_cycle():
    """Above LARGE clusters with fail_passes=1 a trial that did not improve its base is followed
    by a pass of region re-solves over the base: a valid tour, priced as the evaluator prices
    it, and the windows counted in the stats (short trials, so that some fail)."""
    n = LARGE + 20
    inst = generate_instance(n, 2, seed=3, zeta=10.0, area=4000.0)
    r = run_solver(get_solver("lns", fail_passes=1, path_clusters=40, path_iterations=1,
                              iterations=100, trials=6, stop_at_convergence=True), inst, 0.5, seed=1)
    assert sorted(r.order) == list(range(n))
    assert r.stats["windows"] > 0


def test_fail_passes_then_more_trials():
    """A trial after a failed one's region pass runs on: the pass's saving is not taken for the
    mirror trial's saved state (it was, and the next trial's end raised a TypeError). A budget
    run of 2 s has many trials after failed ones."""
    n = LARGE + 20
    inst = generate_instance(n, 2, seed=3, zeta=10.0, area=4000.0)
    r = run_solver(get_solver("lns", fail_passes=1, path_clusters=40, path_iterations=1,
                              iterations=100, effort="budget", workers=1), inst, 0.5,
                   time_limit=2.0, seed=1)
    assert r.status == "feasible" and r.stats["trials"] > 3
    assert sorted(r.order) == list(range(n))
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
    assert not_below(runs[0].objective, optimum)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_fail_passes_on_a_small_cycle_never_below_dp_optimum(seed):
    """fail_passes works at any size on symmetric costs: on K = 12 its region re-solves run
    (windows counted) and the tour is valid, priced as the evaluator prices it
    (run_solver refuses any other claim), and never below
    the DP's proven optimum."""
    inst = generate_instance(12, 3, seed=8)
    r = run_solver(get_solver("lns", fail_passes=2, path_clusters=6, path_iterations=2,
                              iterations=10, trials=8, stop_at_convergence=True), inst, 0.5,
                   seed=seed)
    assert r.stats["windows"] > 0
    assert sorted(r.order) == list(range(12))
    optimum = run_solver("dp", inst, 0.5).objective
    assert not_below(r.objective, optimum)


@pytest.mark.parametrize("options, message", [
    ({"paths": 1.5}, "paths must be a number in"),
    ({"path_clusters": 1}, "path_clusters must be an integer >= 2"),
    ({"path_iterations": -1}, "path_iterations must be an integer >= 0"),
    ({"path_temperature": 0.001}, "path_temperature must be a number >= 0.003"),
    ({"fail_passes": -1}, "fail_passes must be an integer >= 0"),
    ({"fail_temperature": 0.0}, "fail_temperature must be a number >= 0.003"),
])
def test_bad_options_rejected(options, message):
    """Invalid region settings raise InputError naming the setting."""
    with pytest.raises(InputError, match=message):
        get_solver("lns", **options)


def test_region_trials_start_at_their_phase_temperature(monkeypatch):
    """The end phase's region trials start at path_temperature, the re-solves after a failed
    trial at fail_temperature; the tour stays valid and priced as the evaluator prices it
    (run_solver refuses any other claim)."""
    from gtsp_bench.solvers.heuristics import lns_paths

    seen: list[float] = []

    def recording(problem, tour, positions, iterations, temperature=1.0):
        seen.append(temperature)
        return improve_region(problem, tour, positions, iterations, temperature)

    monkeypatch.setattr(lns_paths, "improve_region", recording)
    n = LARGE + 20
    inst = generate_instance(n, 2, seed=3, zeta=10.0, area=4000.0)
    r = run_solver(get_solver("lns", paths=0.5, path_clusters=40, path_iterations=1,
                              path_temperature=5.0, fail_passes=1, fail_temperature=2.0,
                              iterations=100, effort="budget", workers=1),
                   inst, 0.5, seed=1, time_limit=2.0)
    assert set(seen) == {2.0, 5.0}  # both phases ran, each at its own start
    assert sorted(r.order) == list(range(n))

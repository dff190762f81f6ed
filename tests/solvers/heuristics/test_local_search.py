"""The shared local search: exact move prices, never worse, a local optimum, the +ls variants."""

from __future__ import annotations

import numpy as np
import pytest
from gtsp_bench.solvers.heuristics.local_search import LocalSearch, Move, anchor_node, deadline_after, improve

from gtsp_bench.data.io import read_instance
from gtsp_bench.errors import InfeasibleSolutionError, InputError
from gtsp_bench.generator import generate_instance
from gtsp_bench.problem import price
from gtsp_bench.registry import run_solver
from tests.conftest import GTSPLIB
from tests.tiny_cases import not_below, tiny_case


def _random_tour(problem, rng):
    tour = np.array([rng.choice(c) for c in problem.clusters])
    return tour[rng.permutation(len(tour))]


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("depot", [True, False])
def test_every_move_is_priced_exactly(seed, depot):
    """For every 2-opt and or-opt move on a random tour, the priced change is the real one."""
    rng = np.random.default_rng(seed)
    base = generate_instance(int(rng.integers(5, 9)), 3, seed=seed)
    inst = base if depot else base.__class__(name="nd", clusters=base.clusters)
    problem = price(inst, float(rng.uniform()))
    ls = LocalSearch(problem)
    t = _random_tour(problem, rng)
    before = problem.tour_cost(t)
    checked = 0
    d = ls.two_opt_deltas(t)
    for i, j in zip(*np.nonzero(np.isfinite(d)), strict=True):
        after = ls.apply(t, Move(d[i, j], "2opt", int(i), int((j - i) % len(t))))
        assert problem.tour_cost(after) - before == pytest.approx(d[i, j], abs=1e-7 * before)
        checked += 1
    for (length, reverse), d in ls.or_opt_deltas(t).items():
        for i, p in zip(*np.nonzero(np.isfinite(d)), strict=True):
            after = ls.apply(t, Move(d[i, p], "oropt", int(i), length, int(p), reverse))
            assert sorted(problem.cluster_of[after]) == list(range(problem.n_clusters))
            assert problem.tour_cost(after) - before == pytest.approx(d[i, p], abs=1e-7 * before)
            checked += 1
    assert checked > 50


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("depot", [True, False])
def test_improve_never_worse_and_a_local_optimum(seed, depot):
    """From a random tour: feasible, no worse, no improving move left, never below the optimum."""
    inst, omega, optimum = tiny_case(seed, depot)
    problem = price(inst, omega)
    rng = np.random.default_rng(seed)
    start = _random_tour(problem, rng)
    tour, cost = improve(problem, start)
    assert cost == pytest.approx(problem.tour_cost(tour), rel=1e-12)
    assert cost <= problem.tour_cost(start) + 1e-9
    assert not_below(cost, optimum)
    problem.to_solution(tour)  # feasible, else it raises
    if depot:
        assert tour[0] == problem.depot
    assert LocalSearch(problem).best_move(tour) is None
    _, heads_cost = LocalSearch(problem).reoptimise_heads(tour)
    assert heads_cost >= cost - 1e-9


def test_improve_finds_most_tiny_optima():
    """Local optima of the three neighbourhoods are often global on tiny instances (never
    below the optimum)."""
    hits = 0
    for seed in range(12):
        inst, omega, optimum = tiny_case(seed)
        problem = price(inst, omega)
        _, cost = improve(problem, _random_tour(problem, np.random.default_rng(seed)))
        assert not_below(cost, optimum)
        hits += cost <= optimum + 1e-9 * optimum
    assert hits >= 8


def test_bad_tour_is_rejected():
    """A tour missing a cluster is refused with a clear error."""
    inst, omega, _ = tiny_case(0)
    problem = price(inst, omega)
    with pytest.raises(InfeasibleSolutionError, match="exactly one node of every cluster"):
        improve(problem, [problem.depot, 0])


def test_past_deadline_still_returns_a_tour():
    """With a deadline already past, the input (or better) comes back, flagged as timed out."""
    inst = generate_instance(12, 5, seed=3)
    problem = price(inst, 0.5)
    start = _random_tour(problem, np.random.default_rng(0))
    tour, cost, timed_out = LocalSearch(problem).run(start, deadline=0.0)
    assert timed_out and cost <= problem.tour_cost(start)
    problem.to_solution(tour)


def test_deadline_after_rejects_bad_limits():
    """A negative time limit is an InputError."""
    with pytest.raises(InputError, match="time limit"):
        deadline_after(-1.0)


@pytest.mark.parametrize("seed", range(4))
def test_greedy_ls_between_optimum_and_greedy(seed):
    """greedy+ls is feasible, never below the optimum and never above greedy."""
    inst, omega, optimum = tiny_case(seed)
    g = run_solver("greedy", inst, omega)
    gl = run_solver("greedy+ls", inst, omega)
    assert optimum - 1e-9 <= gl.objective <= g.objective + 1e-9
    assert gl.status == "feasible"


def test_greedy_ls_on_gtsplib():
    """On a .gtsp file (no depot) greedy+ls gives a valid tour no shorter than the optimum."""
    inst = read_instance(GTSPLIB / "11berlin52.gtsp.gz")
    r = run_solver("greedy+ls", inst, None)
    assert sorted(r.order) == list(range(11))
    assert r.objective >= 4040
    assert r.objective <= run_solver("greedy", inst, None).objective


def test_anchor_node():
    """Constructions start at the depot, else at the smallest cluster's first node."""
    inst, omega, _ = tiny_case(1, depot=False)
    problem = price(inst, omega)
    assert anchor_node(problem) == min(problem.clusters, key=len)[0]
    inst, omega, _ = tiny_case(1)
    assert anchor_node(price(inst, omega)) == price(inst, omega).depot


def test_greedy_ls_warm_start_and_reports():
    """greedy+ls improves a warm start instead of the greedy tour, reporting each better tour
    (objectives never rise, the first is the warm start's); a local optimum comes back as it
    is."""
    from gtsp_bench.registry import get_solver

    inst = generate_instance(15, 8, seed=8)
    problem = price(inst, 0.5)
    rng = np.random.default_rng(4)
    order, heads = problem.to_solution(_random_tour(problem, rng))
    r = run_solver(get_solver("greedy+ls"), inst, 0.5, initial=(order, heads))
    objectives = [p.objective for p in r.trajectory]
    assert objectives == sorted(objectives, reverse=True) and objectives[-1] == r.objective
    assert len(objectives) >= 2 and r.stats["warm_start"] is True
    assert r.trajectory[0].objective == pytest.approx(problem.tour_cost(problem.to_tour(order, heads)))
    again = run_solver("greedy+ls", inst, 0.5, initial=r)
    assert (again.order, again.heads) == (r.order, r.heads)

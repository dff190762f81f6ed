"""The textbook MILP in cvxpy: agrees with dp, reads only single tours, honest at a time limit."""

from __future__ import annotations

import numpy as np
import pytest
from gtsp_bench.solvers.exact.textbook import MilpTextbook, build, extract_tour, n_binaries

from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance
from gtsp_bench.instance import Instance
from gtsp_bench.problem import price
from gtsp_bench.registry import get_solver, run_solver
from tests.tiny_cases import not_below


@pytest.mark.parametrize("subtour", ["mtz", "flow", "dfj"])
@pytest.mark.parametrize(("k", "n", "seed", "omega"), [
    (1, 3, 0, 0.5), (2, 4, 1, 0.0), (4, 3, 2, 0.5), (5, 3, 3, 1.0), (6, 3, 4, 0.3),
])
def test_agrees_with_dp(subtour, k, n, seed, omega):
    """Proven optimum equal to dp's on small UAV instances, K = 1..6, both subtour forms."""
    inst = generate_instance(k, n, seed=seed)
    dp = run_solver("dp", inst, omega)
    r = run_solver(get_solver("milp-textbook", subtour=subtour, backend="highs"), inst, omega)
    assert r.status == "optimal"
    assert r.objective == pytest.approx(dp.objective, rel=1e-6)
    assert r.lower_bound <= r.objective
    assert r.lower_bound == pytest.approx(dp.objective, rel=1e-6)


@pytest.mark.parametrize("subtour", ["mtz", "flow", "dfj"])
def test_agrees_with_dp_on_a_distance_only_gtsp(subtour):
    """A GTSPLIB-like instance (no depot, integer EUC_2D weights, uneven clusters): dp's optimum."""
    rng = np.random.default_rng(7)
    inst = Instance(name="5tiny", params=None, edge_weight_type="EUC_2D",
                    clusters=tuple(rng.uniform(0, 100, size=(s, 2)) for s in (3, 1, 2, 3, 2)))
    dp = run_solver("dp", inst, None)
    r = run_solver(MilpTextbook(subtour=subtour, backend="highs"), inst, None)
    assert r.status == "optimal"
    assert r.objective == dp.objective
    assert sorted(r.order) == list(range(5))


def test_tiny_time_limit_is_reported_honestly():
    """At a tiny time limit: a valid status; a bound, when there is one, is below the optimum;
    when the model found no tour, the greedy tour is returned as such (status time_limit)."""
    inst = generate_instance(6, 8, seed=3)
    best = run_solver("dp", inst, 0.5).objective
    seen = set()
    for limit in (0.01, 0.5):
        r = run_solver(MilpTextbook(backend="highs"), inst, 0.5, time_limit=limit)
        assert r.status in ("optimal", "time_limit")
        assert r.objective >= best - 1e-6
        assert r.lower_bound is None or r.lower_bound <= best + 1e-6
        seen.add(r.stats["tour"])
        if r.stats["tour"] == "greedy":
            assert r.status == "time_limit" and "found no tour" in r.stats["note"]
            assert r.objective <= run_solver("greedy", inst, 0.5).objective + 1e-6
    assert "greedy" in seen  # 0.01 s is too short for HiGHS to find a tour


def test_extract_tour_reads_one_cycle_and_refuses_two():
    """Rounded values giving one cycle are the tour (root cluster first); two subtours, or
    values far from integral, are refused (None)."""
    inst = generate_instance(4, 2, seed=0)
    problem = price(inst, 0.5)
    tm = build(problem, "mtz", relax=True)  # same arcs; cvxpy takes any value in [0, 1]
    heads = [int(c[0]) for c in problem.clusters]  # node 0 of each cluster; the depot last

    def set_cycles(*cycles):
        arc = {(int(u), int(v)): i for i, (u, v) in enumerate(zip(tm.tail, tm.head, strict=True))}
        x = np.zeros(len(tm.tail))
        for cyc in cycles:
            for u, v in zip(cyc, cyc[1:] + cyc[:1], strict=True):
                x[arc[(u, v)]] = 1.0 - 1e-7
        y = np.zeros(problem.n_nodes)
        y[[v for cyc in cycles for v in cyc]] = 1.0
        tm.x.value, tm.y.value = x, y

    set_cycles(heads)
    tour = extract_tour(tm)
    assert tour is not None and tour[0] == problem.depot and sorted(tour) == sorted(heads)
    set_cycles(heads[:2], heads[2:])
    assert extract_tour(tm) is None
    set_cycles(heads)
    tm.x.value = np.where(tm.x.value > 0.5, 0.6, 0.0)
    assert extract_tour(tm) is None


@pytest.mark.parametrize(("options", "message"), [
    ({"subtour": "tsp"}, "subtour must be one of 'mtz', 'flow', 'dfj', got 'tsp'"),
    ({"backend": "cplex"}, "backend must be one of 'highs', 'gurobi', 'auto', got 'cplex'"),
    ({"max_binaries": 0}, "max_binaries must be"),
    ({"threads": True}, "threads must be"),
])
def test_bad_options_are_refused_in_one_line(options, message):
    with pytest.raises(InputError, match=message) as e:
        get_solver("milp-textbook", **options)
    assert "\n" not in str(e.value)


def test_refuses_a_model_above_max_binaries():
    """The refusal names the count and the limit, before building anything."""
    inst = generate_instance(5, 4, seed=0)
    need = n_binaries(price(inst, 0.5))
    assert need == build(price(inst, 0.5)).n_binaries
    with pytest.raises(InputError, match=rf"needs {need} binary variables, above its limit of 100"):
        run_solver(MilpTextbook(max_binaries=100), inst, 0.5)


def test_dfj_refuses_too_many_clusters():
    """subtour=dfj writes every set: refused beyond its cluster limit, in one line."""
    with pytest.raises(InputError, match=r"subtour=dfj .* at most 14 besides the root, .* has 15"):
        run_solver(MilpTextbook(subtour="dfj"), generate_instance(15, 1, seed=0), 0.5)


def test_gurobi_backend_when_installed():
    """gurobipy installed: a small model solves through Gurobi to dp's optimum; with the
    size-limited licence, a model above it is refused in one line."""
    pytest.importorskip("gurobipy")
    inst = generate_instance(4, 2, seed=1)
    r = run_solver(MilpTextbook(backend="gurobi"), inst, 0.5)
    assert r.stats["backend"] == "gurobi"
    assert r.status == "optimal"
    assert r.objective == pytest.approx(run_solver("dp", inst, 0.5).objective, rel=1e-6)
    big = generate_instance(4, 15, seed=1)
    try:
        r = run_solver(MilpTextbook(backend="gurobi"), big, 0.5, time_limit=0.5)
    except InputError as e:
        assert "size-limited licence" in str(e) and "\n" not in str(e)
        sol = MilpTextbook(backend="auto").solve(big, 0.5, time_limit=0.5)
        assert sol.stats["backend"] == "highs"
        assert sol.stats["gurobi"] == "size-limited licence refused the model"
    else:  # a full licence: the big model is solved by Gurobi, never below dp's optimum
        assert r.stats["backend"] == "gurobi" and r.status in ("optimal", "time_limit")
        assert not_below(r.objective, run_solver("dp", big, 0.5).objective)

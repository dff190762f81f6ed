"""The LKH peer: the Noon-Bean transformation, integer scaling, optima on small cases, GTSPLIB."""

from __future__ import annotations

import itertools
import json
import sys
import time

import numpy as np
import pytest
from gtsp_bench.solvers.peers import lkh as peer
from gtsp_bench.solvers.peers.lkh import noon_bean, scaled_weights, tour_from_atsp

from gtsp_bench.cli import main
from gtsp_bench.data import gtsplib
from gtsp_bench.errors import InputError, SolverError
from gtsp_bench.generator import generate_instance
from gtsp_bench.instance import Instance
from gtsp_bench.problem import price
from gtsp_bench.registry import get_solver, run_solver
from tests.tiny_cases import not_below, tiny_case

pytest.importorskip("elkai")


def test_noon_bean_by_hand():
    """Clusters {0, 1}, {2}, {3, 4}: cycle arcs cost 0, the arc for u -> v leaves pred(u) and
    costs w(u, v) + M, every other arc M; the ATSP optimum (all 4! tours) is the GTSP optimum."""
    clusters = (np.array([0, 1]), np.array([2]), np.array([3, 4]))
    rng = np.random.default_rng(3)
    w = rng.integers(1, 20, size=(5, 5))
    big_m = 1000
    a = noon_bean(w, clusters, big_m)
    assert a[0, 1] == a[1, 0] == a[3, 4] == a[4, 3] == a[2, 2] == 0  # the cycles
    assert a[1, 2] == w[0, 2] + big_m  # leaving 0 (pred(0) = 1) for 2
    assert a[0, 3] == w[1, 3] + big_m  # leaving 1 (pred(1) = 0) for 3
    assert a[2, 4] == w[2, 4] + big_m  # a one-node cluster is its own predecessor
    assert a[4, 0] == w[3, 0] + big_m
    assert a[0, 0] == a[4, 4] == big_m  # inside a cluster, off the cycle
    cluster_of = np.array([0, 0, 1, 2, 2])
    best = min(((0, *p) for p in itertools.permutations(range(1, 5))),
               key=lambda t: a[list(t), list(t[1:] + t[:1])].sum())
    atsp_cost = a[list(best), list(best[1:] + best[:1])].sum()
    tour, contiguous = tour_from_atsp(best, cluster_of)
    assert contiguous
    gtsp = {(x, 2, y): w[x, 2] + w[2, y] + w[y, x] for x in (0, 1) for y in (3, 4)}
    gtsp |= {(x, y, 2): w[x, y] + w[y, 2] + w[2, x] for x in (0, 1) for y in (3, 4)}
    cost = lambda t: sum(w[t[i], t[(i + 1) % 3]] for i in range(3))  # noqa: E731
    assert cost(tour) == min(gtsp.values())
    assert atsp_cost == 3 * big_m + min(gtsp.values())


def test_tour_from_atsp_flags_a_broken_tour():
    """A tour that enters a cluster twice is not contiguous; its clusters still come once each."""
    cluster_of = np.array([0, 0, 1, 1, 2])
    tour, contiguous = tour_from_atsp([0, 2, 1, 3, 4], cluster_of)
    assert not contiguous
    assert sorted(cluster_of[tour]) == [0, 1, 2]
    tour, contiguous = tour_from_atsp([3, 4, 1, 0, 2], cluster_of)  # starts inside a run
    assert contiguous and list(tour) == [4, 1, 2]


def test_whole_number_weights_are_used_as_they_are():
    """GTSPLIB weights are integers: shifted by the cheapest arc, not scaled; M fits the limit."""
    problem = price(gtsplib.read("11berlin52"), None)
    weights, big_m, scale = scaled_weights(problem)
    inter = problem.cluster_of[:, None] != problem.cluster_of[None, :]
    shift = problem.edge_cost[inter].min()
    assert scale == 1.0
    assert np.array_equal(weights[inter], (problem.edge_cost[inter] - shift).astype(np.int64))
    assert big_m + weights.max() <= peer.LIMIT


def test_scaled_weights_stay_within_the_limit():
    """Energy costs are scaled so that every transformed weight, M included, fits the limit."""
    problem = price(generate_instance(20, 5, seed=0), 0.5)
    weights, big_m, scale = scaled_weights(problem)
    matrix = noon_bean(weights, problem.clusters, big_m)
    assert scale != 1.0 and 0.9 * peer.LIMIT <= matrix.max() <= peer.LIMIT
    tour = problem.to_tour(tuple(range(20)), (0,) * 20)
    w = problem.edge_cost + problem.node_cost[:, None]
    exact = w[tour, np.roll(tour, -1)].sum()
    shift = min(w[u, v] for u in range(problem.n_nodes) for v in range(problem.n_nodes)
                if problem.cluster_of[u] != problem.cluster_of[v])
    assert weights[tour, np.roll(tour, -1)].sum() / scale == pytest.approx(exact - 21 * shift,
                                                                           rel=1e-4)


def test_scaling_refusal_is_one_line(monkeypatch):
    """Weights that cannot fit LKH's integer range with enough resolution are refused clearly."""
    inst = generate_instance(7, 4, seed=0)
    with pytest.raises(InputError, match="must stay below 500") as err:
        scaled_weights(price(inst, 0.5), limit=500)
    assert "\n" not in str(err.value)
    monkeypatch.setattr(peer, "LIMIT", 500)
    with pytest.raises(InputError, match="big-M included"):
        run_solver("lkh", inst, 0.5)


def test_costs_that_are_not_finite_are_refused():
    """Non-finite costs give one InputError line, never a tour."""
    far = Instance(name="far", clusters=(np.array([[0.0, 0.0]]), np.array([[1e308, -1e308]]),
                                         np.array([[1.0, 1.0]])),
                   params=None, edge_weight_type="EUC_2D")
    with np.errstate(over="ignore"):
        problem = price(far, None)
    with pytest.raises(InputError, match="not finite numbers"):
        scaled_weights(problem)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("depot", [True, False])
def test_tiny_instances_reach_the_optimum(seed, depot):
    """On tiny instances (several omegas) LKH's tour is never below brute force, and matches it."""
    inst, omega, optimum = tiny_case(seed, depot)
    r = run_solver("lkh", inst, omega, seed=seed)
    assert r.status == "feasible"
    assert r.objective >= optimum - 1e-9
    assert r.objective == pytest.approx(optimum, rel=1e-9)


@pytest.mark.parametrize("k", [1, 2])
def test_one_or_two_clusters(k):
    """Too small for LKH (it needs 3 nodes): enumerated, still the optimum."""
    inst = Instance(name="small", clusters=generate_instance(k, 1, seed=0).clusters)
    r = run_solver("lkh", inst, 0.5)
    assert r.stats["lkh"] is False
    assert r.objective == pytest.approx(run_solver("brute", inst, 0.5).objective, rel=1e-12)


def test_uav_instance_against_dp():
    """A generated K = 7 UAV instance: LKH reaches the DP optimum."""
    inst = generate_instance(7, 5, seed=2)
    for omega in (0.0, 0.5, 1.0):
        r = run_solver("lkh", inst, omega)
        optimum = run_solver("dp", inst, omega).objective
        assert not_below(r.objective, optimum)
        assert r.objective == pytest.approx(optimum, rel=1e-9)


@pytest.mark.parametrize("name", ["11berlin52", "20kroA100"])
def test_gtsplib_files(name):
    """GTSPLIB samples: a valid tour, priced exactly, at (11berlin52: exactly) the reference."""
    inst = gtsplib.read(name)
    ref = gtsplib.best_known()[name].value
    r = run_solver("lkh", inst, None)
    assert sorted(r.order) == list(range(inst.n_clusters))
    assert r.objective == price(inst, None).tour_cost(price(inst, None).to_tour(r.order, r.heads))
    assert ref <= r.objective <= 1.01 * ref
    if name == "11berlin52":
        assert r.objective == 4040


def test_broken_atsp_tour_is_repaired(monkeypatch):
    """If LKH's tour were not contiguous, the order it gives is kept, the heads re-chosen, and
    the solution says so; it is still a valid tour priced exactly."""
    inst = generate_instance(5, 3, seed=1)
    problem = price(inst, 0.5)
    scrambled = np.random.default_rng(2).permutation(problem.n_nodes)
    assert not tour_from_atsp(scrambled, problem.cluster_of)[1]

    class Fake:
        @staticmethod
        def solve_problem(params: str, text: str) -> list[int]:
            return [int(v) + 1 for v in scrambled]

    monkeypatch.setattr(peer, "_import_elkai", lambda: Fake)
    r = run_solver("lkh", inst, 0.5)
    assert r.stats["repaired"] is True
    tour = tour_from_atsp(scrambled, problem.cluster_of)[0]
    assert problem.depot not in (tour[0], tour[-1])  # in the middle: the order starts after it
    tour = np.roll(tour, -int(np.flatnonzero(tour == problem.depot)[0]))
    assert list(r.order) == [int(c) for c in problem.cluster_of[tour[1:]]]
    assert r.objective == pytest.approx(problem.tour_cost(problem.to_tour(r.order, r.heads)), rel=1e-12)


def test_seed_reproduces_and_options_reach_lkh(monkeypatch):
    """The same seed gives the same tour; runs, max_trials, seed and the time limit are passed."""
    inst = generate_instance(10, 5, seed=1)
    a = run_solver(get_solver("lkh", runs=2, max_trials=50), inst, 0.5, seed=3)
    b = run_solver(get_solver("lkh", runs=2, max_trials=50), inst, 0.5, seed=3)
    assert (a.order, a.heads) == (b.order, b.heads)
    params = get_solver("lkh", runs=2, max_trials=50, subgradient=False)._params(7.5, 3)
    assert {"RUNS = 2", "MAX_TRIALS = 50", "SEED = 4", "TIME_LIMIT = 3.750000",
            "SUBGRADIENT = NO"} <= set(params.splitlines())
    assert "SUBGRADIENT" not in get_solver("lkh")._params(1.0, 0)
    c = run_solver(get_solver("lkh", subgradient=False), inst, 0.5, seed=3)
    assert c.objective >= run_solver("milp", inst, 0.5).objective - 1e-6


def test_time_limit_status():
    """A limit shorter than LKH's preprocessing still gives a valid tour, status time_limit,
    never below milp's proven optimum."""
    inst = generate_instance(20, 20, seed=0)
    r = run_solver("lkh", inst, 0.5, time_limit=0.01)
    assert r.status == "time_limit"
    assert sorted(r.order) == list(range(20))
    optimum = run_solver("milp", inst, 0.5)
    assert optimum.status == "optimal" and not_below(r.objective, optimum.objective)


@pytest.mark.parametrize("warm", [False, True])
def test_no_tour_from_lkh_falls_back(monkeypatch, warm):
    """When the limit runs out before LKH's first tour (elkai returns none), the solver returns
    the warm start if given, else the greedy tour from the depot, says which, status time_limit."""
    inst = generate_instance(8, 4, seed=3)
    start = run_solver("lkh", inst, 0.5) if warm else None
    greedy = run_solver("greedy", inst, 0.5)

    class Fake:
        @staticmethod
        def solve_problem(params: str, text: str) -> list[int]:
            return []

    monkeypatch.setattr(peer, "_import_elkai", lambda: Fake)
    r = run_solver("lkh", inst, 0.5, time_limit=5.0, initial=start)
    assert r.status == "time_limit"
    assert r.stats["fallback"] == ("warm_start" if warm else "greedy")
    expected = start if warm else greedy
    assert (r.order, r.heads) == (expected.order, expected.heads)
    assert r.objective == pytest.approx(expected.objective, rel=1e-12)
    assert greedy.objective > run_solver("milp", inst, 0.5).objective  # the cases differ


def test_a_partial_tour_after_the_limit_falls_back(monkeypatch):
    """A tour that misses nodes once the limit is spent (LKH stopped mid-tour: seen with a 0.01 s
    limit on a loaded machine) is treated as no tour: the greedy fallback, status time_limit."""
    class Slow:
        @staticmethod
        def solve_problem(params: str, text: str) -> list[int]:
            time.sleep(0.05)
            return [1, 2, 3]

    monkeypatch.setattr(peer, "_import_elkai", lambda: Slow)
    inst = generate_instance(8, 4, seed=3)
    r = run_solver("lkh", inst, 0.5, time_limit=0.01)
    assert r.status == "time_limit" and r.stats["fallback"] == "greedy" and r.stats["lkh_partial"] == 3
    greedy = run_solver("greedy", inst, 0.5)
    assert (r.order, r.heads) == (greedy.order, greedy.heads)


def test_a_partial_tour_from_lkh_is_an_error(monkeypatch):
    """A tour that misses nodes within the limit (not the answer of a spent limit) is refused."""
    class Fake:
        @staticmethod
        def solve_problem(params: str, text: str) -> list[int]:
            return [1, 2, 3]

    monkeypatch.setattr(peer, "_import_elkai", lambda: Fake)
    with pytest.raises(SolverError, match="no tour through all nodes"):
        run_solver("lkh", generate_instance(8, 4, seed=3), 0.5)


@pytest.mark.parametrize("options", [{"runs": 0}, {"max_trials": 0}, {"runs": 1.5},
                                     {"subgradient": "no"}])
def test_bad_options_rejected(options):
    """Invalid options raise InputError."""
    with pytest.raises(InputError):
        get_solver("lkh", **options)


def test_missing_package_is_a_clear_error(monkeypatch):
    """Without elkai installed the solver raises a one-line InputError saying how to install it."""
    monkeypatch.setitem(sys.modules, "elkai", None)
    with pytest.raises(InputError) as err:
        run_solver("lkh", generate_instance(3, 3, seed=0), 0.5)
    assert str(err.value) == "lkh needs the optional package elkai: pip install 'gtsp-bench[lkh]'"


def test_cli_solve_json(tmp_path, capsys):
    """gtsp-bench solve FILE --solver lkh --json prints the DP optimum of a small instance."""
    path = tmp_path / "k5.json"
    assert main(["generate", "--clusters", "5", "--nodes", "4", "--seed", "3", "-o", str(path)]) == 0
    capsys.readouterr()
    assert main(["solve", str(path), "--solver", "lkh", "--omega", "0.4", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["solver"] == "lkh" and data["status"] == "feasible"
    assert sorted(data["order"]) == list(range(5))
    assert main(["solve", str(path), "--solver", "dp", "--omega", "0.4", "--json"]) == 0
    assert data["objective"] == pytest.approx(json.loads(capsys.readouterr().out)["objective"],
                                              rel=1e-9)


def test_atsp_tour_is_the_inverse_of_tour_from_atsp():
    """The Noon-Bean tour of a GTSP tour walks each cluster's cycle from its head and maps back
    to the same tour, contiguous."""
    from gtsp_bench.solvers.peers.lkh import atsp_tour

    problem = price(generate_instance(5, 4, seed=3), 0.5)
    tour = np.array([problem.n_nodes - 1, 6, 1, 13, 19, 9])  # the depot, then one head per cluster
    nodes = atsp_tour(tour, problem.clusters, problem.cluster_of)
    assert sorted(nodes.tolist()) == list(range(problem.n_nodes))
    back, contiguous = tour_from_atsp(nodes, problem.cluster_of)
    assert contiguous and back.tolist() == tour.tolist()


def test_lkh_starts_from_the_warm_start():
    """LKH reads the warm start as its initial tour: with one trial, the answer is no worse
    than the warm start (without it, one trial from LKH's own first tour is worse here)."""
    inst = gtsplib.read("40d198")
    first = run_solver("lns", inst, None, time_limit=1.0, seed=1)
    one = get_solver("lkh", max_trials=1)
    warm = run_solver(one, inst, None, seed=1, initial=first)
    assert warm.objective <= first.objective and warm.stats["warm_start"] is True
    assert run_solver(one, inst, None, seed=1).objective > first.objective

"""lns's edge costs from points: the same numbers as the matrix (compiled and plain Python), the
same search either way, and the matrix never built on the points path."""

from __future__ import annotations

import numpy as np
import pytest
from gtsp_bench.solvers.heuristics import lns_costs
from gtsp_bench.solvers.heuristics import lns_kernels as kernels
from gtsp_bench.solvers.heuristics.lns import Lns
from gtsp_bench.solvers.heuristics.lns_costs import cluster_arrays, ec, kernel_costs, points_of
from numba import njit

from gtsp_bench.errors import InputError
from gtsp_bench.instance import Instance
from gtsp_bench.problem import Problem, price


@njit(cache=False)
def _all_pairs(edge, m):
    out = np.empty((m, m))
    for a in range(m):
        for b in range(m):
            out[a, b] = ec(edge, a, b)
    return out


def _instance(rule: str, seed: int = 0, clusters: int = 12) -> Instance:
    rng = np.random.default_rng(seed)
    # half-integer coordinates: EUC_2D's ties at .5 and CEIL_2D's exact integers both occur
    pts = tuple(rng.integers(0, 600, (int(rng.integers(1, 5)), 2)) / 2.0 for _ in range(clusters))
    if rule == "uav":
        return Instance(name="uav", clusters=pts, depot=np.array([150.0, 0.0]))
    return Instance(name=rule, clusters=pts, params=None, edge_weight_type=rule)


@pytest.mark.parametrize("rule", ["uav", "EUCLIDEAN", "EUC_2D", "CEIL_2D"])
def test_points_give_the_matrix_exactly(rule):
    """Every pair, compiled and in plain Python, equals the priced matrix bit for bit (a UAV
    instance's factor and depot included); the matrix was not built to compute them."""
    omega = 0.3 if rule == "uav" else None
    problem = price(_instance(rule), omega)
    points = points_of(problem)
    assert points is not None
    m = problem.n_nodes
    compiled = _all_pairs(points, m)
    python = np.array([[ec(points, a, b) for b in range(m)] for a in range(m)])
    assert "edge_cost" not in problem.__dict__
    assert np.array_equal(compiled, problem.edge_cost)
    assert np.array_equal(python, problem.edge_cost)
    assert np.array_equal(_all_pairs(problem.edge_cost, m), problem.edge_cost)


def test_rules_without_points_use_the_matrix():
    """ATT, GEO and explicit weights have no points kind: the kernels get the matrix."""
    for rule in ("ATT", "GEO"):
        problem = price(_instance(rule), None)
        assert points_of(problem) is None
        assert isinstance(kernel_costs(problem, points=True), np.ndarray)
    weights = np.array([[0.0, 2.0, 3.0], [2.0, 0.0, 4.0], [3.0, 4.0, 0.0]])
    explicit = Instance(name="w", clusters=(np.zeros((1, 2)), np.zeros((2, 2))), params=None,
                        edge_weight_type="EXPLICIT", weights=weights)
    assert isinstance(kernel_costs(price(explicit, None), points=True), np.ndarray)


def test_the_default_kind_follows_the_size(monkeypatch):
    """Below ``POINTS_FROM`` nodes the matrix, from there the points."""
    problem = price(_instance("EUC_2D"), None)
    assert isinstance(kernel_costs(problem), np.ndarray)
    monkeypatch.setattr(lns_costs, "POINTS_FROM", problem.n_nodes)
    assert isinstance(kernel_costs(problem), tuple)


@pytest.mark.parametrize("rule", ["uav", "EUC_2D"])
def test_lns_searches_the_same_on_points_and_matrix(rule):
    """A seeded search that stops at convergence finds the same tour either way."""
    inst = _instance(rule, seed=4, clusters=30)
    omega = 0.5 if rule == "uav" else None
    runs = [Lns(points=kind, iterations=200, trials=2, stop_at_convergence=True).solve(inst, omega, seed=2)
            for kind in (False, True)]
    assert runs[0].objective == runs[1].objective
    assert (runs[0].order, runs[0].heads) == (runs[1].order, runs[1].heads)


def test_kernels_on_points_keep_the_tour_cost():
    """The local search on points returns the cost the matrix prices the tour at."""
    problem = price(_instance("CEIL_2D", seed=5, clusters=20), None)
    node, start, cluster_of = cluster_arrays(problem)
    points = points_of(problem)
    near = kernels.neighbours(points, start, 5)
    assert np.array_equal(near, kernels.neighbours(problem.edge_cost, start, 5))
    t = start[:-1].copy()
    cost = kernels.local_search(t, points, node, start, near, cluster_of, 1e-9,
                                np.ones(len(start) - 1, dtype=np.bool_), True)
    assert cost == pytest.approx(problem.tour_cost(t), abs=1e-9)


def test_points_setting_is_checked():
    """``points`` must be a bool or None."""
    with pytest.raises(InputError, match="points"):
        Lns(points="yes")


@pytest.mark.parametrize(("rule", "omega"), [("uav", 0.3), ("uav", 1.0), ("EUCLIDEAN", None),
                                             ("EUC_2D", None), ("CEIL_2D", None)])
def test_cluster_distances_on_points_equal_the_matrix(rule, omega):
    """The least edge between two clusters, found over squared distances and rounded once, is the
    matrix's least entry (a zero factor included), compiled and in plain Python."""
    problem = price(_instance(rule, seed=6, clusters=15), omega)
    start = np.array([c[0] for c in problem.clusters] + [problem.n_nodes], dtype=np.int64)
    points = points_of(problem)
    want = kernels.cluster_distances(problem.edge_cost, start)
    assert np.array_equal(kernels.cluster_distances(points, start), want)
    assert np.array_equal(kernels.cluster_distances.py_func(points, start), want)


def test_cluster_arrays_index_clusters_by_ranges():
    """Each node lies in ``start[c] .. start[c + 1]`` of its cluster, the costs are the problem's,
    and a problem whose clusters interleave their nodes is refused."""
    problem = price(_instance("EUC_2D", seed=2, clusters=6), None)
    node, start, cluster_of = cluster_arrays(problem)
    assert start[-1] == problem.n_nodes and len(start) == problem.n_clusters + 1
    for c, members in enumerate(problem.clusters):
        assert list(members) == list(range(start[c], start[c + 1]))
        assert (cluster_of[members] == c).all()
    assert np.array_equal(node, problem.node_cost) and node.dtype == np.float64
    mixed = Problem(problem.instance, None, np.zeros(4),
                    (np.array([0, 2]), np.array([1, 3])), None)
    backwards = Problem(problem.instance, None, np.zeros(4),
                        (np.array([2, 3]), np.array([0, 1])), None)
    for bad in (mixed, backwards):
        with pytest.raises(ValueError, match="numbered cluster by cluster"):
            cluster_arrays(bad)

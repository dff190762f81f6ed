"""The priced GTSP: its tour cost equals the evaluator, conversions round-trip."""

from __future__ import annotations

import numpy as np
import pytest

from gtsp_bench.data.io import read_instance
from gtsp_bench.energy import evaluate
from gtsp_bench.errors import InfeasibleSolutionError
from gtsp_bench.generator import generate_instance
from gtsp_bench.instance import Instance
from gtsp_bench.problem import price

from .conftest import GTSPLIB


@pytest.mark.parametrize("omega", [0.0, 0.3, 0.9, 1.0])
def test_tour_cost_equals_evaluator_on_random_solutions(omega):
    """Node + edge costs of the priced problem equal evaluate() on random tours."""
    inst = generate_instance(5, 7, seed=11)
    problem = price(inst, omega)
    rng = np.random.default_rng(0)
    for _ in range(20):
        order = rng.permutation(5).tolist()
        heads = rng.integers(0, 7, size=5).tolist()
        tour = problem.to_tour(order, heads)
        assert tour[0] == problem.depot
        assert problem.tour_cost(tour) == pytest.approx(
            evaluate(inst, omega, order, heads).objective, rel=1e-12)
        assert problem.to_solution(tour) == (tuple(order), tuple(heads))
        # Any rotation of the tour gives the same solution.
        assert problem.to_solution(np.roll(tour, 3)) == (tuple(order), tuple(heads))


def test_depot_is_its_own_cluster_with_zero_cost(tiny):
    """The depot is the last node, alone in the last cluster, and costs nothing."""
    problem = price(tiny, 0.5)
    assert problem.depot == 3
    assert problem.n_clusters == 3
    assert problem.clusters[-1].tolist() == [3]
    assert problem.node_cost[3] == 0.0
    assert problem.cluster_of.tolist() == [0, 1, 1, 2]


def test_gtsplib_problem_has_no_node_costs():
    """A GTSPLIB file prices to integer edge weights and zero node costs."""
    inst = read_instance(GTSPLIB / "11berlin52.gtsp.gz")
    problem = price(inst, None)
    assert problem.depot is None
    assert np.all(problem.node_cost == 0)
    assert np.all(problem.edge_cost == np.round(problem.edge_cost))


def test_to_solution_rejects_bad_tours(tiny):
    """A tour missing a cluster or naming a missing node is rejected."""
    problem = price(tiny, 0.5)
    with pytest.raises(InfeasibleSolutionError):
        problem.to_solution([3, 1, 2])  # two nodes of cluster 1, none of cluster 0
    with pytest.raises(InfeasibleSolutionError):
        problem.to_solution([3, 0, 9])


def test_asymmetric_problem_keeps_the_direction():
    """An asymmetric instance prices to an asymmetric edge_cost (row = from) with symmetric False;
    tour_cost follows the tour's direction, as the evaluator does."""
    w = np.array([[0.0, 1.0, 5.0], [7.0, 0.0, 2.0], [3.0, 11.0, 0.0]])
    inst = Instance(name="a", clusters=tuple(np.full((1, 2), np.nan) for _ in range(3)), params=None,
                    edge_weight_type="EXPLICIT", weights=w, symmetric=False)
    p = price(inst, None)
    assert not p.symmetric and np.array_equal(p.edge_cost, w)
    assert p.tour_cost([0, 1, 2]) == 6.0 == evaluate(inst, None, [0, 1, 2], [0, 0, 0]).objective
    assert p.tour_cost([0, 2, 1]) == 23.0 == evaluate(inst, None, [0, 2, 1], [0, 0, 0]).objective
    assert price(Instance(name="s", clusters=(np.zeros((2, 2)),), params=None,
                          edge_weight_type="EUC_2D"), None).symmetric


@pytest.mark.parametrize("rule", ["uav", "EUC_2D", "CEIL_2D", "ATT", "GEO"])
def test_edges_before_the_matrix_are_its_numbers(rule):
    """edge_row, edge_costs, edge_block and tour_cost give the matrix's numbers before it is built
    (from the coordinates on planar rules, without building it; from the matrix on the others)."""
    rng = np.random.default_rng(7)
    if rule == "uav":
        inst, omega = generate_instance(6, 5, seed=3), 0.4
    else:
        clusters = tuple(rng.integers(0, 3000, (3, 2)) / 2.0 for _ in range(6))
        inst, omega = Instance(name=rule, clusters=clusters, params=None, edge_weight_type=rule), None
    problem = price(inst, omega)
    m = problem.n_nodes
    rows = np.array([problem.edge_row(i) for i in range(m)])
    tails, heads = rng.integers(0, m, 50), rng.integers(0, m, 50)
    pairs = problem.edge_costs(tails, heads)
    tour = np.array([c[0] for c in problem.clusters])
    before = problem.tour_cost(tour)
    some = rng.permutation(m)[:9]
    block = problem.edge_block(some)
    assert ("edge_cost" in problem.__dict__) == (rule in ("ATT", "GEO"))
    assert np.array_equal(rows, problem.edge_cost)
    assert np.array_equal(pairs, problem.edge_cost[tails, heads])
    assert before == problem.tour_cost(tour)
    assert np.array_equal(block, problem.edge_cost[np.ix_(some, some)])

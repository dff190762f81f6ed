"""One run per depot candidate: the base station alone, else each node of the smallest cluster;
the time left shared equally, the cheapest tour kept, a tour owed even when no run fits."""

from __future__ import annotations

import time

import numpy as np
from gtsp_bench.solvers.heuristics.greedy import greedy_tour
from gtsp_bench.solvers.peers.depots import best_of_runs, depot_candidates, run_nodes

from gtsp_bench.data.gtsplib import read
from gtsp_bench.generator import generate_instance
from gtsp_bench.instance import Instance
from gtsp_bench.problem import price


def test_candidates_are_the_base_station_or_the_smallest_cluster():
    """A UAV instance: its base station; 11berlin52: the nodes of its smallest cluster."""
    uav = price(generate_instance(4, 3, seed=1), 0.5)
    assert depot_candidates(uav) == [uav.depot]
    lib = price(read("11berlin52"), None)
    smallest = min(lib.clusters, key=len)
    assert depot_candidates(lib) == [int(v) for v in smallest] and len(smallest) < 52


def test_best_tour_kept_and_time_shared():
    """Each run gets its share of what is left; the cheapest of the runs' tours is returned with
    its exact cost, and the counts add up."""
    problem = price(read("11berlin52"), None)
    depots = depot_candidates(problem)
    first = greedy_tour(problem, depots[0])
    other = first.copy()
    other[[1, 2]] = other[[2, 1]]
    tour, worse = sorted((first, other), key=problem.tour_cost)
    assert problem.tour_cost(tour) < problem.tour_cost(worse)
    budgets = []

    def run(depot, budget):
        budgets.append(budget)
        return (tour if depot == depots[-1] else worse), 2, False

    best, cost, timed_out, count = best_of_runs(problem, depots, 60.0, time.perf_counter(), run, 1e-3)
    assert np.array_equal(best, tour) and cost == problem.tour_cost(tour) and not timed_out
    assert count == 2 * len(depots) and len(budgets) == len(depots)
    assert 60.0 / len(depots) * 0.99 <= budgets[0] <= 60.0 / len(depots)


def test_a_tour_is_owed_when_no_run_fits():
    """A limit already spent: no share is left, one short run still gives a tour, timed out."""
    problem = price(generate_instance(4, 3, seed=1), 0.5)
    calls = []

    def run(depot, budget):
        calls.append(budget)
        return greedy_tour(problem, problem.depot), 1, True

    best, cost, timed_out, _ = best_of_runs(problem, depot_candidates(problem), 1e-9,
                                            time.perf_counter() - 1.0, run, 1e-3)
    assert calls == [1e-3] and timed_out and cost == problem.tour_cost(best)


def test_run_nodes_put_the_depot_first_then_the_other_clusters():
    """From a node of 11berlin52's smallest cluster: that node, then every node of the other
    clusters in cluster order, and those clusters; a one-cluster instance has no others."""
    problem = price(read("11berlin52"), None)
    depot = depot_candidates(problem)[0]
    nodes, others = run_nodes(problem, depot)
    home = int(problem.cluster_of[depot])
    assert others == [c for c in range(problem.n_clusters) if c != home]
    assert nodes[0] == depot and nodes[1:].tolist() == np.concatenate(
        [problem.clusters[c] for c in others]).tolist()
    single = price(Instance(name="one", clusters=(np.array([[0.0, 0.0], [3.0, 4.0]]),), depot=None), 0.5)
    nodes, others = run_nodes(single, 1)
    assert others == [] and nodes.tolist() == [1]

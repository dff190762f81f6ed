"""The compiled lns kernels: feasible tours, costs that never rise, re-opt = the shared DP, and the
compiled code giving the same answers as the same code run as Python."""

from __future__ import annotations

import numpy as np
import pytest
from gtsp_bench.solvers.heads import optimal_heads
from gtsp_bench.solvers.heuristics import lns_kernels as kernels

from gtsp_bench.generator import generate_instance
from gtsp_bench.instance import Instance
from gtsp_bench.problem import price


def _problem(k: int, size: int, seed: int, depot: bool = True):
    base = generate_instance(k, size, seed=seed)
    inst = base if depot else Instance(name="nd", clusters=base.clusters)
    p = price(inst, 0.5)
    start = np.array([c[0] for c in p.clusters] + [p.n_nodes], dtype=np.int64)
    cluster_of = np.ascontiguousarray(p.cluster_of, dtype=np.int64)
    return p, start, cluster_of


def _random_tour(p, rng) -> np.ndarray:
    order = rng.permutation(p.n_clusters)
    return np.array([int(rng.choice(p.clusters[c])) for c in order], dtype=np.int64)


def _feasible(p, t) -> bool:
    return len(t) == p.n_clusters and len(set(p.cluster_of[t].tolist())) == p.n_clusters


@pytest.mark.parametrize("seed", range(3))
def test_local_search_never_worse_and_feasible(seed):
    """From random tours, the local search keeps one node per cluster and never raises the cost;
    its returned cost is the tour's cost."""
    p, start, cluster_of = _problem(14, 5, seed)
    near = kernels.neighbours(p.edge_cost, start, 5)
    rng = np.random.default_rng(seed)
    for _ in range(5):
        t = _random_tour(p, rng)
        before = p.tour_cost(t)
        awake = np.ones(p.n_clusters, dtype=bool)
        cost = kernels.local_search(t, p.edge_cost, p.node_cost, start, near, cluster_of, 1e-9, awake, True)
        assert _feasible(p, t)
        assert cost == pytest.approx(p.tour_cost(t), rel=1e-12)
        assert cost <= before + 1e-9


@pytest.mark.parametrize("depot", [True, False])
def test_reopt_matches_optimal_heads(depot):
    """Re-opt gives the cost of the shared layered shortest path for the same order."""
    p, start, cluster_of = _problem(9, 4, 1, depot)
    rng = np.random.default_rng(0)
    for _ in range(4):
        t = _random_tour(p, rng)
        cost = kernels.reopt(t, p.edge_cost, p.node_cost, start, cluster_of)
        if p.depot is not None:
            t0 = np.roll(t, -int(np.flatnonzero(t == p.depot)[0]))
            order = p.cluster_of[t0[1:]]
        else:
            order = p.cluster_of[t]
        assert cost == pytest.approx(optimal_heads(p, order)[1], rel=1e-12)
        assert cost == pytest.approx(p.tour_cost(t), rel=1e-12)


@pytest.mark.parametrize("how", range(len(kernels.INSERTIONS)))
def test_remove_then_insert_is_a_tour(how):
    """Every removal with every insertion gives back one node per cluster."""
    p, start, cluster_of = _problem(12, 4, 2)
    near = kernels.neighbours(p.edge_cost, start, 2)  # 4 * 2 < 12: the neighbour edges are used
    t = _random_tour(p, np.random.default_rng(1))
    kernels.seed(3)
    for removal in range(len(kernels.REMOVALS)):
        drop = kernels.remove(t, 5, removal, p.edge_cost, p.node_cost)
        assert drop.sum() == 5
        new = kernels.insert(t[~drop], cluster_of[t[drop]], how, 0.5, p.edge_cost, p.node_cost, start,
                             near, cluster_of)
        assert _feasible(p, new)


def test_neighbours_are_nearest_first():
    """Each cluster's neighbour list excludes itself and is sorted by cluster distance."""
    p, start, _ = _problem(10, 3, 4)
    near = kernels.neighbours(p.edge_cost, start, 4)
    assert near.shape == (p.n_clusters, 4)
    for c in range(p.n_clusters):
        assert c not in near[c]
        d = [p.edge_cost[np.ix_(p.clusters[c], p.clusters[o])].min() for o in near[c]]
        assert d == sorted(d)
        others = [p.edge_cost[np.ix_(p.clusters[c], p.clusters[o])].min()
                  for o in range(p.n_clusters) if o != c and o not in near[c]]
        assert max(d) <= min(others)


def test_compiled_equals_python():
    """The deterministic kernels give identical answers compiled and as plain Python (the code
    that ``NUMBA_DISABLE_JIT=1`` runs)."""
    p, start, cluster_of = _problem(11, 4, 5)
    near = kernels.neighbours(p.edge_cost, start, 4)
    t = _random_tour(p, np.random.default_rng(2))
    pos = np.empty(len(t), dtype=np.int64)
    a, b = t.copy(), t.copy()
    pos[cluster_of[a]] = np.arange(len(a))
    active = np.ones((2, len(t)), dtype=bool)
    kernels.two_opt(a, pos.copy(), p.edge_cost, near, cluster_of, 1e-9, active.copy())
    kernels.two_opt.py_func(b, pos.copy(), p.edge_cost, near, cluster_of, 1e-9, active.copy())
    assert np.array_equal(a, b)
    ca = kernels.reopt(a, p.edge_cost, p.node_cost, start, cluster_of)
    cb = kernels.reopt.py_func(b, p.edge_cost, p.node_cost, start, cluster_of)
    assert ca == cb and np.array_equal(a, b)
    clusters = cluster_of[t[:4]]
    ia = kernels.insert(t[4:], clusters, 0, 0.0, p.edge_cost, p.node_cost, start, near, cluster_of)
    ib = kernels.insert.py_func(t[4:], clusters, 0, 0.0, p.edge_cost, p.node_cost, start, near, cluster_of)
    assert np.array_equal(ia, ib)


def _asymmetric_problem(k: int, seed: int):
    """Arrays of a distance-only asymmetric GTSP: K clusters of 1 to 3 nodes, arcs drawn apart."""
    rng = np.random.default_rng([seed, 5])
    sizes = rng.integers(1, 4, size=k)
    start = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    m = int(start[-1])
    edge = rng.uniform(1.0, 100.0, size=(m, m))
    np.fill_diagonal(edge, 0.0)
    cluster_of = np.repeat(np.arange(k), sizes).astype(np.int64)
    return edge, np.zeros(m), start, cluster_of


def _directed_cost(t, edge):
    return float(sum(edge[t[i], t[(i + 1) % len(t)]] for i in range(len(t))))


@pytest.mark.parametrize("seed", range(3))
def test_asymmetric_local_search_prices_each_arc_in_its_direction(seed):
    """Directed costs: the local search (no 2-opt) never raises the directed cost, returns it, and
    leaves a tour that no single move of a cluster (any place, any head), re-opt or or-opt move
    of a run of 2-3 clusters improves."""
    k = 12
    edge, node, start, cluster_of = _asymmetric_problem(k, seed)
    near = kernels.neighbours(edge, start, k - 1)
    rng = np.random.default_rng(seed)
    t = np.array([rng.integers(start[c], start[c + 1]) for c in rng.permutation(k)], dtype=np.int64)
    before = _directed_cost(t, edge)
    cost = kernels.local_search(t, edge, node, start, near, cluster_of, 1e-9, np.ones(k, dtype=bool), False)
    assert len(set(cluster_of[t].tolist())) == k
    assert cost == pytest.approx(_directed_cost(t, edge), rel=1e-12) and cost <= before + 1e-9
    for i in range(k):  # every single-cluster move, priced from scratch
        rest = np.delete(t, i)
        c = cluster_of[t[i]]
        for j in range(k - 1):
            for v in range(start[c], start[c + 1]):
                assert _directed_cost(np.insert(rest, j + 1, v), edge) >= cost - 1e-9
    assert kernels.reopt(t.copy(), edge, node, start, cluster_of) >= cost - 1e-9
    for length in (2, 3):  # every or-opt move of a run, direction kept, priced from scratch
        for i in range(k):
            rolled = np.roll(t, -i)
            run, rest = rolled[:length], rolled[length:]
            for j in range(len(rest)):
                moved = np.concatenate([rest[:j + 1], run, rest[j + 1:]])
                assert _directed_cost(moved, edge) >= cost - 1e-9


def test_asymmetric_insertion_takes_the_cheapest_directed_place():
    """One cluster inserted: at the place and head of least c[a, v] + c[v, b] - c[a, b], in
    direction (its reverse would be priced otherwise)."""
    k = 9
    edge, node, start, cluster_of = _asymmetric_problem(k, 1)
    near = kernels.neighbours(edge, start, k - 1)
    t = start[:-1].copy()
    c = 4
    partial = np.delete(t, c)
    new = kernels.insert(partial, np.array([c]), 0, 0.0, edge, node, start, near, cluster_of)
    best = min(_directed_cost(np.insert(partial, j + 1, v), edge)
               for j in range(k - 1) for v in range(start[c], start[c + 1]))
    assert _directed_cost(new, edge) == pytest.approx(best, rel=1e-12)


def test_cluster_distances_are_least_arcs():
    """Entry (c, d) is the least arc from a node of cluster c to a node of cluster d (directed)."""
    edge, _, start, _ = _asymmetric_problem(7, 2)
    dist = kernels.cluster_distances(edge, start)
    for c in range(7):
        for d in range(7):
            assert dist[c, d] == edge[start[c]:start[c + 1], start[d]:start[d + 1]].min()


@pytest.mark.parametrize("seed", range(3))
def test_or_opt_never_worse_and_feasible(seed):
    """Or-opt alone on random tours: one node per cluster, heads kept, the cost only falls, and
    it does fall on some of them."""
    p, start, cluster_of = _problem(15, 3, seed)
    near = kernels.neighbours(p.edge_cost, start, 6)
    rng = np.random.default_rng(seed)
    gained = 0
    for _ in range(4):
        t = _random_tour(p, rng)
        pos = np.empty(len(t), dtype=np.int64)
        pos[cluster_of[t]] = np.arange(len(t))
        before, heads = p.tour_cost(t), set(t.tolist())
        moved = kernels.or_opt(t, pos, p.edge_cost, near, cluster_of, 1e-9, np.ones((3, len(t)), dtype=bool))
        assert _feasible(p, t) and set(t.tolist()) == heads
        assert np.array_equal(pos[cluster_of[t]], np.arange(len(t)))
        assert p.tour_cost(t) <= before + 1e-9
        assert moved == (p.tour_cost(t) < before - 1e-9)
        gained += moved
    assert gained > 0

"""The compiled lns kernels: removals and insertions giving tours, directed insertion prices,
neighbour lists, and the compiled code giving the same answers as the same code run as Python."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
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


@pytest.mark.parametrize("plateau", [False, True])
def test_run_trial_plateau_moves(plateau):
    """On costs that are all zero, every new tour costs what the current one does: at temperature
    0 it replaces the current tour only with ``plateau`` (noisy insertions make new orders)."""
    p, start, cluster_of = _problem(9, 3, 5)
    edge, node = np.zeros_like(p.edge_cost), np.zeros(p.n_nodes)
    near = kernels.neighbours(edge, start, p.n_clusters - 1)
    t = _random_tour(p, np.random.default_rng(2))
    cur, best, trial_best = t.copy(), t.copy(), t.copy()
    costs = np.zeros(3)
    counts = np.zeros(4, dtype=np.int64)
    weights_r, weights_i = np.ones(len(kernels.REMOVALS)), np.ones(len(kernels.INSERTIONS))
    settings = kernels.trial_settings(50, 50, 0.0, 0.0, 4, 1.0, 0.1, 0, plateau)
    assert settings[8] == float(plateau)
    kernels.seed(7)
    seen = set()
    for _ in range(50):
        kernels.run_trial(cur, best, trial_best, costs, counts, weights_r, weights_i, settings, 1,
                          edge, node, start, near, cluster_of, True)
        assert _feasible(p, cur)
        seen.add(tuple(cur.tolist()))
    assert (len(seen) > 1) == plateau
    assert np.array_equal(best, t) and np.array_equal(trial_best, t)  # no better tour exists


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


def test_kth_value_is_numpys_partition():
    """The selection behind the partial sort gives ``np.partition(row, k)[k]`` for every rank,
    on rows of many ties, with infinite entries, sorted, reversed and of one value."""
    rng = np.random.default_rng(8)
    rows = [rng.integers(0, 4, 40).astype(np.float64), rng.random(57), np.arange(30.0),
            np.arange(30.0)[::-1].copy(), np.full(9, 2.5), np.array([3.0])]
    rows[0][[3, 17]] = np.inf
    for row in rows:
        for k in range(len(row)):
            assert kernels._kth_value(row, k) == np.partition(row, k)[k], (row, k)


def test_nearest_first_is_the_start_of_a_stable_argsort():
    """The partial sort behind the quadrant lists gives the first entries of a full stable sort,
    ties (common with rounded distances) in index order, an infinite entry included."""
    rng = np.random.default_rng(5)
    for size, at_least in ((30, 5), (200, 12), (7, 7), (7, 10)):
        row = rng.integers(0, 6, size).astype(np.float64)
        row[size // 2] = np.inf
        got = kernels._nearest_first(row, at_least)
        full = np.argsort(row, kind="mergesort")
        assert len(got) >= min(at_least, size)
        assert np.array_equal(got, full[:len(got)])


@pytest.mark.parametrize("seed", range(3))
def test_quadrant_neighbours_hold_the_nearest_of_each_quadrant(seed):
    """Each list excludes its cluster, has no repeat, is sorted by cluster distance, and holds
    the nearest ``count // 4`` clusters of every quadrant around the cluster's centre; the other
    places go to the nearest of the rest."""
    p, start, _ = _problem(40, 3, seed)
    k, count = p.n_clusters, 8
    centre = np.array([p.instance.coords[c[0]] if c[0] < len(p.instance.coords) else p.instance.depot
                       for c in p.clusters])  # any point per cluster will do for the test
    near = kernels.neighbours(p.edge_cost, start, count, centre)
    dist = np.array([[p.edge_cost[np.ix_(p.clusters[c], p.clusters[o])].min() for o in range(k)]
                     for c in range(k)])
    for c in range(k):
        row = near[c].tolist()
        assert c not in row and len(set(row)) == count
        assert [dist[c, o] for o in row] == sorted(dist[c, o] for o in row)
        quadrant = [2 * int(centre[o, 0] >= centre[c, 0]) + int(centre[o, 1] >= centre[c, 1])
                    for o in range(k)]
        by_quadrant = set()
        for q in range(4):
            members = sorted((o for o in range(k) if o != c and quadrant[o] == q), key=lambda o: dist[c, o])
            by_quadrant |= set(members[:count // 4])
        assert by_quadrant <= set(row)
        rest = [o for o in row if o not in by_quadrant]
        left = [o for o in range(k) if o != c and o not in row]
        if rest:
            assert max(dist[c, o] for o in rest) <= min(dist[c, o] for o in left)


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


_MISSES = """
from numba.core.registry import CPUDispatcher
from gtsp_bench.solvers.heuristics import lns_costs, lns_kernels, lns_local, lns_window
lns_kernels.warm_up()
print(sorted(f"{m.__name__}.{n}" for m in (lns_costs, lns_kernels, lns_local, lns_window)
             for n, v in vars(m).items()
             if isinstance(v, CPUDispatcher) and sum(v.stats.cache_misses.values())))
"""


def test_a_second_process_loads_every_kernel_from_the_cache():
    """After one process's warm-up has compiled (or loaded) the kernels, another process's
    warm-up compiles none of them: every signature it uses is found in numba's cache (a default
    ``nan`` argument once made ``iterate`` miss, and compile, in every process)."""
    run = [sys.executable, "-c", _MISSES]
    subprocess.run(run, check=True, capture_output=True, text=True, timeout=600)
    second = subprocess.run(run, check=True, capture_output=True, text=True, timeout=600)
    assert second.stdout.strip().splitlines()[-1] == "[]"


def test_regional_tour_replans_the_region_of_the_far_cluster():
    """A cluster far from the rest has the largest removal saving whatever the random factor: the
    regional tour takes it and the ``k - 1`` clusters whose heads are nearest it out and puts them
    back, so every other cluster keeps its place in the cyclic order, and the result is a tour."""
    p, start, cluster_of = _problem(16, 3, 6)
    edge = p.edge_cost.copy()
    far = 5  # every edge into or out of its nodes ten times as dear
    nodes = np.arange(start[far], start[far + 1])
    edge[nodes, :] *= 10.0
    edge[:, nodes] *= 10.0
    near = kernels.neighbours(edge, start, 4)
    t = _random_tour(p, np.random.default_rng(4))
    k = 6
    centre = int(np.flatnonzero(cluster_of[t] == far)[0])
    dist = np.minimum(edge[t[centre], t], edge[t, t[centre]])
    dist[centre] = -1.0
    dropped = set(cluster_of[t[np.argsort(dist, kind="mergesort")[:k]]].tolist())
    assert far in dropped and len(dropped) == k
    for s in range(5):
        kernels.seed(s)
        new = kernels.regional_tour(t, k, edge, p.node_cost, start, near, cluster_of, True)
        assert _feasible(p, new)
        kept = [c for c in cluster_of[t].tolist() if c not in dropped]
        order = [c for c in cluster_of[new].tolist() if c not in dropped]
        i = order.index(kept[0])
        assert order[i:] + order[:i] == kept  # the same cycle, the same direction
        kept_heads = {int(v) for v in t if cluster_of[v] not in dropped}
        assert kept_heads <= set(new.tolist())  # and their heads


def test_regional_tour_bounds_its_removals():
    """Any ``k`` (0, or more than the cycle holds) still gives a tour."""
    p, start, cluster_of = _problem(8, 3, 1)
    near = kernels.neighbours(p.edge_cost, start, 3)
    t = _random_tour(p, np.random.default_rng(0))
    kernels.seed(1)
    for k in (0, 1, 7, 8, 50):
        assert _feasible(p, kernels.regional_tour(t, k, p.edge_cost, p.node_cost, start, near,
                                                  cluster_of, True))

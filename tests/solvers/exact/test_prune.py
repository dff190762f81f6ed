"""Pair-dominance pruning: never removes every optimal tour, and it does prune."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from gtsp_bench.solvers.exact.prune import prune_heads

from gtsp_bench.generator import generate_instance
from gtsp_bench.instance import Instance
from gtsp_bench.problem import Problem, price
from gtsp_bench.registry import run_solver


def best_over(problem: Problem, kept: tuple[np.ndarray, ...]) -> float:
    """The cheapest tour using only ``kept`` nodes (plain enumeration)."""
    best = np.inf
    for heads in itertools.product(*kept):
        for perm in itertools.permutations(range(1, len(kept))):
            best = min(best, problem.tour_cost([heads[0], *(heads[p] for p in perm)]))
    return best


def _instance(seed: int, depot: bool, grid: bool) -> tuple[Instance, float | None]:
    """K = 2..5 clusters of 1..4 nodes; ``grid``: integer EUC_2D points on a small grid (ties)."""
    rng = np.random.default_rng(seed)
    k = int(rng.integers(2, 6))
    sizes = rng.integers(1, 5, size=k)
    if grid:
        clusters = tuple(rng.integers(0, 6, size=(s, 2)).astype(float) for s in sizes)
        return Instance(name=f"grid{seed}", clusters=clusters, params=None,
                        edge_weight_type="EUC_2D"), None
    base = generate_instance(k, 4, seed=seed)
    inst = Instance(name=f"uav{seed}", depot=base.depot if depot else None,
                    clusters=tuple(c[:s] for c, s in zip(base.clusters, sizes, strict=True)))
    return inst, float(rng.choice([0.0, 1.0, rng.uniform()]))


@pytest.mark.parametrize("seed", range(10))
@pytest.mark.parametrize("kind", ["depot", "no-depot", "grid"])
def test_pruning_keeps_an_optimal_tour(seed, kind):
    """The best tour over the kept nodes is the brute-force optimum (ties included)."""
    inst, omega = _instance(seed, kind == "depot", kind == "grid")
    problem = price(inst, omega)
    kept = prune_heads(problem)
    assert all(len(k) >= 1 for k in kept)
    assert all(set(k) <= set(c) for k, c in zip(kept, problem.clusters, strict=True))
    optimum = run_solver("brute", inst, omega).objective
    assert best_over(problem, kept) == pytest.approx(optimum, rel=1e-12, abs=1e-9)


def test_pruning_removes_dominated_heads_and_more_passes_prune_more():
    """On a K = 8, N = 20 instance it removes nodes; one pass keeps a superset of the fixpoint."""
    problem = price(generate_instance(8, 20, seed=3), 0.5)
    full = prune_heads(problem)
    once = prune_heads(problem, max_passes=1)
    assert sum(len(k) for k in full) < problem.n_nodes - 1
    assert all(set(f) <= set(o) for f, o in zip(full, once, strict=True))
    assert len(full[-1]) == 1 and full[-1][0] == problem.depot


def test_two_clusters_are_not_pruned():
    """With fewer than three clusters a head's two neighbours are one node: nothing is pruned."""
    inst = Instance(name="two", clusters=(np.array([[0.0, 0.0], [1.0, 0.0]]),
                                          np.array([[5.0, 0.0], [9.0, 0.0]])), params=None)
    problem = price(inst, None)
    assert [len(k) for k in prune_heads(problem)] == [2, 2]


def test_past_deadline_stops_early_and_keeps_everything():
    """With its deadline already past it prunes nothing (which is still exact)."""
    problem = price(generate_instance(5, 6, seed=1), 0.5)
    kept = prune_heads(problem, deadline=0.0)
    assert [len(k) for k in kept] == [len(c) for c in problem.clusters]


def _first_cheapest(node: np.ndarray, to_neigh: np.ndarray, cluster: np.ndarray) -> dict:
    """The first cheapest row for every neighbour pair ``a < b`` of two clusters (plain argmin)."""
    return {(a, b): int(np.argmin(node + to_neigh[:, a] + to_neigh[:, b]))
            for a in range(len(cluster)) for b in range(a + 1, len(cluster)) if cluster[a] != cluster[b]}


@pytest.mark.parametrize("seed", range(6))
def test_witness_kernel_matches_a_plain_argmin(seed):
    """The compiled kernel gives each row a pair it is the first cheapest head for, finds one for
    every row that has one when all are pending, and stops once the pending rows have theirs
    (integer costs: many ties)."""
    from gtsp_bench.solvers.exact.prune import _witness_kernel

    rng = np.random.default_rng(seed)
    n, a_count = int(rng.integers(1, 8)), int(rng.integers(2, 30))
    to_neigh = rng.integers(0, 5, (n, a_count)).astype(float)
    node = rng.integers(0, 3, n).astype(float)
    cluster = np.sort(rng.integers(0, 4, a_count))
    best = _first_cheapest(node, to_neigh, cluster)
    expected = np.zeros(n, dtype=bool)
    expected[list(best.values())] = True
    for pending in (np.ones(n, dtype=bool), rng.random(n) < 0.5):
        witness = _witness_kernel(to_neigh, node, cluster, pending)
        found = witness[:, 0] >= 0
        assert np.all(found <= expected)
        np.testing.assert_array_equal(found[pending], expected[pending])
        for v in np.flatnonzero(found):
            assert best[(int(witness[v, 0]), int(witness[v, 1]))] == v
        if pending.all():
            np.testing.assert_array_equal(found, expected)


def _full_scan_prune(problem: Problem) -> list[np.ndarray]:
    """Pruning by a full scan of every cluster in every pass (plain argmins), to the fixpoint."""
    kept = [np.asarray(c) for c in problem.clusters]
    changed = True
    while changed:
        changed = False
        for c in range(len(kept)):
            others = [j for j in range(len(kept)) if j != c]
            neigh = np.concatenate([kept[j] for j in others])
            cluster = np.repeat(others, [len(kept[j]) for j in others])
            to_neigh = problem.edge_cost[np.ix_(kept[c], neigh)]
            keep = np.zeros(len(kept[c]), dtype=bool)
            keep[list(_first_cheapest(problem.node_cost[kept[c]], to_neigh, cluster).values())] = True
            if not keep.all():
                kept[c], changed = kept[c][keep], True
    return kept


@pytest.mark.parametrize("seed", range(4))
def test_pruning_by_witnesses_keeps_what_full_scans_keep(seed):
    """Re-scanning only the clusters whose nodes lost their witness pair keeps exactly the nodes
    that full scans of every cluster in every pass keep (K = 6-9 clusters of 2-6 nodes, with and
    without a depot, ties on a small integer grid)."""
    rng = np.random.default_rng(seed)
    k = int(rng.integers(6, 10))
    if seed % 2:
        clusters = tuple(rng.integers(0, 5, size=(int(s), 2)).astype(float) for s in rng.integers(2, 7, k))
        problem = price(Instance(name=f"grid{seed}", clusters=clusters, params=None,
                                 edge_weight_type="EUC_2D"), None)
    else:
        problem = price(generate_instance(k, 6, seed=seed), float(rng.uniform()))
    kept = prune_heads(problem)
    expected = _full_scan_prune(problem)
    assert [k.tolist() for k in kept] == [e.tolist() for e in expected]
    assert sum(len(e) for e in expected) < problem.n_nodes  # some node was pruned

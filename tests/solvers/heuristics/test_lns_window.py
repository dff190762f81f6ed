"""The windowed re-opt of lns (compiled): a window's heads are the best for the heads kept around
it, marked windows only, and the windowed local search keeps tours valid and never dearer."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from gtsp_bench.solvers.heuristics import lns_kernels as kernels
from gtsp_bench.solvers.heuristics import lns_local, lns_window

from .test_lns_kernels import _asymmetric_problem, _feasible, _problem, _random_tour


def _window_optimum(t, lo, length, edge, node, start, cluster_of):
    """Least cost of the tour over every choice of heads in the window, the rest kept."""
    n = len(t)
    slots = [(lo + x) % n for x in range(length)]
    best = np.inf
    for heads in itertools.product(*[range(start[cluster_of[t[i]]], start[cluster_of[t[i]] + 1])
                                     for i in slots]):
        u = t.copy()
        u[slots] = heads
        best = min(best, lns_local.tour_cost(u, edge, node))
    return best


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("directed", [False, True])
def test_reopt_window_is_the_best_for_its_window(seed, directed):
    """Every window of 1-3 positions (wrapping the end too): the tour afterwards costs the brute
    force optimum over the window's heads, only the window changed, and the saving returned is
    the cost that went."""
    if directed:
        edge, node, start, cluster_of = _asymmetric_problem(9, seed)
        t = start[:-1] + np.random.default_rng(seed).integers(0, np.diff(start))
        t = t[np.random.default_rng(seed + 1).permutation(len(t))].astype(np.int64)
    else:
        p, start, cluster_of = _problem(9, 3, seed)
        edge, node = p.edge_cost, p.node_cost
        t = _random_tour(p, np.random.default_rng(seed))
    n = len(t)
    for lo in (0, 4, n - 2):
        for length in (1, 2, 3):
            u = t.copy()
            before = lns_local.tour_cost(u, edge, node)
            optimum = _window_optimum(t, lo, length, edge, node, start, cluster_of)
            saving = lns_window.reopt_window(u, lo, length, edge, node, start, cluster_of, 1e-9)
            after = lns_local.tour_cost(u, edge, node)
            assert after == pytest.approx(optimum, rel=1e-12)
            assert saving == pytest.approx(before - after, rel=1e-9, abs=1e-9)
            outside = [i for i in range(n) if (i - lo) % n >= length]
            assert np.array_equal(u[outside], t[outside])
            assert np.array_equal(cluster_of[u], cluster_of[t])


def test_reopt_changed_touches_marked_windows_only():
    """Only the windows round the marked clusters may change; the marks are cleared; with every
    cluster marked it is the full re-opt."""
    p, start, cluster_of = _problem(14, 4, 3)
    t = _random_tour(p, np.random.default_rng(5))
    n = len(t)
    active = np.zeros((4, n), dtype=bool)
    active[3, cluster_of[t[6]]] = True
    u = t.copy()
    lns_window.reopt_changed(u, p.edge_cost, p.node_cost, start, cluster_of, 1e-9, active, 2)
    assert np.array_equal(u[:4], t[:4]) and np.array_equal(u[9:], t[9:])
    assert p.tour_cost(u) <= p.tour_cost(t) + 1e-9
    assert p.tour_cost(u) == pytest.approx(_window_optimum(t, 4, 5, p.edge_cost, p.node_cost, start,
                                                           cluster_of), rel=1e-12)
    assert not active[3, cluster_of[t[:3]]].any() and not active[3, cluster_of[t[10:]]].any()
    full = t.copy()
    active = np.zeros((4, n), dtype=bool)
    active[3] = True
    lns_window.reopt_changed(full, p.edge_cost, p.node_cost, start, cluster_of, 1e-9, active, 1)
    dp = t.copy()
    assert p.tour_cost(full) == pytest.approx(lns_local.reopt(dp, p.edge_cost, p.node_cost, start,
                                                              cluster_of), rel=1e-12)


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("directed", [False, True])
def test_windowed_local_search_never_worse_and_feasible(seed, directed):
    """From random tours, with a few clusters awake: a valid tour, never dearer, its cost
    returned, and no window of 3 positions left whose heads could improve."""
    if directed:
        k = 12
        edge, node, start, cluster_of = _asymmetric_problem(k, seed)
        rng = np.random.default_rng(seed)
        t = np.array([rng.integers(start[c], start[c + 1]) for c in rng.permutation(k)], dtype=np.int64)
        near = kernels.neighbours(edge, start, k - 1)
    else:
        p, start, cluster_of = _problem(16, 4, seed)
        edge, node = p.edge_cost, p.node_cost
        t = _random_tour(p, np.random.default_rng(seed))
        near = kernels.neighbours(edge, start, 5)
        k = p.n_clusters
    before = lns_local.tour_cost(t, edge, node)
    awake = np.zeros(k, dtype=bool)
    awake[[1, 5]] = True
    cost = lns_window.local_search_window(t, edge, node, start, near, cluster_of, 1e-9, awake,
                                          not directed, 2, np.nan)
    assert len(set(cluster_of[t].tolist())) == k
    assert cost == pytest.approx(lns_local.tour_cost(t, edge, node), rel=1e-12)
    assert cost <= before + 1e-9
    for lo in range(k):
        assert lns_window.reopt_window(t.copy(), lo, 3, edge, node, start, cluster_of, 1e-9) == 0.0


def test_iterate_with_a_window_gives_tours():
    """An iteration on the windowed path, every removal and insertion: a valid tour whose cost is
    returned."""
    p, start, cluster_of = _problem(20, 3, 7)
    near = kernels.neighbours(p.edge_cost, start, 4)
    t = _random_tour(p, np.random.default_rng(3))
    kernels.seed(1)
    for removal in range(len(kernels.REMOVALS)):
        for insertion in range(len(kernels.INSERTIONS)):
            new, cost = kernels.iterate(t, 5, removal, insertion, 0.2, p.edge_cost, p.node_cost, start,
                                        near, cluster_of, 1e-9, True, 2, np.nan)
            assert _feasible(p, new)
            assert cost == pytest.approx(p.tour_cost(new), rel=1e-12)
            new, cost = kernels.iterate(t, 5, removal, insertion, 0.2, p.edge_cost, p.node_cost, start,
                                        near, cluster_of, 1e-9, True, 2, p.tour_cost(t))
            assert _feasible(p, new)
            assert cost == pytest.approx(p.tour_cost(new), rel=1e-9)


@pytest.mark.parametrize("directed", [False, True])
def test_runs_cost_is_what_the_runs_add(directed):
    """Taking the marked positions out of a cycle saves exactly ``runs_cost``: runs of one, of
    several, and one that wraps past the end, on symmetric and directed costs."""
    if directed:
        edge, node, start, _ = _asymmetric_problem(12, 4)
        rng = np.random.default_rng(4)
        t = np.array([rng.integers(start[c], start[c + 1]) for c in rng.permutation(12)], dtype=np.int64)
    else:
        p, _, _ = _problem(12, 3, 4)
        edge, node = p.edge_cost, p.node_cost
        t = _random_tour(p, np.random.default_rng(4))
    n = len(t)
    rng = np.random.default_rng(0)
    masks = [np.isin(np.arange(n), [0, 1, n - 1]), np.isin(np.arange(n), [3]), np.arange(n) < n - 1]
    masks += [rng.random(n) < 0.4 for _ in range(20)]
    for marked in masks:
        if marked.all() or not marked.any():
            continue
        saved = lns_local.tour_cost(t, edge, node) - lns_local.tour_cost(t[~marked], edge, node)
        assert lns_window.runs_cost(t, marked, edge, node) == pytest.approx(saved, rel=1e-12)


@pytest.mark.parametrize("how", range(len(kernels.REMOVALS)))
def test_remove_near_takes_k_clusters(how):
    """Each large-cycle removal marks exactly k positions (a segment: consecutive ones), and
    putting them back gives a tour."""
    p, start, cluster_of = _problem(40, 2, 4)
    near = kernels.neighbours(p.edge_cost, start, 6)
    t = _random_tour(p, np.random.default_rng(how))
    kernels.seed(how)
    for k in (1, 3, 7):
        drop = lns_window.remove_near(t, k, how, p.edge_cost, p.node_cost, near, cluster_of)
        assert drop.sum() == k
        new = kernels.insert(t[~drop], cluster_of[t[drop]], 0, 0.0, p.edge_cost, p.node_cost, start,
                             near, cluster_of)
        assert _feasible(p, new)
        if how == 2:
            idx = np.flatnonzero(drop)
            assert all((i + 1) % len(t) in idx or (i - 1) % len(t) in idx for i in idx) or k == 1

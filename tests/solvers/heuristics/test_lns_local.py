"""The lns local search (compiled): feasible tours, costs that never rise, re-opt = the shared
DP, and on directed costs no single move, re-opt or or-opt left that improves."""

from __future__ import annotations

import numpy as np
import pytest
from gtsp_bench.solvers.heads import optimal_heads
from gtsp_bench.solvers.heuristics import lns_kernels as kernels
from gtsp_bench.solvers.heuristics import lns_local

from .test_lns_kernels import _asymmetric_problem, _directed_cost, _feasible, _problem, _random_tour


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
        cost = lns_local.local_search(t, p.edge_cost, p.node_cost, start, near, cluster_of, 1e-9, awake, True)
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
        cost = lns_local.reopt(t, p.edge_cost, p.node_cost, start, cluster_of)
        if p.depot is not None:
            t0 = np.roll(t, -int(np.flatnonzero(t == p.depot)[0]))
            order = p.cluster_of[t0[1:]]
        else:
            order = p.cluster_of[t]
        assert cost == pytest.approx(optimal_heads(p, order)[1], rel=1e-12)
        assert cost == pytest.approx(p.tour_cost(t), rel=1e-12)


@pytest.mark.parametrize("seed", range(3))
def test_asymmetric_local_search_prices_each_arc_in_its_direction(seed):
    """Directed costs: the local search (no 2-opt) never raises the directed cost and returns it;
    run again from all clusters awake until it gains nothing (don't-look bits may leave a move
    that a change far away made pay), it leaves a tour that no single move of a cluster (any
    place, any head), re-opt or or-opt move of a run of 2-3 clusters improves."""
    k = 12
    edge, node, start, cluster_of = _asymmetric_problem(k, seed)
    near = kernels.neighbours(edge, start, k - 1)
    rng = np.random.default_rng(seed)
    t = np.array([rng.integers(start[c], start[c + 1]) for c in rng.permutation(k)], dtype=np.int64)
    cost = _directed_cost(t, edge)
    while True:
        before = cost
        cost = lns_local.local_search(t, edge, node, start, near, cluster_of, 1e-9, np.ones(k, dtype=bool),
                                      False)
        assert len(set(cluster_of[t].tolist())) == k
        assert cost == pytest.approx(_directed_cost(t, edge), rel=1e-12) and cost <= before + 1e-9
        if cost >= before - 1e-9:
            break
    for i in range(k):  # every single-cluster move, priced from scratch
        rest = np.delete(t, i)
        c = cluster_of[t[i]]
        for j in range(k - 1):
            for v in range(start[c], start[c + 1]):
                assert _directed_cost(np.insert(rest, j + 1, v), edge) >= cost - 1e-9
    assert lns_local.reopt(t.copy(), edge, node, start, cluster_of) >= cost - 1e-9
    for length in (2, 3):  # every or-opt move of a run, direction kept, priced from scratch
        for i in range(k):
            rolled = np.roll(t, -i)
            run, rest = rolled[:length], rolled[length:]
            for j in range(len(rest)):
                moved = np.concatenate([rest[:j + 1], run, rest[j + 1:]])
                assert _directed_cost(moved, edge) >= cost - 1e-9


@pytest.mark.parametrize("seed", range(3))
def test_or_opt_with_reversal_leaves_no_reversed_move(seed):
    """Or-opt with ``reverse`` run until it stops: valid tour, heads kept, never dearer, and no run
    of 2-3 clusters can be put reversed next to a neighbour of its ends (the places the move
    looks at) for a gain; without ``reverse`` such moves are left on some tours."""
    p, start, cluster_of = _problem(15, 3, seed)
    near = kernels.neighbours(p.edge_cost, start, 6)
    edge = p.edge_cost
    rng = np.random.default_rng(seed)
    left_without = 0
    for _ in range(10):
        first = _random_tour(p, rng)
        for reverse in (True, False):
            t = first.copy()
            pos = np.empty(len(t), dtype=np.int64)
            pos[cluster_of[t]] = np.arange(len(t))
            before, heads = p.tour_cost(t), set(t.tolist())
            awake = np.ones((3, len(t)), dtype=bool)
            while lns_local.or_opt(t, pos, edge, near, cluster_of, 1e-9, awake, reverse):
                pass
            assert _feasible(p, t) and set(t.tolist()) == heads
            assert np.array_equal(pos[cluster_of[t]], np.arange(len(t)))
            assert p.tour_cost(t) <= before + 1e-9
            n, found = len(t), False
            for i in range(n):
                for length in (2, 3):
                    a, b = t[i], t[(i + length - 1) % n]
                    pr, q = t[(i - 1) % n], t[(i + length) % n]
                    gain = edge[pr, a] + edge[b, q] - edge[pr, q]
                    for w in range(near.shape[1]):
                        for j in (pos[near[cluster_of[a], w]], (pos[near[cluster_of[b], w]] - 1) % n):
                            if (j - i + 1) % n <= length:
                                continue
                            x, y = t[j], t[(j + 1) % n]
                            found |= edge[x, b] + edge[a, y] - edge[x, y] < gain - 1e-6
            if reverse:
                assert not found
            else:
                left_without += found
    assert left_without > 0


@pytest.mark.parametrize("seed", range(3))
def test_segment_swap_leaves_no_swap_that_pays(seed):
    """Segment swap with every cluster a neighbour, repeated with all heads awake until a pass
    gains nothing: heads kept, each pass's return the cost it saved, and no two consecutive runs
    of the tour (any lengths) can trade places for a gain, by brute force over all cut triples
    (the partial-gain rule loses no improving swap: one of its three rotations passes it)."""
    k = 11
    edge, _, start, cluster_of = _asymmetric_problem(k, seed)
    near = kernels.neighbours(edge, start, k - 1)
    rng = np.random.default_rng(seed)
    for _ in range(5):
        t = np.array([rng.integers(start[c], start[c + 1]) for c in rng.permutation(k)], dtype=np.int64)
        heads, cost = set(t.tolist()), _directed_cost(t, edge)
        while True:
            pos, active = lns_local.search_state(t, cluster_of, np.ones(k, dtype=bool), 3)
            got = lns_local.segment_swap(t, pos, edge, near, cluster_of, 1e-9, active)
            assert set(t.tolist()) == heads
            assert np.array_equal(pos[cluster_of[t]], np.arange(k))
            assert got == pytest.approx(cost - _directed_cost(t, edge), abs=1e-9)
            cost = _directed_cost(t, edge)
            if got == 0.0:
                break
        for i in range(k):
            for j in range(i + 1, k):
                for m in range(j + 1, k):  # t[:i+1] | t[i+1:j+1] | t[j+1:m+1] | t[m+1:]
                    u = np.concatenate([t[:i + 1], t[j + 1:m + 1], t[i + 1:j + 1], t[m + 1:]])
                    assert _directed_cost(u, edge) >= cost - 1e-6


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
        awake = np.ones((3, len(t)), dtype=bool)
        moved = lns_local.or_opt(t, pos, p.edge_cost, near, cluster_of, 1e-9, awake)
        assert _feasible(p, t) and set(t.tolist()) == heads
        assert np.array_equal(pos[cluster_of[t]], np.arange(len(t)))
        assert p.tour_cost(t) <= before + 1e-9
        assert (moved > 0.0) == (p.tour_cost(t) < before - 1e-9)
        assert moved == pytest.approx(before - p.tour_cost(t), rel=1e-9, abs=1e-9)
        gained += moved > 0.0
    assert gained > 0


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("directed", [False, True])
def test_moves_return_their_savings(seed, directed):
    """2-opt, or-opt and move (all clusters or only the awake ones) each return what they saved,
    the tour's cost before less after; a large-cycle round returns the cost it leaves, counted
    from those savings."""
    if directed:
        k = 12
        edge, node, start, cluster_of = _asymmetric_problem(k, seed)
        near = kernels.neighbours(edge, start, k - 1)
        rng = np.random.default_rng(seed)

        def fresh():
            return np.array([rng.integers(start[c], start[c + 1]) for c in rng.permutation(k)],
                            dtype=np.int64)
    else:
        p, start, cluster_of = _problem(16, 4, seed)
        edge, node, k = p.edge_cost, p.node_cost, p.n_clusters
        near = kernels.neighbours(edge, start, 5)
        rng = np.random.default_rng(seed)

        def fresh():
            return _random_tour(p, rng)

    def state(t, rows=4):
        return lns_local.search_state(t, cluster_of, np.ones(k, dtype=bool), rows)

    saved = 0.0
    moves = [lambda t, pos, act: lns_local.or_opt(t, pos, edge, near, cluster_of, 1e-9, act, not directed),
             lambda t, pos, act: lns_local.move_opt(t, pos, edge, node, start, near, cluster_of, 1e-9, act,
                                                    not directed, False),
             lambda t, pos, act: lns_local.move_opt(t, pos, edge, node, start, near, cluster_of, 1e-9, act,
                                                    not directed, True)]
    if not directed:
        moves.append(lambda t, pos, act: lns_local.two_opt(t, pos, edge, near, cluster_of, 1e-9, act))
    else:
        moves.append(lambda t, pos, act: lns_local.segment_swap(t, pos, edge, near, cluster_of, 1e-9, act))
    for move in moves:
        t = fresh()
        before = lns_local.tour_cost(t, edge, node)
        pos, active = state(t)
        got = move(t, pos, active)
        after = lns_local.tour_cost(t, edge, node)
        assert len(set(cluster_of[t].tolist())) == k
        assert np.array_equal(pos[cluster_of[t]], np.arange(k))
        assert got == pytest.approx(before - after, rel=1e-9, abs=1e-9)
        saved += got
    assert saved > 0.0
    t = fresh()
    before = lns_local.tour_cost(t, edge, node)
    pos, active = state(t)
    moved, cost = lns_local.move_round(t, pos, edge, node, start, near, cluster_of, 1e-9, active,
                                       not directed, True, before)
    assert moved and cost == pytest.approx(lns_local.tour_cost(t, edge, node), rel=1e-9)


@pytest.mark.parametrize(("seed", "directed"), [(0, False), (1, False), (2, True)])
def test_kick_search_never_worse_and_feasible(seed, directed):
    """Double-bridge kicks keep one node per cluster, never raise the cost (directed costs priced
    in their direction), return the tour's cost, and from random local optima find something
    cheaper at least once; a cycle under 8 clusters is left as it is."""
    k = 30
    if directed:
        edge, node, start, cluster_of = _asymmetric_problem(k, seed)
        near = kernels.neighbours(edge, start, k - 1)

        def cost_of(t):
            return _directed_cost(t, edge) + float(node[t].sum())
    else:
        p, start, cluster_of = _problem(k, 5, seed)
        edge, node = p.edge_cost, p.node_cost
        near = kernels.neighbours(edge, start, 5)
        cost_of = p.tour_cost
    n = len(start) - 1  # clusters (with the depot's on the UAV instance)
    kernels.seed(seed)
    rng = np.random.default_rng(seed)
    gained = False
    for _ in range(6):
        t = np.array([rng.integers(start[c], start[c + 1]) for c in rng.permutation(n)], dtype=np.int64)
        awake = np.ones(n, dtype=bool)
        before = lns_local.local_search(t, edge, node, start, near, cluster_of, 1e-9, awake, not directed)
        cost = lns_local.kick_search(t, before, 200, edge, node, start, near, cluster_of, 1e-9,
                                     not directed)
        assert sorted(cluster_of[t]) == list(range(n))
        assert cost == pytest.approx(cost_of(t), rel=1e-12)
        assert cost <= before + 1e-9
        gained = gained or cost < before - 1e-9
    assert gained
    small = np.array([start[c] for c in range(6)], dtype=np.int64)
    kept = small.copy()
    assert lns_local.kick_search(small, 1.0, 50, edge, node, start, near, cluster_of, 1e-9,
                                 not directed) == 1.0
    assert np.array_equal(small, kept)

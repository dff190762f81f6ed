"""The compiled kernels of the separation and pricing: max-flow against scipy's on random
networks, the others against numpy."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from gtsp_bench.solvers.exact.mip import flow
from gtsp_bench.solvers.exact.mip.separation import _Network
from scipy.sparse.csgraph import maximum_flow


def _random_network(rng: np.random.Generator) -> tuple[_Network, np.ndarray, int]:
    """A random network (every arc with its reverse) and random integer capacities both ways."""
    n = int(rng.integers(3, 25))
    pairs = np.unique(np.sort(rng.integers(0, n, (3 * n, 2)), axis=1), axis=0)
    pairs = pairs[pairs[:, 0] != pairs[:, 1]]
    net, where = _Network.build(pairs[:, 0], pairs[:, 1], n)
    cap = np.zeros(len(net.indices), dtype=np.int64)
    cap[where] = rng.integers(0, 10, len(pairs))
    cap[net.rev[where]] = rng.integers(0, 10, len(pairs))
    return net, cap, n


@pytest.mark.parametrize("seed", range(40))
def test_value_and_both_minimum_cuts_match_scipy(seed):
    """The flow value equals scipy's; both sink sides hold the sink, not the source, and the
    arcs from outside into each side carry exactly the flow value (a minimum cut)."""
    net, cap, n = _random_network(np.random.default_rng(seed))
    source, sink = 0, n - 1
    value, sides = net.min_cut_sides(cap, source, sink)
    graph = sp.csr_array((cap.astype(np.int32), net.indices.astype(np.int32),
                          net.indptr.astype(np.int32)), shape=(n, n))
    assert value == maximum_flow(graph, source, sink).flow_value
    for side in sides:
        assert side[sink] and not side[source]
        crossing = ~side[net.row] & side[net.indices]
        assert cap[crossing].sum() == value


def test_flow_is_antisymmetric_and_conserved():
    """Flow on an arc is minus the flow on its reverse, within capacity, and conserved at every
    node but the source and the sink."""
    net, cap, n = _random_network(np.random.default_rng(99))
    value, f = flow.max_flow(net.indptr, net.indices, net.row, net.rev, cap, 0, n - 1)
    assert np.array_equal(f[net.rev], -f)
    assert np.all(f <= cap)
    out = np.bincount(net.row, weights=f, minlength=n)  # net outflow per node
    assert out[0] == value and out[n - 1] == -value
    assert np.all(out[1:n - 1] == 0)


def test_reach_forward_and_backward():
    """On the path 0 -> 1 -> 2 with only forward arcs open: 0 reaches all, 2 is reached by all."""
    net, where = _Network.build(np.array([0, 1]), np.array([1, 2]), 3)
    residual = np.zeros(len(net.indices), dtype=np.int64)
    residual[where] = 1
    assert flow.reach(net.indptr, net.indices, net.rev, residual, 0, False).tolist() == [True] * 3
    assert flow.reach(net.indptr, net.indices, net.rev, residual, 2, True).tolist() == [True] * 3
    assert flow.reach(net.indptr, net.indices, net.rev, residual, 1, False).tolist() == [False, True, True]


@pytest.mark.parametrize("seed", range(20))
def test_teeth_violation_matches_best_teeth(seed):
    """The compiled blossom violation and ``_best_teeth``'s teeth equal a plain numpy statement of
    the rule (teeth: edges leaving the handle with z > 1/2, parity mended by the edge closest to
    1/2, the first in row-major order), on random symmetric cluster tours with half-integral and
    arbitrary values, either parity."""
    from gtsp_bench.solvers.exact.mip.separation import _best_teeth

    def reference(z, handle):
        inner, outer = np.flatnonzero(handle), np.flatnonzero(~handle)
        cut = z[np.ix_(inner, outer)]
        teeth = cut > 0.5
        slack = np.where(teeth, 1 - cut, cut).sum()
        if teeth.sum() % 2 == 0:
            k = np.unravel_index(np.argmin(np.abs(1 - 2 * cut)), cut.shape)
            slack += abs(1 - 2 * cut[k])
            teeth[k] = ~teeth[k]
        i, j = np.nonzero(teeth)
        return 1 - slack, inner[i], outer[j]

    rng = np.random.default_rng(seed)
    m = int(rng.integers(4, 15))
    z = rng.choice([0.0, 0.5, 1.0], size=(m, m)) if seed % 2 else rng.uniform(0, 1, (m, m))
    z = np.triu(z, 1)
    z += z.T
    for _ in range(5):
        handle = rng.uniform(size=m) < 0.5
        if handle.all() or not handle.any():
            continue
        expected, inner, outer = reference(z, handle)
        assert flow.teeth_violation(z, handle)[0] == pytest.approx(expected, abs=1e-12)
        got = _best_teeth(z, handle)
        assert got[0] == pytest.approx(expected, abs=1e-12)
        assert got[1].tolist() == inner.tolist() and got[2].tolist() == outer.tolist()


def test_edge_weights_kernel_equals_numpy_gathers():
    """The compiled per-edge sum equals numpy's gathers over a subset of edges in any order, with
    the per-edge extra term and without it."""
    rng = np.random.default_rng(7)
    cluster = np.repeat(np.arange(5), rng.integers(1, 4, 5))
    n, m = len(cluster), 5
    tail, head = np.triu_indices(n, 1)
    keep = cluster[tail] != cluster[head]
    tail, head = tail[keep].astype(np.int64), head[keep].astype(np.int64)
    pair, node_cluster = rng.random((m, m)), rng.random((n, m))
    extra = rng.random(len(tail))
    edges = rng.permutation(len(tail))[:len(tail) // 2].astype(np.int64)
    ct, ch = cluster[tail[edges]], cluster[head[edges]]
    expected = pair[ct, ch] + node_cluster[head[edges], ct] + node_cluster[tail[edges], ch]
    got = flow.edge_weights(edges, tail, head, cluster, pair, node_cluster, np.zeros(0))
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-15)
    got = flow.edge_weights(edges, tail, head, cluster, pair, node_cluster, extra)
    np.testing.assert_allclose(got, expected + extra[edges], rtol=0, atol=1e-15)


def test_edge_reduced_costs_kernel_equals_numpy_bit_for_bit():
    """The compiled reduced costs are numpy's expression, summed in the same order (so a search
    takes the same path with either)."""
    rng = np.random.default_rng(8)
    n = 9
    tail, head = (a.astype(np.int64) for a in np.triu_indices(n, 1))
    cost, pi_deg = rng.normal(size=len(tail)) * 100, rng.normal(size=n) * 50
    edges = rng.permutation(len(tail))[:20].astype(np.int64)
    on_edge = rng.normal(size=len(edges))
    expected = cost[edges] - pi_deg[tail[edges]] - pi_deg[head[edges]] - on_edge
    got = flow.edge_reduced_costs(edges, cost, tail, head, pi_deg, on_edge)
    assert got.tolist() == expected.tolist()


def test_side_edges_counts_inside_and_crossing_edges():
    """Per side, the edges with both ends in it and those with one, as numpy counts them."""
    rng = np.random.default_rng(9)
    n = 12
    tail, head = (a.astype(np.int64) for a in np.triu_indices(n, 1))
    side = rng.random((6, n)) < 0.4
    inside, crossing = flow.side_edges(side, tail, head)
    st, sh = side[:, tail], side[:, head]
    assert inside.tolist() == (st & sh).sum(axis=1).tolist()
    assert crossing.tolist() == (st ^ sh).sum(axis=1).tolist()


def test_cut_rows_grow_past_their_first_guess():
    """A row block with more entries than the kernel's first allocation (64 a row) is built
    whole: the entries of an all-ones side over every edge (120 a row)."""
    n = 16
    tail, head = (a.astype(np.int64) for a in np.triu_indices(n, 1))
    rows = 3
    side = np.ones((rows, n), dtype=bool)
    cols = n + np.arange(len(tail), dtype=np.int64)
    indptr, indices, data = flow.cut_rows(side, np.arange(rows, dtype=np.int64), np.zeros(rows, bool),
                                          np.zeros((rows, n)), cols, tail, head)
    assert indptr.tolist() == [len(tail) * r for r in range(rows + 1)]
    assert indices.tolist() == list(range(len(tail))) * rows and set(data.tolist()) == {1.0}


def test_loose_nodes_are_the_sides_nodes_outside_whole_clusters():
    """The CSR of ``sides & ~whole[:, cluster]`` equals scipy's from the dense mask."""
    rng = np.random.default_rng(10)
    cluster = np.repeat(np.arange(6), 3)
    sides = rng.random((7, len(cluster))) < 0.5
    sides[0, :3] = True  # a side holding cluster 0 whole
    whole = np.logical_and.reduceat(sides, np.arange(0, len(cluster), 3), axis=1)
    indptr, indices = flow.loose_nodes(sides, whole, cluster)
    expected = sp.csr_array(sides & ~whole[:, cluster])
    assert indptr.tolist() == expected.indptr.tolist() and indices.tolist() == expected.indices.tolist()

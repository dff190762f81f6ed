"""The macro first tour of lns: centres, the tour through them, optimal heads for its order."""

from __future__ import annotations

import time

import numpy as np
import pytest
from gtsp_bench.solvers.heads import optimal_heads
from gtsp_bench.solvers.heuristics import lns_kernels as kernels
from gtsp_bench.solvers.heuristics import lns_macro
from gtsp_bench.solvers.heuristics.lns_costs import kernel_costs
from gtsp_bench.solvers.heuristics.lns_macro import (
    centre_groups,
    centre_order,
    cluster_centres,
    group_chain,
    group_distances,
    group_order,
    grouped_costs,
    macro_tour,
)
from scipy.spatial.distance import cdist

from gtsp_bench.data.io import read_instance
from gtsp_bench.problem import price
from tests.conftest import GTSPLIB


def _length(points: np.ndarray, order: np.ndarray) -> float:
    """Length of the closed tour through ``points`` in ``order``."""
    p = points[order]
    return float(np.hypot(*(p - np.roll(p, -1, axis=0)).T).sum())


def _ring(k: int, seed: int) -> np.ndarray:
    """``k`` points on a circle of radius 100, shuffled (the shortest tour goes round it)."""
    angle = np.random.default_rng(seed).permutation(k) * 2 * np.pi / k
    return np.column_stack([100 * np.cos(angle), 100 * np.sin(angle)])


def test_cluster_centres_are_the_means_of_each_cluster():
    """Each centre is the mean of its cluster's points (clusters of 1, 2 and 3 points)."""
    xy = np.array([[0.0, 0.0], [2.0, 4.0], [4.0, 0.0], [1.0, 1.0], [3.0, 3.0], [5.0, 2.0]])
    start = np.array([0, 1, 3, 6])
    np.testing.assert_allclose(cluster_centres(xy, start), [[0, 0], [3, 2], [3, 2]])


@pytest.mark.parametrize("iterations", [0, 200])
def test_centre_order_visits_every_point_once(iterations):
    """The centre tour is a permutation of the points; on a ring it is the ring (length 2 pi r
    up to the chords), with or without the annealing trial."""
    pts = _ring(60, seed=3)
    kernels.seed(1)
    order = centre_order(pts, iterations, large=400)
    assert sorted(order.tolist()) == list(range(60))
    assert _length(pts, order) == pytest.approx(60 * 2 * 100 * np.sin(np.pi / 60), rel=1e-9)


def test_centre_order_is_seeded_and_the_trial_only_shortens_it():
    """The same kernel seed gives the same order; the trial starts from the local search's tour,
    so with it the tour is never longer than without it (same seed), and usually shorter."""
    pts = np.random.default_rng(7).uniform(0, 1000, size=(150, 2))
    runs = []
    for iterations in (0, 1500, 1500):
        kernels.seed(4)
        runs.append(centre_order(pts, iterations, large=100))  # the large-cycle path above 100
    assert np.array_equal(runs[1], runs[2])
    assert _length(pts, runs[1]) <= _length(pts, runs[0]) + 1e-9
    for order in runs:
        assert sorted(order.tolist()) == list(range(150))


def test_centre_order_stops_at_a_past_deadline():
    """A deadline already past cuts the trial after its first chunk: still a valid order."""
    pts = np.random.default_rng(2).uniform(0, 1000, size=(80, 2))
    kernels.seed(0)
    order = centre_order(pts, 10**9, large=400, deadline=time.perf_counter() - 1.0)
    assert sorted(order.tolist()) == list(range(80))


@pytest.mark.parametrize("k", [1, 2, 3])
def test_centre_order_of_very_few_points(k):
    """Up to three points every order is the same cycle."""
    assert centre_order(np.zeros((k, 2)), 10, large=400).tolist() == list(range(k))


def _blobs(sizes: list[int], seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Blobs of points 2 apart on a jittered grid 8 wide, the blobs 1,000 apart on a line,
    shuffled, and each point's blob."""
    rng = np.random.default_rng(seed)
    blob = np.repeat(np.arange(len(sizes)), sizes)
    j = np.concatenate([np.arange(m) for m in sizes])
    xy = np.column_stack([1000.0 * blob + 2.0 * (j % 8), 2.0 * (j // 8)])
    xy += rng.uniform(-0.3, 0.3, xy.shape)
    perm = rng.permutation(len(blob))
    return xy[perm], blob[perm]


def _crossings(groups: np.ndarray, order: np.ndarray) -> int:
    """Edges of the closed tour ``order`` between two groups."""
    return int(np.sum(groups[order] != groups[np.roll(order, -1)]))


def test_centre_groups_are_the_blobs():
    """Separated blobs are one group each (the same partition, whatever the labels); a uniform
    grid is one group; repeated points (median nearest distance 0) are one group."""
    xy, blob = _blobs([30, 5, 12, 1], seed=0)
    groups = centre_groups(xy, 5.0)
    assert len(np.unique(groups)) == 4
    for b in range(4):  # each blob maps to exactly one label, distinct blobs to distinct labels
        assert len(np.unique(groups[blob == b])) == 1
    assert len({int(groups[blob == b][0]) for b in range(4)}) == 4
    grid = np.array([[x, y] for x in range(20) for y in range(20)], dtype=float)
    assert np.all(centre_groups(grid, 5.0) == 0)
    assert np.all(centre_groups(np.zeros((9, 2)), 5.0) == 0)
    assert centre_groups(np.zeros((1, 2)), 5.0).tolist() == [0]


def test_grouped_costs_add_more_than_any_edge_between_groups():
    """Within a group the distance; between two groups the distance plus the bounding box's
    diagonal (so one crossing more always costs more than any saving in length)."""
    xy = np.array([[0.0, 0.0], [3.0, 4.0], [6.0, 8.0]])
    cost = grouped_costs(xy, np.array([0, 0, 1]))
    diagonal = 10.0
    np.testing.assert_allclose(cost, [[0, 5, 10 + diagonal], [5, 0, 5 + diagonal],
                                      [10 + diagonal, 5 + diagonal, 0]])


def _ring_blobs(count: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """``count`` blobs of 6-20 points each (jittered grids 2 apart) at the corners of a regular
    polygon of radius 1,000, the blobs in a random order of labels; the points and their blob."""
    rng = np.random.default_rng(seed)
    sizes = rng.integers(6, 21, size=count)
    where = rng.permutation(count)  # blob b sits at corner where[b]
    angle = 2 * np.pi * where / count
    blob = np.repeat(np.arange(count), sizes)
    j = np.concatenate([np.arange(m) for m in sizes])
    xy = np.column_stack([1000 * np.cos(angle[blob]) + 2.0 * (j % 4),
                          1000 * np.sin(angle[blob]) + 2.0 * (j // 4)])
    xy += rng.uniform(-0.3, 0.3, xy.shape)
    return xy, blob


def test_group_distances_are_the_nearest_pairs():
    """Between two groups the least distance between their points (brute force), symmetric,
    0 on the diagonal."""
    xy, blob = _ring_blobs(7, seed=1)
    dist = group_distances(xy, blob)
    pairs = cdist(xy, xy)
    for g in range(7):
        for h in range(7):
            want = 0.0 if g == h else pairs[np.ix_(blob == g, blob == h)].min()
            assert dist[g, h] == pytest.approx(want, rel=1e-12)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_group_order_goes_round_the_ring(seed):
    """Twelve blobs round a circle: the group tour visits each once, neighbours on the circle
    next to each other (either way round)."""
    xy, blob = _ring_blobs(12, seed)
    corner = np.round(np.degrees(np.arctan2(*xy[:, ::-1].T)) / 30).astype(int) % 12
    at = np.array([corner[blob == g][0] for g in range(12)])
    kernels.seed(seed)
    order = group_order(xy, blob, large=400)
    assert sorted(order.tolist()) == list(range(12))
    steps = (at[np.roll(order, -1)] - at[order]) % 12
    assert np.all(steps == 1) or np.all(steps == 11)


@pytest.mark.parametrize("seed", [0, 1])
def test_group_chain_visits_the_groups_in_order(seed):
    """The chain is a permutation of the points that enters each group once, in ``order``
    (a one-point group included)."""
    xy, blob = _ring_blobs(9, seed)
    xy, blob = np.vstack([xy, [[0.0, 0.0]]]), np.append(blob, 9)  # a lone point in the middle
    order = np.random.default_rng(seed).permutation(10)
    chain = group_chain(xy, blob, order)
    assert sorted(chain.tolist()) == list(range(len(xy)))
    runs = blob[chain][np.flatnonzero(blob[chain] != np.roll(blob[chain], 1))]
    shift = int(np.flatnonzero(runs == order[0])[0])
    assert np.array_equal(np.roll(runs, -shift), order)


def test_grouped_costs_with_an_order_charge_more_between_groups_apart():
    """With an order of four groups: one diagonal between groups next to each other in it (the
    last and the first too), three between groups two apart."""
    xy = np.array([[0.0, 0.0], [3.0, 4.0], [6.0, 8.0], [0.0, 8.0]])
    groups = np.array([0, 1, 2, 3])
    cost = grouped_costs(xy, groups, order=np.array([0, 2, 1, 3]))
    plain, diagonal = cdist(xy, xy), 10.0
    extra = cost - plain
    assert extra[0, 2] == extra[2, 1] == extra[1, 3] == extra[3, 0] == pytest.approx(diagonal)
    assert extra[0, 1] == extra[2, 3] == pytest.approx(3 * diagonal)
    np.testing.assert_allclose(extra, extra.T)
    assert np.all(np.diag(extra) == 0)


def _scattered_blobs(count: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """``count`` blobs of 20-60 points (jittered grids 2 apart) at random places in a square
    10,000 wide; the points and their blob."""
    rng = np.random.default_rng(seed)
    sizes = rng.integers(20, 61, size=count)
    at = rng.uniform(0, 10000, size=(count, 2))
    blob = np.repeat(np.arange(count), sizes)
    j = np.concatenate([np.arange(m) for m in sizes])
    xy = at[blob] + np.column_stack([2.0 * (j % 6), 2.0 * (j // 6)])
    return xy + rng.uniform(-0.3, 0.3, xy.shape), blob


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_grouped_centre_order_follows_the_group_tour(seed):
    """Thirty blobs scattered in a square: the centre tour enters each blob once, in the order of
    the group tour (the same length through the groups). The penalty alone, from a random-insertion
    tour, left these groups in orders 6-22 % longer (measured when the group tour came in)."""
    xy, _ = _scattered_blobs(30, seed)
    groups = centre_groups(xy, 5.0)
    assert len(np.unique(groups)) == 30
    dist = group_distances(xy, groups)
    kernels.seed(seed)
    want = group_order(xy, groups, large=100)
    kernels.seed(seed)  # the centre tour solves the same group tour first
    order = centre_order(xy, 300, large=100, groups=groups)
    assert sorted(order.tolist()) == list(range(len(xy)))
    runs = groups[order][np.flatnonzero(groups[order] != np.roll(groups[order], 1))]
    assert len(runs) == 30
    length = dist[runs, np.roll(runs, -1)].sum()
    assert length == pytest.approx(dist[want, np.roll(want, -1)].sum(), rel=1e-12)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_grouped_centre_order_enters_each_group_once(seed):
    """Five blobs on a line: the plain centre tour splits blobs between its way out and its way
    back (more crossings than groups); with the groups it crosses once per group, and is still
    a permutation."""
    xy, _ = _blobs([40, 25, 60, 30, 35], seed)
    groups = centre_groups(xy, 5.0)
    assert len(np.unique(groups)) == 5
    kernels.seed(seed)
    plain = centre_order(xy, 300, large=100)
    kernels.seed(seed)
    order = centre_order(xy, 300, large=100, groups=groups)
    assert sorted(order.tolist()) == list(range(len(xy)))
    assert _crossings(groups, order) == 5 < _crossings(groups, plain)


def test_many_groups_are_ordered_by_the_penalty_alone(monkeypatch):
    """Above GROUP_ORDER_MAX groups no group tour is solved (patched to 3 here): the centre tour
    still enters each of the five blobs once."""
    monkeypatch.setattr(lns_macro, "GROUP_ORDER_MAX", 3)
    monkeypatch.setattr(lns_macro, "group_order", None)  # would raise if called
    xy, _ = _blobs([40, 25, 60, 30, 35], seed=4)
    groups = centre_groups(xy, 5.0)
    kernels.seed(4)
    order = centre_order(xy, 300, large=100, groups=groups)
    assert sorted(order.tolist()) == list(range(len(xy)))
    assert _crossings(groups, order) == 5


def test_centre_order_ignores_groups_where_one_holds_half():
    """One group, or one group of at least half the points beside small ones: the ungrouped
    tour (the same kernel seed gives the same order)."""
    pts = np.random.default_rng(3).uniform(0, 1000, size=(120, 2))
    outliers = np.zeros(120, dtype=np.int64)
    outliers[:10] = np.arange(1, 11)
    runs = []
    for g in (None, np.zeros(120, dtype=np.int64), outliers):
        kernels.seed(3)
        runs.append(centre_order(pts, 300, large=100, groups=g))
    assert np.array_equal(runs[0], runs[1]) and np.array_equal(runs[0], runs[2])


def test_macro_tour_keeps_the_order_with_optimal_heads():
    """On 11berlin52 (no depot) the macro tour visits every cluster once, in the given order (up
    to rotation), one node of each, at the cost of optimal_heads for that order."""
    problem = price(read_instance(GTSPLIB / "11berlin52.gtsp.gz"), None)
    start = np.array([c[0] for c in problem.clusters] + [problem.n_nodes], dtype=np.int64)
    cluster_of = np.ascontiguousarray(problem.cluster_of, dtype=np.int64)
    edge = kernel_costs(problem, False)
    node = np.ascontiguousarray(problem.node_cost, dtype=np.float64)
    order = np.random.default_rng(5).permutation(problem.n_clusters)
    t = macro_tour(order, edge, node, start, cluster_of)
    visited = cluster_of[t]
    assert sorted(visited.tolist()) == list(range(problem.n_clusters))
    shift = int(np.flatnonzero(visited == order[0])[0])
    assert np.array_equal(np.roll(visited, -shift), order)
    _, best = optimal_heads(problem, order)
    assert problem.tour_cost(t) == pytest.approx(best, rel=1e-12)
    assert kernels.tour_cost(t, edge, node) == pytest.approx(best, rel=1e-12)


@pytest.mark.parametrize("order", [[0, 1, 1, 2], [0, 1, 2], [0, 1, 2, 3, 4]])
def test_macro_tour_refuses_an_order_that_is_not_a_permutation(order):
    """A repeated, missing or extra cluster is refused before the kernels see it (their trials
    assume each cluster once, and did not end on a tour with a repeat)."""
    start = np.array([0, 2, 4, 6, 8], dtype=np.int64)
    xy = np.arange(16, dtype=np.float64).reshape(8, 2)
    with pytest.raises(ValueError, match="every cluster exactly once"):
        macro_tour(np.array(order), (xy, 1, 1.0), np.zeros(8), start, np.repeat(np.arange(4), 2))

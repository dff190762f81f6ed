"""The MILP model: columns, base rows, cycles and tour of an integer point, core columns."""

from __future__ import annotations

import itertools

import numpy as np
from gtsp_bench.solvers.exact.mip.model import GtspModel, build_model, core_columns

from gtsp_bench.generator import generate_instance
from gtsp_bench.instance import Instance
from gtsp_bench.problem import price


def _model(seed: int, k: int = 5, depot: bool = True, max_size: int = 3) -> GtspModel:
    rng = np.random.default_rng(seed)
    base = generate_instance(k, 3, seed=seed)
    sizes = rng.integers(1, max_size + 1, size=k)
    inst = Instance(name="m", depot=base.depot if depot else None,
                    clusters=tuple(c[:s] for c, s in zip(base.clusters, sizes, strict=True)))
    problem = price(inst, float(rng.uniform()))
    return build_model(problem, problem.clusters)


def _vector(model: GtspModel, cycles: list[list[int]]) -> np.ndarray:
    """Column vector of local-node cycles (each of 3 nodes or more)."""
    edge = {(int(a), int(b)): e for e, (a, b) in enumerate(zip(model.tail, model.head, strict=True))}
    v = np.zeros(model.n_cols)
    for cyc in cycles:
        v[cyc] = 1
        for a, b in zip(cyc, cyc[1:] + cyc[:1], strict=True):
            v[model.n_nodes + edge[(min(a, b), max(a, b))]] = 1
    return v


def _all_tours(model: GtspModel) -> np.ndarray:
    """Every tour over the model's nodes, one row each."""
    kept = [np.flatnonzero(model.cluster == c) for c in range(model.n_clusters)]
    rows = []
    for heads in itertools.product(*kept):
        for perm in itertools.permutations(range(1, len(kept))):
            if perm[0] < perm[-1]:
                rows.append(_vector(model, [[int(heads[0]), *(int(heads[p]) for p in perm)]]))
    return np.array(rows)


def _random_tour(model: GtspModel, rng: np.random.Generator) -> list[int]:
    order = rng.permutation(model.n_clusters)
    return [int(rng.choice(np.flatnonzero(model.cluster == c))) for c in order]


def test_columns_are_the_nodes_and_the_edges_between_clusters():
    """One y column per kept node, one x column per pair of nodes in different clusters, priced."""
    model = _model(4, k=6)
    problem = model.problem
    n = model.n_nodes
    assert model.n_clusters == problem.n_clusters
    assert np.all(np.diff(model.cluster) >= 0)
    assert np.all(model.tail < model.head)
    assert np.all(model.cluster[model.tail] != model.cluster[model.head])
    sizes = np.bincount(model.cluster)
    assert len(model.tail) == (n * n - (sizes**2).sum()) // 2  # every such pair, once
    y_cost, x_cost = model.split(model.cost)
    np.testing.assert_array_equal(y_cost, problem.node_cost[model.nodes])
    np.testing.assert_array_equal(x_cost, problem.edge_cost[model.nodes[model.tail], model.nodes[model.head]])


def test_tour_extraction():
    """tour() gives back a tour's nodes in cycle order (either direction), as one component."""
    model = _model(1)
    rng = np.random.default_rng(0)
    cyc = _random_tour(model, rng)
    v = _vector(model, [cyc])
    assert len(model.components(v)) == 1
    got = [int(i) for i in np.searchsorted(model.nodes, model.tour(v))]
    start = got.index(cyc[0])
    rotated = got[start:] + got[:start]
    assert rotated in (cyc, [cyc[0], *cyc[1:][::-1]])


def test_components_of_two_cycles():
    """An integer point of two cycles has both as components, each with its own nodes."""
    model = _model(5, k=6, max_size=1)
    v = _vector(model, [[0, 1, 2], [3, 4, 5, 6]])
    comps = sorted(sorted(int(i) for i in c) for c in model.components(v))
    assert comps == [[0, 1, 2], [3, 4, 5, 6]]


def test_base_rows_hold_for_tours():
    """Cluster and degree rows are equalities every tour satisfies."""
    model = _model(2)
    tours = _all_tours(model)
    matrix, rhs = model.base_rows(np.arange(model.n_cols))
    assert np.allclose(matrix @ tours.T, rhs[:, None])


def test_core_columns_keep_all_y_the_cheapest_edges_and_the_tour():
    """All y columns, at least ``per_node`` edges at each node, and the given tour's edges."""
    model = _model(3, k=6)
    rng = np.random.default_rng(1)
    tour_local = _random_tour(model, rng)
    cols = core_columns(model, 2, model.nodes[tour_local])
    assert set(range(model.n_nodes)) <= set(cols)
    tour_cols = np.flatnonzero(_vector(model, [tour_local])[model.n_nodes:]) + model.n_nodes
    assert set(tour_cols) <= set(cols)
    edges = cols[cols >= model.n_nodes] - model.n_nodes
    degree = np.bincount(np.concatenate([model.tail[edges], model.head[edges]]), minlength=model.n_nodes)
    assert np.all(degree >= np.minimum(2, model.n_nodes - np.bincount(model.cluster)[model.cluster]))
    assert len(core_columns(model, 0, None)) == model.n_cols


def _core_by_lexsort(model: GtspModel, per_node: int) -> np.ndarray:
    """The core edges by one sort of both ends of every edge by (node, cost, edge position)."""
    n = model.n_nodes
    e = np.arange(len(model.tail))
    ends = np.concatenate([model.tail, model.head])
    order = np.lexsort((np.concatenate([model.cost[n:], model.cost[n:]]), ends))
    rank = np.empty(len(order), dtype=np.int64)
    start = np.searchsorted(ends[order], np.arange(n))
    rank[order] = np.arange(len(order)) - np.repeat(start, np.bincount(ends, minlength=n))
    keep = np.zeros(len(e), dtype=bool)
    keep[np.concatenate([e, e])[rank < per_node]] = True
    return np.concatenate([np.arange(n), n + np.flatnonzero(keep)])


def test_core_columns_by_blocks_of_rows_equal_one_sort_of_every_edge():
    """The cheapest edges per node, found a block of rows of the cost matrix at a time, are those
    of one sort of every edge's two ends (ties broken the same way: integer costs on a grid, many
    ties), for blocks of one row to all, and for more edges asked than a node has."""
    rng = np.random.default_rng(5)
    for _ in range(6):
        clusters = tuple(rng.integers(0, 4, size=(int(s), 2)).astype(float)
                         for s in rng.integers(1, 5, int(rng.integers(3, 8))))
        problem = price(Instance(name="grid", clusters=clusters, params=None,
                                 edge_weight_type="EUC_2D"), None)
        model = build_model(problem, problem.clusters)
        for per_node in (1, 2, 3, model.n_nodes + 1):
            expected = _core_by_lexsort(model, per_node)
            for block in (1, 7, 10**6):
                np.testing.assert_array_equal(core_columns(model, per_node, None, block), expected)
    model = _model(2, k=7)
    np.testing.assert_array_equal(core_columns(model, 3, None), _core_by_lexsort(model, 3))


def test_edge_ids_number_every_pair_between_clusters():
    """The edge number of each edge's own ends is its position; a model with an edge left out is
    refused (the numbers assume every pair between clusters)."""
    import pytest

    model = _model(4, k=6)
    np.testing.assert_array_equal(model.edge_ids(model.tail, model.head), np.arange(len(model.tail)))
    fewer = GtspModel(model.problem, model.nodes, model.cluster, model.tail[1:], model.head[1:],
                      np.delete(model.cost, model.n_nodes))
    with pytest.raises(ValueError, match="every pair"):
        fewer.edge_ids(model.tail[:1], model.head[:1])

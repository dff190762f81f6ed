"""Cuts and their separation: every cut found is valid for every tour and cuts its point off."""

from __future__ import annotations

from collections import Counter

import numpy as np
from gtsp_bench.solvers.exact.mip import branch_cut, separation
from gtsp_bench.solvers.exact.mip.model import GtspModel
from gtsp_bench.solvers.exact.mip.separation import Cuts, subtour_cut, subtour_cuts

from .test_model import _all_tours, _model, _random_tour, _vector

SEPARATORS = ("node_cluster_cuts", "flow_cuts", "blossom_cuts", "subtour_cuts")


def _capture(monkeypatch) -> list[tuple[str, GtspModel, Cuts, np.ndarray]]:
    """Record every cut block the separators return during solves, with its point.

    A separator is replaced wherever the search looks it up (the separation module, and the
    branch-and-cut module for the subtour rows of integer points).
    """
    seen: list[tuple[str, GtspModel, Cuts, np.ndarray]] = []

    def recording(name: str):
        separator = getattr(separation, name)

        def wrapped(model, values, *args):
            cuts = separator(model, values, *args)
            if cuts is not None:
                seen.append((name, model, cuts, values.copy()))
            return cuts
        return wrapped

    for name in SEPARATORS:
        wrapped = recording(name)
        for module in (separation, branch_cut):
            if hasattr(module, name):
                monkeypatch.setattr(module, name, wrapped)
    return seen


def test_every_cut_is_valid_and_violated(monkeypatch):
    """Cuts found at the LP points of real solves hold for every tour and cut their point off.

    HiGHS provides the LP points (root loop and branch and cut on tiny instances, no pruning and
    a small core so that all separators and the branching run).
    """
    from gtsp_bench.solvers.exact.milp import Milp

    seen = _capture(monkeypatch)
    found: Counter[str] = Counter()
    for seed in range(8):
        model = _model(seed, k=6, max_size=2)
        solver = Milp(prune=False, lns_trials=0, core_edges=2, root_rounds=1 + 3 * (seed % 2))
        seen.clear()
        solver.solve(model.problem.instance, model.problem.omega)
        tours = None
        for name, m, cuts, point in seen:
            tours = _all_tours(m) if tours is None else tours
            lhs = cuts.matrix(m, np.arange(m.n_cols)) @ tours.T  # (cuts, tours)
            assert np.all(lhs <= cuts.rhs[:, None] + 1e-9), name
            assert np.all(cuts.slack(m, point) < -1e-7), name
            found[name] += len(cuts)
    assert all(found[name] for name in SEPARATORS), found


def test_subtour_cuts_none_for_a_tour():
    """A tour has no subtour cut."""
    model = _model(1)
    rng = np.random.default_rng(0)
    v = _vector(model, [_random_tour(model, rng)])
    assert subtour_cuts(model, v) is None


def test_subtour_cuts_cut_off_two_cycles():
    """Two cycles: one cut (for the smaller), violated there and valid for every tour."""
    model = _model(5, k=6, max_size=1)
    v = _vector(model, [[0, 1, 2], [3, 4, 5, 6]])
    cuts = subtour_cuts(model, v)
    assert cuts is not None and len(cuts) == 1
    assert cuts.slack(model, v)[0] < -0.5
    lhs = cuts.matrix(model, np.arange(model.n_cols)) @ _all_tours(model).T
    assert np.all(lhs <= cuts.rhs[:, None] + 1e-9)


def test_stack_select_and_matrix_keep_rows_with_several_sides():
    """A blossom-like row of eight sides survives stack and select (same coefficients and slack),
    and the dual weights (both ways of computing them) are the duals times the coefficients."""
    model = _model(6, k=6)
    rng = np.random.default_rng(2)
    n = model.n_nodes
    blocks = [Cuts.one(rng.random(n) < 0.5, -rng.random(n), 1.0),
              Cuts.one(rng.random((8, n)) < 0.5, np.zeros(n), 2.5),
              Cuts.one(rng.random(n) < 0.5, -rng.random(n), 0.0)]
    cuts = Cuts.stack(blocks)
    assert len(cuts) == 3 and cuts.row.tolist() == [0, *[1] * 8, 2]
    cols = np.arange(model.n_cols)
    point = rng.random(model.n_cols)
    kept = cuts.select(np.array([False, True, True]))
    np.testing.assert_allclose(kept.matrix(model, cols), cuts.matrix(model, cols)[1:])
    np.testing.assert_allclose(kept.slack(model, point), cuts.slack(model, point)[1:])
    # slack is rhs - matrix @ point
    np.testing.assert_allclose(cuts.slack(model, point), cuts.rhs - cuts.matrix(model, cols) @ point)
    duals = np.array([-0.7, -1.3, -0.2])
    # all edges: through the node-pair matrix; a few: side by side
    for edges in (np.arange(len(model.tail)), np.arange(0, len(model.tail), 7)):
        on_edge, on_y = cuts.dual_weights(model, duals, edges)
        np.testing.assert_allclose(on_edge, duals @ cuts.matrix(model, n + edges))
        np.testing.assert_allclose(on_y, duals @ cuts.ycoef)


def test_sparsest_form_is_the_same_row_on_every_tour_with_fewer_nonzeros():
    """Sides rewritten over their crossing edges give the same left-hand side at every tour
    (the degree rows hold there), no more nonzeros over the columns it was chosen for, and dual
    weights (both ways) equal to the duals times the new coefficients."""

    model = _model(7, k=5, max_size=3)
    rng = np.random.default_rng(4)
    n = model.n_nodes
    tours = _all_tours(model)
    blocks = [subtour_cut(model, rng.random(n) < p, 0, 1) for p in (0.2, 0.5, 0.8, 0.9)]
    blocks.append(Cuts.one(rng.random((4, n)) < 0.6, np.zeros(n), 2.5))  # several sides
    cuts = Cuts.stack(blocks)
    turned = 0
    some = np.concatenate([np.arange(n), n + np.arange(0, len(model.tail), 3)])
    for cols in (np.arange(model.n_cols), some):
        sparse = cuts.sparsest(model, cols)
        turned += int(sparse.cross.sum())
        full = np.arange(model.n_cols)
        np.testing.assert_allclose(sparse.matrix(model, full) @ tours.T, cuts.matrix(model, full) @ tours.T,
                                   atol=1e-9)
        np.testing.assert_allclose(sparse.slack(model, tours[0]), cuts.slack(model, tours[0]), atol=1e-9)
        single = np.arange(len(cuts)) < len(blocks) - 1  # the rows of one side
        before = np.count_nonzero(cuts.matrix(model, cols)[single], axis=1)
        after = np.count_nonzero(sparse.matrix(model, cols)[single], axis=1)
        assert np.all(after <= before)
        duals = -rng.random(len(cuts))
        for edges in (np.arange(len(model.tail)), np.arange(0, len(model.tail), 7)):
            on_edge, on_y = sparse.dual_weights(model, duals, edges)
            np.testing.assert_allclose(on_edge, duals @ sparse.matrix(model, n + edges), atol=1e-12)
            np.testing.assert_allclose(on_y, duals @ sparse.ycoef, atol=1e-12)
    assert turned > 0


def _dense_dual_weights(cuts: Cuts, model: GtspModel, duals: np.ndarray,
                       edges: np.ndarray) -> np.ndarray:
    """The edge weights by the ``(n, n)`` node-pair product (the form before node classes)."""
    d = duals[cuts.row]
    sf = cuts.side.astype(float)
    pair = (sf * d[:, None]).T @ sf
    half = -0.5 * (d[cuts.cross] @ sf[cuts.cross])
    t, h = model.tail[edges], model.head[edges]
    return pair[t, h] + half[t] + half[h]


def _random_family(model: GtspModel, rng: np.random.Generator) -> Cuts:
    """Random cuts as the separators make them: unions of whole clusters, a cluster and one node
    of another, generalized subtour sides splitting clusters (either form), multi-side rows."""
    n, m = model.n_nodes, model.n_clusters
    blocks = []
    for _ in range(12):
        union = np.isin(model.cluster, np.flatnonzero(rng.random(m) < 0.4))
        blocks.append(Cuts.one(union, -union.astype(float), float(union.sum() - 1)))
        node_cluster = model.cluster == rng.integers(m)
        node_cluster[rng.integers(n)] = True
        blocks.append(Cuts.one(node_cluster, np.zeros(n), 1.0))
        c, d = rng.choice(m, 2, replace=False)
        blocks.append(subtour_cut(model, rng.random(n) < rng.uniform(0.2, 0.8), int(c), int(d)))
    handle = [np.isin(model.cluster, np.flatnonzero(rng.random(m) < 0.5))]
    teeth = [np.isin(model.cluster, rng.choice(m, 2, replace=False)) for _ in range(3)]
    blocks.append(Cuts.one(np.array(handle + teeth), np.zeros(n), 2.0))
    cuts = Cuts.stack(blocks)
    return cuts.sparsest(model, np.arange(model.n_cols))  # some sides crossing


def test_dual_weights_by_whole_clusters_equal_the_dense_product(monkeypatch):
    """On random cut families (sides of whole clusters, sides that split clusters, crossing sides,
    several sides a row, zero duals among them), the edge weights computed from the clusters each
    side holds whole and its other nodes (the form above ``DENSE_NODES`` nodes, here forced)
    equal the dense node-pair product and the duals times the cut matrix, over every edge and
    over a subset in another order."""
    monkeypatch.setattr(separation, "DENSE_NODES", 0)
    crossed = split = 0
    for seed in range(6):
        rng = np.random.default_rng(seed)
        model = _model(seed, k=7, max_size=4)
        cuts = _random_family(model, rng)
        crossed += int(cuts.cross.sum())
        split += sum(len(np.unique(cuts.side[k, model.cluster == c])) > 1
                     for k in range(len(cuts.row)) for c in range(model.n_clusters))
        duals = -rng.random(len(cuts)) * (rng.random(len(cuts)) < 0.7)
        n = model.n_nodes
        every = np.arange(len(model.tail))
        for edges in (every, rng.permutation(every)[:len(every) // 2 + 1]):
            nz = np.abs(duals[cuts.row]) > 1e-12
            assert len(edges) * nz.sum() >= 4 * n**2  # the clusters' path is taken
            on_edge, on_y = cuts.dual_weights(model, duals, edges)
            np.testing.assert_allclose(on_edge, _dense_dual_weights(cuts, model, duals, edges),
                                       rtol=0, atol=1e-12)
            np.testing.assert_allclose(on_edge, duals @ cuts.matrix(model, n + edges), rtol=0, atol=1e-12)
            np.testing.assert_allclose(on_y, duals @ cuts.ycoef, rtol=0, atol=1e-12)
    assert crossed > 0 and split > 0


def test_generalized_subtour_cut_holds_for_every_tour_and_is_tight():
    """``Subtour(S, C, D)`` for random node sets (splitting clusters, on either side's form)
    holds for every tour, and some tour with its heads of C inside S and of D outside meets it
    at equality (it crosses S exactly twice)."""
    rng = np.random.default_rng(3)
    model = _model(7, k=5, max_size=3)
    tours = _all_tours(model)
    cols = np.arange(model.n_cols)
    forms = Counter()
    for _ in range(60):
        s = rng.random(model.n_nodes) < rng.uniform(0.2, 0.8)
        c, d = rng.choice(model.n_clusters, 2, replace=False)
        cut = subtour_cut(model, s, int(c), int(d))
        lhs = cut.matrix(model, cols) @ tours.T
        assert np.all(lhs <= cut.rhs[:, None] + 1e-9)
        forms[(bool(np.array_equal(cut.side[0], s)), float(cut.rhs[0]))] += 1
        y = tours[:, :model.n_nodes]
        inside = (y[:, s & (model.cluster == c)].sum(1) == 1) & (y[:, ~s & (model.cluster == d)].sum(1) == 1)
        if inside.any():
            assert np.isclose(lhs[0, inside].max(), cut.rhs[0])
    assert len(forms) >= 3, forms  # both sides, with and without a whole cluster on one side


def test_network_min_cut_sides_are_minimum_cuts():
    """On random networks the two sides returned are minimum cuts: each separates source and
    sink and its arcs leaving the source side carry exactly the max-flow value."""
    from gtsp_bench.solvers.exact.mip.separation import _Network

    rng = np.random.default_rng(4)
    for _ in range(20):
        size = int(rng.integers(4, 12))
        pairs = {(int(u), int(v)) for u, v in rng.integers(0, size, (3 * size, 2)) if u < v}
        tails, heads = np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])
        net, where = _Network.build(tails, heads, size)
        cap = np.zeros(len(net.indices), dtype=np.int32)
        cap[where] = rng.integers(0, 5, len(where))
        cap[net.rev[where]] = rng.integers(0, 5, len(where))
        value, sides = net.min_cut_sides(cap, 0, size - 1)
        for sink_side in sides:
            assert sink_side[size - 1] and not sink_side[0]
            leaving = ~sink_side[net.row] & sink_side[net.indices]
            assert cap[leaving].sum() == value


def test_no_max_flow_or_handle_after_the_deadline():
    """At a fractional root point where the max-flows and the blossoms find cuts, a deadline
    already past stops both before their first max-flow or handle (the cheap node-cluster rows
    are still returned by ``separate``)."""
    from gtsp_bench.solvers.exact.mip.backends import HighsBackend, LpModel
    from gtsp_bench.solvers.exact.mip.model import build_model
    from gtsp_bench.solvers.exact.mip.options import MipOptions

    from gtsp_bench.generator import generate_instance
    from gtsp_bench.problem import price

    problem = price(generate_instance(12, 3, seed=0), 0.5)
    model = build_model(problem, problem.clusters)
    lp = LpModel(model, HighsBackend(MipOptions()), np.arange(model.n_cols))
    found = set()
    for _ in range(30):
        values = lp.full(lp.backend.solve_lp(60.0).values)
        for name in ("flow_cuts", "blossom_cuts"):
            if getattr(separation, name)(model, values) is not None:
                found.add(name)
                assert getattr(separation, name)(model, values, deadline=0.0) is None
        late = separation.separate(model, values, deadline=0.0)
        assert late is None or np.allclose(late.slack(model, values),
                                           late.slack(model, values).clip(max=0))  # all violated
        cuts = separation.separate(model, values)
        if cuts is None:
            break
        lp.add_cuts(cuts)
    assert found == {"flow_cuts", "blossom_cuts"}


def test_the_sparse_matrix_equals_the_dense_one():
    """:meth:`Cuts.sparse` gives the dense matrix exactly (sides inside and crossing, a row of
    several sides), over all columns and over a shuffled subset, and only its nonzero entries."""
    model = _model(6, k=6)
    rng = np.random.default_rng(5)
    n = model.n_nodes
    cuts = Cuts.stack([Cuts.one(rng.random(n) < 0.5, -rng.random(n), 1.0),
                       Cuts.one(rng.random((4, n)) < 0.5, np.zeros(n), 2.0)])
    crossed = Cuts(cuts.side, cuts.row, cuts.ycoef, cuts.rhs, np.array([True, False, True, True, False]))
    for block in (cuts, crossed):
        for cols in (np.arange(model.n_cols), rng.permutation(model.n_cols)[: model.n_cols // 3]):
            dense = block.matrix(model, cols)
            sparse = block.sparse(model, cols)
            assert sparse.shape == dense.shape
            assert sparse.nnz == np.count_nonzero(dense) and sparse.has_canonical_format
            np.testing.assert_array_equal(sparse.toarray(), dense)
    assert cuts.sparse(model, np.zeros(0, dtype=np.int64)).shape == (2, 0)

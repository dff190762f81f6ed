"""The backend-neutral MILP: model, cut validity (against every tour), options, helpers."""

from __future__ import annotations

import itertools
from collections import Counter

import numpy as np
import pytest
from gtsp_bench.solvers.exact import gtsp_mip as gm

from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance
from gtsp_bench.instance import Instance
from gtsp_bench.problem import price


def _model(seed: int, k: int = 5, depot: bool = True, max_size: int = 3) -> gm.GtspModel:
    rng = np.random.default_rng(seed)
    base = generate_instance(k, 3, seed=seed)
    sizes = rng.integers(1, max_size + 1, size=k)
    inst = Instance(name="m", depot=base.depot if depot else None,
                    clusters=tuple(c[:s] for c, s in zip(base.clusters, sizes, strict=True)))
    problem = price(inst, float(rng.uniform()))
    return gm.build_model(problem, problem.clusters)


def _vector(model: gm.GtspModel, cycles: list[list[int]]) -> np.ndarray:
    """Column vector of local-node cycles (each of 3 nodes or more)."""
    edge = {(int(a), int(b)): e for e, (a, b) in enumerate(zip(model.tail, model.head, strict=True))}
    v = np.zeros(model.n_cols)
    for cyc in cycles:
        v[cyc] = 1
        for a, b in zip(cyc, cyc[1:] + cyc[:1], strict=True):
            v[model.n_nodes + edge[(min(a, b), max(a, b))]] = 1
    return v


def _all_tours(model: gm.GtspModel) -> np.ndarray:
    """Every tour over the model's nodes, one row each."""
    kept = [np.flatnonzero(model.cluster == c) for c in range(model.n_clusters)]
    rows = []
    for heads in itertools.product(*kept):
        for perm in itertools.permutations(range(1, len(kept))):
            if perm[0] < perm[-1]:
                rows.append(_vector(model, [[int(heads[0]), *(int(heads[p]) for p in perm)]]))
    return np.array(rows)


def _random_tour(model: gm.GtspModel, rng: np.random.Generator) -> list[int]:
    order = rng.permutation(model.n_clusters)
    return [int(rng.choice(np.flatnonzero(model.cluster == c))) for c in order]


SEPARATORS = ("node_cluster_cuts", "flow_cuts", "blossom_cuts", "subtour_cuts")


def _capture(monkeypatch) -> list[tuple[str, gm.GtspModel, gm.Cuts, np.ndarray]]:
    """Record every cut block the separators return during solves, with its point."""
    seen: list[tuple[str, gm.GtspModel, gm.Cuts, np.ndarray]] = []

    def recording(name: str):
        separator = getattr(gm, name)

        def wrapped(model, values):
            cuts = separator(model, values)
            if cuts is not None:
                seen.append((name, model, cuts, values.copy()))
            return cuts
        return wrapped

    for name in SEPARATORS:
        monkeypatch.setattr(gm, name, recording(name))
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


def test_subtour_cuts_none_for_a_tour_and_tour_extraction():
    """A tour has no subtour cut, and tour() gives back its nodes in cycle order."""
    model = _model(1)
    rng = np.random.default_rng(0)
    cyc = _random_tour(model, rng)
    v = _vector(model, [cyc])
    assert gm.subtour_cuts(model, v) is None
    got = [int(i) for i in np.searchsorted(model.nodes, model.tour(v))]
    start = got.index(cyc[0])
    rotated = got[start:] + got[:start]
    assert rotated in (cyc, [cyc[0], *cyc[1:][::-1]])


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
    cols = gm.core_columns(model, 2, model.nodes[tour_local])
    assert set(range(model.n_nodes)) <= set(cols)
    tour_cols = np.flatnonzero(_vector(model, [tour_local])[model.n_nodes:]) + model.n_nodes
    assert set(tour_cols) <= set(cols)
    edges = cols[cols >= model.n_nodes] - model.n_nodes
    degree = np.bincount(np.concatenate([model.tail[edges], model.head[edges]]), minlength=model.n_nodes)
    assert np.all(degree >= np.minimum(2, model.n_nodes - np.bincount(model.cluster)[model.cluster]))
    assert len(gm.core_columns(model, 0, None)) == model.n_cols


@pytest.mark.parametrize("bad, message", [
    ({"prune": "yes"}, "prune must be true or false"),
    ({"lns_trials": -1}, "lns_trials must be an integer >= 0"),
    ({"root_rounds": 1.5}, "root_rounds must be an integer >= 0"),
    ({"core_edges": True}, "core_edges must be an integer >= 0"),
    ({"abs_gap": float("nan")}, "abs_gap must be a number"),
    ({"abs_gap": -1.0}, "abs_gap must be a number"),
])
def test_options_are_validated(bad, message):
    """Bad option values raise InputError naming the option."""
    with pytest.raises(InputError, match=message):
        gm.MipOptions(**bad)


def test_asymmetric_costs_are_refused():
    """An EXPLICIT instance with asymmetric weights is refused with a clear message."""
    w = np.array([[0, 1, 2, 3], [5, 0, 1, 2], [2, 1, 0, 1], [3, 2, 1, 0]], dtype=float)
    inst = Instance(name="asym", clusters=tuple(np.zeros((1, 2)) for _ in range(4)), params=None,
                    edge_weight_type="EXPLICIT", weights=w)
    with pytest.raises(InputError, match="not symmetric"):
        gm.check_symmetric(price(inst, None))

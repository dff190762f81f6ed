"""Labels of the imitation training: lns tours of seeded sets, the same in worker processes,
cached with the validation sets' references so that a second run solves nothing."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("torch")

from gtsp_bench.solvers.heads import optimal_heads
from gtsp_bench.solvers.learned.imitation import get_recipe
from gtsp_bench.solvers.learned.labels import (
    label_set,
    load_or_solve_labels,
    parse_entry,
    solve_labels,
    validation_set,
)

from gtsp_bench.problem import price


def test_label_sets_are_seeded_and_tiled_ones_at_omega_zero():
    insts, omegas = label_set(6, 3, 1000.0, 71_000, 20, 0.9, tiled=True)
    assert [i.name for i in insts] == [f"tiled-K6-s71000-{i:03d}" for i in range(3)]
    assert (omegas == 0).all()
    a, wa = label_set(5, 4, 1000.0, 71_000, 6, 0.9)
    b, wb = label_set(5, 4, 1000.0, 71_000, 6, 0.9)
    assert (wa == wb).all() and ((wa >= 0) & (wa <= 0.9)).all() and len(set(wa)) == 4
    assert [x.coords.tolist() for x in a] == [x.coords.tolist() for x in b]
    assert parse_entry((20, 5, 1000.0, "tiled")) == (20, 5, 1000.0, True)
    assert parse_entry((20, 5, 1000)) == (20, 5, 1000.0, False)


def test_workers_give_the_same_labels():
    """Labels solved in two forked processes equal those of one; each is a tour priced at its
    value."""
    insts, omegas = label_set(6, 4, 1000.0, 71_000, 6, 0.9)
    one, v1 = solve_labels(insts, omegas)
    two, v2 = solve_labels(insts, omegas, workers=2)
    assert (one == two).all() and (v1 == v2).all()
    for inst, w, order, value in zip(insts, omegas, one, v1, strict=True):
        assert sorted(order) == list(range(6))
        # lns's heads are the best for its order: the value is that order's optimal-heads price
        assert value == pytest.approx(optimal_heads(price(inst, float(w)), list(order))[1])


def test_cache_holds_labels_and_validation_references(tmp_path):
    """The first call solves the mix and the validation sets into the cache; the second reads
    them back (no time spent) unchanged; a validation reference is lns's value at omega 0.3 /
    0.6 in turn."""
    cfg = get_recipe("local-small", mix=((5, 3, 1000.0),), val=((5, 2, 1000.0), (6, 2, 1000.0)))
    cache = tmp_path / "c.npz"
    orders, refs, spent = load_or_solve_labels(cfg, cache)
    assert spent > 0 and set(orders) == {(5, 3, 1000.0)} and set(refs) == set(cfg.val)
    again, refs2, spent2 = load_or_solve_labels(cfg, cache)
    assert spent2 == 0.0
    assert (again[(5, 3, 1000.0)] == orders[(5, 3, 1000.0)]).all()
    assert all((refs[e] == refs2[e]).all() for e in cfg.val)
    insts, omegas = validation_set((6, 2, 1000.0), 20)
    assert omegas == [0.3, 0.6]
    assert np.allclose(refs[(6, 2, 1000.0)], solve_labels(insts, omegas)[1])

"""Columns leaving the branch and cut's LP: aging, which leave, node bounds, and exactness."""

from __future__ import annotations

import numpy as np
import pytest
from gtsp_bench.solvers.exact.mip import columns
from gtsp_bench.solvers.exact.mip.backends import HighsBackend
from gtsp_bench.solvers.exact.mip.options import MipOptions
from gtsp_bench.solvers.exact.mip.solve import solve_exact

from gtsp_bench.generator import generate_instance
from gtsp_bench.problem import price
from gtsp_bench.registry import run_solver


def test_a_column_ages_while_its_reduced_cost_stays_above_the_share_of_the_gap(monkeypatch):
    monkeypatch.setattr(columns, "DROP_SHARE", 0.5)
    age = np.array([0, 2, 5, 1, 3])
    rc = np.array([1.1, 0.9, 3.0, 1.0, -2.0])  # gap 2: large above 1
    np.testing.assert_array_equal(columns.age_columns(age, rc, 2.0), [1, 0, 6, 0, 0])
    # a negative gap (an LP above the incumbent) counts as 0: any positive reduced cost is large
    np.testing.assert_array_equal(columns.age_columns(age, rc, -1.0), [1, 3, 6, 2, 0])


def test_stale_columns_are_old_enough_and_not_kept(monkeypatch):
    monkeypatch.setattr(columns, "DROP_AGE", 3)
    age = np.array([3, 2, 4, 7])
    keep = np.array([False, False, True, False])
    np.testing.assert_array_equal(columns.stale_columns(age, keep), [0, 3])
    monkeypatch.setattr(columns, "DROP_AGE", 0)
    assert len(columns.stale_columns(age, keep)) == 0


def test_the_share_and_the_age_limit_can_be_given():
    age = np.array([0, 2, 5])
    rc = np.array([0.3, 0.1, 3.0])  # gap 2: above 0.2 with share 0.1
    np.testing.assert_array_equal(columns.age_columns(age, rc, 2.0, share=0.1), [1, 0, 6])
    keep = np.zeros(3, dtype=bool)
    np.testing.assert_array_equal(columns.stale_columns(np.array([1, 0, 6]), keep, limit=1), [0, 2])
    assert len(columns.stale_columns(np.array([1, 0, 6]), keep, limit=0)) == 0


def test_the_root_drops_only_edge_columns_aged_enough(monkeypatch):
    """drop_root_stale: a y column never leaves; an edge column leaves at ROOT_DROP_AGE."""
    monkeypatch.setattr(columns, "ROOT_DROP_SHARE", 0.1)
    monkeypatch.setattr(columns, "ROOT_DROP_AGE", 2)

    class Lp:  # the three attributes drop_root_stale reads, and the drop it calls
        def __init__(self) -> None:
            self.model = type("M", (), {"n_nodes": 3})()
            self.cols = np.array([0, 1, 2, 5, 7, 9])
            self.col_age = np.array([1, 1, 0, 1, 0, 1])
            self.dropped: list[np.ndarray] = []

        def drop_cols(self, positions):
            self.dropped.append(positions)
            self.cols = np.delete(self.cols, positions)
            self.col_age = np.delete(self.col_age, positions)

    lp = Lp()
    rc = np.array([5.0, 5.0, 5.0, 5.0, 5.0, 0.1])  # gap 10: large above 1
    np.testing.assert_array_equal(columns.drop_root_stale(lp, rc, 10.0), [5])
    np.testing.assert_array_equal(lp.dropped[0], [3])  # model column 5: an edge aged 2
    np.testing.assert_array_equal(lp.cols, [0, 1, 2, 7, 9])
    np.testing.assert_array_equal(lp.col_age, [2, 2, 1, 1, 0])


def test_bound_moves_change_only_the_lp_columns_whose_code_differs():
    applied = np.array([-1, 0, 1, -1, 0, -1], dtype=np.int8)
    target = np.array([1, -1, 1, 0, 0, -1], dtype=np.int8)
    fixed = np.array([False, True, False, False, False, False])
    cols = np.array([4, 1, 0, 2, 3])  # model column 5 is not in the LP: its code is irrelevant
    change, lower, upper = columns.bound_moves(target, applied, cols, fixed)
    np.testing.assert_array_equal(change, [1, 2, 4])  # model columns 1, 0 and 3
    np.testing.assert_array_equal(lower, [0.0, 1.0, 0.0])
    np.testing.assert_array_equal(upper, [0.0, 1.0, 0.0])  # column 1 is free but fixed for the search
    change, lower, upper = columns.bound_moves(target, target, cols, fixed)
    assert len(change) == 0


@pytest.mark.parametrize("share", [0.0, columns.DROP_SHARE])
@pytest.mark.parametrize("seed", range(6))
def test_dropping_priced_out_columns_after_one_lp_keeps_the_search_exact(seed, share, monkeypatch):
    """Columns leave after one node LP, with any positive reduced cost (share 0: the most dropping
    there can be) or at the default share: the branch and cut, left the work by one root round
    and the greedy tour, still proves the dp optimum, and columns did leave."""
    monkeypatch.setattr(columns, "DROP_AGE", 1)
    monkeypatch.setattr(columns, "DROP_SHARE", share)
    inst = generate_instance(9, 5, seed=seed)
    r = solve_exact(price(inst, 0.5), HighsBackend, MipOptions(root_rounds=1, lns_trials=0))
    assert r.status == "optimal"
    assert r.objective == pytest.approx(run_solver("dp", inst, 0.5).objective, rel=1e-9)
    assert r.lower_bound == pytest.approx(r.objective, rel=1e-9)
    assert r.stats["bc_nodes"] >= 1 and r.stats.get("cols_dropped", 0) > 0

"""Tests for the pseudo-costs and reliability branching of the branch and cut."""

from __future__ import annotations

import math

import numpy as np
import pytest
from gtsp_bench.solvers.exact.mip import branching
from gtsp_bench.solvers.exact.mip.backends import HighsBackend
from gtsp_bench.solvers.exact.mip.branching import PseudoCosts, StrongResult, choose, score
from gtsp_bench.solvers.exact.mip.options import MipOptions
from gtsp_bench.solvers.exact.mip.solve import solve_exact

from gtsp_bench.generator import generate_instance
from gtsp_bench.problem import price
from gtsp_bench.registry import run_solver


def test_pseudo_costs_are_means_per_unit_of_change():
    pc = PseudoCosts(4)
    pc.record(1, False, 3.0, 0.25)  # down by 0.25: 12 per unit
    pc.record(1, False, 1.0, 0.5)  # 2 per unit
    pc.record(1, True, 1.5, 0.25)  # up by 0.75: 2 per unit
    pc.record(2, True, -4.0, 0.5)  # a loss counts as no gain
    pc.record(3, True, math.inf, 0.5)  # ignored
    pc.record(3, False, 1.0, 0.0)  # an integral value: ignored
    assert pc.counts.tolist() == [[0, 2, 0, 0], [0, 1, 1, 0]]
    unit = pc.per_unit(np.array([1, 2, 0]))
    assert unit[:, 0].tolist() == pytest.approx([7.0, 2.0])
    assert unit[:, 1].tolist() == pytest.approx([7.0, 0.0])  # no down observation: the mean
    assert unit[:, 2].tolist() == pytest.approx([7.0, 1.0])  # up mean: (2 + 0) / 2
    est = pc.estimate(np.array([1]), np.array([0.4]))
    assert est[:, 0].tolist() == pytest.approx([7.0 * 0.4, 2.0 * 0.6])
    assert pc.reliable(np.array([1, 2, 0]), 1).tolist() == [True, False, False]
    assert pc.reliable(np.array([1]), 2).tolist() == [False]
    assert PseudoCosts(2).mean(True) == 1.0  # nothing seen yet


def _strong_from(table: dict[int, StrongResult], calls: list[int]):
    def strong(col: int) -> StrongResult:
        calls.append(col)
        return table[col]
    return strong


def test_choose_strong_branches_unreliable_candidates_and_takes_the_best_product():
    pc = PseudoCosts(10)
    table = {0: StrongResult((11.0, 12.0), (False, False)),  # gains 1 x 2
             1: StrongResult((13.0, 13.0), (False, False)),  # 3 x 3: the best
             2: StrongResult((10.0, 19.0), (False, False))}  # 0 x 9 (floored)
    calls: list[int] = []
    c = choose(np.array([0, 1, 2]), np.array([5, 6, 7]), np.array([0.5, 0.4, 0.3]), 10.0, 100.0,
               pc, _strong_from(table, calls))
    assert sorted(calls) == [0, 1, 2]
    assert (c.col, c.value, c.only) == (1, 0.0, False)
    assert pc.counts[:, [5, 6, 7]].tolist() == [[1, 1, 1], [1, 1, 1]]
    # gain capped at the incumbent: 3 over 0.4 down
    assert pc.sums[0, 6] == pytest.approx(3.0 / 0.4)


def test_choose_trusts_reliable_pseudo_costs_without_lps():
    pc = PseudoCosts(3)
    for _ in range(2):
        pc.record(0, False, 1.0, 0.5)
        pc.record(0, True, 1.0, 0.5)
        pc.record(1, False, 5.0, 0.5)
        pc.record(1, True, 4.0, 0.5)
    calls: list[int] = []
    c = choose(np.array([0, 1]), np.array([0, 1]), np.array([0.5, 0.5]), 0.0, 100.0, pc,
               _strong_from({}, calls), reliable=2)
    assert calls == []
    assert (c.col, c.value) == (1, 1.0)  # the up child's estimate (4 x 0.5) is the lower


def test_choose_lookahead_and_budget_limit_the_strong_lps():
    pc = PseudoCosts(8)
    table = {i: StrongResult((1.0 + (i == 0), 1.0 + (i == 0)), (False, False)) for i in range(8)}
    calls: list[int] = []
    c = choose(np.arange(8), np.arange(8), np.full(8, 0.5), 0.0, 100.0, pc,
               _strong_from(table, calls), lookahead=2, max_strong=8)
    assert len(calls) == 3  # the best first (by fraction order: 0), then two without a gain
    assert c.col == 0
    calls.clear()
    choose(np.arange(8), np.arange(8), np.full(8, 0.5), 0.0, 100.0, PseudoCosts(8),
           _strong_from(table, calls), lookahead=8, max_strong=5)
    assert len(calls) == 5
    calls.clear()
    choose(np.arange(8), np.arange(8), np.full(8, 0.5), 0.0, 100.0, PseudoCosts(8),
           _strong_from(table, calls), stop=lambda: True)
    assert calls == []


def test_choose_fixes_or_prunes_on_empty_children():
    calls: list[int] = []
    one = {0: StrongResult((math.inf, 3.0), (True, False))}
    c = choose(np.array([0, 1]), np.array([0, 1]), np.array([0.5, 0.2]), 0.0, 100.0,
               PseudoCosts(2), _strong_from(one, calls))
    assert (c.col, c.value, c.only) == (0, 1.0, True)
    both = {0: StrongResult((math.inf, math.inf), (True, True))}
    assert choose(np.array([0, 1]), np.array([0, 1]), np.array([0.5, 0.2]), 0.0, 100.0,
                  PseudoCosts(2), _strong_from(both, [])) is None
    with pytest.raises(ValueError):
        choose(np.array([], dtype=int), np.array([], dtype=int), np.array([]), 0.0, 1.0,
               PseudoCosts(1), _strong_from({}, []))


def test_score_floors_each_gain():
    assert score(2.0, 3.0, 10.0) == 6.0
    assert score(0.0, 3.0, 1e6) == pytest.approx(3.0)  # floor 1e-6 x 1e6 = 1


@pytest.mark.parametrize("share", [0.0, 2.0])
@pytest.mark.parametrize("seed", range(3))
def test_branch_and_cut_with_either_branching_proves_the_dp_optimum(share, seed, monkeypatch):
    """A K = 8 instance left to the branch and cut (two root rounds, greedy tour): with
    reliability branching (from the 16th strong-branching LP on, whatever their iterations) and
    with strong branching only, the dp optimum is proven."""
    monkeypatch.setattr(branching, "PARTIAL_SHARE", share)
    inst = generate_instance(8, 6, seed=seed + 5)
    r = solve_exact(price(inst, 0.5), HighsBackend, MipOptions(root_rounds=2, lns_trials=0))
    assert r.status == "optimal"
    assert r.objective == pytest.approx(run_solver("dp", inst, 0.5).objective, rel=1e-9)
    assert r.stats["bc_nodes"] >= 1


def test_the_branching_option_fixes_the_rule_and_each_proves_the_dp_optimum():
    """A K = 16 instance that branches: "strong" strong-branches every close candidate at every
    node (as "auto" does while strong LPs finish), "reliability" trusts pseudo-costs from the
    first node on and so solves fewer strong LPs; each proves the dp optimum."""
    inst = generate_instance(16, 6, seed=8)
    best = run_solver("dp", inst, 0.5).objective
    got = {}
    for mode in ("auto", "strong", "reliability"):
        r = solve_exact(price(inst, 0.5), HighsBackend,
                        MipOptions(root_rounds=2, lns_trials=0, branching=mode))
        assert r.status == "optimal" and r.objective == pytest.approx(best, rel=1e-9), mode
        got[mode] = r.stats["strong_lps"]
    assert got["strong"] == got["auto"] > got["reliability"] > 0


def test_reliability_needs_two_nodes_of_mostly_stopped_strong_lps():
    assert not branching.reliability(0, 0)
    assert not branching.reliability(2 * branching.CANDIDATES - 1, 2 * branching.CANDIDATES - 1)
    assert branching.reliability(2 * branching.CANDIDATES, branching.CANDIDATES)
    assert not branching.reliability(100, 49)
    assert branching.reliability(100, 50)


def test_choose_by_default_strong_branches_at_most_max_strong():
    """Each candidate scores better than the last (the look-ahead never stops it): the default
    budget :data:`MAX_STRONG` does."""
    from gtsp_bench.solvers.exact.mip.branching import MAX_STRONG

    table = {i: StrongResult((1.0 + i, 1.0 + i), (False, False)) for i in range(8)}
    calls: list[int] = []
    c = choose(np.arange(8), np.arange(8), np.full(8, 0.5), 0.0, 100.0, PseudoCosts(8),
               _strong_from(table, calls))
    assert len(calls) == MAX_STRONG < 8
    assert c.col == calls[-1]

"""Anytime metrics: Berthold's primal gap and integral, times to target, the compact trajectory."""

from __future__ import annotations

import math

import pytest

from gtsp_bench.bench.anytime import (
    format_trajectory,
    metrics,
    parse_trajectory,
    points_of,
    primal_gap,
    primal_integral,
    proof_time,
    time_to_target,
)


def test_primal_gap_follows_berthold():
    """0 at the reference, relative to the larger magnitude, 1 for opposite signs, capped at 1."""
    assert primal_gap(100.0, 100.0) == 0.0 and primal_gap(0.0, 0.0) == 0.0
    assert primal_gap(110.0, 100.0) == pytest.approx(10 / 110)
    assert primal_gap(-5.0, 5.0) == 1.0
    assert primal_gap(1e9, 1.0) == pytest.approx(1 - 1e-9)


def test_primal_integral_of_a_step_trajectory_by_hand():
    """Nothing for 1 s, 110 until 3 s, then the reference 100, over a 10 s limit."""
    points = [(1.0, 110.0, None), (3.0, 100.0, None)]
    assert primal_integral(points, 100.0, 10.0) == pytest.approx((1 + 2 * 10 / 110) / 10)
    assert primal_integral([], 100.0, 10.0) == 1.0
    assert primal_integral([(0.0, 100.0, None)], 100.0, 10.0) == 0.0
    assert math.isnan(primal_integral(points, math.nan, 10.0))
    assert math.isnan(primal_integral(points, 100.0, 0.0))


def test_points_after_the_horizon_count_up_to_it_only():
    """A solve that answers after its limit (a hard-killed overrun) integrates to the limit."""
    assert primal_integral([(12.0, 100.0, None)], 100.0, 10.0) == 1.0


def test_time_to_target_is_the_first_incumbent_within_it():
    """1 %: reached at 3 s by 100.5; 0.1 %: at 5 s by 100.0; never when the run stops above."""
    points = [(1.0, 110.0, None), (3.0, 100.5, None), (5.0, 100.0, None)]
    assert time_to_target(points, 100.0, 0.01) == 3.0
    assert time_to_target(points, 100.0, 0.001) == 5.0
    assert math.isnan(time_to_target(points[:1], 100.0, 0.01))
    assert math.isnan(time_to_target(points, 100.0, 0.001, horizon=4.0)), "after the limit: not in time"
    m = metrics(points, 100.0, 10.0)
    assert m["time_to_1pct_s"] == 3.0 and m["time_to_0p1pct_s"] == 5.0 and 0 < m["primal_integral"] < 1


def test_a_record_without_trajectory_is_its_answer_at_its_runtime():
    """Older logs and one-answer solvers: one point; a failed solve: none."""
    assert points_of(None, 2.5, 7.0) == [(2.5, 7.0, None)]
    assert points_of([[0.1, 9.0, None], [0.2, 7.0, 6.5]], 2.5, 7.0) == [(0.1, 9.0, None), (0.2, 7.0, 6.5)]
    assert points_of(None, math.nan, math.nan) == []


def test_the_compact_trajectory_round_trips():
    """format_trajectory then parse_trajectory gives the points back (times to 4 digits)."""
    points = [(0.001234, 1549.261192, None), (0.5, 1443.592956, 1400.25)]
    assert parse_trajectory(format_trajectory(points)) == points
    assert parse_trajectory("") == []


def test_proof_time_is_when_the_bound_first_meets_the_answer():
    """Integer costs: the bound within 1 of the cost; a bound short of it, or none, is no proof."""
    points = [(1.0, 110.0, None), (2.0, 105.0, 98.5), (3.0, 105.0, 99.0), (9.0, 105.0, 105.0)]
    assert proof_time(points, 100.0, 1.0) == 3.0
    assert proof_time(points, 105.0, 0.0) == 9.0
    assert math.isnan(proof_time(points[:2], 100.0, 1.0))

"""Performance profiles and gap tables on hand-made rows, and their plots."""

from __future__ import annotations

import math

import matplotlib
import numpy as np
import pandas as pd
import pytest

from gtsp_bench.report.profiles import (
    gap_by_k,
    gap_k_figure,
    gap_time,
    gap_time_figure,
    performance_profile,
    plot_profile,
    profile_figure,
    profile_ratios,
)

matplotlib.use("Agg")
NAN = math.nan
#: 3 solvers x 5 instances; NaN: no answer. Instance e has none and is left out.
OBJ = {
    "a": {"x": 10, "y": 12, "z": 15},    # best 10: ratios 1, 1.2, 1.5
    "b": {"x": 20, "y": 20, "z": NAN},   # best 20: 1, 1, inf
    "c": {"x": NAN, "y": 30, "z": 33},   # best 30: inf, 1, 1.1
    "d": {"x": 8, "y": 10, "z": 8},      # best 8: 1, 1.25, 1
    "e": {"x": NAN, "y": NAN, "z": NAN},
}


def _rows() -> pd.DataFrame:
    return pd.DataFrame([{"set": "s", "instance": i, "omega": NAN, "seed": 0, "solver": s, "objective": v}
                         for i, by in OBJ.items() for s, v in by.items()])


def test_ratios_by_hand():
    r = profile_ratios(_rows())
    assert list(r.columns) == ["x", "y", "z"]
    assert [k[1] for k in r.index] == ["a", "b", "c", "d"]
    assert np.allclose(r.to_numpy(), [[1, 1.2, 1.5], [1, 1, np.inf], [np.inf, 1, 1.1], [1, 1.25, 1]])


def test_profile_fractions_by_hand():
    """rho_s(tau) = share of the 4 answered instances with ratio <= tau, at every step point."""
    p = performance_profile(_rows())
    assert sorted(p["tau"].unique()) == pytest.approx([1, 1.1, 1.2, 1.25, 1.5])
    got = {s: g.sort_values("tau")["fraction"].tolist() for s, g in p.groupby("solver")}
    assert got == {"x": [0.75] * 5, "y": [0.5, 0.5, 0.75, 1, 1], "z": [0.25, 0.5, 0.5, 0.5, 0.75]}


def test_seeds_and_omegas_are_separate_problems():
    """A problem is (set, instance, omega, seed): two seeds are two problems; a zero best is
    matched exactly."""
    df = pd.DataFrame({"set": "s", "instance": "a", "omega": [0.5, 0.5, 0.5, 0.5, 0.9, 0.9],
                       "seed": [0, 0, 1, 1, 0, 0], "solver": ["x", "y"] * 3,
                       "objective": [1.0, 2.0, 4.0, 2.0, 0.0, 0.0]})
    r = profile_ratios(df)
    assert len(r) == 3 and r.loc[("s", "a", 0.5, 1), "x"] == 2.0 and (r.loc[("s", "a", 0.9, 0)] == 1).all()


def test_gap_tables_and_plots():
    df = pd.DataFrame({"set": "s", "solver": ["x", "x", "y", "y", "x"], "K": [5, 5, 5, 50, 50],
                       "gap_percent": [1.0, 3.0, 0.0, 2.0, NAN], "runtime_s": [0.1, 0.3, 1.0, 2.0, 5.0],
                       "instance": list("abcde"), "omega": 0.5, "seed": 0,
                       "objective": [101, 103, 100, 102, NAN]})
    gk = gap_by_k(df)
    assert gk[["solver", "K", "mean_gap_pct", "max_gap_pct", "n"]].values.tolist() == [
        ["x", 5, 2.0, 3.0, 2], ["y", 5, 0.0, 0.0, 1], ["y", 50, 2.0, 2.0, 1]]
    gt = gap_time(df)
    assert gt[["solver", "median_s", "mean_gap_pct", "n"]].values.tolist() == [["x", 0.2, 2.0, 2],
                                                                                ["y", 1.5, 1.0, 2]]
    for fig in (profile_figure(performance_profile(df)), gap_k_figure(gk), gap_time_figure(df)):
        ax = fig.axes[0]
        assert ax.get_legend() is not None and len(ax.get_legend().get_texts()) == 2
    from matplotlib.figure import Figure

    ax = Figure().subplots()
    assert plot_profile(performance_profile(df), ax=ax) is ax
    assert ax.get_xlim()[0] == 1.0

"""The experiments' figures, laid out from the committed result tables: one panel per K or omega
as the paper has them, titles that say what is shown, and PNG files written whole."""

from __future__ import annotations

import matplotlib
import pandas as pd
import pytest

from gtsp_bench.data.io import read_instance
from gtsp_bench.generator import generate_instance
from gtsp_bench.report.figures import experiment_figure, save_png, tour_figure, training_figure
from tests.conftest import REPO

matplotlib.use("Agg")
RESULTS = REPO / "results" / "paper"


def _table(name: str) -> pd.DataFrame:
    return pd.read_csv(RESULTS / f"{name}.csv", keep_default_na=False, na_values=[""])


def _visible(fig) -> list:
    return [ax for ax in fig.axes if ax.get_visible()]


def test_ratio_omega_has_one_panel_per_k():
    """K = 4 and 7: two panels, each titled with its K and instance count."""
    fig = experiment_figure("ratio-omega", _table("ratio-omega"), {})
    titles = [ax.get_title() for ax in _visible(fig)]
    assert titles == ["Energy / optimum, K = 4 (30 instances)", "Energy / optimum, K = 7 (30 instances)"]


def test_ratio_k_is_titled_with_its_omega():
    """One panel, omega 0.5 in its title."""
    fig = experiment_figure("ratio-k", _table("ratio-k"), {})
    assert [ax.get_title() for ax in _visible(fig)] == ["Energy / optimum, omega = 0.5"]


def test_trajectories_one_panel_per_k_and_omega(tmp_path):
    """Four omegas at K = 4 and at K = 7, drawn on each K's first instance; the PNG is whole."""
    first = {k: read_instance(REPO / "instances" / f"uav-K{k}-N20-s1" / f"uav-K{k}-N20-s1-000.json")
             for k in (4, 7)}
    fig = experiment_figure("trajectories", _table("trajectories"), first)
    assert len(_visible(fig)) == 8
    save_png(fig, tmp_path / "t.png")
    assert (tmp_path / "t.png").read_bytes().startswith(b"\x89PNG\r\n\x1a\n")


def test_training_figure_has_three_panels():
    """Loss, reward and validation energy side by side."""
    df = _table("training")
    assert len(_visible(training_figure(df))) == 3


def test_an_unknown_experiment_is_refused():
    """Only the paper's experiments have a figure."""
    with pytest.raises(ValueError, match="training"):
        experiment_figure("training", _table("ratio-k"), {})


def test_tour_figure_one_panel_per_solution():
    """Two solutions side by side under the instance's name; none: the instance alone; four: a
    second row, the unused panels hidden."""
    inst = generate_instance(3, 4, seed=2)
    tours = [("a", [0, 1, 2], [0, 0, 0]), ("b", [2, 1, 0], [1, 1, 1])]
    fig = tour_figure(inst, tours)
    assert [ax.get_title() for ax in _visible(fig)] == ["a", "b"]
    assert fig.get_suptitle() == inst.name
    assert [ax.get_title() for ax in _visible(tour_figure(inst, []))] == [inst.name]
    fig = tour_figure(inst, tours * 2)
    assert len(fig.axes) == 6 and len(_visible(fig)) == 4

"""Plot functions: each draws what it is given on the Axes passed (or a new one) and returns it."""

from __future__ import annotations

import io

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from gtsp_bench.generator import generate_instance
from gtsp_bench.report import plots
from gtsp_bench.report.paper import PAPER_RUNTIME_S

matplotlib.use("Agg")


@pytest.fixture
def rows() -> pd.DataFrame:
    """Tidy rows: two solvers and the reference over two omegas and two K, two instances each."""
    out = []
    for k in (4, 5):
        for w in (0.0, 0.5):
            for i in range(2):
                for s, r, t in (("greedy", 1.1 + 0.1 * i, 0.001), ("aco", 1.02, 0.5), ("dp", 1.0, 0.05)):
                    out.append({"K": k, "omega": w, "instance": f"i{i}", "solver": s, "ratio": r,
                                "runtime_s": t * k, "status": "optimal" if s == "dp" else "feasible"})
    return pd.DataFrame(out)


def _png(ax) -> bytes:
    buf = io.BytesIO()
    ax.figure.savefig(buf, format="png")
    return buf.getvalue()


def test_plot_ratio_means_and_spread(rows):
    """One error-bar series per non-reference solver at the mean ratio, plus the line at 1."""
    ax = Figure().subplots()
    assert plots.plot_ratio(rows[rows["K"] == 4], "omega", ax=ax, reference="dp") is ax
    labels = ax.get_legend_handles_labels()[1]
    assert labels == ["optimum (dp)", "aco", "greedy"]
    greedy = next(c for c in ax.containers if c.get_label() == "greedy")
    assert np.allclose(greedy.lines[0].get_ydata(), [1.15, 1.15])
    assert _png(ax).startswith(b"\x89PNG")


def test_plot_runtime_log_scale_with_paper_values(rows):
    """Median seconds per solver against K on a log axis; the paper's values dashed."""
    ax = Figure().subplots()
    plots.plot_runtime(rows, ax=ax, paper=PAPER_RUNTIME_S)
    assert ax.get_yscale() == "log"
    lines = {line.get_label(): line for line in ax.get_lines()}
    assert np.allclose(lines["aco"].get_ydata(), [2.0, 2.5])
    assert lines["paper: Gurobi"].get_linestyle() == "--"
    assert set(lines) == {"aco", "dp", "greedy", *(f"paper: {m}" for m in PAPER_RUNTIME_S)}


def test_plot_trajectory_draws_closed_tours_through_heads():
    """Each tour starts and ends at the base station and passes through the chosen heads."""
    inst = generate_instance(3, 4, seed=2)
    ax = Figure().subplots()
    plots.plot_trajectory(inst, {"greedy": ([2, 0, 1], [0, 1, 2]), "dp": ([0, 1, 2], [3, 3, 3])},
                          ax=ax, title="K = 3")
    line = next(ln for ln in ax.get_lines() if ln.get_label() == "greedy")
    xy = np.column_stack([line.get_xdata(), line.get_ydata()])
    assert np.allclose(xy[0], inst.depot) and np.allclose(xy[-1], inst.depot)
    heads = [inst.clusters[2][2], inst.clusters[0][0], inst.clusters[1][1]]  # heads[k]: cluster k's
    assert np.allclose(xy[1:4], heads) and len(xy) == 5
    assert ax.get_title() == "K = 3"


def test_plot_training_one_line_per_model():
    """One line per model, step on x."""
    df = pd.DataFrame({"model": ["a", "a", "b"], "step": [0, 10, 0], "loss": [3.0, 1.0, 2.0]})
    ax = Figure().subplots()
    plots.plot_training(df, "loss", ax=ax)
    assert [ln.get_label() for ln in ax.get_lines()] == ["a", "b"]
    assert list(ax.get_lines()[0].get_xdata()) == [0, 10]


def test_plot_training_skips_empty_steps():
    """A sparsely logged column (validation every few steps) still draws one connected line."""
    df = pd.DataFrame({"model": ["a"] * 4, "step": [0, 10, 20, 30],
                       "val_energy": [5.0, np.nan, 4.0, np.nan]})
    ax = Figure().subplots()
    plots.plot_training(df, "val_energy", ax=ax)
    line = ax.get_lines()[0]
    assert list(line.get_xdata()) == [0, 20] and list(line.get_ydata()) == [5.0, 4.0]


def test_without_ax_a_new_figure_is_made(rows):
    """ax=None draws on a new pyplot figure and returns its Axes."""
    ax = plots.plot_ratio(rows, "K")
    try:
        assert ax.figure is plt.gcf() and ax.get_xlabel() == "K"
    finally:
        plt.close(ax.figure)


def test_solver_colors_are_stable():
    """Known solvers keep their colour; unknown names get the same colour every time."""
    assert plots.solver_color("greedy") == "tab:orange"
    assert plots.solver_color("new-solver") == plots.solver_color("new-solver")

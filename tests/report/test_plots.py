"""Plot functions: each draws what it is given on the Axes passed (or a new one) and returns it."""

from __future__ import annotations

import io

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from gtsp_bench.data.io import read_instance
from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance
from gtsp_bench.report import plots
from gtsp_bench.report.paper import PAPER_RUNTIME_S
from tests.conftest import GTSPLIB

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


def _line(ax, label: str) -> np.ndarray:
    line = next(ln for ln in ax.get_lines() if ln.get_label() == label)
    return np.column_stack([line.get_xdata(), line.get_ydata()])


def test_plot_tour_flies_from_the_base_station_through_the_chosen_heads():
    """A UAV tour: base station, the heads in visiting order, base station; every node drawn as a
    candidate head, one shaded hull per cluster, the chosen heads marked on top."""
    inst = generate_instance(3, 4, seed=2)
    ax = Figure().subplots()
    assert plots.plot_tour(inst, [2, 0, 1], [0, 1, 2], ax=ax, title="greedy") is ax
    xy = _line(ax, "tour")
    heads = [inst.clusters[2][2], inst.clusters[0][0], inst.clusters[1][1]]
    assert np.allclose(xy, [inst.depot, *heads, inst.depot])
    marks = {c.get_label(): c for c in ax.collections}
    assert len(marks["candidate heads"].get_offsets()) == inst.n_nodes
    assert np.allclose(marks["chosen heads"].get_offsets(), heads)
    assert np.allclose(marks["base station"].get_offsets(), [inst.depot])
    assert len(ax.collections[0].get_paths()) == 3  # the clusters' hulls
    assert ax.get_title() == "greedy" and ax.get_xlabel() == "x (m)"


def test_plot_tour_of_a_gtsplib_file_is_a_closed_cycle():
    """No base station: the tour returns from the last head to the first; no solution, no tour."""
    inst = read_instance(GTSPLIB / "11berlin52.gtsp.gz")
    ax = Figure().subplots()
    plots.plot_tour(inst, list(range(11)), [0] * 11, ax=ax)
    xy = _line(ax, "tour")
    assert len(xy) == 12 and np.allclose(xy[0], xy[-1]) and np.allclose(xy[0], inst.clusters[0][0])
    assert "base station" not in [c.get_label() for c in ax.collections]
    bare = plots.plot_tour(inst, ax=Figure().subplots())
    assert bare.get_lines() == [] and "chosen heads" not in [c.get_label() for c in bare.collections]


def test_plot_tour_draws_geo_coordinates_with_longitude_across():
    """GEO files give (latitude, longitude): the x axis is the longitude."""
    inst = read_instance(GTSPLIB / "20gr96.gtsp.gz")
    ax = plots.plot_tour(inst, ax=Figure().subplots())
    points = next(c for c in ax.collections if c.get_label() == "candidate heads").get_offsets()
    assert np.allclose(points, inst.coords[:, ::-1]) and ax.get_xlabel() == "longitude"


def test_plot_tour_refuses_a_file_of_weights_alone():
    """A matrix-only GTSPLIB file has nothing to draw: an InputError that says why."""
    inst = read_instance(GTSPLIB / "10gr48.gtsp.gz")
    with pytest.raises(InputError, match=r"^no node coordinates to draw: the file gives EXPLICIT weights"):
        plots.plot_tour(inst, ax=Figure().subplots())


def test_convex_hull_corners():
    """The hull of a square with an inner point and a repeated corner is its four corners."""
    hull = plots._convex_hull(np.array([[0, 0], [2, 0], [2, 2], [0, 2], [1, 1], [2, 2]], float))
    assert sorted(map(tuple, hull.tolist())) == [(0, 0), (0, 2), (2, 0), (2, 2)]
    assert len(plots._convex_hull(np.array([[0, 0], [1, 1], [2, 2]], float))) < 3


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
    """Known solvers keep their colour; an unknown name gets the same colour in every process
    (another process with another string-hash seed picks the same one)."""
    import os
    import subprocess
    import sys

    assert plots.solver_color("greedy") == "tab:orange"
    code = "from gtsp_bench.report import plots; print(plots.solver_color('new-solver'))"
    env = dict(os.environ, PYTHONHASHSEED="12345")
    other = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                           check=True).stdout.strip()
    assert other == plots.solver_color("new-solver")
    assert plots.solver_color("new-solver") in plots._PALETTE

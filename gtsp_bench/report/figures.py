"""The figures of the paper's experiments, laid out from their tidy tables by the plot
functions of :mod:`gtsp_bench.report.plots`, the tour pictures of ``gtsp-bench plot``, and
writing them as PNG."""

from __future__ import annotations

import io
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from gtsp_bench.data.io import atomic_write_bytes
from gtsp_bench.instance import Instance
from gtsp_bench.report import plots
from gtsp_bench.report.paper import PAPER_RUNTIME_S, parse_ints


def save_png(fig: Any, path: Path) -> None:
    """Write ``fig`` as a PNG (110 dpi), atomically."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    atomic_write_bytes(path, buf.getvalue())


def _figure(nrows: int, ncols: int, size: tuple[float, float]) -> tuple[Any, np.ndarray]:
    from matplotlib.figure import Figure

    fig = Figure(figsize=(size[0] * ncols, size[1] * nrows), layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=False)
    return fig, axes


def experiment_figure(experiment: str, df: pd.DataFrame, first: Mapping[int, Instance]) -> Any:
    """The figure of one of the paper's experiments from its table (``ratio-omega``, ``ratio-k``,
    ``runtime``, ``trajectories``); ``first[K]`` is the instance the trajectories are drawn on."""
    if experiment == "ratio-omega":
        ks = sorted(df["K"].unique())
        fig, axes = _figure(1, len(ks), (5.5, 4))
        for ax, k in zip(axes[0], ks, strict=True):
            sub = df[df["K"] == k]
            plots.plot_ratio(sub, "omega", ax=ax, reference=sub["reference"].iloc[0])
            ax.set_title(f"Energy / optimum, K = {k} ({sub['instance'].nunique()} instances)")
        return fig
    if experiment == "ratio-k":
        fig, axes = _figure(1, 1, (6, 4))
        plots.plot_ratio(df, "K", ax=axes[0, 0], reference="/".join(sorted(df["reference"].unique())))
        omegas = "/".join(f"{w:g}" for w in sorted(df["omega"].unique()))
        axes[0, 0].set_title(f"Energy / optimum, omega = {omegas}")
        return fig
    if experiment == "runtime":
        fig, axes = _figure(1, 1, (6.5, 4.5))
        plots.plot_runtime(df, ax=axes[0, 0], paper=PAPER_RUNTIME_S)
        return fig
    if experiment == "trajectories":
        ks = sorted(df["K"].unique())
        ncols = max(len(df[df["K"] == k]["omega"].unique()) for k in ks)
        fig, axes = _figure(len(ks), ncols, (4.6, 4.6))
        for r, k in enumerate(ks):
            sub = df[df["K"] == k]
            omegas = sorted(sub["omega"].unique())
            for c in range(ncols):
                ax = axes[r, c]
                if c >= len(omegas):
                    ax.set_visible(False)
                    continue
                panel = sub[sub["omega"] == omegas[c]]
                tours = {row.solver: (parse_ints(row.order), parse_ints(row.heads))
                         for row in panel.itertuples() if row.order}
                plots.plot_trajectory(first[k], tours, ax=ax,
                                      title=f"K = {k}, omega = {omegas[c]:g}")
        return fig
    raise ValueError(experiment)


#: Most panels side by side in a tour figure; more start a new row.
TOUR_COLUMNS = 3


def tour_figure(instance: Instance, tours: Sequence[tuple[str, Sequence[int], Sequence[int]]]) -> Any:
    """One panel per ``(title, order, heads)`` drawn by :func:`plots.plot_tour`, side by side (at
    most :data:`TOUR_COLUMNS` in a row), under the instance's name; the instance alone when
    ``tours`` is empty."""
    ncols = min(max(len(tours), 1), TOUR_COLUMNS)
    nrows = -(-max(len(tours), 1) // ncols)
    fig, axes = _figure(nrows, ncols, (4.8, 4.8))
    if not tours:
        plots.plot_tour(instance, ax=axes[0, 0], title=instance.name)
        return fig
    for i, ax in enumerate(axes.flat):
        if i >= len(tours):
            ax.set_visible(False)
            continue
        title, order, heads = tours[i]
        plots.plot_tour(instance, order, heads, ax=ax, title=title)
    fig.suptitle(instance.name, fontsize=11)
    return fig


def training_figure(df: pd.DataFrame) -> Any:
    """Actor loss, training reward and validation energy against training step, per model."""
    fig, axes = _figure(1, 3, (5.5, 4))
    plots.plot_training(df, "loss", ax=axes[0, 0])
    plots.plot_training(df, "reward", ax=axes[0, 1])
    plots.plot_training(df, "val_energy", ax=axes[0, 2])
    return fig

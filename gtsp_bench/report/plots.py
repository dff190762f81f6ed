"""Plots of the benchmark tables and of instances and tours; each function draws on ``ax`` (a new
figure if ``None``) and returns the Axes.

The runner builds its figures with :class:`matplotlib.figure.Figure` (no pyplot, no display
needed); pyplot is imported only when a function is called without ``ax``.
"""

from __future__ import annotations

import zlib
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

from gtsp_bench.errors import InputError
from gtsp_bench.instance import Instance
from gtsp_bench.report.paper import PAPER_SOLVERS

#: Fixed colours for the solvers the paper compares; others get one from their name.
SOLVER_COLORS = {
    "greedy": "tab:orange", "aco": "tab:green", "drl": "tab:red", "am": "tab:purple",
    "milp": "tab:blue", "dp": "tab:cyan", "brute": "tab:gray", "lns": "tab:brown",
}
_PALETTE = ("tab:olive", "tab:pink", "tab:brown", "tab:purple", "tab:cyan", "tab:green")
_MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")


def solver_color(name: str) -> str:
    """A stable colour per solver name."""
    return SOLVER_COLORS.get(name) or _PALETTE[zlib.crc32(name.encode()) % len(_PALETTE)]


def _axes(ax: Any) -> Any:
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots()
    return ax


def plot_ratio(df: pd.DataFrame, x: str, ax: Any = None, reference: str | None = None) -> Any:
    """Mean energy / optimum against ``x`` per solver, with one standard deviation as bars.

    Parameters
    ----------
    df
        Tidy rows with columns ``solver``, ``ratio`` and ``x`` (e.g. ``"omega"`` or ``"K"``).
    x
        The column on the horizontal axis.
    reference
        Name of the exact reference (names joined by ``/`` when it varies with K): drawn as the
        line at 1 rather than as a series.
    """
    ax = _axes(ax)
    refs = set(reference.split("/")) if reference else set()
    solvers = sorted(set(df["solver"].unique()) - refs)
    xs = np.sort(df[x].unique())
    step = float(np.min(np.diff(xs))) if len(xs) > 1 else 1.0
    for i, s in enumerate(solvers):
        stats = df[df["solver"] == s].groupby(x)["ratio"].agg(["mean", "std"]).dropna(subset=["mean"])
        if stats.empty:
            continue
        shift = (i - (len(solvers) - 1) / 2) * 0.08 * step
        ax.errorbar(stats.index.to_numpy(dtype=float) + shift, stats["mean"],
                    yerr=stats["std"].fillna(0), label=s, color=solver_color(s),
                    marker=_MARKERS[i % len(_MARKERS)], markersize=4, capsize=2, linewidth=1.2)
    ax.axhline(1.0, color="black", linestyle="--", linewidth=0.8,
               label=f"optimum ({reference})" if reference else "optimum")
    ax.set_xlabel("omega" if x == "omega" else x)
    ax.set_ylabel("energy / optimum")
    ax.set_xticks(xs)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return ax


def plot_runtime(df: pd.DataFrame, ax: Any = None,
                 paper: Mapping[str, Mapping[int, float]] | None = None) -> Any:
    """Median ``runtime_s`` per solver against ``K`` (log scale); optional reported values dashed.

    Parameters
    ----------
    df
        Tidy rows with columns ``solver``, ``K``, ``runtime_s`` and ``status``.
    paper
        Reported seconds by the paper's method name (``"Greedy"``, ``"ACO"``, ...) and K, drawn
        dashed with open markers in the colour of the solver standing for that method.
    """
    ax = _axes(ax)
    ok = df[df["status"] != "failed"]
    for i, s in enumerate(sorted(ok["solver"].unique())):
        med = ok[ok["solver"] == s].groupby("K")["runtime_s"].median()
        ax.plot(med.index, med.to_numpy(), marker=_MARKERS[i % len(_MARKERS)], label=s,
                color=solver_color(s))
    for method, values in (paper or {}).items():
        ks = sorted(values)
        ax.plot(ks, [values[k] for k in ks], linestyle="--", marker="o", markerfacecolor="none",
                color=solver_color(PAPER_SOLVERS.get(method, method)), alpha=0.7, linewidth=0.8,
                markersize=4, label=f"paper: {method}")
    ax.set_yscale("log")
    ax.set_xlabel("K (clusters)")
    ax.set_ylabel("median seconds per instance")
    ax.set_title("Running time (dashed: the paper's table)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    return ax


def plot_trajectory(instance: Instance, tours: Mapping[str, tuple[Sequence[int], Sequence[int]]],
                    ax: Any = None, title: str | None = None) -> Any:
    """Nodes, each solver's chosen cluster heads and its closed tour from the base station.

    Parameters
    ----------
    instance
        A UAV instance (with a depot).
    tours
        ``{solver: (order, heads)}`` as in :class:`gtsp_bench.solver.Result`.
    """
    ax = _axes(ax)
    for k, pts in enumerate(instance.clusters):
        ax.scatter(pts[:, 0], pts[:, 1], s=4, color="lightgray", zorder=1)
        centre = pts.mean(axis=0)
        ax.annotate(f"G{k + 1}", centre, xytext=(0, 14), textcoords="offset points", fontsize=7,
                    ha="center", color="dimgray")
    depot = instance.depot
    if depot is not None:
        ax.scatter([depot[0]], [depot[1]], marker="s", s=40, color="black", zorder=4, label="BS")
    styles = ("-", "--", "-.", ":")
    for i, (solver, (order, heads)) in enumerate(sorted(tours.items())):
        pts = np.array([instance.clusters[c][heads[c]] for c in order])
        path = pts if depot is None else np.vstack([depot, pts, depot])
        if depot is None:
            path = np.vstack([pts, pts[:1]])
        color = solver_color(solver)
        ax.plot(path[:, 0], path[:, 1], linestyle=styles[i % len(styles)], color=color,
                linewidth=1.3, label=solver, zorder=2)
        ax.scatter(pts[:, 0], pts[:, 1], s=22, color=color, marker=_MARKERS[i % len(_MARKERS)],
                   zorder=3)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    if title:
        ax.set_title(title, fontsize=10)
    ax.legend(fontsize=7, loc="best")
    return ax


def check_drawable(instance: Instance) -> None:
    """Raise :class:`InputError` when ``instance`` has no coordinates to draw: a GTSPLIB file of
    EXPLICIT weights without a ``DISPLAY_DATA_SECTION``."""
    if not np.all(np.isfinite(instance.coords)):
        raise InputError("no node coordinates to draw: the file gives EXPLICIT weights without "
                         "a DISPLAY_DATA_SECTION")


def _convex_hull(points: np.ndarray) -> np.ndarray:
    """The corners of the convex hull of ``(m, 2)`` points, counter-clockwise (Andrew's monotone
    chain); fewer than three for points on a line."""
    pts = [tuple(p) for p in np.unique(points, axis=0).tolist()]  # sorted by x, then y
    if len(pts) < 3:
        return np.array(pts)

    def half(seq: list[tuple[float, float]]) -> list[tuple[float, float]]:
        chain: list[tuple[float, float]] = []
        for x, y in seq:
            while len(chain) >= 2 and ((chain[-1][0] - chain[-2][0]) * (y - chain[-2][1])
                                       - (chain[-1][1] - chain[-2][1]) * (x - chain[-2][0])) <= 0:
                chain.pop()
            chain.append((x, y))
        return chain[:-1]

    return np.array(half(pts) + half(pts[::-1]))


def plot_tour(instance: Instance, order: Sequence[int] | None = None, heads: Sequence[int] | None = None,
              ax: Any = None, title: str | None = None) -> Any:
    """An instance and one solution: the base station, each cluster (its candidate heads, in the
    cluster's colour, on its shaded hull), the chosen heads and the closed tour through them.

    Parameters
    ----------
    instance
        An instance with coordinates (:func:`check_drawable`); GEO and GEOM coordinates (latitude,
        longitude) are drawn with longitude across.
    order, heads
        A feasible solution as in :class:`gtsp_bench.solver.Result`, or ``None`` for the instance
        alone.
    title
        The Axes title.
    """
    from matplotlib import colormaps
    from matplotlib.collections import PolyCollection

    check_drawable(instance)
    ax = _axes(ax)
    geo = instance.edge_weight_type in ("GEO", "GEOM")
    axes_of = [1, 0] if geo else [0, 1]  # (latitude, longitude): longitude across
    colors = colormaps["tab20"](np.arange(instance.n_clusters) % 20)
    hulls, hull_colors = [], []
    for k, pts in enumerate(instance.clusters):
        hull = _convex_hull(pts)
        if len(hull) >= 3:
            hulls.append(hull[:, axes_of])
            hull_colors.append(colors[k])
    if hulls:
        ax.add_collection(PolyCollection(hulls, facecolors=hull_colors, alpha=0.12, edgecolors="none",
                                         zorder=0))
    xy = instance.coords[:, axes_of]
    ax.scatter(xy[:, 0], xy[:, 1], s=6, c=colors[instance.cluster_of], zorder=1,
               label="candidate heads")
    if instance.n_clusters <= 30:
        for k, pts in enumerate(instance.clusters):
            ax.annotate(f"G{k + 1}", pts.mean(axis=0)[axes_of], xytext=(0, 12), textcoords="offset points",
                        fontsize=7, ha="center", color="dimgray")
    depot = None if instance.depot is None else instance.depot[axes_of]
    if depot is not None:
        ax.scatter([depot[0]], [depot[1]], marker="s", s=50, color="black", zorder=4, label="base station")
    if order is not None and heads is not None:
        order_arr, heads_arr = instance.check_solution(order, heads)
        pts = xy[instance.offsets[order_arr] + heads_arr[order_arr]]
        path = np.vstack([pts, pts[:1]]) if depot is None else np.vstack([depot, pts, depot])
        ax.plot(path[:, 0], path[:, 1], color="black", linewidth=1.1, zorder=2, label="tour")
        ax.scatter(pts[:, 0], pts[:, 1], s=36, c=colors[order_arr], edgecolors="black",
                   linewidths=0.9, zorder=3, label="chosen heads")
    ax.autoscale_view()
    ax.set_aspect("equal", adjustable="datalim")
    unit = " (m)" if instance.is_uav else ""
    ax.set_xlabel("longitude" if geo else f"x{unit}")
    ax.set_ylabel("latitude" if geo else f"y{unit}")
    if title:
        ax.set_title(title, fontsize=10)
    # "best" weighs every point and hull against each place: seconds on the largest files
    ax.legend(fontsize=7, loc="best" if instance.n_nodes <= 2000 else "upper right", markerscale=1.2)
    return ax


def plot_training(df: pd.DataFrame, y: str = "loss", ax: Any = None) -> Any:
    """A training-log column against ``step``, one line per ``model``.

    Steps where the column is empty (validation is logged only every few steps) are skipped, so
    sparse columns still draw as lines.
    """
    ax = _axes(ax)
    for model, sub in df.groupby("model"):
        sub = sub[["step", y]].dropna()
        ax.plot(sub["step"], sub[y], label=str(model), color=solver_color(str(model)), linewidth=1)
    ax.set_xlabel("training step")
    ax.set_ylabel(y)
    ax.set_title(f"Training: {y}")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return ax

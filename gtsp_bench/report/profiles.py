"""Performance profiles, gap plots and time-to-target curves of a benchmark's rows
(:mod:`gtsp_bench.bench.rows`).

A performance profile (E. D. Dolan and J. J. More, "Benchmarking optimization software with
performance profiles", Mathematical Programming 91, 2002) compares solvers over a set of problems:
for problem ``p`` and solver ``s`` the ratio ``r(p, s) = objective(p, s) / min_s objective(p, s)``
(infinite when ``s`` gave no answer), and ``rho_s(tau)`` is the fraction of problems with
``r(p, s) <= tau``. ``rho_s(1)`` is the share of problems where ``s`` found the best tour; the
curve reaching 1 early means robust. A problem is one set instance at one omega and one solver
seed; problems no solver answered are left out.

Each plot function draws on ``ax`` (a new figure if ``None``) and returns the Axes, as in
:mod:`gtsp_bench.report.plots`; the ``*_figure`` functions lay them out for the sweep's PNG files.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd

from gtsp_bench.report.plots import _MARKERS, _axes, solver_color

#: Columns that name one problem of a profile.
PROBLEM = ("set", "instance", "omega", "seed")
#: Ratios within this relative tolerance of tau count as within tau.
TAU_TOL = 1e-12


def profile_ratios(df: pd.DataFrame, metric: str = "objective",
                   by: Sequence[str] = PROBLEM) -> pd.DataFrame:
    """Performance ratios, one row per problem and one column per solver (``inf``: no answer).

    Parameters
    ----------
    df
        Tidy rows with columns ``solver``, ``metric`` (smaller is better, NaN for no answer) and
        those of ``by``.
    """
    d = df.assign(omega=df["omega"].astype(float).fillna(-1.0)) if "omega" in by else df
    table = d.groupby([*by, "solver"], sort=False)[metric].min().unstack("solver")
    table = table.reindex(columns=list(dict.fromkeys(df["solver"])))
    vals = table.to_numpy(dtype=float)
    answered = np.isfinite(vals).any(axis=1)
    vals = vals[answered]
    best = np.min(np.where(np.isfinite(vals), vals, np.inf), axis=1, initial=np.inf)[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        ratios = np.where(best > 0, vals / best, np.where(vals == best, 1.0, np.inf))
    ratios[~np.isfinite(vals)] = np.inf
    return pd.DataFrame(ratios, index=table.index[answered], columns=table.columns)


def performance_profile(df: pd.DataFrame, metric: str = "objective",
                        by: Sequence[str] = PROBLEM) -> pd.DataFrame:
    """The profile as a tidy table ``solver, tau, fraction``: for every solver, every tau at
    which some solver's curve steps (1 and each finite ratio), with the fraction of problems
    whose ratio is within tau."""
    ratios = profile_ratios(df, metric, by)
    finite = ratios.to_numpy()[np.isfinite(ratios.to_numpy())]
    taus = np.unique(np.concatenate([[1.0], finite]))
    rows = []
    for s in ratios.columns:
        r = ratios[s].to_numpy()
        for t in taus:
            rows.append({"solver": s, "tau": float(t),
                         "fraction": float(np.mean(r <= t * (1 + TAU_TOL))) if len(r) else np.nan})
    return pd.DataFrame(rows, columns=["solver", "tau", "fraction"])


def gap_by_k(df: pd.DataFrame) -> pd.DataFrame:
    """Mean and max gap in percent and the number of gaps per set, solver and K."""
    ok = df[df["gap_percent"].notna()]
    g = ok.groupby(["set", "solver", "K"], sort=True)["gap_percent"]
    return g.agg(mean_gap_pct="mean", max_gap_pct="max", n="count").reset_index()


def gap_time(df: pd.DataFrame) -> pd.DataFrame:
    """Per set and solver: the median seconds and the mean gap in percent of the answered solves."""
    ok = df[df["gap_percent"].notna()]
    g = ok.groupby(["set", "solver"], sort=False)
    return g.agg(median_s=("runtime_s", "median"), mean_gap_pct=("gap_percent", "mean"),
                 n=("gap_percent", "count")).reset_index()


def plot_profile(profile: pd.DataFrame, ax: Any = None) -> Any:
    """Each solver's fraction of problems within a factor tau of the best (a step curve)."""
    ax = _axes(ax)
    top = float(profile["tau"].max()) if len(profile) else 1.0
    right = 1.0 + max(top - 1.0, 1e-3) * 1.05
    for i, (s, g) in enumerate(profile.groupby("solver", sort=False)):
        x = np.append(g["tau"].to_numpy(), right)
        y = np.append(g["fraction"].to_numpy(), g["fraction"].iloc[-1])
        ax.step(x, y, where="post", label=str(s), color=solver_color(str(s)), linewidth=1.4,
                marker=_MARKERS[i % len(_MARKERS)], markevery=[0], markersize=4)
    ax.set_xlim(1.0, right)
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlabel("tau (objective / best objective)")
    ax.set_ylabel("fraction of problems within tau")
    ax.set_title("Performance profile")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    return ax


def plot_gap_k(table: pd.DataFrame, ax: Any = None) -> Any:
    """Mean gap in percent against K, one line per solver across the sets (the UAV sets of
    K = 20, 50, ... make one line each); one line per set and solver when two sets share a K."""
    ax = _axes(ax)
    shared_k = len(table) > 0 and int(table.groupby("K")["set"].nunique().max()) > 1
    keys = ["set", "solver"] if shared_k else ["solver"]
    for i, (key, g) in enumerate(table.groupby(keys, sort=False)):
        s = key[-1] if isinstance(key, tuple) else key
        label = f"{s} ({key[0]})" if shared_k else str(s)
        g = g.sort_values("K")
        ax.plot(g["K"], g["mean_gap_pct"], marker=_MARKERS[i % len(_MARKERS)], label=label,
                color=solver_color(str(s)), linewidth=1.2, markersize=4)
    if len(table) and table["K"].max() > 10 * max(table["K"].min(), 1):
        ax.set_xscale("log")
    ax.set_xlabel("K (clusters)")
    ax.set_ylabel("mean gap (%)")
    ax.set_title("Gap against K")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    return ax


def plot_gap_time(df: pd.DataFrame, ax: Any = None) -> Any:
    """Each answered solve's gap against its seconds (small points) and each solver's mean gap
    at its median seconds (large marker)."""
    ax = _axes(ax)
    ok = df[df["gap_percent"].notna()]
    for i, (s, g) in enumerate(ok.groupby("solver", sort=False)):
        color, marker = solver_color(str(s)), _MARKERS[i % len(_MARKERS)]
        ax.scatter(g["runtime_s"], g["gap_percent"], s=8, alpha=0.35, color=color, marker=marker)
        ax.scatter([g["runtime_s"].median()], [g["gap_percent"].mean()], s=60, color=color,
                   marker=marker, edgecolors="black", label=str(s), zorder=3)
    if len(ok) and (ok["runtime_s"] > 0).all() and ok["runtime_s"].max() > 20 * ok["runtime_s"].min():
        ax.set_xscale("log")
    ax.set_xlabel("seconds per solve")
    ax.set_ylabel("gap (%)")
    ax.set_title("Gap against time (large: mean gap at median time)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return ax


def _figure(size: tuple[float, float]) -> tuple[Any, Any]:
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, layout="constrained")
    return fig, fig.subplots()


def profile_figure(profile: pd.DataFrame) -> Any:
    """The performance profile's figure."""
    fig, ax = _figure((6, 4.2))
    plot_profile(profile, ax=ax)
    return fig


def gap_k_figure(table: pd.DataFrame) -> Any:
    """The gap-against-K figure from :func:`gap_by_k`'s table."""
    fig, ax = _figure((6, 4.2))
    plot_gap_k(table, ax=ax)
    return fig


def gap_time_figure(df: pd.DataFrame) -> Any:
    """The gap-against-time figure from the tidy rows."""
    fig, ax = _figure((6, 4.2))
    plot_gap_time(df, ax=ax)
    return fig


# ---------------------------------------------------------------------- anytime
def anytime_table(df: pd.DataFrame) -> pd.DataFrame:
    """Per set and solver (``label``): solves, mean primal integral, the share of solves that
    reached 1 % and 0.1 % of the reference and their median time to get there."""
    out = []
    for (set_name, label), g in df.groupby(["set", "label"], sort=False):
        row = {"set": set_name, "solver": label, "solves": len(g),
               "mean_primal_integral": g["primal_integral"].mean()}
        for col, name in (("time_to_1pct_s", "1pct"), ("time_to_0p1pct_s", "0p1pct")):
            reached = g[col].dropna()
            row[f"reached_{name}"] = len(reached) / len(g) if len(g) else np.nan
            row[f"median_s_to_{name}"] = reached.median() if len(reached) else np.nan
        out.append(row)
    return pd.DataFrame(out)


def plot_time_to_target(df: pd.DataFrame, ax: Any = None) -> Any:
    """COCO-style ECDF of times to target: for each solver (``label``), the share of (solve,
    target) pairs, targets 1 % and 0.1 % of the reference, reached by each time (log scale)."""
    ax = _axes(ax)
    pairs = df.melt(id_vars=["label"], value_vars=["time_to_1pct_s", "time_to_0p1pct_s"], value_name="t")
    positive = pairs["t"][pairs["t"] > 0]
    low = float(positive.min()) if len(positive) else 1e-3
    high = float(df["time_limit"].max()) if df["time_limit"].notna().any() else float(pairs["t"].max() or 1.0)
    for i, (label, g) in enumerate(pairs.groupby("label", sort=False)):
        times = np.sort(np.maximum(g["t"].dropna().to_numpy(), low))
        x = np.concatenate([[low], times, [max(high, low)]])
        y = np.concatenate([[0.0], np.arange(1, len(times) + 1) / len(g), [len(times) / len(g)]])
        ax.step(x, y, where="post", label=label, marker=_MARKERS[i % len(_MARKERS)], markevery=[-1])
    ax.set_xscale("log")
    ax.set_xlabel("seconds")
    ax.set_ylabel("share of (solve, target) pairs reached")
    ax.set_ylim(0, 1.02)
    ax.set_title("time to 1 % and 0.1 % of the reference")
    ax.legend(fontsize="small")
    ax.grid(True, alpha=0.3)
    return ax


def time_to_target_figure(df: pd.DataFrame) -> Any:
    """The time-to-target ECDF on a figure of its own."""
    fig, ax = _figure((7.0, 4.5))
    plot_time_to_target(df, ax)
    return fig

"""The benchmark report: the paper's reported values, its claims checked against this run's
tables, and the generated blocks of ``results/paper/README.md`` and of the documentation pages.

Everything here reads the CSV files the runner wrote, so the report can be refreshed without
re-running anything (``gtsp-bench bench --report-only``). A generated block is the text between
``<!-- BEGIN generated:NAME -->`` and ``<!-- END generated:NAME -->``; any Markdown file may hold
any block, and :func:`refresh_blocks` rewrites the ones it has, keeping the text around them.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from gtsp_bench.data.io import atomic_write_text
from gtsp_bench.errors import InputError

#: Columns a training log must start with.
TRAINING_COLUMNS = ("step", "loss", "reward", "val_energy", "wall_s")
#: The paper's running-time table (seconds), by its column names.
PAPER_RUNTIME_S: dict[str, dict[int, float]] = {
    "Greedy": {4: 0.18, 5: 0.19, 6: 0.22, 7: 0.25, 8: 0.29, 9: 0.32, 10: 0.33},
    "ACO": {4: 6.92, 5: 10.15, 6: 14.33, 7: 19.23, 8: 25.82, 9: 31.21, 10: 38.14},
    "Gurobi": {4: 1800, 5: 2711, 6: 3722, 7: 5405, 8: 6908, 9: 9701, 10: 12500},
    "DRL": {4: 0.36, 5: 0.37, 6: 0.39, 7: 0.39, 8: 0.41, 9: 0.41, 10: 0.42},
}
#: Which registered solver stands for each of the paper's methods.
PAPER_SOLVERS = {"Greedy": "greedy", "ACO": "aco", "Gurobi": "milp", "DRL": "drl"}
#: "Within a few %" in the paper's claims is read as a mean ratio of at most 1 + this.
CLOSE_TO_OPTIMUM = 0.05


def read_training_logs(checkpoint_dir: Path) -> pd.DataFrame | None:
    """All ``<model>.train.csv`` logs as one table with a ``model`` column (``None`` if none).

    Raises
    ------
    InputError
        A log whose first columns are not ``step,loss,reward,val_energy,wall_s``.
    """
    frames = []
    for path in sorted(checkpoint_dir.glob("*.train.csv")):
        try:
            df = pd.read_csv(path)
        except (ValueError, OSError) as e:
            raise InputError(f"{path}: cannot read the training log ({e})") from None
        if tuple(df.columns[: len(TRAINING_COLUMNS)]) != TRAINING_COLUMNS:
            raise InputError(f"{path}: a training log must start with the columns "
                             f"{','.join(TRAINING_COLUMNS)}")
        df.insert(0, "model", path.name.removesuffix(".train.csv"))
        frames.append(df)
    return pd.concat(frames, ignore_index=True) if frames else None


def median_runtimes(df: pd.DataFrame) -> pd.DataFrame:
    """Median ``runtime_s`` per K (rows) and solver (columns), failed solves left out."""
    ok = df[df["status"] != "failed"]
    return ok.pivot_table(index="K", columns="solver", values="runtime_s", aggfunc="median", dropna=False)


def mean_ratios(df: pd.DataFrame, by: str) -> pd.DataFrame:
    """Mean ratio to the optimum per ``by`` (rows) and solver (columns)."""
    return df.pivot_table(index=by, columns="solver", values="ratio", aggfunc="mean", dropna=False)


def parse_ints(text: Any) -> list[int]:
    """``"2 0 1"`` -> ``[2, 0, 1]`` (the CSV's ``order`` and ``heads``); ``[]`` for a missing value."""
    return [int(x) for x in text.split()] if isinstance(text, str) else []


def ks_text(ks: Sequence[int]) -> str:
    """``4..10`` for a run of consecutive values, else ``4,7``."""
    ks = sorted(ks)
    if len(ks) > 2 and ks == list(range(ks[0], ks[-1] + 1)):
        return f"{ks[0]}..{ks[-1]}"
    return ",".join(map(str, ks))


_BEGIN, _END = "<!-- BEGIN generated:{} -->", "<!-- END generated:{} -->"
REPORT_BLOCKS = ("setup", "ratio-omega", "ratio-k", "runtime", "trajectories", "training", "claims")
#: Blocks the documentation pages may hold: every block but ``setup`` (it has the run's date and
#: machine, which would change the pages on every run), plus ``summary``.
DOCS_BLOCKS = ("summary", *REPORT_BLOCKS[1:])


def _md_table(df: pd.DataFrame, fmt: Callable[[Any], str], index_name: str) -> str:
    cols = [str(c) for c in df.columns]
    lines = ["| " + " | ".join([index_name, *cols]) + " |", "|" + "---|" * (len(cols) + 1)]
    for idx, row in df.iterrows():
        label = f"{idx:g}" if isinstance(idx, float) else str(idx)
        lines.append("| " + " | ".join([label, *(fmt(v) for v in row)]) + " |")
    return "\n".join(lines)


def _ratio_fmt(v: Any) -> str:
    return "-" if v is None or not np.isfinite(v) else f"{v:.4f}"


def _secs(v: Any) -> str:
    if v is None or not np.isfinite(v):
        return "-"
    return f"{v:.3g} s" if v < 100 else f"{v:.0f} s"


def _read(out_dir: Path, name: str) -> pd.DataFrame | None:
    path = out_dir / f"{name}.csv"
    return pd.read_csv(path, keep_default_na=False, na_values=[""]) if path.exists() else None


def _runtime_table(df: pd.DataFrame) -> pd.DataFrame:
    med = median_runtimes(df)
    table = pd.DataFrame(index=med.index)
    for s in med.columns:
        table[f"{s}"] = med[s]
    for name, vals in PAPER_RUNTIME_S.items():
        table[f"paper {name}"] = [vals.get(int(k), math.nan) for k in med.index]
    return table


def _summary_table(ratios: pd.DataFrame, runtimes: pd.DataFrame | None) -> str:
    """Per solver: mean gap to the optimum in % at each K, and the median time at the largest K."""
    gaps = (mean_ratios(ratios, "K") - 1.0) * 100.0
    table = pd.DataFrame(index=gaps.columns)
    for k in gaps.index:
        table[f"gap % K={k}"] = gaps.loc[k]
    if runtimes is not None:
        med = median_runtimes(runtimes)
        k = med.index.max()
        table[f"median time K={k}"] = med.loc[k].reindex(table.index)

    def fmt(v: Any, col: str) -> str:
        if col.startswith("median"):
            return _secs(v)
        return "-" if v is None or not np.isfinite(v) else f"{v:.2f}"

    cols = list(table.columns)
    lines = ["| " + " | ".join(["solver", *cols]) + " |", "|" + "---|" * (len(cols) + 1)]
    for solver, row in table.iterrows():
        lines.append("| " + " | ".join([f"`{solver}`", *(fmt(row[c], c) for c in cols)]) + " |")
    return "\n".join(lines)


def _trajectory_table(df: pd.DataFrame) -> str:
    """Each panel's access order per solver, and whether its order / heads are the optimum's."""
    lines = ["| K | omega | solver | access order | energy / optimum | same order as optimum | "
             "same heads |", "|---|---|---|---|---|---|---|"]
    for (_, _), panel in df.sort_values(["K", "omega", "solver"]).groupby(["K", "omega"], sort=False):
        ref = panel[panel["solver"] == panel["reference"]]
        ref_order = parse_ints(ref["order"].iloc[0]) if len(ref) else []
        ref_heads = parse_ints(ref["heads"].iloc[0]) if len(ref) else []
        for row in panel.itertuples():
            order, heads = parse_ints(row.order), parse_ints(row.heads)
            text = " -> ".join(["b0", *(f"G{c + 1}" for c in order), "b0"]) if order else "-"
            same_order = bool(order) and order in (ref_order, ref_order[::-1])
            same_heads = bool(heads) and heads == ref_heads
            lines.append(f"| {row.K} | {row.omega:g} | {row.solver} | {text} | "
                         f"{_ratio_fmt(row.ratio)} | {'yes' if same_order else 'no'} | "
                         f"{'yes' if same_heads else 'no'} |")
    return "\n".join(lines)


def report_blocks(
    out_dir: Path, checkpoint_dir: Path | None = None, jobs: int | None = None
) -> dict[str, str]:
    """The generated parts of ``README.md``, computed from the CSV files in ``out_dir``.

    ``checkpoint_dir`` holds the training logs; ``jobs`` is the number of workers the run used.
    """
    blocks: dict[str, str] = {}
    frames = {e: _read(out_dir, e) for e in ("ratio-omega", "ratio-k", "runtime", "trajectories")}
    solves = [f for f in frames.values() if f is not None]
    if solves:
        every = pd.concat(solves)
        refs = ", ".join(f"{r} (K = {ks_text(sorted(every[every['reference'] == r]['K'].unique()))})"
                         for r in sorted(every["reference"].unique()))
        statuses = every.drop_duplicates(["instance", "omega", "solver"])["status"].value_counts()
        blocks["setup"] = "\n".join([
            f"- solvers: {', '.join(sorted(every['solver'].unique()))}; reference optimum: {refs}",
            f"- instances: {every['instance'].nunique()} "
            f"(K = {ks_text(sorted(every['K'].unique()))}, "
            f"N = {', '.join(map(str, sorted(every['N'].unique())))} nodes per cluster)",
            f"- per-solve time limit {every['time_limit_s'].max():g} s; solves by status: "
            + ", ".join(f"{s} {n}" for s, n in statuses.items()),
            f"- generated {time.strftime('%Y-%m-%d %H:%M')} on {os.cpu_count()} cores"
            + (f", {jobs} worker(s)" if jobs else ""),
        ])
    df = frames["ratio-omega"]
    if df is not None:
        parts = []
        for k in sorted(df["K"].unique()):
            sub = df[df["K"] == k]
            parts.append(f"K = {k}, mean energy / optimum over {sub['instance'].nunique()} instances "
                         f"(rows: omega)\n\n" + _md_table(mean_ratios(sub, "omega"), _ratio_fmt, "omega"))
        blocks["ratio-omega"] = "\n\n".join(parts)
    df = frames["ratio-k"]
    if df is not None:
        omegas = ", ".join(f"{w:g}" for w in sorted(df["omega"].unique()))
        blocks["ratio-k"] = (f"omega = {omegas}, mean energy / optimum over "
                             f"{df.groupby('K')['instance'].nunique().min()} instances per K\n\n"
                             + _md_table(mean_ratios(df, "K"), _ratio_fmt, "K"))
    if frames["ratio-k"] is not None:
        blocks["summary"] = _summary_table(frames["ratio-k"], frames["runtime"])
    df = frames["runtime"]
    if df is not None:
        blocks["runtime"] = ("Median seconds per instance (this run), then the paper's table\n\n"
                             + _md_table(_runtime_table(df), _secs, "K"))
    df = frames["trajectories"]
    if df is not None:
        blocks["trajectories"] = _trajectory_table(df)
    logs = read_training_logs(checkpoint_dir) if checkpoint_dir else None
    if logs is not None:
        last = logs.groupby("model").tail(1).set_index("model")[list(TRAINING_COLUMNS)]
        blocks["training"] = ("Last logged step of each model\n\n"
                              + _md_table(last, lambda v: f"{v:.4g}", "model"))
    elif (out_dir / "training.csv").exists():
        blocks["training"] = "(see training.csv)"
    else:
        blocks["training"] = "No training log was found: the figure was not generated."
    blocks["claims"] = _claims_table(frames)
    return blocks


def _claims_table(frames: Mapping[str, pd.DataFrame | None]) -> str:
    lines = ["| figure / table | the paper says | this run | verdict |", "|---|---|---|---|"]
    for fig, claim, measured, verdict in check_claims(frames):
        lines.append(f"| {fig} | {claim} | {measured} | {verdict} |")
    return "\n".join(lines)


def check_claims(frames: Mapping[str, pd.DataFrame | None]) -> list[tuple[str, str, str, str]]:
    """The paper's claims per figure checked against this run's tables.

    Returns ``(figure, claim, measured, verdict)`` with verdict ``holds``, ``does not hold`` or
    ``not checked (...)``.
    """
    drl, aco, greedy = PAPER_SOLVERS["DRL"], PAPER_SOLVERS["ACO"], PAPER_SOLVERS["Greedy"]
    out = []

    def missing(df: pd.DataFrame | None, names: Sequence[str]) -> str | None:
        if df is None:
            return "not checked (experiment not run)"
        absent = [n for n in names if n not in set(df["solver"])]
        if absent:
            return f"not checked ({', '.join(absent)} not run)"
        failed = [n for n in names if df.loc[df["solver"] == n, "ratio"].isna().all()]
        return f"not checked ({', '.join(failed)} failed on every solve)" if failed else None

    def verdict(ok: bool) -> str:
        return "holds" if ok else "does not hold"

    df = frames.get("ratio-omega")
    for k in ([] if df is None else sorted(df["K"].unique())) or [4, 7]:
        sub = None if df is None else df[df["K"] == k]
        fig = f"ratio-omega, K = {k}"
        m = mean_ratios(sub, "omega") if sub is not None and len(sub) else None
        why = missing(sub, [drl])
        if why or m is None:
            out.append((fig, "DRL within a few % of the optimum for every omega", "-", why or "-"))
        else:
            worst = m[drl].max()
            out.append((fig, "DRL within a few % of the optimum for every omega",
                        f"worst mean ratio {worst:.4f} (omega {m[drl].idxmax():g})",
                        verdict(worst <= 1 + CLOSE_TO_OPTIMUM)))
        why = missing(sub, [drl, aco, greedy])
        if why or m is None:
            out.append((fig, "DRL below ACO and greedy for every omega", "-", why or "-"))
        else:
            a, g = int((m[drl] < m[aco]).sum()), int((m[drl] < m[greedy]).sum())
            out.append((fig, "DRL below ACO and greedy for every omega",
                        f"below ACO at {a}/{len(m)}, below greedy at {g}/{len(m)} omegas",
                        verdict(a == g == len(m))))
        why = missing(sub, [aco, greedy])
        if why or m is None:
            out.append((fig, "ACO below greedy", "-", why or "-"))
        else:
            a = int((m[aco] < m[greedy]).sum())
            out.append((fig, "ACO below greedy", f"at {a}/{len(m)} omegas", verdict(a == len(m))))
    df = frames.get("ratio-k")
    fig = "ratio-k"
    present = [s for s in (greedy, aco, drl) if df is not None and s in set(df["solver"])]
    if df is None or not present:
        out.append((fig, "the gap to the optimum grows with K (greedy, ACO, DRL)", "-",
                    missing(df, [greedy, aco, drl]) or "-"))
    else:
        m = mean_ratios(df, "K")
        parts, ok = [], True
        for s in present:
            corr = pd.Series(m[s].values).rank().corr(pd.Series(m.index.values).rank())
            grows = m[s].iloc[-1] > m[s].iloc[0] and bool(corr > 0)
            ok &= grows
            parts.append(f"{s}: {m[s].iloc[0]:.3f} at K={m.index[0]} -> {m[s].iloc[-1]:.3f} at "
                         f"K={m.index[-1]}, rank corr {corr:+.2f}")
        absent = [s for s in (greedy, aco, drl) if s not in present]
        out.append((fig, "the gap to the optimum grows with K (greedy, ACO, DRL)", "; ".join(parts),
                    verdict(ok) + (f" (for {', '.join(present)}; {', '.join(absent)} not run)"
                                   if absent else "")))
        why = missing(df, [drl, aco, greedy])
        if why:
            out.append((fig, "DRL below greedy and ACO at every K", "-", why))
        else:
            a, g = int((m[drl] < m[aco]).sum()), int((m[drl] < m[greedy]).sum())
            out.append((fig, "DRL below greedy and ACO at every K",
                        f"below ACO at {a}/{len(m)}, below greedy at {g}/{len(m)} K",
                        verdict(a == g == len(m))))
    df = frames.get("runtime")
    fig = "runtime"
    exact = PAPER_SOLVERS["Gurobi"]
    if df is not None and exact not in set(df["solver"]) and "reference" in df.columns:
        # The paper's exact method is Gurobi; without `milp` in the run, the reference is the
        # exact method whose times were measured.
        refs = set(df["reference"].dropna()) & set(df["solver"])
        exact = refs.pop() if len(refs) == 1 else exact
    claim = f"greedy < DRL < ACO < Gurobi (exact; here {exact}) at every K"
    why = missing(df, [greedy, drl, aco, exact])
    if why:
        out.append((fig, claim, "-", why))
    else:
        med = median_runtimes(df)
        ok = (med[greedy] < med[drl]) & (med[drl] < med[aco]) & (med[aco] < med[exact])
        out.append((fig, claim, f"order holds at {int(ok.sum())}/{len(ok)} K",
                    verdict(bool(ok.all()))))
    if df is not None:
        med = median_runtimes(df)
        if len(med) > 1:
            grows = [s for s in med.columns if med[s].iloc[-1] > med[s].iloc[0]]
            out.append((fig, "every method's time grows with K",
                        f"grows from K={med.index[0]} to K={med.index[-1]} for "
                        f"{len(grows)}/{len(med.columns)} solvers"
                        + (f" (not: {', '.join(sorted(set(med.columns) - set(grows)))})"
                           if len(grows) < len(med.columns) else ""),
                        verdict(len(grows) == len(med.columns))))
    df = frames.get("trajectories")
    why = missing(df, [drl])
    if why:
        out.append(("trajectories", "DRL's tour coincides or nearly coincides with the optimum in "
                    "every panel", "-", why))
    else:
        sub = df[df["solver"] == drl]
        same = int(sub["same_tour_as_reference"].astype(str).eq("True").sum())
        out.append(("trajectories", "DRL's tour coincides or nearly coincides with the optimum in "
                    "every panel", f"same tour in {same}/{len(sub)} panels, worst ratio "
                    f"{sub['ratio'].max():.4f}", verdict(sub["ratio"].max() <= 1 + CLOSE_TO_OPTIMUM)))
    return out


_REPORT_TEMPLATE = """# Reproduction of the paper's section VI

Regenerated by `make bench`; the blocks between `generated` markers are rewritten from the CSV
files on every run, the rest is hand-written.

## Setup

{setup}

## Energy ratio against omega (`ratio-omega.csv`, `ratio-omega.png`)

{ratio-omega}

## Energy ratio against K (`ratio-k.csv`, `ratio-k.png`)

{ratio-k}

## Running time (`runtime.csv`, `runtime.png`)

{runtime}

## Trajectories (`trajectories.csv`, `trajectories.png`)

{trajectories}

## Training curve (`training.csv`, `training.png`)

{training}

## The paper's claims, checked

{claims}
"""


def _block(name: str, body: str) -> str:
    return f"{_BEGIN.format(name)}\n{body}\n{_END.format(name)}"


def refresh_blocks(path: Path, blocks: Mapping[str, str], names: Sequence[str] | None = None) -> bool:
    """Rewrite the generated blocks ``path`` holds, keeping the text around them.

    Only the blocks named in ``names`` (default: every key of ``blocks``) are touched; a block the
    file holds but ``blocks`` lacks becomes ``(not run)``. The file is rewritten atomically, and only
    if its text changes. Returns whether it changed.
    """
    old = text = path.read_text(encoding="utf-8")
    for name in blocks if names is None else names:
        begin, end = _BEGIN.format(name), _END.format(name)
        i, j = text.find(begin), text.find(end)
        if i < 0 or j < i:
            continue
        text = text[:i] + _block(name, blocks.get(name, "(not run)")) + text[j + len(end):]
    if text != old:
        atomic_write_text(path, text)
    return text != old


def docs_dir_for(out_dir: Path) -> Path | None:
    """The documentation folder whose pages a run into ``out_dir`` refreshes, or ``None``.

    That is ``docs/`` of the checkout when ``out_dir`` is its results folder or a benchmark's
    folder in it (``results/paper``): the checkout holds ``mkdocs.yml``. A run into another
    folder (``results/quick``, a temporary folder) leaves the documentation alone.
    """
    out = Path(out_dir).resolve()
    root = out.parent.parent if out.parent.name == "results" and out.name == "paper" else out.parent
    docs = root / "docs"
    return docs if (root / "mkdocs.yml").is_file() and docs.is_dir() else None


def refresh_docs(docs_dir: Path, blocks: Mapping[str, str]) -> list[Path]:
    """Refresh the generated blocks (:data:`DOCS_BLOCKS`) of every Markdown page under ``docs_dir``.

    Returns the pages that changed.
    """
    return [page for page in sorted(Path(docs_dir).rglob("*.md"))
            if refresh_blocks(page, blocks, DOCS_BLOCKS)]


def write_report(out_dir: Path, checkpoint_dir: Path | None = None, jobs: int | None = None) -> Path:
    """Refresh the generated blocks of ``out_dir/README.md`` from the CSVs (create it if absent).

    Hand-written text outside the blocks is kept; a block missing from the file is left out. When
    ``out_dir`` is the project's results folder (:func:`docs_dir_for`), the documentation pages'
    generated blocks are refreshed from the same tables.
    """
    path = out_dir / "README.md"
    blocks = report_blocks(out_dir, checkpoint_dir, jobs)
    if not path.exists():
        atomic_write_text(path, _REPORT_TEMPLATE.format(**{n: _block(n, "(not run)") for n in REPORT_BLOCKS}))
    refresh_blocks(path, blocks, REPORT_BLOCKS)
    docs = docs_dir_for(out_dir)
    if docs is not None:
        refresh_docs(docs, blocks)
    return path

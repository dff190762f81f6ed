"""The named outputs a benchmark definition may ask for (:data:`OUTPUTS`), each a function of the
rows alone: ``(benchmark, rows, out_dir, settings, say) -> files written``.

``profile``, ``gap-k``
    the performance profile and the mean gap by K (CSV + PNG, :mod:`gtsp_bench.report.profiles`);
``glns``
    ``glns.md``: per instance, lns's mean gap, hits and worst run beside GLNS's published numbers
    (``glns-45.csv``), and the three target lines;
``doc-heuristics``, ``doc-learned``, ``doc-learned-transfer``, ``doc-exact-scale``,
``doc-exact-frontier``, ``doc-exact-frontier-uav``, ``doc-textbook``
    a generated block of a documentation page (:data:`DOC_BLOCKS`), refreshed only when the run
    wrote into the committed folder ``results/NAME`` of a checkout (``docs/`` beside it);
``update-references``
    the sets' ``reference.csv``: new rows for points without one, better tours for ``best_known``
    rows (with ``--update-reference``, or always for the ``references`` benchmark);
``best-known``
    GTSPLIB's ``best_known.csv``: with ``--update-reference``, a tour shorter than a file's
    best-known value is kept in the library the run read (:mod:`gtsp_bench.bench.best_known`).
"""

from __future__ import annotations

import datetime as dt
import math
import statistics
from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import pandas as pd

from gtsp_bench.bench.best_known import best_known_output
from gtsp_bench.bench.definitions import Benchmark
from gtsp_bench.bench.rows import HIT_GAP_PCT
from gtsp_bench.data.io import atomic_write_csv, atomic_write_text

Output = Callable[[Benchmark, pd.DataFrame, Path, Any, Callable[[str], None]], list[Path]]


def _as_sweep(df: pd.DataFrame) -> pd.DataFrame:
    """The rows with the column names the profile functions read."""
    return df.assign(solver=df["label"], gap_percent=df["gap_pct"])


def _profile(bench: Benchmark, df: pd.DataFrame, out_dir: Path, settings: Any, say: Any) -> list[Path]:
    from gtsp_bench.report import profiles
    from gtsp_bench.report.figures import save_png

    prof = profiles.performance_profile(_as_sweep(df))
    atomic_write_csv(out_dir / "profile.csv", prof)
    save_png(profiles.profile_figure(prof), out_dir / "profile.png")
    return [out_dir / "profile.csv", out_dir / "profile.png"]


def _gap_k(bench: Benchmark, df: pd.DataFrame, out_dir: Path, settings: Any, say: Any) -> list[Path]:
    from gtsp_bench.report import profiles
    from gtsp_bench.report.figures import save_png

    sweep = _as_sweep(df)
    if sweep.loc[sweep["gap_percent"].notna(), "K"].nunique() < 2:
        return []
    table = profiles.gap_by_k(sweep)
    atomic_write_csv(out_dir / "gap-k.csv", table)
    save_png(profiles.gap_k_figure(table), out_dir / "gap-k.png")
    return [out_dir / "gap-k.csv", out_dir / "gap-k.png"]


def _anytime(bench: Benchmark, df: pd.DataFrame, out_dir: Path, settings: Any, say: Any) -> list[Path]:
    from gtsp_bench.report import profiles
    from gtsp_bench.report.figures import save_png

    table = profiles.anytime_table(df)
    atomic_write_csv(out_dir / "anytime.csv", table)
    save_png(profiles.time_to_target_figure(df), out_dir / "time-to-target.png")
    return [out_dir / "anytime.csv", out_dir / "time-to-target.png"]


# ---------------------------------------------------------------------- tables for the docs
def gap_time_cell(rows: pd.DataFrame, ms: bool = False) -> str:
    """Mean gap and median time of the answered solves (``*``: a solve stopped at its limit;
    ``(n/m)``: only n of m answered), else why none did."""
    answered = rows[rows["objective"].notna()]
    if answered.empty:
        return "refused" if (rows["status"] == "refused").all() else "failed"
    gaps = answered["gap_pct"].dropna()
    gap = f"{gaps.mean():.2f}%" if len(gaps) else "-"
    if ms:
        time = f"{1000 * answered['runtime_s'].mean():.1f}ms"
    else:
        time = f"{statistics.median(answered['runtime_s']):.2f}s"
    star = "*" if (answered["status"] == "time_limit").any() else ""
    part = f" ({len(answered)}/{len(rows)})" if len(answered) < len(rows) else ""
    return f"{gap} {time}{star}{part}"


def _gap_text(pct: float) -> str:
    """A bound gap in per cent, to 0.001; one that would print as 0.000 but is not 0 shows its
    first significant digit (0.0001: a bound 11 below 9,187,884), so it never reads as a proof."""
    if 0.0 < pct < 0.0005:
        return f"{pct:.{-math.floor(math.log10(pct))}f}"
    return f"{pct:.3f}"


def proof_cell(rows: pd.DataFrame) -> str:
    """Proven count, median time to the answer and the largest gap to the solver's own bound."""
    proven = int((rows["status"] == "optimal").sum())
    times = rows["runtime_s"].dropna()
    median = f"{statistics.median(times):.2f}s" if len(times) else "-"
    worst = rows["bound_gap_pct"].max()
    gap = "" if proven == len(rows) or not math.isfinite(worst) else f", bound gap <= {_gap_text(worst)}%"
    return f"{proven}/{len(rows)} proven, {median}{gap}"


def pivot_markdown(
    df: pd.DataFrame, row: str, column: str, cell: Callable[[pd.DataFrame], str], row_title: str
) -> str:
    """A Markdown table: one line per value of ``row``, one column per value of ``column``."""
    cols = list(dict.fromkeys(df[column]))
    head = [
        f"| {row_title} | " + " | ".join(f"{column}={c}" if column == "K" else str(c) for c in cols) + " |",
        "|---|" + "---:|" * len(cols),
    ]
    lines = []
    for value, g in df.groupby(row, sort=False):
        cells = [cell(g[g[column] == c]) if (g[column] == c).any() else "-" for c in cols]
        lines.append(f"| {value} | " + " | ".join(cells) + " |")
    return "\n".join(head + lines)


def _made_by(bench: Benchmark, df: pd.DataFrame, command: str) -> str:
    limits = sorted({f"{v:g} s" for v in df["time_limit"].dropna()}) or ["no time limit"]
    return (
        f"Made by `{command or 'gtsp-bench bench ' + bench.name}` into `results/{bench.name}/rows.csv` "
        f"({len(df)} solves; {', '.join(limits[:3])}{' ...' if len(limits) > 3 else ''} per solve; "
        f"the date and the machine in its `manifest.json`)."
    )


def read_manifest(out_dir: Path) -> dict[str, Any]:
    """``out_dir/manifest.json`` as a dict (empty when it is missing, unreadable or not an
    object)."""
    import json

    try:
        data = json.loads((out_dir / "manifest.json").read_text())
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


#: A page quotes at most this many merged reruns' commands; beyond, their count and the last.
MERGES_QUOTED = 2


def run_command(out_dir: Path) -> str:
    """The command a run into ``out_dir`` was made with (its ``manifest.json``), else ``""``;
    then the commands of the partial reruns merged into it (``--merge-into``), each quoted on its
    own (joined by ``"`, then `"``: the page shows them in code spans after "Made by"). Past
    :data:`MERGES_QUOTED` reruns, their count and the last one's command (every command stays in
    the manifest): a table merged into many times keeps a readable line."""
    manifest = read_manifest(out_dir)
    try:
        merges = [str(m["command"]) for m in manifest.get("merges", [])]
        first = str(manifest["command"])
    except (KeyError, TypeError, AttributeError):
        return ""
    if len(merges) <= MERGES_QUOTED:
        return "`, then `".join([first, *merges])
    return (f"{first}`, then {len(merges)} partial reruns merged in (each command in its "
            f"`manifest.json`), the last `{merges[-1]}")


def heuristics_block(bench: Benchmark, df: pd.DataFrame, command: str = "") -> str:
    """The heuristics page's table: a line per group, a column per solver."""
    listing = "\n".join(
        f"- {s}: {', '.join(dict.fromkeys(g['instance']))}" for s, g in df.groupby("set", sort=False)
    )
    return (
        f"{_made_by(bench, df, command)}\n\n"
        f"{pivot_markdown(df, 'set', 'label', gap_time_cell, 'group')}\n\n"
        "Cells: mean gap to the reference / median solve time; `*`: some solves stopped at the "
        "time limit; `(n/m)`: only n of m solves answered; `refused`: the solver declines the "
        f"instances by design.\n\n{listing}"
    )


def anytime_block(bench: Benchmark, df: pd.DataFrame, command: str = "") -> str:
    """The primal integrals and times to target: a line per group, a column per solver."""

    def cell(g: pd.DataFrame) -> str:
        g = g[g["status"] != "refused"]
        if g.empty:
            return "refused"
        reached = g["time_to_1pct_s"].notna().sum()
        return f"{g['primal_integral'].mean():.3f} ({reached}/{len(g)})"

    return (
        f"{_made_by(bench, df, command)}\n\n"
        f"{pivot_markdown(df, 'set', 'label', cell, 'group')}\n\n"
        "Cells: mean primal integral (Berthold 2013; the primal gap over the time limit, divided by "
        "it: 0 is the reference at once, 1 nothing in time; a solve killed at its hard limit counts 1) "
        "and how many solves came within 1 % of the reference in time; `refused`: the solver declines "
        "the instances by design. The times to target are in the figure below and in the rows."
    )


def learned_block(bench: Benchmark, df: pd.DataFrame, command: str = "") -> str:
    """The learned page's table: a line per policy, a column per K (both omegas)."""
    return (
        f"{_made_by(bench, df, command)}\n\n"
        f"{pivot_markdown(df, 'label', 'K', lambda g: gap_time_cell(g, ms=True), 'solver')}\n\n"
        "Cells: mean gap to the reference (K <= 10: the optimum by `dp`; above: the sets' "
        "`reference.csv`) / batched milliseconds per instance."
    )


def transfer_block(bench: Benchmark, df: pd.DataFrame, command: str = "") -> str:
    """The learned page's transfer table: a line per set, a column per solver."""
    return (
        f"{_made_by(bench, df, command)}\n\n"
        f"{pivot_markdown(df, 'set', 'label', lambda g: gap_time_cell(g, ms=True), 'set')}\n\n"
        "Cells: mean gap to the reference (the UAV sets: the best tour of the benchmark, `lns` "
        "to convergence; GTSPLIB: `best_known.csv`) / milliseconds per instance."
    )


def exact_scale_block(bench: Benchmark, df: pd.DataFrame, command: str = "") -> str:
    """The exact page's tables at scale (``exact-scale``, ``exact-frontier-uav``): a line per
    set, a column per solver."""
    return (
        f"{_made_by(bench, df, command)}\n\n"
        f"{pivot_markdown(df, 'set', 'label', proof_cell, 'set')}\n\n"
        "Cells: optima proven / solves, median seconds, and the largest gap to `milp`'s own "
        "bound among the unproven."
    )


def _value(v: float) -> str:
    if not math.isfinite(v):
        return "-"
    return f"{v:,.0f}" if float(v).is_integer() else f"{v:,.2f}"


def frontier_block(bench: Benchmark, df: pd.DataFrame, command: str = "") -> str:
    """The exact page's GTSPLIB frontier (``exact-frontier``): a line per file of the benchmark
    and solve; a file without a solve shows its ``best_known.csv`` status. The certified gap is
    the solve's bound against the better of its tour and the best-known tour."""
    from gtsp_bench.bench.anytime import parse_trajectory, proof_time
    from gtsp_bench.bench.definitions import Gtsplib
    from gtsp_bench.bench.pool import certificate_verdict
    from gtsp_bench.bench.sources import gtsplib_references

    refs = [r for src in bench.sources if isinstance(src, Gtsplib) for _, r in gtsplib_references(src)]
    lines = ["| file | best known | milp | seconds | tour | bound | certified gap |",
             "|---|---:|---|---:|---:|---:|---:|"]
    for r in refs:
        known = _value(r.value) + (" (optimal)" if r.status == "optimal" else "")
        mine = df[df["instance"] == r.name]
        if mine.empty:
            proof = "not run; proven earlier, certificate shipped" if r.certificate else "not run"
            lines.append(f"| {r.name} | {known} | {proof} | | | | |")
        for row in mine.itertuples():
            what = "proven" if row.status == "optimal" else str(row.status).replace("_", " ")
            verdict = certificate_verdict(row.note)
            what += f", {verdict}" if verdict else ""
            upper = min(row.objective, r.value) if math.isfinite(row.objective) else r.value
            lb = row.lower_bound
            gap = f"{_gap_text(100.0 * (upper - lb) / upper)} %" if math.isfinite(lb) else "-"
            secs = f"{row.runtime_s:.0f}"
            if verdict and row.status == "optimal" and isinstance(row.trajectory, str):
                at = proof_time(parse_trajectory(row.trajectory), row.objective, 1.0)  # integer costs
                late = row.runtime_s - at  # NaN (no proof point): the solve's seconds
                secs = f"{at:.0f} (+{late:.0f} certificate)" if late > 0.5 else secs
            lines.append(f"| {r.name} | {known} | {what} ({row.label}, seed {row.seed}) | "
                         f"{secs} | {_value(row.objective)} | {_value(lb)} | {gap} |")
    here = set(df.loc[df["status"] == "optimal", "instance"])
    proven = [r for r in refs if r.name in here or r.status == "optimal"]
    run = sum(r.name in set(df["instance"]) for r in refs)
    return (
        f"{_made_by(bench, df, command)}\n\n{len(proven)} of {len(refs)} files proven optimal "
        f"({len(here & {r.name for r in refs})} by the solves below); {run} of {len(refs)} "
        "run.\n\n" + "\n".join(lines) + "\n\n"
        "Best known: `instances/gtsplib/best_known.csv` (optimal: proven by `milp`, its certificate "
        "in `instances/gtsplib/proofs/`). Certified gap: the solve's lower bound against the "
        "better of its own tour and the best-known tour. Seconds: the solve's, or until the proof "
        "and then writing its certificate."
    )


def textbook_block(bench: Benchmark, df: pd.DataFrame, command: str = "") -> str:
    """The textbook models against milp and dp: a line per K, a column per model."""
    return (
        f"{_made_by(bench, df, command)}\n\n"
        f"{pivot_markdown(df, 'K', 'label', proof_cell, 'K')}\n\n"
        "Cells: optima proven / solves, median seconds, and the largest gap to the model's own "
        "bound among the unproven."
    )


@dataclass(frozen=True)
class GlnsTotals:
    """lns over GLNS's files: the mean gap (over files, of each file's mean over seeds), files
    with a run at the best known, the worst run and its file, runs at the best known."""

    mean_gap: float
    files: int
    files_hit: int
    worst: float
    worst_instance: str
    runs: int
    runs_hit: int


def glns_totals(df: pd.DataFrame) -> GlnsTotals | None:
    """The totals of the rows that have a gap (``None``: none has)."""
    gaps = df.dropna(subset=["gap_pct"])
    if gaps.empty:
        return None
    per_file = gaps.groupby("instance", sort=False)["gap_pct"]
    worst = gaps.iloc[int(gaps["gap_pct"].to_numpy().argmax())]
    return GlnsTotals(float(per_file.mean().mean()), per_file.ngroups,
                      int((per_file.min() <= HIT_GAP_PCT).sum()), float(worst["gap_pct"]),
                      str(worst["instance"]), len(gaps), int((gaps["gap_pct"] <= HIT_GAP_PCT).sum()))


def glns_targets_block(bench: Benchmark, df: pd.DataFrame, command: str = "") -> str:
    """lns on GLNS's files (:func:`glns_totals`) as a table of the page."""
    t = glns_totals(df)
    if t is None:
        return f"{_made_by(bench, df, command)}\n\nNo run has a gap."
    return (
        f"{_made_by(bench, df, command)}\n\n"
        "| measure | lns |\n|---|---:|\n"
        f"| mean gap | {t.mean_gap:.4f} % |\n"
        f"| files at the best known at least once | {t.files_hit} of {t.files} |\n"
        f"| worst run | {t.worst:.3f} % ({t.worst_instance}) |\n"
        f"| runs at the best known | {t.runs_hit} of {t.runs} |"
    )


#: Output name -> (page, block, renderer).
DOC_BLOCKS: dict[str, tuple[str, str, Callable[..., str]]] = {
    "doc-heuristics": ("docs/solvers/heuristics.md", "heuristics-table", heuristics_block),
    "doc-learned": ("docs/solvers/learned.md", "learned-table", learned_block),
    "doc-learned-transfer": ("docs/solvers/learned.md", "learned-transfer-table", transfer_block),
    "doc-exact-scale": ("docs/solvers/exact.md", "exact-scale-table", exact_scale_block),
    "doc-exact-frontier-uav": ("docs/solvers/exact.md", "exact-frontier-uav-table",
                               exact_scale_block),
    "doc-exact-frontier": ("docs/solvers/exact.md", "exact-frontier-table", frontier_block),
    "doc-textbook": ("docs/solvers/exact.md", "textbook-table", textbook_block),
    "doc-glns": ("docs/solvers/heuristics.md", "glns-targets", glns_targets_block),
    "doc-glns-large": ("docs/solvers/heuristics.md", "glns-large-targets", glns_targets_block),
}


def _ttt_figure(df: pd.DataFrame) -> Any:
    from gtsp_bench.report.profiles import time_to_target_figure

    return time_to_target_figure(df)


#: More blocks of the same page an output refreshes: output -> ((block, renderer), ...).
EXTRA_BLOCKS: dict[str, tuple[tuple[str, Callable[..., str]], ...]] = {
    "doc-heuristics": (("heuristics-anytime", anytime_block),),
}
#: Figures an output writes into the docs: output -> ((path in the checkout, maker), ...).
DOC_FIGURES: dict[str, tuple[tuple[str, Callable[[pd.DataFrame], Any]], ...]] = {
    "doc-heuristics": (("docs/img/heuristics-time-to-target.png", _ttt_figure),),
}


def committed_root(bench: Benchmark, out_dir: Path) -> Path | None:
    """The checkout whose ``results/NAME`` is ``out_dir`` (it holds ``mkdocs.yml``), else None."""
    out = out_dir.resolve()
    root = out.parent.parent
    if out.parent.name == "results" and out.name == bench.name and (root / "mkdocs.yml").is_file():
        return root
    return None


def _doc(name: str) -> Output:
    def write(bench: Benchmark, df: pd.DataFrame, out_dir: Path, settings: Any, say: Any) -> list[Path]:
        from gtsp_bench.report.paper import refresh_blocks

        page, block, renderer = DOC_BLOCKS[name]
        root = committed_root(bench, out_dir)
        if root is None:
            return []
        narrowed = settings.narrowed() if hasattr(settings, "narrowed") else []
        if narrowed:  # a part of the benchmark would replace the whole table
            say(f"note: {page}: its table was not refreshed (a run narrowed by "
                f"{', '.join(narrowed)}; the whole benchmark refreshes it)")
            return []
        path = root / page
        if not path.is_file():
            say(f"warning: {path}: no such page; its table was not refreshed")
            return []
        refresh_blocks(path, {block: renderer(bench, df, run_command(out_dir))}, [block])
        written = [path]
        for extra_block, extra in EXTRA_BLOCKS.get(name, ()):
            refresh_blocks(path, {extra_block: extra(bench, df, run_command(out_dir))}, [extra_block])
        for figure, make in DOC_FIGURES.get(name, ()):
            from gtsp_bench.report.figures import save_png

            save_png(make(df), root / figure)
            written.append(root / figure)
        return written

    return write


# ---------------------------------------------------------------------- GLNS
def glns_lines(df: pd.DataFrame) -> list[str]:
    """Per instance: budget, mean gap, hits and worst run beside GLNS's C++ numbers; the targets."""
    import csv

    from gtsp_bench.data import gtsplib

    with (gtsplib.folder() / "glns-45.csv").open(newline="") as f:
        glns = {r["instance"]: r for r in csv.DictReader(f)}
    lines = [
        "| instance | budget s | mean gap % | hits | worst % | GLNS C++ gap % | GLNS hits | GLNS s |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for name, g in df.groupby("instance", sort=False):
        gaps = g["gap_pct"].dropna()
        if gaps.empty:
            continue
        hits = int((gaps <= HIT_GAP_PCT).sum())
        ref = glns.get(name, {})
        lines.append(
            f"| {name} | {g['time_limit'].iloc[0]:.2f} | {gaps.mean():.4f} | {hits}/{len(gaps)} | "
            f"{gaps.max():.3f} | {ref.get('glns_cpp_mean_gap_pct', '-')} | "
            f"{ref.get('glns_cpp_hits10', '-')}/10 | {ref.get('glns_cpp_mean_s', '-')} |"
        )
    t = glns_totals(df)
    if t is not None:
        lines += [
            "",
            f"- mean gap: {t.mean_gap:.4f} % over {t.files} instances",
            f"- instances at the best known at least once: {t.files_hit} of {t.files}",
            f"- worst run: {t.worst:.4f} %",
        ]
    return lines


def _glns(bench: Benchmark, df: pd.DataFrame, out_dir: Path, settings: Any, say: Any) -> list[Path]:
    path = out_dir / "glns.md"
    atomic_write_text(
        path, f"# lns against GLNS\n\n{bench.budget.describe()}.\n\n" + "\n".join(glns_lines(df)) + "\n"
    )
    return [path]


# ---------------------------------------------------------------------- reference.csv
def _source(row: pd.Series) -> str:
    """Who found a reference tour: the run's label, its time limit (when it had one), its seed."""
    limit, seed = row["time_limit"], row["seed"]
    return (
        str(row["label"])
        + (f" {float(limit):g}s" if pd.notna(limit) else "")
        + (f" seed {int(seed)}" if pd.notna(seed) else "")
    )


def _best_rows(df: pd.DataFrame) -> Iterator[tuple[tuple[str, str, float | None], pd.DataFrame, pd.Series]]:
    """Per ``(set, instance, omega)`` of the answered rows (omega ``None``: distance-only): its
    rows and the one with the lowest objective."""
    ok = df[df["objective"].notna()]
    omega = ok["omega"].astype(float).fillna(-1.0)
    for (s, inst, w), g in ok.groupby(["set", "instance", omega], sort=False):
        yield (s, inst, None if w < 0 else float(w)), g, g.iloc[int(g["objective"].to_numpy().argmin())]


def new_references(df: pd.DataFrame, today: str) -> dict[str, list[Any]]:
    """Per set folder, the reference rows the run's best tours give: the best objective of each
    (instance, omega), ``optimal`` when a solve proved it, its best lower bound."""
    from gtsp_bench.data.sets import ReferenceRow

    out: dict[str, list[Any]] = {}
    for (s, inst, w), g, best in _best_rows(df):
        proven = bool((g["status"] == "optimal").any())
        lower = g["lower_bound"].max()
        source = _source(best)
        out.setdefault(s, []).append(
            ReferenceRow(
                inst,
                w,
                float(best["objective"]),
                None if not math.isfinite(lower) else float(lower),
                "optimal" if proven else "best_known",
                source,
                today,
            )
        )
    return out


def _set_named(name: str, settings: Any) -> Any:
    """The set a run's rows call ``name``: one of its ``--set`` arguments, else a committed set."""
    from gtsp_bench.data.sets import resolve_set
    from gtsp_bench.errors import InputError

    where = getattr(settings, "instance_dir", "instances")
    for arg in (*(getattr(settings, "sets", None) or ()), name):
        try:
            s = resolve_set(arg, where)
        except InputError:
            continue
        if s.name == name:
            return s
    return None


def _repriced(found: Any, row: Any, best: pd.Series) -> Any:
    """``row`` valued at the exact cost of ``best``'s tour, re-priced from the set's instance file
    (rows.csv keeps 10 digits); as it is when the row holds no tour."""
    from gtsp_bench.data.io import read_instance
    from gtsp_bench.energy import evaluate

    path = next((f.path for f in found.files if f.stem == row.instance), None)
    if path is None or pd.isna(best["order"]) or not str(best["order"]).strip():
        return row
    order, heads = (list(map(int, str(best[c]).split())) for c in ("order", "heads"))
    return replace(row, value=evaluate(read_instance(path), row.omega, order, heads).objective)


def _update_references(
    bench: Benchmark, df: pd.DataFrame, out_dir: Path, settings: Any, say: Any
) -> list[Path]:
    from gtsp_bench.checks import strictly_better
    from gtsp_bench.data import gtsplib
    from gtsp_bench.data.sets import read_reference, write_reference

    if bench.name != "references" and not getattr(settings, "update_reference", False):
        return []
    today = dt.date.today().isoformat()
    library = set(gtsplib.names())
    settled = {s for s, g in df.groupby("set") if (g["reference_kind"] == "optimal").all()}
    tours = {point: best for point, _, best in _best_rows(df)}
    written = []
    for set_name, rows in new_references(df, today).items():
        s = _set_named(set_name, settings)
        if s is None and ({r.instance for r in rows} <= library or set_name in settled):
            continue  # a group of GTSPLIB files, or a generated set measured against proven optima
        if s is None:
            say(f"warning: {set_name}: no such set folder; its reference.csv was not updated")
            continue
        if s.reference_path is None:  # GTSPLIB: the output best-known, which --update-reference adds
            continue
        have = read_reference(s.reference_path)
        merged = dict(have)
        changed = []
        # Only the references benchmark adds omegas: a set holds the omegas its file names
        # (a set measured at omega 0 and 0.9 by another benchmark keeps its own grid).
        if have and bench.name != "references":
            held = {o for _, o in have}
            skipped = sorted({str(r.omega) for r in rows if r.omega not in held})
            if skipped:
                say(f"{s.reference_path}: not updated at omega {', '.join(skipped)} "
                    "(the set does not hold it; the rows keep those tours)")
            rows = [r for r in rows if r.omega in held]
        for r in rows:
            old = have.get((r.instance, r.omega))
            if old is None or (
                old.status != "optimal" and (strictly_better(r.value, old.value) or r.status == "optimal")
            ):
                r = _repriced(s, r, tours[(set_name, r.instance, r.omega)])
                if old is not None and old.lower_bound is not None:  # a bound holds whatever the tour
                    r = replace(r, lower_bound=max(old.lower_bound, r.lower_bound or old.lower_bound))
                merged[(r.instance, r.omega)] = r
                was = None if old is None else old.value
                proof = " (proven optimal)" if r.status == "optimal" else ""
                changed.append(f"{r.instance} omega {r.omega}: {was!r} -> {r.value!r}{proof}")
            elif old.status != "optimal" and r.lower_bound is not None and (
                old.lower_bound is None or r.lower_bound > old.lower_bound
            ):  # no better tour, but a better proven bound: the row keeps its tour and source
                if strictly_better(old.value, r.lower_bound):
                    say(f"warning: {s.reference_path}: {r.instance} omega {r.omega}: a bound "
                        f"{r.lower_bound!r} above the tour {old.value!r}; not written")
                    continue
                merged[(r.instance, r.omega)] = replace(old, lower_bound=r.lower_bound)
                changed.append(
                    f"{r.instance} omega {r.omega}: lower bound {old.lower_bound!r} -> {r.lower_bound!r}"
                )
        if changed:
            write_reference(
                s.reference_path, sorted(merged.values(), key=lambda r: (r.instance, r.omega or -1.0))
            )
            written.append(s.reference_path)
            for line in changed:
                say(f"updated {s.reference_path}: {line}")
    return written


OUTPUTS: dict[str, Output] = {
    "profile": _profile,
    "anytime": _anytime,
    "gap-k": _gap_k,
    "glns": _glns,
    "update-references": _update_references,
    "best-known": best_known_output,
    **{name: _doc(name) for name in DOC_BLOCKS},
}


__all__ = [
    "DOC_BLOCKS",
    "OUTPUTS",
    "gap_time_cell",
    "glns_lines",
    "glns_totals",
    "new_references",
    "pivot_markdown",
    "proof_cell",
]

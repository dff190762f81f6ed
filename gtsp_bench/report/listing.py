"""The table of benchmarks in ``docs/benchmarks.md``, made from their definitions.

:func:`benchmarks_markdown` turns :data:`gtsp_bench.bench.definitions.BENCHMARKS` into one
Markdown table (a line per benchmark: what it measures, its instances, solvers, budget and
reference rules, outputs and the rough time of a full run). The page holds it as the generated
block ``benchmarks``; ``python -m gtsp_bench.report.listing`` rewrites that block, and a test
checks that the page and the definitions agree.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path

from gtsp_bench.bench.definitions import BENCHMARKS, Benchmark

#: The generated block of the benchmarks page that holds the table.
BLOCK = "benchmarks"
#: The page, relative to the repository root.
PAGE = Path("docs") / "benchmarks.md"


def _cell(text: str) -> str:
    """``text`` made safe for a Markdown table cell (no pipe, no line break)."""
    return " ".join(text.replace("|", "\\|").split())


def _solvers(bench: Benchmark) -> str:
    """The solver labels of ``bench``, or what it runs when it names none."""
    if not bench.runs:
        return "every registered solver marked for benchmarks (`gtsp-bench solvers`)"
    labels = []
    for r in bench.runs:
        label = f"`{r.name}`"
        hidden = [f"{k}={v}" for k, v in r.options if f"{k}=" not in r.name]  # options the label hides
        notes = [*hidden, *([f"K <= {r.max_k}"] if r.max_k is not None else [])]
        labels.append(label + (f" ({', '.join(notes)})" if notes else ""))
    return ", ".join(labels)


def _budget(bench: Benchmark) -> str:
    """The budget rule, with how a batched benchmark times its solves."""
    text = bench.budget.describe()
    if bench.batched:
        text += f"; batched, median of {bench.repeats} run(s)"
    return text


def _outputs(bench: Benchmark) -> str:
    """The output folder and the named outputs beyond the three files every run writes."""
    named = ", ".join(bench.outputs) if bench.outputs else "-"
    return f"`{bench.output_dir}/`; {named}"


def _grid(bench: Benchmark) -> str:
    """Omegas and seeds, e.g. ``omega 0.3, 0.6; seed 0``."""
    omegas = ", ".join(f"{w:g}" for w in bench.omegas)
    seeds = ", ".join(str(s) for s in bench.seeds)
    return f"omega {omegas}; seed{'s' if len(bench.seeds) > 1 else ''} {seeds}"


def benchmarks_markdown(benchmarks: Mapping[str, Benchmark] | None = None) -> str:
    """The benchmarks as one Markdown table, in definition order.

    Parameters
    ----------
    benchmarks
        The definitions to list (default: :data:`~gtsp_bench.bench.definitions.BENCHMARKS`).

    Returns
    -------
    str
        The table: a header, a rule and one line per benchmark, without a final newline.
    """
    rows: Sequence[Benchmark] = list((BENCHMARKS if benchmarks is None else benchmarks).values())
    lines = [
        "| benchmark | what it measures | instances | solvers | omegas, seeds | budget | reference "
        "| outputs | full run |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for b in rows:
        cells = [
            f"`{b.name}`",
            b.description,
            "; ".join(s.describe() for s in b.sources),
            _solvers(b),
            _grid(b),
            _budget(b),
            b.reference.describe(),
            _outputs(b),
            b.rough_time or "-",
        ]
        lines.append("| " + " | ".join(_cell(c) for c in cells) + " |")
    return "\n".join(lines)


def write_listing(page: Path) -> bool:
    """Rewrite the ``benchmarks`` block of ``page`` from the definitions.

    Parameters
    ----------
    page
        A Markdown file holding the block (normally ``docs/benchmarks.md``).

    Returns
    -------
    bool
        Whether the file changed.
    """
    from gtsp_bench.report.paper import refresh_blocks

    return refresh_blocks(page, {BLOCK: benchmarks_markdown()}, [BLOCK])


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m gtsp_bench.report.listing [PAGE]``: refresh the block (default :data:`PAGE`)."""
    parser = argparse.ArgumentParser(
        prog="python -m gtsp_bench.report.listing",
        description="refresh the generated list of benchmark definitions in a Markdown page")
    parser.add_argument("page", nargs="?", type=Path, default=PAGE,
                        help=f"the page holding the block (default: {PAGE})")
    page = parser.parse_args(argv).page
    if not page.is_file():
        print(f"gtsp-bench: error: {page}: no such file", file=sys.stderr)
        return 2
    changed = write_listing(page)
    print(f"{page}: {'refreshed' if changed else 'already up to date'}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())


__all__ = ["BLOCK", "PAGE", "benchmarks_markdown", "main", "write_listing"]

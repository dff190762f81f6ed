"""The table of benchmarks: made from the definitions, and the docs page holds it as it is made."""

from __future__ import annotations

import re
from dataclasses import replace

from gtsp_bench.bench.definitions import BENCHMARKS, Budget, Committed, run
from gtsp_bench.report.listing import BLOCK, PAGE, benchmarks_markdown, write_listing
from tests.conftest import REPO

_BLOCK = re.compile(rf"<!-- BEGIN generated:{BLOCK} -->\n(.*?)\n<!-- END generated:{BLOCK} -->", flags=re.S)


def _names(table: str) -> list[str]:
    """The first cell of each body line of a Markdown table, without its backticks."""
    return re.findall(r"^\| `([^`]+)` \|", table, flags=re.M)


def test_every_benchmark_is_listed_once_in_definition_order():
    """One line per definition, in the order of BENCHMARKS, each with as many cells as the header."""
    table = benchmarks_markdown()
    lines = table.splitlines()
    assert _names(table) == list(BENCHMARKS)
    assert len(lines) == 2 + len(BENCHMARKS)
    cells = [len(re.split(r"(?<!\\)\|", line)) for line in lines]
    assert len(set(cells)) == 1, cells


def test_a_line_says_what_the_definition_says():
    """A benchmark's line carries its sources, runs' labels, omegas, seeds, budget and reference
    rules, output folder and named outputs, and its rough time."""
    b = BENCHMARKS["learned"]
    (line,) = [x for x in benchmarks_markdown().splitlines() if x.startswith("| `learned` |")]
    for text in (
        b.description,
        *(s.describe() for s in b.sources),
        *(f"`{r.name}`" for r in b.runs),
        "omega 0.3, 0.6",
        b.budget.describe(),
        f"median of {b.repeats}",
        b.reference.describe(),
        f"`{b.output_dir}/`",
        *b.outputs,
        b.rough_time,
    ):
        assert text in line, text


def test_a_new_definition_shows_up_and_pipes_are_escaped():
    """Listing other definitions lists exactly those; a pipe in a description cannot split a cell."""
    mine = replace(
        BENCHMARKS["sets"],
        name="mine",
        description="a | b",
        sources=(Committed(("uav-K20-N20-s1",), 2),),
        runs=(run("lns", "lns starts=4", max_k=50, starts=4),),
        budget=Budget(3.0),
        outputs=(),
        rough_time="",
    )
    table = benchmarks_markdown({"mine": mine})
    assert _names(table) == ["mine"]
    line = table.splitlines()[2]
    assert "a \\| b" in line and "`lns starts=4` (K <= 50)" in line and "3 s per solve" in line
    assert "`results/sets/`; -" in line and line.endswith("| - |")


def test_the_benchmarks_page_holds_the_table_as_made():
    """docs/benchmarks.md's generated block is exactly benchmarks_markdown(); refresh it with
    python -m gtsp_bench.report.listing."""
    (body,) = _BLOCK.findall((REPO / PAGE).read_text(encoding="utf-8"))
    assert body == benchmarks_markdown(), "stale: run python -m gtsp_bench.report.listing"


def test_write_listing_rewrites_only_its_block(tmp_path):
    """write_listing fills the block, keeps the text around it, and reports no change the second
    time."""
    page = tmp_path / "page.md"
    block = f"<!-- BEGIN generated:{BLOCK} -->\n(not run)\n<!-- END generated:{BLOCK} -->"
    page.write_text(f"before\n{block}\nafter\n")
    assert write_listing(page) is True
    text = page.read_text()
    assert text.startswith("before\n") and text.endswith("after\n")
    assert _BLOCK.findall(text) == [benchmarks_markdown()]
    assert write_listing(page) is False


def test_main_refuses_a_missing_page_in_one_line(tmp_path, capsys):
    """A page that does not exist is one error line and exit 2, not a traceback."""
    from gtsp_bench.report.listing import main

    missing = tmp_path / "nope.md"
    assert main([str(missing)]) == 2
    err = capsys.readouterr().err
    assert err == f"gtsp-bench: error: {missing}: no such file\n"
    assert not missing.exists()

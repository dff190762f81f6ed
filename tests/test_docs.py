"""The documentation: the site builds with --strict, every relative link (and anchor) resolves,
and the tables of results in the docs are the ones the code generates from the committed results
(results/paper/*.csv for the paper's blocks, results/NAME/rows.csv for a benchmark's)."""

from __future__ import annotations

import re
import subprocess
import sys
import unicodedata
from pathlib import Path

import pytest

from gtsp_bench.bench.definitions import BENCHMARKS
from gtsp_bench.bench.output_kinds import DOC_BLOCKS, EXTRA_BLOCKS, run_command
from gtsp_bench.bench.rows import read_rows
from gtsp_bench.report.listing import BLOCK as LISTING_BLOCK
from gtsp_bench.report.paper import DOCS_BLOCKS, docs_dir_for, report_blocks

from .conftest import REPO

PAGES = [
    REPO / "README.md",
    REPO / "results" / "README.md",
    REPO / "results" / "paper" / "README.md",
    *sorted((REPO / "instances").glob("*/README.md")),
    *sorted((REPO / "docs").rglob("*.md")),
]
#: The body of a generated block whose benchmark's rows are not committed yet.
NOT_RUN = "(not run)"
_FENCE = re.compile(r"^```.*?^```", flags=re.S | re.M)
_CODE = re.compile(r"`[^`\n]*`")
_LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
_HEADING = re.compile(r"^#{1,6}\s+(.*?)\s*#*\s*$", flags=re.M)
_BLOCK = re.compile(r"<!-- BEGIN generated:(\S+) -->\n(.*?)\n<!-- END generated:\1 -->", flags=re.S)


def _prose(text: str) -> str:
    """The text without fenced code blocks and inline code (their brackets are not links)."""
    return _CODE.sub("", _FENCE.sub("", text))


def _slugs(heading: str) -> set[str]:
    """The anchors a heading gets: on GitHub, and from mkdocs (Python-Markdown's toc)."""
    text = re.sub(r"[`*_]|\[([^\]]*)\]\([^)]*\)", r"\1", heading).strip()
    github = re.sub(r"[^\w\- ]", "", text.lower()).replace(" ", "-")
    ascii_text = unicodedata.normalize("NFKD", text).encode("ascii", "ignore").decode()
    mkdocs = re.sub(r"[-\s]+", "-", re.sub(r"[^\w\s-]", "", ascii_text).strip().lower())
    return {github, mkdocs}


def _anchors(path: Path) -> set[str]:
    headings = _HEADING.findall(_FENCE.sub("", path.read_text(encoding="utf-8")))
    return set().union(*(_slugs(h) for h in headings)) if headings else set()


def _links(path: Path) -> list[str]:
    return _LINK.findall(_prose(path.read_text(encoding="utf-8")))


def test_site_builds_strict(tmp_path):
    """mkdocs build --strict passes: no broken link or anchor."""
    site = tmp_path / "site"
    proc = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--quiet",
         "--config-file", str(REPO / "mkdocs.yml"), "--site-dir", str(site)],
        cwd=REPO, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert (site / "index.html").is_file() and (site / "solvers" / "exact" / "index.html").is_file()


def test_every_docs_page_is_in_the_nav():
    """Every page under docs/ is named in mkdocs.yml's nav (mkdocs only notes a page left out,
    even with --strict)."""
    import yaml

    def paths(node: object) -> list[str]:
        if isinstance(node, str):
            return [node]
        if isinstance(node, list):
            return [p for item in node for p in paths(item)]
        if isinstance(node, dict):
            return [p for value in node.values() for p in paths(value)]
        return []

    config = yaml.safe_load((REPO / "mkdocs.yml").read_text(encoding="utf-8"))
    in_nav = set(paths(config["nav"]))
    pages = {p.relative_to(REPO / "docs").as_posix() for p in (REPO / "docs").rglob("*.md")}
    assert sorted(pages - in_nav) == []


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(REPO)))
def test_relative_links_resolve(page):
    """Every relative link names an existing file, and its anchor (if any) a heading there."""
    broken = []
    for link in _links(page):
        if re.match(r"[a-z][a-z0-9+.-]*:", link):  # https:, mailto:, ...
            continue
        target, _, anchor = link.partition("#")
        path = (page.parent / target).resolve() if target else page
        if not path.exists():
            broken.append(f"{link}: no such file")
        elif anchor and path.suffix == ".md" and anchor not in _anchors(path):
            broken.append(f"{link}: no heading with anchor #{anchor}")
    assert not broken, f"{page.relative_to(REPO)}: " + "; ".join(broken)


def test_link_checker_finds_broken_links(tmp_path):
    """The checker itself: a missing file and a missing anchor are both caught."""
    page = tmp_path / "page.md"
    page.write_text("# Title `x`\n\n[a](#title-x) [b](missing.md) [c](page.md#nope) `[d](code.md)`\n")
    assert _links(page) == ["#title-x", "missing.md", "page.md#nope"]
    assert "title-x" in _anchors(page) and "nope" not in _anchors(page)


def _benchmark_blocks() -> dict[str, str]:
    """Each benchmark's documentation block by name (its doc-* output's block and the extra ones):
    what its renderer makes of the committed ``results/NAME/rows.csv``, or ``(not run)`` while that
    file is not committed."""
    out = {}
    for output, (_, block, renderer) in DOC_BLOCKS.items():
        (bench,) = [b for b in BENCHMARKS.values() if output in b.outputs]
        folder = REPO / bench.output_dir
        rows = read_rows(folder / "rows.csv") if (folder / "rows.csv").is_file() else None
        for name, make in ((block, renderer), *EXTRA_BLOCKS.get(output, ())):
            out[name] = NOT_RUN if rows is None else make(bench, rows, run_command(folder))
    return out


def test_docs_tables_are_generated_from_the_committed_results():
    """Each generated block of a docs page is exactly what the code makes of the committed results:
    the paper's blocks from results/paper/*.csv (and a run into results/paper refreshes the docs,
    mkdocs.yml being beside results/), a benchmark's block from its results/NAME/rows.csv."""
    assert docs_dir_for(REPO / "results" / "paper") == REPO / "docs"
    assert docs_dir_for(REPO / "results" / "quick") is None
    paper = report_blocks(REPO / "results" / "paper", REPO / "solvers" / "learned" / "checkpoints")
    benchmarks = _benchmark_blocks()
    found: dict[str, int] = {}
    for page in sorted((REPO / "docs").rglob("*.md")):
        for name, body in _BLOCK.findall(page.read_text(encoding="utf-8")):
            found[name] = found.get(name, 0) + 1
            if name == LISTING_BLOCK:  # the table of benchmarks: tests/report/test_listing.py
                continue
            if name in benchmarks:
                want, how = benchmarks[name], "gtsp-bench bench NAME --report-only"
            else:
                assert name in DOCS_BLOCKS, f"{page.name}: block {name!r} is not a docs block"
                want, how = paper[name], "gtsp-bench bench paper --report-only"
            assert body == want, f"{page.name}: block {name!r} is stale; run {how}"
    assert found.get("summary", 0) >= 1
    for name in benchmarks:  # each benchmark's block is on its page, once
        assert found.get(name) == 1, f"block {name!r} is on {found.get(name, 0)} pages"


def test_docs_blocks_are_on_the_pages_their_outputs_name():
    """Every doc-* output names a page that holds its blocks, so a run into results/NAME refreshes
    them (a block on another page would never be refreshed)."""
    for output, (page, block, _) in DOC_BLOCKS.items():
        text = (REPO / page).read_text(encoding="utf-8")
        for name in (block, *(b for b, _ in EXTRA_BLOCKS.get(output, ()))):
            assert f"<!-- BEGIN generated:{name} -->" in text, f"{page} lacks the block {name} of {output}"


def test_benchmarks_page_lists_every_docs_block():
    """docs/benchmarks.md names every doc-* output in its table of outputs and gives its page and
    block in the table of blocks (a new output is documented where users look it up)."""
    text = (REPO / "docs" / "benchmarks.md").read_text(encoding="utf-8")
    rows = [line for line in text.splitlines() if line.startswith("| `doc-")]
    for output, (page, block, _) in DOC_BLOCKS.items():
        assert any(f"`{output}`" in r and "generated table" in r for r in rows), f"no {output}"
        assert any(r.startswith(f"| `{output}` |") and page.removeprefix("docs/") in r
                   and f"`{block}`" in r for r in rows), f"no page and block row for {output}"


def test_results_index_names_every_committed_benchmark():
    """results/README.md has a line for each benchmark `make bench-all` regenerates (BENCH_ALL in the
    Makefile), naming its folder and its make target."""
    makefile = (REPO / "Makefile").read_text(encoding="utf-8")
    (line,) = re.findall(r"^BENCH_ALL\s*=\s*(.+)$", makefile, flags=re.M)
    names = line.split()
    index = (REPO / "results" / "README.md").read_text(encoding="utf-8")
    assert "paper" in names and len(names) >= 2
    for name in names:
        assert f"`{name}/`" in index, f"results/README.md: no line for {name}"
        target = "make bench" if name == "paper" else f"make bench-{name}"
        assert f"`{target}`" in index, f"results/README.md: no {target} for {name}"


#: The folder beside the checkout that development machines have and users do not (spelt in
#: parts so that this file does not name it).
OUTSIDE = "/".join(("..", "shared"))


def test_nothing_refers_to_the_folder_beside_the_checkout():
    """No code, test, doc, build or data-description file names a path outside the repository."""
    roots = ("gtsp_bench", "solvers", "tests", "docs", "examples", "benchmarks", ".ci", "instances")
    files = [REPO / name for name in ("README.md", "Makefile", "pyproject.toml", "mkdocs.yml")]
    files += [p for root in roots for p in (REPO / root).rglob("*")
              if p.suffix in {".py", ".md", ".toml", ".yml", ".txt", ""} and p.is_file()]
    assert len(files) > 50
    bad = [str(p.relative_to(REPO)) for p in files
           if OUTSIDE in p.read_text(encoding="utf-8", errors="replace")]
    assert not bad, bad


def test_no_issue_numbers_or_outside_paths():
    """The README and the docs never refer to issue numbers or to files outside the repository."""
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        assert OUTSIDE not in text, page
        assert not re.search(r"\bissues? #?\d+|(?<![\w(/])#\d+\b", text, flags=re.I), page

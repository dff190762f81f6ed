"""The documentation: the site builds with --strict, every relative link (and anchor) resolves,
and the tables of results in the docs are the ones the report code generates from results/*.csv."""

from __future__ import annotations

import re
import subprocess
import sys
import unicodedata
from pathlib import Path

import pytest

from gtsp_bench.report.paper import DOCS_BLOCKS, docs_dir_for, report_blocks

from .conftest import REPO

PAGES = [REPO / "README.md", REPO / "results" / "README.md", *sorted((REPO / "docs").rglob("*.md"))]
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
    """mkdocs build --strict passes: every page is in the nav, no broken link or anchor."""
    site = tmp_path / "site"
    proc = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--quiet",
         "--config-file", str(REPO / "mkdocs.yml"), "--site-dir", str(site)],
        cwd=REPO, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert (site / "index.html").is_file() and (site / "solvers" / "exact" / "index.html").is_file()


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


def test_docs_tables_are_generated_from_the_committed_results():
    """Each generated block of a docs page is exactly what the report code makes of results/*.csv,
    and a run into results/ refreshes the docs (mkdocs.yml beside it)."""
    assert docs_dir_for(REPO / "results") == REPO / "docs"
    assert docs_dir_for(REPO / "results" / "quick") is None
    blocks = report_blocks(REPO / "results", REPO / "solvers" / "learned" / "checkpoints")
    found = 0
    for page in sorted((REPO / "docs").rglob("*.md")):
        for name, body in _BLOCK.findall(page.read_text(encoding="utf-8")):
            if name == "heuristics-table":  # made by make bench-heuristics-table (its own test)
                continue
            assert name in DOCS_BLOCKS, f"{page.name}: block {name!r} is not a docs block"
            assert body == blocks[name], f"{page.name}: block {name!r} is stale; run " \
                "gtsp-bench bench --report-only"
            found += 1
    assert found >= 1


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

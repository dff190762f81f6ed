"""What a run writes: the manifest's provenance and the summary beside the rows."""

from __future__ import annotations

import hashlib
import json

from gtsp_bench.bench.definitions import BENCHMARKS
from gtsp_bench.bench.outputs import manifest, write_core
from tests.bench.frames import row_frame as _rows


def test_the_manifest_names_commit_machine_command_and_instance_hashes(tmp_path):
    """The three files are written; the manifest holds the provenance the docs promise."""
    bench = BENCHMARKS["heuristics"]
    text = "abc"
    sha = hashlib.sha256(text.encode()).hexdigest()
    written, summary = write_core(tmp_path, bench, _rows(), "gtsp-bench bench heuristics", {"x.json": sha},
                                  {"tasks": 1})
    assert [p.name for p in written] == ["rows.csv", "summary.md", "manifest.json"]
    m = json.loads((tmp_path / "manifest.json").read_text())
    assert m["command"] == "gtsp-bench bench heuristics" and m["instances"] == {"x.json": sha}
    assert m["git_commit"] and isinstance(m["git_dirty"], bool) and m["cores"] >= 1
    assert m["budget_rule"] == "10 s per solve" and "dp" in m["reference_rule"]
    assert m["packages"]["numpy"] and m["tasks"] == 1
    assert "| s | lns | 1 | optimal | 0.000 |" in summary
    assert manifest(bench, "", {}, {})["command"].startswith("gtsp-bench")


def test_a_checkout_is_dirty_for_code_not_for_results(tmp_path):
    """A changed file under results/ or docs/ (what runs write) leaves the tree clean; a changed
    solver file makes it dirty; untracked files never count."""
    import subprocess

    from gtsp_bench.bench.outputs import tree_dirty

    def git(*args: str) -> None:
        subprocess.run(["git", *args], cwd=tmp_path, check=True, capture_output=True)

    for rel in ("results/b/rows.csv", "docs/page.md", "solvers/s.py"):
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_text("a\n")
    git("init", "-q")
    git("add", ".")
    git("-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "c")
    (tmp_path / "results" / "b" / "rows.csv").write_text("b\n")
    (tmp_path / "docs" / "page.md").write_text("b\n")
    (tmp_path / "new.py").write_text("x\n")
    assert not tree_dirty(tmp_path / "results")
    (tmp_path / "solvers" / "s.py").write_text("b\n")
    assert tree_dirty(tmp_path / "results")

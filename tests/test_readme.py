"""The README's and the docs' code examples run as written."""

from __future__ import annotations

import re
from pathlib import Path

from gtsp_bench.energy import evaluate
from gtsp_bench.generator import generate_instance
from gtsp_bench.registry import register_solver, run_solver, solver_names

from .conftest import REPO

ADDING = REPO / "docs" / "adding-a-solver.md"


def _blocks(path: Path, lang: str = "python") -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", path.read_text(encoding="utf-8"), flags=re.S)


def test_readme_api_example_runs():
    """The README's Python example runs, and stays within ten lines: its result is a tour of the
    instance it made, priced as the evaluator prices it."""
    (block,) = _blocks(REPO / "README.md")
    assert "run_solver" in block and len(block.strip().splitlines()) <= 10
    ns: dict = {}
    exec(compile(block, "README.md", "exec"), ns)
    inst, result = ns["inst"], ns["result"]
    assert result.status == "feasible" and sorted(result.order) == list(range(inst.n_clusters))
    assert result.objective == evaluate(inst, 0.3, result.order, result.heads).objective


def test_readme_lists_every_builtin_solver():
    """The README's solver table has one row per built-in solver, and no other; the README and
    the docs' front page count them right."""
    from gtsp_bench.solvers import BUILTIN

    readme = (REPO / "README.md").read_text(encoding="utf-8")
    rows = re.findall(r"^\| `([^`]+)` \|", readme, flags=re.M)
    assert sorted(rows) == sorted(b.name for b in BUILTIN)
    for text in (readme, (REPO / "docs" / "index.md").read_text(encoding="utf-8")):
        assert re.findall(r"(\d+) pluggable solvers", text) == [str(len(BUILTIN))]


def test_adding_a_solver_example_plugs_in():
    """The 'adding a solver' class, registered by class, solves and passes the harness checks."""
    block = next(b for b in _blocks(ADDING) if "class NearestCenter" in b)
    assert len(block.strip().splitlines()) <= 16  # the page promises a ~15-line solver
    namespace: dict = {}
    exec(compile(block, str(ADDING), "exec"), namespace)
    register_solver("docs-nearest-center", namespace["NearestCenter"], "docs example", replace=True)
    result = run_solver("docs-nearest-center", generate_instance(6, seed=4), 0.4)
    assert sorted(result.order) == list(range(6)) and result.status == "feasible"


def test_adding_a_solver_builtin_line_matches_the_file_it_names():
    """The page's Builtin(...) line is valid and its target is the module of the file it names."""
    from gtsp_bench.solvers import Builtin

    line = next(b for b in _blocks(ADDING) if b.lstrip().startswith("Builtin("))
    (builtin,) = eval(line, {"Builtin": Builtin})  # the line ends with a comma: a 1-tuple
    assert builtin.name == "nearest-center" and builtin.name not in solver_names()
    file = re.search(r"one file, `(solvers/[\w/]+\.py)`", ADDING.read_text(encoding="utf-8")).group(1)
    module = "gtsp_bench." + file.removesuffix(".py").replace("/", ".")
    assert builtin.target == f"{module}:NearestCenter"
    assert (REPO / Path(file).parent).is_dir()


def test_adding_a_solver_register_example_runs():
    """The page's register_solver snippet registers the class under its name (the registry is
    restored after each test by conftest)."""
    block = next(b for b in _blocks(ADDING) if "register_solver(" in b)
    cls = type("NearestCenter", (), {"solve": lambda self, *a, **k: None})
    exec(compile(block, str(ADDING), "exec"), {"NearestCenter": cls})
    assert "nearest-center" in solver_names()

"""The README's examples run as written."""

from __future__ import annotations

import re

from gtsp_bench.generator import generate_instance
from gtsp_bench.registry import register_solver, run_solver

from .conftest import REPO


def _python_blocks() -> list[str]:
    return re.findall(r"```python\n(.*?)```", (REPO / "README.md").read_text(), flags=re.S)


def test_readme_solver_example_plugs_in():
    """The 'adding a solver' class, registered by class, solves and passes the harness checks."""
    block = next(b for b in _python_blocks() if "class NearestCenter" in b)
    assert len(block.strip().splitlines()) <= 16  # the README promises a ~15-line solver
    namespace: dict = {}
    exec(compile(block, "README.md", "exec"), namespace)
    register_solver("readme-nearest-center", namespace["NearestCenter"], "README example",
                    replace=True)
    result = run_solver("readme-nearest-center", generate_instance(6, seed=4), 0.4)
    assert sorted(result.order) == list(range(6))


def test_readme_api_example_runs():
    """The first Python example runs."""
    block = _python_blocks()[0]
    assert "run_solver" in block
    exec(compile(block, "README.md", "exec"), {})
    assert run_solver("greedy", generate_instance(3, seed=0), 0.5).status == "feasible"

"""gurobi: the shared model through gurobipy; a clear error without gurobipy or past its licence."""

from __future__ import annotations

import sys

import pytest

from gtsp_bench.cli import main
from gtsp_bench.data.io import write_instance
from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance
from gtsp_bench.registry import get_solver, run_solver

from .test_milp import _instance


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("depot", [True, False])
def test_gurobi_agrees_with_brute(seed, depot):
    """Tiny instances (K = 1..5, one-node clusters included): gurobi, milp and brute agree."""
    pytest.importorskip("gurobipy")
    k = 1 + seed % 5
    sizes = [1 + (seed + i) % 4 for i in range(k)]
    inst = _instance(seed, k, sizes, depot)
    brute = run_solver("brute", inst, 0.4)
    for options in ({}, {"root_rounds": 0, "lns_trials": 0}):  # root proof, then Gurobi's MILP
        r = run_solver(get_solver("gurobi", **options), inst, 0.4)
        assert r.status == "optimal"
        assert r.objective == pytest.approx(brute.objective, rel=1e-9, abs=1e-9)


def test_gurobi_lazy_rows_on_a_real_instance():
    """K = 7, N = 6 without root cuts: Gurobi's search with lazy subtour rows finds the dp optimum."""
    pytest.importorskip("gurobipy")
    inst = generate_instance(7, 6, seed=3)
    r = run_solver(get_solver("gurobi", root_rounds=0), inst, 0.5)
    assert r.status == "optimal"
    assert r.objective == pytest.approx(run_solver("dp", inst, 0.5).objective, rel=1e-9)


def test_model_above_the_licence_is_refused_clearly():
    """A model with more than 2000 columns stops with a message naming the licence limit."""
    pytest.importorskip("gurobipy")
    inst = generate_instance(7, 10, seed=0)
    with pytest.raises(InputError, match="too large for Gurobi's size-limited licence"):
        run_solver(get_solver("gurobi", prune=False, core_edges=0, lns_trials=0), inst, 0.5)


def test_without_gurobipy_the_error_is_clear(monkeypatch, tmp_path, capsys):
    """No gurobipy (simulated): get_solver and `solve --solver gurobi` say how to install it."""
    monkeypatch.setitem(sys.modules, "gurobipy", None)  # makes `import gurobipy` fail
    with pytest.raises(InputError, match="needs gurobipy, which is not installed: pip install"):
        get_solver("gurobi")
    path = tmp_path / "k3.json"
    write_instance(generate_instance(3, 3, seed=0), path)
    assert main(["solve", str(path), "--solver", "gurobi"]) == 2
    assert "needs gurobipy" in capsys.readouterr().err


def test_gurobi_reports_incumbents_and_bounds():
    """gurobi reports like milp (the shared search): objectives never rise, bounds never fall."""
    pytest.importorskip("gurobipy")
    r = run_solver("gurobi", generate_instance(8, 4, seed=3), 0.5, time_limit=60.0)
    objectives = [p.objective for p in r.trajectory]
    bounds = [p.lower_bound for p in r.trajectory if p.lower_bound is not None]
    assert objectives == sorted(objectives, reverse=True) and objectives[-1] == r.objective
    assert bounds and bounds == sorted(bounds)

"""The bad-input and time-limit contract of every heuristic, through the CLI."""

from __future__ import annotations

import importlib.util
import json

import pytest

from gtsp_bench.cli import main
from gtsp_bench.data.io import read_instance
from gtsp_bench.energy import evaluate
from gtsp_bench.registry import run_solver
from tests.conftest import OPTIONAL_PACKAGE
from tests.tiny_cases import not_below

HEURISTICS = ["greedy+ls", "aco", "aco+ls", "lns", "ortools"]
#: Peers whose package is an optional extra: tested where it is installed.
HEURISTICS += [name for name in ("pyvrp", "lkh")
               if importlib.util.find_spec(OPTIONAL_PACKAGE[name]) is not None]


@pytest.fixture
def k12(tmp_path, capsys):
    """A generated K = 12, N = 10 instance file."""
    path = tmp_path / "k12.json"
    assert main(["generate", "-k", "12", "-n", "10", "--seed", "4", "-o", str(path)]) == 0
    capsys.readouterr()
    return path


@pytest.mark.parametrize("solver, args, message", [
    *[(s, ["-p", "ants=0"], "ants must be an integer >= 1, got 0") for s in ("aco", "aco+ls")],
    *[(s, ["-p", "ants=-5"], "ants must be an integer >= 1, got -5") for s in ("aco", "aco+ls")],
    *[(s, ["-p", "rho=0"], "rho must be a number in (0, 1], got 0") for s in ("aco", "aco+ls")],
    *[(s, ["-p", "rho=1.5"], "rho must be a number in (0, 1], got 1.5") for s in ("aco", "aco+ls")],
    *[(s, ["-p", "rho=-0.1"], "rho must be a number in (0, 1], got -0.1") for s in ("aco", "aco+ls")],
    *[(s, ["--time-limit", "-1"], "time limit must be > 0 seconds, got -1.0") for s in HEURISTICS],
])
def test_invalid_parameters_exit_2(capsys, k12, solver, args, message):
    """One error line naming the parameter, nothing on stdout, exit code 2."""
    assert main(["solve", str(k12), "--solver", solver, *args]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err.strip().splitlines() == [f"gtsp-bench: error: {message}"]


def test_rho_one_is_allowed(capsys, k12):
    """rho = 1 is inside (0, 1]."""
    assert main(["solve", str(k12), "--solver", "aco", "-p", "rho=1", "-p", "iterations=2"]) == 0


@pytest.mark.parametrize("solver", HEURISTICS)
def test_time_limit_hit_returns_best_tour(capsys, k12, solver):
    """A limit far too short: still a feasible tour, status time_limit, its objective the
    evaluator's price of its tour and never below the DP's optimum."""
    assert main(["solve", str(k12), "--solver", solver, "--time-limit", "1e-6", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["status"] == "time_limit"
    assert sorted(result["order"]) == list(range(12))
    inst, omega = read_instance(k12), result["omega"]
    priced = evaluate(inst, omega, result["order"], result["heads"]).objective
    assert result["objective"] == pytest.approx(priced, rel=1e-12)
    assert not_below(priced, run_solver("dp", inst, omega).objective)

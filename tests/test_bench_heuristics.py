"""benchmarks/heuristics.py: reference picking with its fallback, the table, the CSV."""

from __future__ import annotations

import csv
import importlib.util
import sys

import pytest

from gtsp_bench.errors import InputError

from .conftest import REPO

_spec = importlib.util.spec_from_file_location("bench_heuristics", REPO / "benchmarks" / "heuristics.py")
bench = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = bench  # dataclasses look their module up there
_spec.loader.exec_module(bench)

SMALL = ["--k", "4", "--instances", "2", "--solvers", "greedy", "greedy+ls", "--no-gtsplib"]


def test_parse_exact():
    """NAME[:MAX_K] entries in order; a bad K is an InputError."""
    assert bench.parse_exact("dp:10,milp") == [("dp", 10), ("milp", None)]
    with pytest.raises(InputError, match="bad entry"):
        bench.parse_exact("dp:ten")


def test_exact_reference_and_csv(tmp_path, capsys):
    """With dp as the reference the gaps are to the optimum; the CSV has one row per solve."""
    out = tmp_path / "runs.csv"
    assert bench.main([*SMALL, "--exact", "dp", "--csv", str(out)]) == 0
    text = capsys.readouterr().out
    assert "optimum (dp)" in text and "greedy+ls" in text
    rows = list(csv.DictReader(out.open()))
    assert len(rows) == 4
    assert all(float(r["gap_percent"]) >= -1e-9 for r in rows)
    assert {r["reference_kind"] for r in rows} == {"optimum (dp)"}


def test_fallback_to_best_found(capsys):
    """An exact solver that is not registered falls back to the best found, labelled so."""
    assert bench.main([*SMALL, "--exact", "no-such-solver"]) == 0
    assert "best found" in capsys.readouterr().out


def test_unknown_solver_exits_2(capsys):
    """An unknown solver name is reported on one line, exit code 2."""
    assert bench.main(["--k", "4", "--instances", "1", "--solvers", "nope", "--no-gtsplib"]) == 2
    assert "unknown solver 'nope'" in capsys.readouterr().err

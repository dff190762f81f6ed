"""benchmarks/exact.py: list parsing, the table and CSV, and the agreement check."""

from __future__ import annotations

import csv
import importlib.util
import sys

import pytest

from .conftest import REPO

_spec = importlib.util.spec_from_file_location("bench_exact", REPO / "benchmarks" / "exact.py")
bench = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = bench  # dataclasses look their module up there
_spec.loader.exec_module(bench)


def test_parse_lists():
    """Ranges and lists of K; omegas; a bad entry is refused."""
    assert bench.parse_ints("4..6,10") == [4, 5, 6, 10]
    assert bench.parse_floats("0,0.5") == [0.0, 0.5]
    with pytest.raises(Exception, match="bad list"):
        bench.parse_ints("4..x")


def test_small_run_table_and_csv(tmp_path, capsys):
    """milp and dp on two K = 4 instances: both prove every optimum, they agree, one CSV row each."""
    out = tmp_path / "exact.csv"
    code = bench.main(["--k", "4", "--instances", "2", "--omegas", "0.5", "--no-gtsplib",
                       "--csv", str(out)])
    assert code == 0
    text = capsys.readouterr().out
    assert "2/2" in text and "0 disagreement(s)" in text
    rows = list(csv.DictReader(out.open()))
    assert len(rows) == 4
    assert {r["solver"] for r in rows} == {"milp", "dp"}
    assert all(r["status"] == "optimal" for r in rows)


def test_disagreement_is_reported():
    """Two proven optima that differ are listed; unproven solves are ignored."""
    runs = [bench.Run("K=4", "a", 0.5, "milp", "optimal", 10.0, 10.0, 0.1),
            bench.Run("K=4", "a", 0.5, "dp", "optimal", 10.5, 10.5, 0.1),
            bench.Run("K=4", "b", 0.5, "milp", "time_limit", 11.0, 9.0, 60.0),
            bench.Run("K=4", "b", 0.5, "dp", "optimal", 10.0, 10.0, 0.1)]
    bad = bench.disagreements(runs)
    assert len(bad) == 1 and bad[0].startswith("a omega=0.5")
    cell = bench.median_time(runs[2:], 60.0)  # one of two proven: the median is past the limit
    assert cell.startswith(">") and cell.split()[-1] == "1/2"

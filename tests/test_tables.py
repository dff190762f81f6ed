"""The suites' shared rows, cells, tables, timing and CSV writing (gtsp_bench.bench.tables)."""

from __future__ import annotations

import csv
import math

import pytest

from gtsp_bench.bench.tables import (
    Row,
    count_failed,
    gap_time_cell,
    grid_header,
    grid_line,
    median_wall,
    solve,
    time_to_proof_cell,
    write_csv,
)
from gtsp_bench.errors import InputError
from gtsp_bench.generator import instance_set
from gtsp_bench.registry import register_solver
from gtsp_bench.solver import Solution


def _row(solver: str, objective: float, runtime: float, status: str = "feasible") -> Row:
    return Row("K=4", "a", 0.5, solver, status, objective, runtime_s=runtime).against(100.0, "optimum (dp)")


def test_row_gap_and_reference():
    """The gap is in percent of the reference; without one it is NaN."""
    r = _row("greedy", 104.0, 0.1)
    assert r.gap == pytest.approx(4.0) and r.reference_kind == "optimum (dp)"
    assert math.isnan(Row("K=4", "a", 0.5, "greedy", "feasible", 1.0).gap)


class _Infeasible:
    def solve(self, instance, omega, *, time_limit=None, seed=0):
        return Solution((0,), (0,), 0.0)


class _Crash:
    def solve(self, instance, omega, *, time_limit=None, seed=0):
        raise RuntimeError("boom")


def test_solve_records_result_and_failure():
    """A solve through the harness keeps status, objective, bound and time; an unknown solver
    becomes a refused row, a solver that raises a failed one, each with the error's first line
    as its note; count_failed counts only the failures."""
    inst = instance_set(1, 3, 0, n_nodes=3)[0]
    ok = solve("K=3", inst, 0.5, "dp", 10.0, 0)
    assert ok.status == "optimal" and ok.objective > 0 and ok.runtime_s >= 0
    assert ok.lower_bound == pytest.approx(ok.objective)
    bad = solve("K=3", inst, 0.5, "no-such-solver", 10.0, 0)
    assert bad.status == "refused" and math.isnan(bad.objective) and "no-such-solver" in bad.note
    assert "\n" not in bad.note
    register_solver("tables-infeasible", _Infeasible, "visits one cluster")
    register_solver("tables-crash", _Crash, "raises")
    wrong = solve("K=3", inst, 0.5, "tables-infeasible", 10.0, 0)
    assert wrong.status == "failed" and "returned an infeasible solution" in wrong.note
    crash = solve("K=3", inst, 0.5, "tables-crash", 10.0, 0)
    assert crash.status == "failed" and crash.note == "RuntimeError: boom"
    assert count_failed([ok, bad, wrong, crash]) == 2


def test_time_to_proof_cell():
    """Median over all solves; unproven ones count as beyond the limit."""
    rows = [_row("dp", 1, t, "optimal") for t in (0.1, 0.3, 0.2)]
    assert time_to_proof_cell(rows, 60.0) == "   0.20s 3/3"
    rows[0] = _row("dp", 1, 60.0, "time_limit")
    rows[1] = _row("dp", 1, 60.0, "time_limit")
    assert time_to_proof_cell(rows, 60.0) == ">    60s 1/3"


def test_gap_time_cell_and_grid():
    """Mean gap, median time and the time-limit star; the grid right-aligns cells under their
    headings and prints a missing cell as '-'."""
    rows = [_row("aco", 101.0, 0.5), _row("aco", 103.0, 0.1, "time_limit"), _row("aco", 100.0, 0.2)]
    assert gap_time_cell(rows) == " 1.333%  0.20s*"
    assert gap_time_cell(rows[2:]) == " 0.000%  0.20s "
    head, rule = grid_header("K", ["aco", "dp"], 6)
    assert head == "K |    aco |     dp" and rule == "-" * len(head)
    assert grid_line("4", ["1.0", None], 6) == "4 |    1.0 |      -"


def test_median_wall_returns_last_result():
    """The call runs `repeats` times; its last result comes back with a non-negative time."""
    calls = []
    result, wall = median_wall(lambda: calls.append(1) or len(calls), 3)
    assert result == 3 and len(calls) == 3 and wall >= 0
    with pytest.raises(InputError, match="repeats must be >= 1"):
        median_wall(lambda: None, 0)


def test_write_csv(tmp_path):
    """The CSV gets its folder, header and rows (no temporary file left)."""
    path = write_csv(tmp_path / "a" / "b.csv", ["x", "y"], [[1, "p,q"], [2, ""]])
    with path.open(newline="") as f:
        assert list(csv.reader(f)) == [["x", "y"], ["1", "p,q"], ["2", ""]]
    assert [p.name for p in path.parent.iterdir()] == ["b.csv"]

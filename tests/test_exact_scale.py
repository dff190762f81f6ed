"""benchmarks/exact_scale.py: the exact-at-scale table, on two tiny solves."""

from __future__ import annotations

import csv
import importlib.util
import sys

from .conftest import REPO


def _script():
    spec = importlib.util.spec_from_file_location("exact_scale", REPO / "benchmarks" / "exact_scale.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # (its dataclass looks its module up)
    spec.loader.exec_module(module)
    return module


def test_table_rows_and_csv(tmp_path, capsys):
    """A GTSPLIB instance (named as the library names it) and a UAV instance at two omegas: one
    line each, proven, gap 0, the GTSPLIB optimum matching the best known; the CSV has the rows."""
    script = _script()
    out = tmp_path / "rows.csv"
    code = script.main(["--gtsplib", "3burma14", "--uav", "4", "--seeds", "1", "--omegas", "0,0.9",
                        "--time-limit", "30", "--csv", str(out)])
    text = capsys.readouterr().out
    assert code == 0
    assert "GTSPLIB: 1/1 proven" in text and "UAV K=4: 2/2 proven" in text
    rows = list(csv.DictReader(out.open()))
    assert [r["instance"] for r in rows] == ["3burma14", "uav-K4-N20-s1", "uav-K4-N20-s1"]
    assert all(r["status"] == "optimal" and float(r["gap_percent"]) == 0 for r in rows)
    assert rows[0]["match"] == "yes" and float(rows[0]["objective"]) == 1805


def test_gtsplib_groups():
    """The symmetric instances: 63 of at most 442 nodes, 20 of 493-1,084."""
    script = _script()
    small, large = script.gtsplib_names("small"), script.gtsplib_names("large")
    assert len(small) == 63 and len(large) == 20
    assert not set(small) & set(large)
    assert script.gtsplib_names("none") == [] and script.gtsplib_names("a, b") == ["a", "b"]

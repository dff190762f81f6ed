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


def test_an_interrupted_run_resumes_from_its_csv(tmp_path, capsys, monkeypatch):
    """A second run with the same settings solves only what the CSV lacks (the kept line is
    marked); a run with another time limit solves again and keeps the first run's rows in the file;
    ``--redo`` solves everything again."""
    script = _script()
    out = tmp_path / "rows.csv"
    calls = []
    real = script.solve

    def counting(group, inst, omega, *rest):
        calls.append((inst.name, omega))
        return real(group, inst, omega, *rest)

    monkeypatch.setattr(script, "solve", counting)
    base = ["--gtsplib", "none", "--uav", "4", "--seeds", "1", "--time-limit", "30", "--csv", str(out)]
    assert script.main([*base, "--omegas", "0"]) == 0
    first = list(csv.DictReader(out.open()))
    assert calls == [("uav-K4-N20-s1", 0.0)]
    capsys.readouterr()
    assert script.main([*base, "--omegas", "0,0.9"]) == 0
    text = capsys.readouterr().out
    assert calls == [("uav-K4-N20-s1", 0.0), ("uav-K4-N20-s1", 0.9)]
    assert text.count("  kept") == 1 and "UAV K=4: 2/2 proven" in text
    rows = list(csv.DictReader(out.open()))
    assert rows[0] == first[0] and [r["omega"] for r in rows] == ["0.0", "0.9"]
    assert script.main(["--gtsplib", "none", "--uav", "4", "--seeds", "1", "--omegas", "0",
                        "--time-limit", "20", "--csv", str(out)]) == 0
    assert len(calls) == 3
    rows = list(csv.DictReader(out.open()))
    assert sorted(float(r["time_limit_s"]) for r in rows) == [20.0, 30.0, 30.0]
    assert script.main([*base, "--omegas", "0", "--redo"]) == 0
    assert len(calls) == 4 and len(list(csv.DictReader(out.open()))) == 3


def test_a_csv_of_something_else_is_refused_in_one_line(tmp_path, capsys):
    """A CSV that is not this benchmark's table: exit 2, one line naming the file, untouched."""
    script = _script()
    bad = tmp_path / "other.csv"
    bad.write_text("a,b\n1,2\n")
    assert script.main(["--gtsplib", "none", "--uav", "4", "--seeds", "1", "--omegas", "0",
                        "--csv", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"exact_scale: error: {bad}: line 2 ")
    assert bad.read_text() == "a,b\n1,2\n"

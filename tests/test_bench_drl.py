"""benchmarks/drl.py: the learned policies' table against cached exact optima, and its CSV."""

from __future__ import annotations

import csv
import importlib.util
import shutil
import sys

import pytest

pytest.importorskip("torch")

from .conftest import REPO

_spec = importlib.util.spec_from_file_location("bench_drl", REPO / "benchmarks" / "drl.py")
bench = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = bench
_spec.loader.exec_module(bench)


def test_table_and_csv_against_cached_optima(tmp_path, monkeypatch, capsys):
    """Three K = 4 instances: a bound row and one row per solver and omega, gaps >= 0, the paper
    rule's bound never above drl (which uses that rule), and the cached optima are dp's."""
    cache = tmp_path / "exact.csv"
    shutil.copy(bench.CACHE, cache)
    monkeypatch.setattr(bench, "CACHE", cache)
    out = tmp_path / "drl.csv"
    argv = ["--k", "4", "--instances", "3", "--repeats", "1", "--only", "greedy,drl,am", "--csv", str(out)]
    assert bench.main(argv) == 0
    assert "bound: paper heads" in capsys.readouterr().out
    rows = list(csv.DictReader(out.open()))
    labels = {r["solver"] for r in rows}
    assert {"bound: paper heads", "greedy", "drl", "am"} <= labels
    assert len(rows) == 2 * len(labels)  # one row per omega
    gap = {(r["solver"], r["omega"]): float(r["mean_gap_pct"]) for r in rows}
    assert all(v >= -1e-7 for v in gap.values())
    for w in ("0.3", "0.6"):
        assert gap[("bound: paper heads", w)] <= gap[("drl", w)] + 1e-9
    with cache.open(newline="") as f:
        cached = {(r["instance"], float(r["omega"])): float(r["optimum"]) for r in csv.DictReader(f)}
    inst = bench.instance_set(1, 4, bench.TEST_SEED)[0]
    dp = bench.run_solver("dp", inst, 0.3)
    assert dp.objective == pytest.approx(cached[(inst.name, 0.3)], rel=1e-9)

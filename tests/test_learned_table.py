"""The learned table: cells from the generated and the committed sets, the text table, the CLI."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from gtsp_bench.bench.learned_table import large_cells, main, table
from gtsp_bench.data.sets import read_reference

ROOT = Path(__file__).resolve().parents[1]


def test_large_cells_take_the_rows_reference_csv_has():
    """Every instance with a row at an omega, and only those; gaps against the row's value."""
    cells = large_cells([20], [0.3, 0.6], ROOT / "instances")
    refs = read_reference(ROOT / "instances" / "uav-K20-N20-s1" / "reference.csv")
    for cell in cells:
        want = sorted((stem, r.value) for (stem, w), r in refs.items()
                      if w is not None and math.isclose(w, cell.omega))
        assert [i.name for i in cell.instances] == [s for s, _ in want]
        assert np.array_equal(cell.reference, [v for _, v in want])
        assert all(i.n_clusters == 20 for i in cell.instances)
    assert {c.omega for c in cells} == {0.3, 0.6}


def test_table_means_over_omegas():
    results = {("a", 4): [(np.array([1.0, 3.0]), 10.0), (np.array([2.0]), 20.0)]}
    text = table(results, ["a", "b"], [4, 20], {4: 2, 20: 0})
    lines = text.splitlines()
    assert "K=4 (n=2)" in lines[0] and "K=20 (n=0)" in lines[0]
    assert lines[2].split() == ["a", "2.00%", "15.0ms", "-"]
    assert lines[3].split() == ["b", "-", "-"]


def test_cli_runs_a_small_table_and_rejects_bad_input(tmp_path, capsys):
    out = tmp_path / "t.csv"
    code = main(["--solvers", "greedy", "--clusters", "4", "--instances", "2",
                 "--cache", str(tmp_path / "opt.csv"), "--csv", str(out)])
    assert code == 0
    text = capsys.readouterr().out
    assert "greedy" in text and "K=4 (n=2)" in text
    with out.open() as f:
        rows = list(csv.DictReader(f))
    assert [(r["solver"], r["K"], r["omega"]) for r in rows] == [("greedy", "4", "0.3"),
                                                                 ("greedy", "4", "0.6")]
    assert all(float(r["mean_gap_pct"]) >= 0 for r in rows)
    assert main(["--clusters", "30"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("gtsp-bench: error: --clusters: no test set for K = 30") and "\n" not in err
    assert main(["--solvers", "nope", "--clusters", "4", "--instances", "1",
                 "--cache", str(tmp_path / "opt.csv")]) == 2

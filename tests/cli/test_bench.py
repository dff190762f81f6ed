"""The bench command (gtsp_bench.cli.bench): one set of options for every benchmark, each checked
before anything runs or is written; --list; --report-only redraws a run from its rows.csv;
--merge-into folds a partial rerun into a whole run's rows."""

from __future__ import annotations

import pandas as pd
import pytest

from gtsp_bench.bench.definitions import BENCHMARKS
from gtsp_bench.cli import build_parser, main


@pytest.mark.parametrize("args, message", [
    (["exact", "--omegas", "0.5,2"], "bad omegas '0.5,2'"),
    (["heuristics", "-K", "10..4"], "bad K '10..4'"),
    (["heuristics", "--seeds", "x"], "bad seeds 'x'"),
    (["heuristics", "--time-limit", "0"], "time limit must be > 0"),
    (["heuristics", "--jobs", "0"], "jobs must be an integer >= 1"),
    (["sets", "--set", "no-such-set"], "unknown set 'no-such-set': no such folder or file"),
    (["glns", "--names", "nowhere"], "--names: no instance 'nowhere'"),
    (["scale", "--solvers", ","], "--solvers: no solver given"),
    (["heuristics", "--executor", "spark"], "bad executor 'spark'"),
    (["learned", "--report-only"], "rows.csv: cannot read the rows"),
    (["sets", "--solvers", "greedy,lns", "-p", "nope=1"], "solver 'greedy' has no option 'nope'"),
    (["paper", "-p", "effort=fast"], "--param: the paper benchmark fixes its solvers' options"),
])
def test_bad_options_are_one_line_and_write_nothing(tmp_path, capsys, args, message):
    """A bad value of any option: one error line, exit 2, no output folder."""
    code = main(["bench", *args, "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("gtsp-bench: error: ") and err.count("\n") == 1, err
    assert message in err, err
    assert not (tmp_path / "out").exists()


def test_help_explains_the_outputs_and_names_list(capsys):
    """bench --help says what a run writes and how to list the benchmarks."""
    with pytest.raises(SystemExit) as stop:
        build_parser().parse_args(["bench", "--help"])
    assert stop.value.code == 0
    out = capsys.readouterr().out
    for word in ("rows.csv", "summary.md", "manifest.json", "--list", "--quick", "--report-only"):
        assert word in out, word


def test_report_only_redraws_summary_and_doc_table_from_rows(tmp_path, capsys):
    """--report-only solves nothing: it rewrites summary.md from rows.csv (the same table a run
    printed), and the answer on stdout is that table."""
    out = tmp_path / "out"
    argv = ["bench", "heuristics", "-K", "3", "--nodes", "4", "--instances", "2", "--solvers", "greedy",
            "--jobs", "1", "--out", str(out), "--instance-dir", str(tmp_path / "inst"), "--no-progress"]
    assert main(argv) == 0
    first = capsys.readouterr().out
    summary = (out / "summary.md").read_text()
    (out / "summary.md").unlink()
    assert main([*argv, "--report-only"]) == 0
    captured = capsys.readouterr()
    assert captured.out == first and (out / "summary.md").read_text() == summary
    assert "solves run" not in captured.err
    assert len(pd.read_csv(out / "rows.csv")) == 2


def test_list_lines_up_its_columns():
    """--list puts every description in the same column, however long a rough time is."""
    from gtsp_bench.cli.bench import list_text

    lines = list_text().splitlines()
    assert len(lines) == len(BENCHMARKS) + 1
    column = lines[0].index("what it measures")
    for line, b in zip(lines[1:], BENCHMARKS.values(), strict=True):
        assert line.index(b.description) == column, b.name


def test_merge_into_folds_a_partial_rerun_into_a_whole_run(tmp_path, capsys):
    """--merge-into: the rerun's rows replace the same solves' rows of DIR/rows.csv, the others
    stay, DIR's summary is redrawn and its manifest names the command."""
    import json

    whole, part = tmp_path / "whole", tmp_path / "part"
    argv = ["bench", "heuristics", "-K", "3", "--nodes", "4", "--solvers", "greedy", "--jobs", "1",
            "--instance-dir", str(tmp_path / "inst"), "--no-progress"]
    assert main([*argv, "--instances", "2", "--out", str(whole)]) == 0
    rows = pd.read_csv(whole / "rows.csv")
    right = rows["objective"].tolist()
    rows.loc[0, "objective"] = 1e9  # a stale row, that the rerun of the first instance replaces
    rows.to_csv(whole / "rows.csv", index=False)
    capsys.readouterr()
    assert main([*argv, "--instances", "1", "--out", str(part), "--merge-into", str(whole)]) == 0
    captured = capsys.readouterr()
    assert "1 rows replaced, 0 added" in captured.err
    merged = pd.read_csv(whole / "rows.csv")
    assert merged["objective"].tolist() == pytest.approx(right)
    assert merged["instance"].tolist() == rows["instance"].tolist()
    assert "| 2 |" in (whole / "summary.md").read_text() and "| 2 |" in captured.out
    merges = json.loads((whole / "manifest.json").read_text())["merges"]
    assert len(merges) == 1 and "--merge-into" in merges[0]["command"]
    assert merges[0]["replaced"] == 1 and merges[0]["added"] == 0


@pytest.mark.parametrize("target, message", [
    ("missing", "rows.csv: cannot read the rows"),
    ("out", "needs a folder other than the run's --out"),
])
def test_merge_into_a_bad_folder_is_refused_before_anything_runs(tmp_path, capsys, target, message):
    """--merge-into a folder without rows, or the run's own --out: one line, exit 2, no output."""
    out = tmp_path / "out"
    code = main(["bench", "heuristics", "-K", "3", "--nodes", "4", "--instances", "1", "--solvers",
                 "greedy", "--out", str(out), "--merge-into", str(tmp_path / target),
                 "--instance-dir", str(tmp_path / "inst"), "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("gtsp-bench: error: ") and err.count("\n") == 1, err
    assert message in err and not out.exists()


def test_merge_into_is_refused_for_the_paper_benchmark(tmp_path, capsys):
    """The paper benchmark writes experiment CSV files, no rows.csv: nothing to merge."""
    code = main(["bench", "paper", "--out", str(tmp_path / "out"), "--merge-into", str(tmp_path)])
    err = capsys.readouterr().err
    assert code == 2 and "the paper benchmark writes no rows.csv" in err, err
    assert not (tmp_path / "out").exists()

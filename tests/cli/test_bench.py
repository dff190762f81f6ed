"""The bench command (gtsp_bench.cli.bench): each option belongs to a kind of run (the paper's
experiments, --suite, --set), and one given to the wrong kind is one error line before anything
runs or is written."""

from __future__ import annotations

import pytest

from gtsp_bench.cli import build_parser, main


@pytest.mark.parametrize("args, message", [
    (["--omegas", "0.5"], "--omegas is an option of the benchmark suites: add --suite"),
    (["--suite", "exact", "--jobs", "2"], "--jobs is an option of the paper's experiments, not of --suite"),
    (["--suite", "learned", "--executor", "dask"], "--executor is an option of the paper's experiments"),
    (["--set", "x", "--suite", "exact"], "--set runs a sweep of its own: it cannot be combined with --suite"),
    (["--set", "x", "--experiments", "ratio-k"],
     "--set runs a sweep of its own: it cannot be combined with --experiments"),
    (["--set", "x", "--reference", "dp"], "--reference is not an option of --set (see gtsp-bench bench"),
    (["--set", "x", "--seed", "3"], "--seed is not an option of --set (the solver seeds are --seeds)"),
    (["--seeds", "0,1"], "--seeds is an option of --set"),
    (["--update-reference", "--suite", "exact"], "--update-reference is an option of --set"),
])
def test_an_option_of_another_kind_of_run_is_one_line(tmp_path, capsys, args, message):
    code = main(["bench", *args, "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith(f"gtsp-bench: error: {message}") and err.count("\n") == 1
    assert not (tmp_path / "out").exists()


def test_help_names_the_three_kinds_and_every_suite(capsys):
    """bench --help explains the experiments, --suite and --set, and lists each suite's options."""
    with pytest.raises(SystemExit) as stop:
        build_parser().parse_args(["bench", "--help"])
    assert stop.value.code == 0
    out = capsys.readouterr().out
    assert "Run the paper's experiments" in out and "With --suite" in out and "With --set" in out
    for suite in ("exact", "heuristics", "learned"):
        assert f"\n  {suite} " in out

"""The benchmark engine through the command line: quick runs of the main benchmarks write the
three files and a rerun re-uses every solve; a hanging plug-in is killed at its hard limit; a
killed run of a learned and of a suite benchmark resumes without losing or repeating a solve;
damaged logs, killed workers, failures and refusals."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import matplotlib
import pandas as pd
import pytest

from gtsp_bench.bench import tasks
from gtsp_bench.bench.definitions import BENCHMARKS
from gtsp_bench.bench.rows import COLUMNS
from gtsp_bench.cli import main
from tests import runner_solvers
from tests.conftest import REPO

matplotlib.use("Agg")
runner_solvers.register()


def _grid(tmp_path: Path, solvers: str | None, instances: int, *more: str) -> list[str]:
    """A tiny grid benchmark: heuristics at K = 3 (N = 4) with dp's optimum as the reference."""
    argv = [
        "bench",
        "heuristics",
        "-K",
        "3",
        "--nodes",
        "4",
        "--instances",
        str(instances),
        "--jobs",
        "1",
        "--out",
        str(tmp_path / "out"),
        "--instance-dir",
        str(tmp_path / "inst"),
        "--no-progress",
        *more,
    ]
    return argv if solvers is None else [*argv, "--solvers", solvers]


def _log(out: Path) -> list[str]:
    path = out / "tmp" / "runs.jsonl"
    return path.read_text().splitlines() if path.exists() else []


def _three_files(out: Path) -> pd.DataFrame:
    rows = pd.read_csv(out / "rows.csv")
    assert tuple(rows.columns) == COLUMNS
    assert (out / "summary.md").read_text().startswith("# ")
    manifest = json.loads((out / "manifest.json").read_text())
    for key in (
        "git_commit",
        "git_dirty",
        "packages",
        "cpu_model",
        "cores",
        "ram_gib",
        "command",
        "budget_rule",
        "instances",
    ):
        assert key in manifest, key
    assert manifest["packages"]["numpy"] and manifest["instances"]
    assert all(len(h) == 64 for h in manifest["instances"].values())
    return rows


def test_list_names_every_benchmark(capsys):
    """--list prints one line per definition, on stdout, and exits 0."""
    assert main(["bench", "--list"]) == 0
    out = capsys.readouterr().out
    for name in BENCHMARKS:
        assert any(line.startswith(name + " ") for line in out.splitlines()), name


@pytest.mark.parametrize(
    "name, more",
    [
        ("paper", ["-K", "4", "--instances", "1", "--solvers", "greedy"]),
        ("exact", ["-K", "4"]),
        ("heuristics", ["-K", "4,11", "--instances", "1", "--solvers", "greedy,aco"]),
        ("learned", ["-K", "4", "--instances", "4", "--solvers", "greedy,local"]),
        ("glns", ["--names", "31pr152"]),
    ],
)
def test_quick_runs_write_the_three_files_and_a_rerun_reuses_every_solve(tmp_path, capsys, name, more):
    """Each main benchmark's quick variant into a scratch folder: rows.csv (the schema, a tour
    per answered row, gaps >= 0 to a proven optimum), summary.md on stdout, manifest.json; the
    second run runs nothing."""
    argv = [
        "bench",
        name,
        "--quick",
        "--out",
        str(tmp_path / "out"),
        "--instance-dir",
        str(tmp_path / "inst"),
        "--jobs",
        "2",
        "--no-progress",
        *more,
    ]
    assert main(argv) == 0, capsys.readouterr().err
    first = capsys.readouterr()
    rows = _three_files(tmp_path / "out")
    assert first.out.startswith("| set | solver |") and len(rows) > 0
    answered = rows[rows["objective"].notna()]
    assert (answered["order"].str.len() > 0).all() and (answered["heads"].str.len() > 0).all()
    proven = answered[answered["reference_kind"] == "optimal"]
    assert (proven["gap_pct"] >= -1e-7).all()
    assert set(rows["reference_kind"].dropna()) <= {"optimal", "best_known", "best_found"}
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert " 0 to run" in err and "0 solves run" in err, err
    pd.testing.assert_frame_equal(pd.read_csv(tmp_path / "out" / "rows.csv"), rows)


def test_a_hanging_plugin_is_killed_recorded_failed_and_the_run_exits_1(tmp_path, capsys, monkeypatch):
    """A plug-in solver declared by entry point that ignores its time limit, run inside the
    heuristics benchmark, is killed at its hard limit; its rows have no answer and the run exits 1
    while greedy's rows are fine."""
    from importlib.metadata import EntryPoint

    from gtsp_bench import registry

    monkeypatch.setattr(
        registry,
        "entry_points",
        lambda group: [EntryPoint("t-plugin-hang", "tests.runner_solvers:Hang", group)],
    )
    monkeypatch.setattr(registry, "_builtins_loaded", False)
    registry._REGISTRY.clear()  # conftest restores it after the test
    monkeypatch.setattr(tasks, "HARD_LIMIT_GRACE_S", 0.5)
    start = time.monotonic()
    code = main(_grid(tmp_path, "greedy,t-plugin-hang", 1, "--time-limit", "0.2"))
    err = capsys.readouterr().err
    assert code == 1 and time.monotonic() - start < 30, err
    rows = pd.read_csv(tmp_path / "out" / "rows.csv").set_index("solver")
    hang = rows.loc[["t-plugin-hang"]]
    assert (hang["status"] == "time_limit").all() and hang["objective"].isna().all()
    assert hang["note"].str.contains("killed: no answer after 0.9 s").all()
    assert rows.loc[["greedy"]]["objective"].notna().all()
    assert "1 failed" in err and "exit code 1" in err


def _kill_midway(tmp_path: Path, argv: list[str], at: int, total: int) -> list[str]:
    """Start ``gtsp-bench`` with ``argv`` in a fresh process and SIGKILL it once the log holds
    ``at`` records; the log's lines then (fewer than ``total``)."""
    launcher = (
        "import tests.runner_solvers as t; t.register(); from gtsp_bench.cli import main; "
        f"raise SystemExit(main({argv!r}))"
    )
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    proc = subprocess.Popen(
        [sys.executable, "-c", launcher],
        cwd=REPO,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    deadline = time.monotonic() + 120
    try:
        while len(_log(tmp_path / "out")) < at and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.02)
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    before = _log(tmp_path / "out")
    assert at <= len(before) < total, f"not killed midway: {len(before)} of {total}"
    return before


def _resumes(tmp_path: Path, argv: list[str], before: list[str], total: int, capsys) -> None:
    """The rerun keeps every logged solve, runs exactly the others, and logs each key once."""
    capsys.readouterr()
    assert main(argv) == 0
    err = capsys.readouterr().err
    after = _log(tmp_path / "out")
    assert after[: len(before)] == before and len(after) == total
    keys = [json.loads(line)["key"] for line in after]
    assert len(set(keys)) == total
    assert f"{total} solves, {len(before)} already in" in err and f"{total - len(before)} solves run" in err


def test_a_killed_suite_benchmark_resumes_losing_and_repeating_nothing(tmp_path, capsys):
    """kill -9 of the heuristics benchmark midway (a solver taking 0.3 s per solve), then a
    rerun: every finished solve is kept and none is solved twice."""
    argv = _grid(tmp_path, "t-slow", 6)
    total = 12  # six dp references, six t-slow solves
    before = _kill_midway(tmp_path, argv, 8, total)
    _resumes(tmp_path, argv, before, total, capsys)


def test_a_killed_learned_benchmark_resumes_losing_and_repeating_nothing(tmp_path, capsys):
    """kill -9 of the learned benchmark between its batches, then a rerun: the batches logged are
    kept, the others run, and no instance is solved twice."""
    argv = [
        "bench",
        "learned",
        "--quick",
        "-K",
        "4",
        "--instances",
        "30",
        "--solvers",
        "greedy,t-slow",
        "--jobs",
        "1",
        "--out",
        str(tmp_path / "out"),
        "--instance-dir",
        str(tmp_path / "inst"),
        "--no-progress",
    ]
    total = 30 * 2 + 2 * 30 * 2  # dp references; greedy and t-slow, both omegas
    before = _kill_midway(tmp_path, argv, 30 * 2 + 30, total)
    _resumes(tmp_path, argv, before, total, capsys)
    rows = pd.read_csv(tmp_path / "out" / "rows.csv")
    assert len(rows) == 2 * 30 * 2 and rows["objective"].notna().all()


def test_an_unknown_benchmark_or_solver_is_one_line_exit_2(tmp_path, capsys):
    """A misspelt benchmark names the valid ones; a solver of no benchmark nor registry too."""
    assert main(["bench", "heuristic", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("gtsp-bench: error: unknown benchmark 'heuristic' (valid: paper, exact,")
    assert err.count("\n") == 1
    assert main(["bench", "learned", "--solvers", "magic", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "'magic' is no solver of the learned benchmark (its solvers: greedy, drl," in err
    assert not (tmp_path / "o").exists()


def test_unwritable_output_folder_fails_before_any_work(tmp_path, capsys):
    """An --out that is a file: one error line naming the first file the run makes there, exit 2,
    nothing else written (it used to be a traceback after the first solve)."""
    blocker = tmp_path / "out"
    blocker.write_text("not a folder")
    code = main(_grid(tmp_path, "greedy", 1))
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith(f"gtsp-bench: error: {blocker}/") and err.count("\n") == 1
    assert err.endswith(": cannot write (Not a directory)\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


def _csv_without_runtimes(path: Path) -> pd.DataFrame:
    timed = ["runtime_s", "trajectory", "primal_integral", "time_to_1pct_s", "time_to_0p1pct_s"]
    return pd.read_csv(path).drop(columns=timed)


def test_damaged_log_records_are_redone_and_give_the_same_csv(tmp_path, capsys):
    """Each bad record of the log (a list key, a text objective, a line holding only the
    reference's key) is skipped with one warning naming its line; the run exits 0 and writes the
    same table as an undamaged run."""
    argv = _grid(tmp_path, "greedy", 2)
    assert main(argv) == 0
    capsys.readouterr()
    csv = tmp_path / "out" / "rows.csv"
    clean = _csv_without_runtimes(csv)
    log = tmp_path / "out" / "tmp" / "runs.jsonl"
    lines = log.read_text().splitlines()
    records = [json.loads(line) for line in lines]
    dp = next(i for i, r in enumerate(records) if r["solver"] == "dp")
    greedy = next(i for i, r in enumerate(records) if r["solver"] == "greedy")
    damaged = list(lines)
    damaged[dp] = json.dumps({"key": records[dp]["key"]})
    damaged[greedy] = json.dumps({**records[greedy], "objective": "abc"})
    damaged.insert(0, json.dumps({"key": ["x"]}))
    log.write_text("\n".join(damaged) + "\n")
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert "Traceback" not in err
    warnings = [line for line in err.splitlines() if line.startswith("warning: ")]
    assert len(warnings) == 3 and all(f"{log}:" in w for w in warnings), err
    assert f"{log}:1: 'key' is not a non-empty string" in err
    assert "2 solves run" in err and "0 failed" in err
    pd.testing.assert_frame_equal(_csv_without_runtimes(csv), clean)


@pytest.mark.parametrize("ending", ["\n", ""])
def test_a_cut_last_record_is_redone_with_a_warning(tmp_path, capsys, ending):
    """The log's last record cut mid-write, with or without a newline after it: the run exits 0,
    redoes exactly that solve (with a warning naming the line when it is a whole line) and writes
    the same table; the record it appends starts on a line of its own."""
    argv = _grid(tmp_path, "greedy", 2)
    assert main(argv) == 0
    capsys.readouterr()
    csv = tmp_path / "out" / "rows.csv"
    clean = _csv_without_runtimes(csv)
    log = tmp_path / "out" / "tmp" / "runs.jsonl"
    lines = log.read_text().splitlines()
    log.write_text("\n".join([*lines[:-1], lines[-1][: len(lines[-1]) // 2]]) + ending)
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert "Traceback" not in err and "1 solves run, 3 re-used" in err
    warned = [line for line in err.splitlines() if line.startswith("warning: ")]
    assert warned == (
        [f"warning: {log}:{len(lines)}: not a JSON record; skipped, its solve is redone"] if ending else []
    )
    after = log.read_text().splitlines()
    assert after[: len(lines) - 1] == lines[:-1]
    assert json.loads(after[-1])["key"] == json.loads(lines[-1])["key"]
    pd.testing.assert_frame_equal(_csv_without_runtimes(csv), clean)


def test_a_killed_worker_is_retried_by_the_next_run(tmp_path, capsys, monkeypatch):
    """A worker killed from outside under every attempt of a solve: that row is recorded failed
    (cause infrastructure) and bench exits 1 saying so; the next run solves it again, with 0
    failed and exit 0. A solver's own error stays failed until --retry-failed."""
    kills = tmp_path / "kills"
    kills.write_text(str(runner_pool_attempts()))
    monkeypatch.setenv(runner_solvers.KILLS_FILE, str(kills))
    argv = _grid(tmp_path, "t-killed", 1)
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert "1 failed, 0 refused (exit code 1" in err
    row = pd.read_csv(tmp_path / "out" / "rows.csv").set_index("solver").loc["t-killed"]
    assert row["status"] == "failed" and "worker died (exit code -9)" in row["note"]
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert "1 solves run" in err and "0 failed" in err
    row = pd.read_csv(tmp_path / "out" / "rows.csv").set_index("solver").loc["t-killed"]
    assert row["status"] == "feasible"


def runner_pool_attempts() -> int:
    from gtsp_bench.bench.pool import MAX_ATTEMPTS

    return MAX_ATTEMPTS


def test_solver_failures_stay_until_retry_failed_and_refusals_are_not_failures(tmp_path, capsys):
    """A solver's own error is final (a rerun re-uses it, exit 1) until --retry-failed redoes
    it; a refusal by design is counted as refused, and alone does not fail the run."""
    base = _grid(tmp_path, None, 1)
    assert main([*base, "--solvers", "t-refuses"]) == 0
    err = capsys.readouterr().err
    assert "0 failed, 1 refused" in err
    assert main([*base, "--solvers", "t-crash"]) == 1
    assert "1 solves run" in capsys.readouterr().err
    assert main([*base, "--solvers", "t-crash"]) == 1
    assert "0 solves run, 2 re-used, 1 failed" in capsys.readouterr().err
    assert main([*base, "--solvers", "t-crash", "--retry-failed"]) == 1
    assert "1 solves run, 1 re-used, 1 failed" in capsys.readouterr().err


def test_update_reference_writes_a_better_tour_into_the_sets_reference_csv(tmp_path, capsys):
    """A set whose best_known value greedy beats: the run says so; with --update-reference the
    row is replaced (solver, date) and a point without a row gets one; a proven optimum stays."""
    from gtsp_bench.data.io import write_instance
    from gtsp_bench.data.sets import read_reference
    from gtsp_bench.generator import generate_instance

    folder = tmp_path / "mine"
    for i in range(2):
        write_instance(generate_instance(3, 4, seed=i, name=f"mine-{i}"), folder / f"mine-{i}.json")
    (folder / "reference.csv").write_text(
        "instance,omega,value,lower_bound,status,source,date\n"
        "mine-0,0.5,1e9,,best_known,a guess,2026-01-01\n")
    argv = ["bench", "sets", "--set", str(folder), "--solvers", "greedy", "--omegas", "0.5", "--jobs", "1",
            "--out", str(tmp_path / "out"), "--no-progress"]
    assert main(argv) == 0
    assert "better than the best known: mine/mine-0" in capsys.readouterr().err
    assert read_reference(folder / "reference.csv")[("mine-0", 0.5)].value == 1e9
    assert main([*argv, "--update-reference"]) == 0
    refs = read_reference(folder / "reference.csv")
    rows = pd.read_csv(tmp_path / "out" / "rows.csv").set_index("instance")
    assert refs[("mine-0", 0.5)].value == pytest.approx(rows.loc["mine-0", "objective"], rel=1e-9)
    assert (refs[("mine-0", 0.5)].source, refs[("mine-0", 0.5)].status) == ("greedy 10s seed 0", "best_known")
    assert refs[("mine-1", 0.5)].value == pytest.approx(rows.loc["mine-1", "objective"], rel=1e-9)


def test_params_set_options_where_a_solver_takes_them_and_name_them_in_the_label():
    """-p KEY=VALUE: set on every run whose solver takes it (over the run's own value), named in
    its label; runs whose solver does not take it unchanged; an option nobody takes refused."""
    from gtsp_bench.bench.definitions import run
    from gtsp_bench.bench.engine import with_params
    from gtsp_bench.errors import InputError

    runs = (run("lns", "lns budget", effort="budget", mirror=False), run("greedy"))
    lns, greedy = with_params(runs, [("mirror", True), ("remove_fraction", 0.15)])
    assert lns.name == "lns budget mirror=true remove_fraction=0.15"
    assert dict(lns.options) == {"effort": "budget", "mirror": True, "remove_fraction": 0.15}
    assert greedy == runs[1]
    (named,) = with_params((run("lns"),), [("effort", "fast")])
    assert named.name == "lns effort=fast" and named.options == (("effort", "fast"),)
    with pytest.raises(InputError, match="has no option 'nope'"):
        with_params(runs, [("nope", 1)])


def test_initial_best_known_starts_each_gtsplib_solve_from_the_librarys_tour(tmp_path, capsys):
    """-p initial=best-known: the solver gets the library's tour (a solver that returns its warm
    start unchanged lands at the best-known value), the label says so and the task key names the
    tour file; a file without a tour, a solver that cannot start from one and another value are
    one error line each, exit code 2, nothing written."""
    from gtsp_bench.data import gtsplib

    out = tmp_path / "out"
    argv = ["bench", "sets", "--set", "gtsplib", "--names", "11berlin52,16eil76", "--solvers", "t-echo",
            "-p", "initial=best-known", "--out", str(out), "--jobs", "1", "--no-progress"]
    assert main(argv) == 0
    rows = pd.read_csv(out / "rows.csv").set_index("instance")
    table = gtsplib.best_known()
    for name in ("11berlin52", "16eil76"):
        assert rows.loc[name, "objective"] == pytest.approx(table[name].value, rel=1e-12)
        assert rows.loc[name, "label"] == "t-echo initial=best-known"
    keys = [json.loads(line)["key"] for line in (out / "tmp" / "runs.jsonl").read_text().splitlines()]
    assert sorted(k.split("|")[1] for k in keys) == sorted(
        f"t-echo[initial={table[n].tour!r}]" for n in ("11berlin52", "16eil76"))
    capsys.readouterr()
    for bad, says in (
        (["--set", str(REPO / "instances" / "uav-K4-N20-s1"), "--instances", "1", "--solvers", "t-echo"],
         "uav-K4-N20-s1-000.json: initial=best-known starts from the tour of a GTSPLIB file that"),
        (["--set", "gtsplib", "--names", "11berlin52", "--solvers", "t-fixed"],
         "no solver of the run can start from a tour (solvers: t-fixed)"),
    ):
        assert main(["bench", "sets", *bad, "-p", "initial=best-known", "--out", str(tmp_path / "bad"),
                     "--no-progress"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and says in err, err
    assert main(["bench", "sets", "--set", "gtsplib", "--names", "11berlin52", "--solvers", "t-echo",
                 "-p", "initial=glkh", "--out", str(tmp_path / "bad"), "--no-progress"]) == 2
    assert "the one warm start of a benchmark is initial=best-known" in capsys.readouterr().err
    assert not (tmp_path / "bad").exists()


def test_certificate_true_writes_and_checks_each_proof(tmp_path, capsys):
    """-p certificate=true: each proof's certificate lands in OUT/proofs/, the worker's check
    is the row's note (and ``check-proof`` agrees), the label says so and the key keeps it (a
    certifying search is another search); another value and a run whose solvers write no
    certificate are one error line each, exit code 2, nothing written."""
    from gtsp_bench.bench.engine import certificate_path

    out = tmp_path / "out"
    argv = ["bench", "sets", "--set", "gtsplib", "--names", "3burma14,11berlin52", "--solvers", "milp",
            "-p", "certificate=true", "--out", str(out), "--jobs", "1", "--no-progress"]
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert f"certificates: 2 written to {out.resolve() / 'proofs'} and checked, 0 not" in err
    rows = pd.read_csv(out / "rows.csv").set_index("instance")
    records = [json.loads(line) for line in (out / "tmp" / "runs.jsonl").read_text().splitlines()]
    assert all("|milp[certificate=True]|" in r["key"] for r in records)
    for r in records:
        name, path = r["instance"], certificate_path(out, r["instance"], r["key"])
        value = int(rows.loc[name, "objective"])
        assert rows.loc[name, "label"] == "milp certificate=true" and rows.loc[name, "status"] == "optimal"
        assert rows.loc[name, "note"] == f"certificate checked: proven optimal: {value} (proofs/{path.name})"
        assert main(["check-proof", str(REPO / "instances" / "gtsplib" / f"{name}.gtsp.gz"), str(path)]) == 0
        assert capsys.readouterr().out == f"proven optimal: {value}\n"
    assert sorted(p.name for p in (out / "proofs").iterdir()) == sorted(
        certificate_path(out, r["instance"], r["key"]).name for r in records)
    for bad, says in (
        (["--solvers", "milp", "-p", "certificate=c.gz"],
         "--param certificate=c.gz: in a benchmark it is certificate=true"),
        (["--solvers", "greedy", "-p", "certificate=true"],
         "--param certificate=true: no solver of the run writes proof certificates (solvers: greedy)"),
    ):
        assert main(["bench", "sets", "--set", "gtsplib", "--names", "3burma14", *bad,
                     "--out", str(tmp_path / "bad"), "--no-progress"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and says in err, err
    assert not (tmp_path / "bad").exists()


def test_a_gtsplib_tour_below_the_best_known_is_kept_only_with_update_reference(tmp_path, capsys):
    """A GTSPLIB copy whose best_known value greedy beats: the run says how many solves went below
    and how to keep them, and writes nothing there; with --update-reference (the solve re-used)
    the tour is kept in that copy, priced to the row's new value, its published value kept; a
    row proven optimal that a tour undercuts is one error line and exit code 2."""
    from dataclasses import replace

    from gtsp_bench.data import gtsplib
    from gtsp_bench.data.io import read_instance, read_tour
    from gtsp_bench.energy import evaluate
    from tests.conftest import GTSPLIB

    lib = tmp_path / "lib"
    lib.mkdir()
    (lib / "11berlin52.gtsp.gz").write_bytes((GTSPLIB / "11berlin52.gtsp.gz").read_bytes())
    ref = replace(gtsplib.best_known()["11berlin52"], status="best_known", value=10**6, published=10**6)
    (lib / "best_known.csv").write_text(gtsplib.format_best_known([ref]))
    argv = ["bench", "sets", "--set", str(lib), "--solvers", "greedy", "--jobs", "1",
            "--out", str(tmp_path / "out"), "--no-progress"]
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert "better than the best known: lib/11berlin52: greedy seed 0" in err
    assert "1 solve(s) of 1 file(s) went below the best-known value; `gtsp-bench bench sets" in err
    assert not (lib / "tours").exists()
    assert main([*argv, "--update-reference"]) == 0
    err = capsys.readouterr().err
    assert "0 solves run, 1 re-used" in err and "new best known: 11berlin52: 1e+06 -> " in err
    row = gtsplib.parse_best_known((lib / "best_known.csv").read_text())["11berlin52"]
    assert (row.status, row.published, row.source) == ("best_known", 10**6, "gtsp-bench greedy 10s seed 0")
    inst = read_instance(lib / "11berlin52.gtsp.gz")
    assert evaluate(inst, None, *read_tour(lib / row.tour, inst)).objective == row.value
    (lib / "best_known.csv").write_text(gtsplib.format_best_known([replace(row, status="optimal",
                                                                           value=row.value + 1)]))
    assert main([*argv, "--update-reference"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err[-1].startswith(f"gtsp-bench: error: {lib / 'best_known.csv'}: 11berlin52: a tour of length ")
    assert "below the proven optimum" in err[-1]
    assert [p.name for p in (lib / "tours").iterdir()] == [row.tour.removeprefix("tours/")]


def test_whole_settings_drop_what_narrows_a_run(tmp_path):
    """Settings.whole: the same run into another folder without the options that narrowed it
    (what --merge-into redraws); the rest, e.g. the executor, stays."""
    from gtsp_bench.bench.engine import Settings

    narrow = Settings(solvers=("lns",), ks=(10,), names=("a",), seeds=(1,), time_limit=5.0,
                      params=(("kicks", 0),), executor="dask", command="c")
    assert narrow.narrowed() == ["--solvers", "-K", "--names", "--seeds", "--time-limit", "-p"]
    whole = narrow.whole(tmp_path)
    assert whole.narrowed() == [] and whole.out_dir == tmp_path
    assert (whole.executor, whole.command, whole.params) == ("dask", "c", ())

"""The benchmark runner: quick mode end to end, resuming after an interruption or a kill, failing
and hanging solvers as rows, instance sets, and bad input rejected before anything is written."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import matplotlib
import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gtsp_bench.bench import runner, tasks
from gtsp_bench.bench.runner import CSV_COLUMNS, make_config, resolve_references, run_bench
from gtsp_bench.bench.tasklog import TaskLog
from gtsp_bench.cli import main
from gtsp_bench.errors import InputError
from tests import runner_solvers
from tests.bench.test_tasklog import record as _record
from tests.conftest import REPO

matplotlib.use("Agg")
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


runner_solvers.register()


def _dirs(tmp_path: Path) -> list[str]:
    return ["--out", str(tmp_path / "out"), "--instance-dir", str(tmp_path / "inst"), "--no-progress"]


def _config(tmp_path: Path, **kw):
    kw = {"out_dir": tmp_path / "out", "instance_dir": tmp_path / "inst",
          "checkpoint_dir": tmp_path / "ckpt", "progress": False, "n_nodes": 4, "jobs": 2, **kw}
    return make_config(**kw)


def _log_lines(config) -> list[str]:
    return config.log_path.read_text().splitlines() if config.log_path.exists() else []


def test_reference_resolution():
    """dp up to K=12 then milp; brute when neither is registered; unknown names refused."""
    refs = resolve_references("auto", [4, 12, 13], ["dp", "greedy", "milp"])
    assert refs == {4: "dp", 12: "dp", 13: "milp"}
    assert resolve_references(None, [4], ["brute", "greedy"]) == {4: "brute"}
    assert resolve_references("milp", [4, 5], ["dp", "milp"]) == {4: "milp", 5: "milp"}
    with pytest.raises(InputError, match="unknown reference solver 'gurobi'"):
        resolve_references("gurobi", [4], ["dp"])
    with pytest.raises(InputError, match="no exact reference solver"):
        resolve_references("auto", [4], ["greedy"])


@pytest.mark.parametrize("args, message", [
    (["-K", "10..4"], "bad K '10..4'"),
    (["-K", "4..x"], "bad K '4..x'"),
    (["-K", "60"], "would cover"),
    (["--solvers", "greedy,magic"], "unknown solver 'magic' (valid: "),
    (["--jobs", "0"], "jobs must be an integer >= 1"),
    (["--time-limit", "0"], "time limit must be > 0"),
    (["--instances", "0"], "number of instances must be an integer >= 1"),
    (["--report-only"], "no experiment CSV files to report on"),
])
def test_bad_input_exits_2_and_writes_nothing(tmp_path, capsys, args, message):
    """A bad K, solver, experiment or option: one error line, exit 2, no file or folder made."""
    code = main(["bench", "paper", *args, *_dirs(tmp_path)])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("gtsp-bench: error: ") and message in err and err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []


def _check_png(path: Path) -> None:
    from PIL import Image

    data = path.read_bytes()
    assert data.startswith(PNG_SIGNATURE), path
    with Image.open(path) as im:
        im.verify()
    img = matplotlib.image.imread(path)
    assert img.ndim == 3 and img.shape[0] > 100 and img.shape[1] > 100


def test_quick_mode_end_to_end(tmp_path, capsys):
    """--quick exactly as `make bench-quick` runs it (default solvers, N = 20, the shipped
    checkpoints) writes every CSV (documented columns, one row per instance x omega x solver,
    no failed solve, sane ratios), a valid PNG per experiment and the report."""
    code = main(["bench", "--quick", "--jobs", "2", *_dirs(tmp_path)])
    err = capsys.readouterr().err
    assert code == 0, err
    out = tmp_path / "out"
    config = _config(tmp_path, quick=True, n_nodes=20, checkpoint_dir=None)
    n_solvers = len(set(config.solvers) | set(config.references.values()))
    for exp in ("ratio-omega", "ratio-k", "runtime", "trajectories"):
        df = pd.read_csv(out / f"{exp}.csv")
        assert tuple(df.columns) == CSV_COLUMNS
        cells = runner.experiment_cells(config, exp)
        assert len(df) == len(cells) * n_solvers
        assert not df.duplicated(["instance", "omega", "solver"]).any()
        ref = df[df["solver"] == df["reference"]]
        assert (ref["status"] == "optimal").all() and np.allclose(ref["ratio"], 1.0)
        assert set(df["status"]) <= {"optimal", "feasible"}, df[["solver", "note"]].drop_duplicates()
        assert (df["ratio"] >= 1 - 1e-9).all() and (df["runtime_s"] >= 0).all()
        greedy = df[df["solver"] == "greedy"]
        assert len(greedy) and (greedy["status"] == "feasible").all()
        _check_png(out / f"{exp}.png")
    assert set(pd.read_csv(out / "ratio-omega.csv")["omega"]) == set(runner.QUICK_OMEGAS)
    assert set(pd.read_csv(out / "ratio-k.csv")["K"]) == set(runner.QUICK_KS)
    training = pd.read_csv(out / "training.csv")
    assert list(training.columns[:6]) == ["model", "step", "loss", "reward", "val_energy", "wall_s"]
    _check_png(out / "training.png")
    report = (out / "README.md").read_text()
    assert "<!-- BEGIN generated:runtime -->" in report and "| paper Greedy |" in report
    assert "(not run)" not in report
    n_files = sum(1 for _ in (tmp_path / "inst").rglob("*.json"))
    assert n_files == runner.QUICK_INSTANCES * len(runner.QUICK_KS)


def test_interrupt_then_resume_redoes_nothing(tmp_path, monkeypatch):
    """Ctrl-C after 5 finished solves keeps them; the rerun runs only the rest, with no duplicates."""
    config = _config(tmp_path, experiments="ratio-k", ks="3,4", solvers="greedy,t-fixed",
                     n_instances=3)
    calls = {"n": 0}
    original = TaskLog.append

    def append_then_interrupt(self, record):
        original(self, record)
        calls["n"] += 1
        if calls["n"] == 5:
            raise KeyboardInterrupt

    monkeypatch.setattr(TaskLog, "append", append_then_interrupt)
    with pytest.raises(KeyboardInterrupt):
        run_bench(config, log=lambda m: None)
    first = _log_lines(config)
    assert len(first) == 5
    assert not (tmp_path / "out" / "ratio-k.csv").exists()
    monkeypatch.setattr(TaskLog, "append", original)
    summary = run_bench(config, log=lambda m: None)
    assert summary.cached == 5 and summary.run == summary.tasks - 5
    lines = _log_lines(config)
    assert lines[:5] == first and len(lines) == summary.tasks
    keys = [json.loads(line)["key"] for line in lines]
    assert len(set(keys)) == len(keys)
    again = run_bench(config, log=lambda m: None)
    assert again.run == 0 and again.cached == again.tasks
    assert _log_lines(config) == lines


def test_new_solver_revision_is_solved_again(tmp_path, monkeypatch):
    """A solver whose revision changes (a learned policy's new weights) is solved again on the
    next run; solvers without a revision stay re-used, and so does the old revision's log."""
    config = _config(tmp_path, experiments="ratio-k", ks="3", solvers="greedy,t-revised",
                     n_instances=2)
    first = run_bench(config, log=lambda m: None)
    assert first.run == first.tasks
    assert run_bench(config, log=lambda m: None).run == 0
    monkeypatch.setattr(runner_solvers.Revised, "REV", "b")
    tasks._revision.cache_clear()
    try:
        again = run_bench(config, log=lambda m: None)
    finally:
        tasks._revision.cache_clear()
    revised = [json.loads(line) for line in _log_lines(config) if "|t-revised@b|" in line]
    assert again.run == len(revised) > 0 and again.cached == again.tasks - again.run
    assert sum("|t-revised@a|" in line for line in _log_lines(config)) == len(revised)


def test_killed_run_resumes(tmp_path):
    """SIGKILL of a running paper benchmark midway, plus a torn last line: the rerun keeps every
    finished solve, drops the torn line, and runs exactly the missing ones."""
    config = _config(tmp_path, experiments="ratio-omega", ks="3", solvers="t-slow", n_instances=3)
    kw = {"experiments": "ratio-omega", "ks": "3", "solvers": "t-slow", "n_instances": 3, "n_nodes": 4,
          "jobs": 2, "out_dir": str(tmp_path / "out"), "instance_dir": str(tmp_path / "inst"),
          "checkpoint_dir": str(tmp_path / "ckpt"), "progress": False}
    launcher = ("import tests.runner_solvers as t; t.register(); "
                "from gtsp_bench.bench.runner import make_config, run_bench; "
                f"run_bench(make_config(**{kw!r}), log=lambda m: None)")
    cmd = [sys.executable, "-c", launcher]
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    proc = subprocess.Popen(cmd, cwd=REPO, env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    n_ref = 3 * len(runner.OMEGAS)  # the reference solves come first
    deadline = time.monotonic() + 30
    try:
        while len(_log_lines(config)) < n_ref + 3 and time.monotonic() < deadline:
            time.sleep(0.02)
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    before = _log_lines(config)
    total = 2 * n_ref
    assert n_ref + 3 <= len(before) < total, "the run was not killed midway"
    with open(config.log_path, "a") as f:
        f.write('{"key": "torn')
    summary = run_bench(config, log=lambda m: None)
    after = _log_lines(config)
    assert summary.tasks == total and summary.cached == len(before)
    assert summary.run == total - len(before)
    assert after[: len(before)] == before and len(after) == total
    assert all(json.loads(line)["status"] == "feasible" for line in after if "t-slow" in line)


def test_failing_and_hanging_solvers_become_rows(tmp_path, monkeypatch):
    """A solver that raises gives 'failed' rows, one that hangs is killed ('time_limit' without an
    answer), one that cannot be built gives 'failed' rows that are not logged; the other solvers'
    rows are fine. Every row without an answer counts as failed."""
    monkeypatch.setattr(tasks, "HARD_LIMIT_GRACE_S", 0.5)
    config = _config(tmp_path, experiments="ratio-k", ks="3", n_instances=2,
                     solvers="greedy,t-crash,t-hang,t-missing", time_limit=0.2, jobs=2)
    summary = run_bench(config, log=lambda m: None)
    df = pd.read_csv(tmp_path / "out" / "ratio-k.csv")
    by = {s: g for s, g in df.groupby("solver")}
    assert (by["greedy"]["status"] == "feasible").all()
    assert (by["t-crash"]["status"] == "failed").all()
    assert by["t-crash"]["note"].str.contains("RuntimeError: boom").all()
    assert by["t-crash"]["objective"].isna().all()
    assert (by["t-hang"]["status"] == "time_limit").all()
    assert by["t-hang"]["note"].str.contains("killed: no answer after").all()
    assert (by["t-missing"]["status"] == "failed").all()
    assert by["t-missing"]["note"].str.contains("could not be built").all()
    logged = {json.loads(line)["solver"] for line in _log_lines(config)}
    assert "t-missing" not in logged and {"t-crash", "t-hang", "greedy"} <= logged
    assert summary.failed == len(by["t-crash"]) + len(by["t-hang"]) + len(by["t-missing"])
    assert summary.refused == 0


def test_highspy_ortools_torch_solvers_share_a_run(tmp_path):
    """Solvers importing highspy, ortools and torch run in one bench (never in one process),
    torch with one thread; a reference that is not optimal leaves every ratio empty, with a note."""
    config = _config(tmp_path, experiments="ratio-k", ks="3", n_instances=1,
                     solvers="t-highs,t-ortools,t-torch", reference="t-fixed")
    run_bench(config, log=lambda m: None)
    df = pd.read_csv(tmp_path / "out" / "ratio-k.csv")
    assert set(df["solver"]) == {"t-highs", "t-ortools", "t-torch", "t-fixed"}
    assert (df["status"] == "feasible").all(), df["note"].tolist()
    assert df["ratio"].isna().all() and df["optimum"].isna().all()
    assert df["note"].str.contains(r"reference t-fixed not optimal \(feasible\)").all()
    stats = {json.loads(line)["solver"]: json.loads(line)["stats"] for line in _log_lines(config)}
    assert stats["t-torch"] == {"module": "torch", "torch_threads": 1}
    assert stats["t-highs"]["module"] == "highspy"


def test_instance_sets_are_reused_and_checked(tmp_path, capsys):
    """Instance files are written once and re-read; a file with other generator settings is an
    error, a file with changed coordinates is used with a warning."""
    config = _config(tmp_path, ks="3")
    first = runner.load_instance_set(config, 3, 2)
    path = first[1].path
    assert path.exists() and path.parent.name == "uav-K3-N4-s1"
    assert runner.load_instance_set(config, 3, 2)[1].fingerprint == first[1].fingerprint
    data = json.loads(path.read_text())
    data["clusters"][0][0] = [1.0, 2.0]
    path.write_text(json.dumps(data))
    changed = runner.load_instance_set(config, 3, 2)[1]
    assert changed.instance.clusters[0][0].tolist() == [1.0, 2.0]
    assert changed.fingerprint != first[1].fingerprint
    assert "differs from what the generator gives now" in capsys.readouterr().err
    data["meta"]["generator"]["n_nodes"] = 9
    path.write_text(json.dumps(data))
    with pytest.raises(InputError, match="generator settings"):
        runner.load_instance_set(config, 3, 2)


def test_solver_registered_by_class_runs_in_the_workers(tmp_path):
    """README: outside the repository, register_solver(name, YourClass, ...) and the runner uses
    it. A class from an importable module runs in the workers; one defined inside a function
    cannot be imported there and gives 'failed' rows that say why (not 'unknown solver')."""
    from gtsp_bench.registry import register_solver

    def local_class():
        class Local(runner_solvers.FixedTour):
            pass

        return Local

    register_solver("t-by-class", runner_solvers.FixedTour, "by class", bench=False, replace=True)
    register_solver("t-local-class", local_class(), "local class", bench=False, replace=True)
    config = _config(tmp_path, experiments="ratio-k", ks="3", n_instances=2,
                     solvers="t-by-class,t-local-class")
    run_bench(config, log=lambda m: None)
    by = {s: g for s, g in pd.read_csv(tmp_path / "out" / "ratio-k.csv").groupby("solver")}
    assert (by["t-by-class"]["status"] == "feasible").all(), by["t-by-class"]["note"].tolist()
    assert (by["t-local-class"]["status"] == "failed").all()
    assert by["t-local-class"]["note"].str.contains("a worker process cannot import").all()


# ---------------------------------------------------------------------- fuzzing the log reader
# GTSP_BENCH_FUZZ_EXAMPLES=2000 make test runs many more examples than the default.
FUZZ = settings(max_examples=int(os.environ.get("GTSP_BENCH_FUZZ_EXAMPLES", "40")), deadline=None,
                database=None, suppress_health_check=list(HealthCheck))
_json_values = st.recursive(
    st.none() | st.booleans() | st.integers(-(10**20), 10**20) | st.floats() | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner, max_size=4),
    max_leaves=10,
)
_FIELDS = ["key", "solver", "omega", "seed", "status", "objective", "order", "heads", "runtime_s",
           "lower_bound", "note", "cause", "ground_J"]


@st.composite
def _log_line(draw) -> bytes:
    """A log line: a real record with fields replaced or dropped, a random JSON value, or bytes."""
    kind = draw(st.sampled_from(["mutated", "json", "bytes"]))
    if kind == "bytes":
        return draw(st.binary(max_size=40)).replace(b"\n", b"")
    if kind == "json":
        return json.dumps(draw(_json_values)).encode()
    rec = _record("a")
    for _ in range(draw(st.integers(1, 3))):
        name = draw(st.sampled_from(_FIELDS))
        if draw(st.booleans()):
            rec.pop(name, None)
        else:
            rec[name] = draw(_json_values | st.sampled_from(["failed", "refused", "time_limit", "optimal"]))
    return json.dumps(rec).encode()


@FUZZ
@given(lines=st.lists(_log_line(), max_size=6), torn=st.binary(max_size=10))
def test_fuzz_the_log_reader_keeps_only_records_a_table_can_use(tmp_path_factory, lines, torn):
    """Any lines at all (and a torn tail): the reader never raises; each line is kept or named
    in a warning; every record it keeps makes a table row, as a solve or as the reference."""
    from gtsp_bench.data.parse import format_json_instance
    from gtsp_bench.generator import generate_instance

    path = tmp_path_factory.mktemp("log") / "runs.jsonl"
    path.write_bytes(b"".join(line + b"\n" for line in lines) + torn.replace(b"\n", b""))
    log = TaskLog(path)
    key = _record("a")["key"]
    records = log.load({key: (1, 3)})
    assert len(records) + len(log.skipped) <= len(lines)
    assert all(line.startswith(f"{path}:") for line in log.skipped)
    inst = generate_instance(2, 3, seed=0)
    stored = tasks.StoredInstance(inst, format_json_instance(inst), "0123", path)
    cell = runner.Cell(2, 0, 0.5)
    for rec in records.values():
        row = runner._row("ratio-k", cell, stored, "greedy", "dp", rec, rec, 10.0)
        assert row["status"] in ("optimal", "feasible", "time_limit", "failed", "refused")
        assert isinstance(row["objective"], float)


def test_paper_experiments_run_lns_to_convergence(tmp_path):
    """The paper's experiments give lns `stop_at_convergence` (its runtime there is its time to
    converge, not the budget): the option is in the task key and reaches the worker, whose
    solve stops after the default 3 trials; without options the key is as before."""
    import json

    from gtsp_bench.bench.runner import paper_options, plan

    config = _config(tmp_path, experiments="ratio-k", ks="4", solvers="lns", n_instances=1,
                     time_limit=5)
    _, tasks = plan(config)
    lns = [t for t in tasks.values() if t.solver == "lns"]
    assert len(lns) == 1 and lns[0].options == paper_options("lns") == (("stop_at_convergence", True),)
    assert "|lns[stop_at_convergence=True]|" in lns[0].key
    assert all("[" not in t.key for t in tasks.values() if t.solver != "lns")
    summary = run_bench(config, log=lambda m: None)
    assert summary.failed == 0
    rec = next(json.loads(line) for line in _log_lines(config) if '"solver": "lns"' in line)
    assert rec["stats"]["trials"] == 3 and rec["stats"]["converged"] is True
    assert rec["status"] == "feasible"

"""Worker processes of the runner: a solve that raises, a worker that dies mid-solve, a solver
that cannot be built. (test_runner covers hanging solvers and the runner around the pool.)"""

from __future__ import annotations

import json
import os
import subprocess
import sys

from gtsp_bench.solvers.heuristics.greedy import Greedy

from gtsp_bench.bench.pool import (
    CERTIFICATE_CHECKED,
    CERTIFICATE_FAILS,
    MAX_ATTEMPTS,
    NO_CERTIFICATE,
    SOLVE_THREADS_VAR,
    certificate_verdict,
    check_written_certificate,
    run_jobs,
    solve_message,
    solve_threads,
    worker_path,
)
from gtsp_bench.data.parse import format_json_instance
from gtsp_bench.generator import generate_instance
from gtsp_bench.solver import usable_cores
from tests.conftest import REPO
from tests.runner_solvers import KILLS_FILE, Crash, OutOfMemory, Refuses

INSTANCE = generate_instance(3, 4, seed=1)


def _msg(omega: float, instance=INSTANCE) -> dict:
    return {"fingerprint": instance.name, "text": format_json_instance(instance), "omega": omega,
            "seed": 0, "time_limit": 5.0}


def test_solve_message_gives_a_record_or_a_one_line_failure():
    """A good solve gives the checked numbers; an exception gives status 'failed' (cause
    'solver') with its one-line description, an input the solver declines 'refused', running
    out of memory 'failed' with cause 'infrastructure'; the instance text is parsed once per
    fingerprint."""
    cache: dict = {}
    rec = solve_message(Greedy(), "greedy", _msg(0.4), cache)
    assert rec["status"] == "feasible" and sorted(rec["order"]) == [0, 1, 2]
    assert rec["objective"] > 0 and rec["runtime_s"] >= 0 and list(cache) == [INSTANCE.name]
    bad = solve_message(Crash(), "crash", _msg(0.4), cache)
    assert bad["status"] == "failed" and bad["objective"] is None and bad["cause"] == "solver"
    assert bad["note"] == "RuntimeError: boom"
    omega = solve_message(Greedy(), "greedy", _msg(1.5), cache)
    assert omega["status"] == "refused" and "omega must be in [0, 1]" in omega["note"]
    refused = solve_message(Refuses(), "refuses", _msg(0.4), cache)
    assert refused["status"] == "refused" and "cause" not in refused
    oom = solve_message(OutOfMemory(), "oom", _msg(0.4), cache)
    assert oom["status"] == "failed" and oom["cause"] == "infrastructure"
    assert oom["note"].startswith("out of memory: MemoryError: Unable to allocate")


def test_a_worker_that_always_dies_is_retried_then_failed_and_the_rest_go_on():
    """A job whose worker dies every time is tried MAX_ATTEMPTS times, then reported once as a
    persisted 'failed' record (cause 'infrastructure') naming the exit code; fresh workers replace
    the dead ones (here the only one) for the remaining jobs."""
    got: dict = {}
    calls: list = []
    jobs = [(i, _msg(w)) for i, w in enumerate([0.1, 0.9, 0.2, 0.3, 0.4])]

    def on_result(job, rec, persist):
        calls.append(job)
        got[job] = (rec, persist)

    stats = run_jobs("t-die", "tests.runner_solvers:DieAboveHalf", "test", jobs, 1, 60.0, on_result)
    assert sorted(calls) == [0, 1, 2, 3, 4]
    rec, persist = got[1]
    assert rec["status"] == "failed" and rec["cause"] == "infrastructure" and persist
    assert rec["note"] == f"worker died (exit code 3) in {MAX_ATTEMPTS} attempts"
    assert all(got[j][0]["status"] == "feasible" and got[j][1] for j in (0, 2, 3, 4))
    assert stats.solves == 4 and stats.workers == 1


def test_a_worker_killed_mid_solve_is_retried_in_a_fresh_worker(tmp_path, monkeypatch):
    """SIGKILL under a solve (the OOM killer, kill -9): the job is solved again by a new worker
    and reported once, solved; nothing of the dead attempt is reported."""
    kills = tmp_path / "kills"
    kills.write_text("2")
    monkeypatch.setenv(KILLS_FILE, str(kills))
    got: dict = {}
    calls: list = []

    def on_result(job, rec, persist):
        calls.append(job)
        got[job] = rec

    run_jobs("t-killed", "tests.runner_solvers:KilledFromOutside", "test",
             [(0, _msg(0.1)), (1, _msg(0.2))], 1, 60.0, lambda job, rec, p: on_result(job, rec, p))
    assert sorted(calls) == [0, 1] and kills.read_text() == "0"
    assert all(rec["status"] == "feasible" for rec in got.values())


def test_workers_print_nothing_on_stdout_and_ignore_the_working_directory(tmp_path):
    """A solver writing to fd 1 in a worker does not reach the caller's stdout; a module in the
    caller's working directory named like one the worker imports does not shadow it."""
    (tmp_path / "gtsp_bench.py").write_text("raise SystemExit('shadowed')\n")
    (tmp_path / "numpy.py").write_text("raise SystemExit('shadowed')\n")
    code = (
        "import sys, json\n"
        f"sys.path[:0] = [{str(REPO)!r}]\n"
        "from gtsp_bench.bench.pool import run_jobs\n"
        "from tests.bench.test_pool import _msg\n"
        "got = {}\n"
        "run_jobs('t-banner', 'tests.runner_solvers:Banner', 'test', [(0, _msg(0.3))], 1, 60.0,\n"
        "         lambda job, rec, p: got.__setitem__(job, rec))\n"
        "sys.stdout.write(json.dumps(got[0]['status']))\n"
    )
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    proc = subprocess.run([sys.executable, "-P", "-c", code], cwd=tmp_path, capture_output=True,
                          text=True, timeout=120, env=env)
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout) == "feasible"
    assert "banner on fd 1" in proc.stderr and "a stray print" in proc.stderr
    assert "" not in worker_path()


def test_a_solver_that_cannot_be_built_fails_every_job_unpersisted():
    """An import error at start-up fails all jobs with persist=False, so a rerun retries them."""
    got: dict = {}
    run_jobs("t-nowhere", "tests.no_such_module:Solver", "test", [(0, _msg(0.1)), (1, _msg(0.2))],
             2, 60.0, lambda job, rec, persist: got.__setitem__(job, (rec, persist)))
    assert sorted(got) == [0, 1]
    for rec, persist in got.values():
        assert rec["status"] == "failed" and not persist
        assert rec["note"].startswith("solver could not be built: ")
        assert "not available" in rec["note"]


def test_solve_message_record_carries_the_trajectory():
    """A solved record holds the result's trajectory as [[time_s, objective, lower_bound], ...],
    ending at the record's objective, and passes check_log_record; a failed one has none."""
    from gtsp_bench.checks import check_log_record

    rec = solve_message(Greedy(), "greedy", _msg(0.4), {})
    assert len(rec["trajectory"]) == 1
    t, objective, bound = rec["trajectory"][0]
    assert 0 <= t <= rec["runtime_s"] and objective == rec["objective"] and bound is None
    keyed = {**rec, "key": f"{INSTANCE.name}#ab|greedy|w=0.4|seed=0|tl=5", "solver": "greedy",
             "omega": 0.4, "seed": 0}
    assert check_log_record(json.loads(json.dumps(keyed)), INSTANCE.sizes) == keyed
    assert "trajectory" not in solve_message(Crash(), "crash", _msg(0.4), {})


def test_a_records_stats_keep_their_structure_in_json_types():
    """milp's stats reach the record as JSON: its root trace a list of records, not text."""
    from gtsp_bench.solvers.exact.milp import Milp

    rec = solve_message(Milp(), "milp", {**_msg(0.4, generate_instance(6, 4, seed=2)),
                                         "time_limit": 30.0}, {})
    trace = json.loads(json.dumps(rec["stats"], allow_nan=False))["root_trace"]
    assert isinstance(trace, list) and trace and {"time_s", "bound", "cuts"} <= set(trace[0])


def test_solve_threads_share_the_cores_among_the_workers():
    """A solve may run the cores over the workers, at least one."""
    assert solve_threads(1, cores=2) == 2 and solve_threads(2, cores=2) == 1
    assert solve_threads(3, cores=2) == 1 and solve_threads(2, cores=16) == 8
    assert solve_threads(1, cores=None) >= 1


def test_workers_are_told_the_threads_a_solve_may_run(monkeypatch):
    """One worker on two cores: lns's islands may take two threads while the BLAS pools keep one
    (OMP_NUM_THREADS 1); two workers on two cores: one thread each."""
    cores = usable_cores()  # the worker's own, before the patch below
    monkeypatch.delenv(SOLVE_THREADS_VAR, raising=False)
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1}, raising=False)
    got: dict = {}
    for n_workers, want in ((1, 2), (2, 1)):
        run_jobs("t-threads", "tests.runner_solvers:Threads", "test", [(n_workers, _msg(0.3))],
                 n_workers, 60.0, lambda job, rec, p: got.__setitem__(job, rec))
        assert got[n_workers]["stats"]["omp"] == "1"
        assert got[n_workers]["stats"]["workers"] == min(want, cores)


def test_a_written_certificate_is_checked_and_a_bad_one_named(tmp_path):
    """A solve message with a certificate path: the solver writes the proof there (a stale file
    of an earlier attempt removed first) and the record's note is the checker's verdict; a
    tampered certificate, a proof without one, and a solve that proved nothing each say so."""
    import gzip
    from dataclasses import replace

    from gtsp_bench.solvers.exact.milp import Milp

    from gtsp_bench.proof.format import read_certificate, write_certificate
    from gtsp_bench.registry import run_solver

    path = tmp_path / "proofs" / "k4.cert.json.gz"
    path.parent.mkdir()
    path.write_bytes(gzip.compress(b"{}"))  # a stale, unreadable file from an earlier attempt
    rec = solve_message(Milp(), "milp", {**_msg(0.5), "certificate": str(path)}, {})
    assert rec["status"] == "optimal"
    assert rec["note"].startswith(f"certificate checked: proven optimal: {rec['objective']:.10g} ")
    assert rec["note"].endswith(f" (proofs/{path.name})")  # float costs: the certified gap between
    cert = read_certificate(path)
    cert["value"] -= 1.0  # a tour priced wrong
    write_certificate(path, cert)
    res = run_solver("milp", INSTANCE, 0.5)
    assert check_written_certificate(INSTANCE, str(path), res).startswith("certificate fails: ")
    path.unlink()
    assert check_written_certificate(INSTANCE, str(path), res) == "no certificate: none written"
    assert check_written_certificate(INSTANCE, str(path), replace(res, status="time_limit")) == ""
    # every note is read back as its verdict (the summary line and the frontier table read them)
    notes = [rec["note"], check_written_certificate(INSTANCE, str(path), res), "", "nan"]
    assert [certificate_verdict(n) for n in notes] == [CERTIFICATE_CHECKED, NO_CERTIFICATE, None, None]
    assert certificate_verdict("certificate fails: leaf 3 open") == CERTIFICATE_FAILS

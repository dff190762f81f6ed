"""Worker processes of the runner: a solve that raises, a worker that dies mid-solve, a solver
that cannot be built. (test_runner covers hanging solvers and the runner around the pool.)"""

from __future__ import annotations

import math

from gtsp_bench.solvers.heuristics.greedy import Greedy

from gtsp_bench.generator import generate_instance
from gtsp_bench.parse import format_json_instance
from gtsp_bench.pool import run_jobs, solve_message

from .runner_solvers import Crash

INSTANCE = generate_instance(3, 4, seed=1)


def _msg(omega: float, instance=INSTANCE) -> dict:
    return {"fingerprint": instance.name, "text": format_json_instance(instance), "omega": omega,
            "seed": 0, "time_limit": 5.0}


def test_solve_message_gives_a_record_or_a_one_line_failure():
    """A good solve gives the checked numbers; an exception gives status 'failed' with its
    one-line description; the instance text is parsed once per fingerprint."""
    cache: dict = {}
    rec = solve_message(Greedy(), "greedy", _msg(0.4), cache)
    assert rec["status"] == "feasible" and sorted(rec["order"]) == [0, 1, 2]
    assert rec["objective"] > 0 and rec["runtime_s"] >= 0 and list(cache) == [INSTANCE.name]
    bad = solve_message(Crash(), "crash", _msg(0.4), cache)
    assert bad["status"] == "failed" and math.isnan(bad["objective"])
    assert bad["note"] == "RuntimeError: boom"
    omega = solve_message(Greedy(), "greedy", _msg(1.5), cache)
    assert omega["status"] == "failed" and "omega must be in [0, 1]" in omega["note"]


def test_a_worker_that_dies_mid_solve_gives_a_failed_row_and_the_rest_go_on():
    """The job whose worker died is a persisted 'failed' record naming the exit code; a fresh
    worker replaces the dead one (here the only one) for the remaining jobs."""
    got: dict = {}
    jobs = [(i, _msg(w)) for i, w in enumerate([0.1, 0.9, 0.2, 0.3, 0.4])]
    stats = run_jobs("t-die", "tests.runner_solvers:DieAboveHalf", "test", jobs, 1, 60.0,
                     lambda job, rec, persist: got.__setitem__(job, (rec, persist)))
    assert sorted(got) == [0, 1, 2, 3, 4]
    rec, persist = got[1]
    assert rec["status"] == "failed" and rec["note"] == "worker died (exit code 3)" and persist
    assert all(got[j][0]["status"] == "feasible" and got[j][1] for j in (0, 2, 3, 4))
    assert stats.solves == 4 and stats.workers == 1


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

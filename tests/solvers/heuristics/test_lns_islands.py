"""lns on several threads: the islands' rule and starts, the merged answer, the end phase."""

from __future__ import annotations

import numpy as np
import pytest
from gtsp_bench.solvers.heuristics.greedy import greedy_tour
from gtsp_bench.solvers.heuristics.lns import LARGE, LnsSettings, _Run, _Search
from gtsp_bench.solvers.heuristics.lns_islands import (
    AUTO_WORKERS,
    default_workers,
    island_kinds,
    merge,
)
from gtsp_bench.solvers.heuristics.local_search import anchor_node

from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance
from gtsp_bench.problem import price
from gtsp_bench.registry import get_solver, run_solver


@pytest.mark.parametrize("options, timed, workers", [
    ({"workers": 2, "effort": "budget"}, True, 2),
    ({"workers": 1, "effort": "budget"}, True, 1),
    ({"workers": 2, "effort": "budget"}, False, 1),  # no time limit
    ({"workers": 2}, True, 1),  # the default effort stops after its trials
    ({"workers": 2, "stop_at_convergence": True}, True, 1),
])
def test_threads_by_budget(options, timed, workers):
    """``workers`` threads in a time-limited run with effort ``budget``, whatever the cycle's
    size (a run that stops after its trials stays reproducible), else one."""
    assert LnsSettings(**options).workers_for(timed) == workers


def test_default_threads_follow_the_cores_and_omp(monkeypatch):
    """By default two threads where two cores are free, one on one core or where the environment
    says 1, never more than two; a setting that is not a number is ignored. The threads a
    benchmark's worker may run (GTSP_BENCH_SOLVE_THREADS) win over OMP_NUM_THREADS, which those
    workers set to 1 for the BLAS pools. An effort that stops runs one thread."""
    assert default_workers({}, cores=2) == 2
    assert default_workers({}, cores=16) == AUTO_WORKERS == 2
    assert default_workers({}, cores=1) == 1
    assert default_workers({"OMP_NUM_THREADS": "1"}, cores=8) == 1
    assert default_workers({"OMP_NUM_THREADS": "4"}, cores=8) == 2
    assert default_workers({"OMP_NUM_THREADS": "auto"}, cores=2) == 2
    both = {"OMP_NUM_THREADS": "1", "GTSP_BENCH_SOLVE_THREADS": "2"}
    assert default_workers(both, cores=2) == 2 and default_workers(both, cores=1) == 1
    assert default_workers({"OMP_NUM_THREADS": "4", "GTSP_BENCH_SOLVE_THREADS": "1"}, cores=8) == 1
    assert default_workers({"OMP_NUM_THREADS": "1", "GTSP_BENCH_SOLVE_THREADS": "x"}, cores=8) == 1
    monkeypatch.delenv("GTSP_BENCH_SOLVE_THREADS", raising=False)
    monkeypatch.setenv("OMP_NUM_THREADS", "1")
    assert LnsSettings(effort="budget").workers_for(True) == 1
    monkeypatch.delenv("OMP_NUM_THREADS")
    assert LnsSettings().workers_for(True) == 1
    assert LnsSettings(effort="budget").workers_for(True) == default_workers()


def test_island_starts():
    """The islands start from the usual first tour, then the macro tour on a planar instance, then
    random insertion; with macro=True the macro tour comes first and is not repeated."""
    inst = generate_instance(LARGE + 5, 2, seed=1, zeta=10.0, area=4000.0)
    plain = _Search(price(inst, 0.5), LnsSettings(), np.random.default_rng(0))
    assert plain.centre is not None  # quadrants above LARGE: the centres are known
    assert island_kinds(plain, 3) == ["greedy", "macro", "random"]
    assert island_kinds(plain, 1) == ["greedy"]
    macro = _Search(price(inst, 0.5), LnsSettings(macro=True), np.random.default_rng(0))
    assert island_kinds(macro, 3) == ["macro", "random", "random"]


def test_merge_keeps_the_cheapest_and_sums_the_counts():
    """The merged state is the cheapest island's tour with every island's iterations and trials."""
    ones = np.ones(3)
    runs = [_Run(np.arange(4), cost, ones, ones, 0.0, done=10 * i + 5, trials=i + 1,
                 converged=True) for i, cost in enumerate((5.0, 3.0, 4.0))]
    win = merge(runs)
    assert win.best_cost == 3.0 and win.done == 5 + 15 + 25 and win.trials == 6
    assert win.converged and not win.timed_out


@pytest.mark.parametrize("exchange", [0.5, 1.0])
def test_two_workers_on_a_large_cycle(exchange):
    """With workers=2 above LARGE clusters both islands search (their iterations summed in the
    stats, both cores' worth of CPU time is not asserted: CI may have one): a valid tour, priced
    as the evaluator prices it, no worse than the greedy tour it can start from."""
    n = LARGE + 20
    inst = generate_instance(n, 2, seed=3, zeta=10.0, area=4000.0)
    r = run_solver(get_solver("lns", workers=2, exchange=exchange, effort="budget"), inst, 0.5, seed=1,
                   time_limit=3.0)
    assert sorted(r.order) == list(range(n))
    assert r.stats["workers"] == 2 and r.stats["iterations"] > 0 and r.stats["windows"] > 0
    problem = price(inst, 0.5)
    greedy = problem.tour_cost(np.array(greedy_tour(problem, anchor_node(problem))))
    assert r.objective <= greedy


@pytest.mark.parametrize("options, message", [
    ({"workers": 0}, "workers must be an integer >= 1"),
    ({"exchange": 1.5}, "exchange must be a number in"),
])
def test_bad_options_rejected(options, message):
    """Invalid thread settings raise InputError naming the setting."""
    with pytest.raises(InputError, match=message):
        get_solver("lns", **options)

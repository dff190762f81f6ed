"""MILP options: checked on construction; the upper-bound tour is a tour."""

from __future__ import annotations

import time

import numpy as np
import pytest
from gtsp_bench.solvers.exact.mip.options import (
    LP_THREADS,
    MipOptions,
    restart_tours,
    upper_bound_tour,
)

from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance
from gtsp_bench.problem import price
from gtsp_bench.registry import run_solver
from gtsp_bench.solver import SOLVE_THREADS_VAR, usable_cores


@pytest.mark.parametrize("bad, message", [
    ({"prune": "yes"}, "prune must be true or false"),
    ({"lns_trials": -1}, "lns_trials must be an integer >= 0"),
    ({"root_rounds": 1.5}, "root_rounds must be an integer >= 0"),
    ({"core_edges": True}, "core_edges must be an integer >= 0"),
    ({"abs_gap": float("nan")}, "abs_gap must be a number"),
    ({"abs_gap": -1.0}, "abs_gap must be a number"),
    ({"threads": 0}, "threads must be an integer >= 1"),
    ({"threads": 2.0}, "threads must be an integer >= 1"),
    ({"branching": "best"}, "branching must be one of 'auto', 'strong', 'reliability'"),
])
def test_options_are_validated(bad, message):
    """Bad option values raise InputError naming the option."""
    with pytest.raises(InputError, match=message):
        MipOptions(**bad)


def test_lp_threads_are_the_option_else_what_the_environment_allows(monkeypatch):
    """``threads`` wins; unset, LP_THREADS at most, and at most what a benchmark's worker is
    allowed (``GTSP_BENCH_SOLVE_THREADS``)."""
    assert MipOptions(threads=3).lp_threads() == 3
    monkeypatch.setenv(SOLVE_THREADS_VAR, "1")
    assert MipOptions().lp_threads() == 1
    monkeypatch.setenv(SOLVE_THREADS_VAR, "8")
    assert MipOptions().lp_threads() == min(LP_THREADS, usable_cores())


@pytest.mark.parametrize("trials", [0, 1])
@pytest.mark.parametrize("seed", range(3))
def test_upper_bound_tour_is_a_tour_no_better_than_the_optimum(trials, seed):
    """Greedy + local search (0 trials) and the LNS (1 trial): one node of every GTSP cluster,
    costing at least the dp optimum."""
    inst = generate_instance(7, 4, seed=seed)
    problem = price(inst, 0.5)
    tour = upper_bound_tour(problem, trials, seed, None)
    assert sorted(problem.cluster_of[tour].tolist()) == list(range(problem.n_clusters))
    assert problem.tour_cost(tour) >= run_solver("dp", inst, 0.5).objective * (1 - 1e-12)
    assert np.array_equal(tour, upper_bound_tour(problem, trials, seed, None))  # reproducible


@pytest.mark.parametrize("deadline", [None, 0.0])
def test_restart_tours_never_worse_and_a_tour(deadline):
    """LNS restarts from the greedy tour: a tour through every cluster, no dearer than the one
    given and no cheaper than the optimum; a deadline already past still allows one restart."""
    inst = generate_instance(12, 5, seed=4)
    problem = price(inst, 0.5)
    start = upper_bound_tour(problem, 0, 0, None)
    when = None if deadline is None else time.perf_counter() + deadline
    tour = restart_tours(problem, start, 0, when)
    assert sorted(problem.cluster_of[tour].tolist()) == list(range(problem.n_clusters))
    assert problem.tour_cost(tour) <= problem.tour_cost(start)
    assert problem.tour_cost(tour) >= run_solver("dp", inst, 0.5).objective * (1 - 1e-12)

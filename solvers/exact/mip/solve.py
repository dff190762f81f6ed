"""The exact solve: upper bound, pruning, the root loop and the search; the solvers' base class.

:func:`solve_exact` takes an upper bound from the large neighbourhood search, prunes candidate
heads, runs the root LP loop and, unless the root proved the upper bound optimal, the branch and
cut of :mod:`gtsp_bench.solvers.exact.mip.branch_cut` (or the backend's own MILP); with a
certificate path it logs the proof (:mod:`gtsp_bench.solvers.exact.mip.certify`) and writes it.
:class:`MipSolver` is the base of the ``milp`` and ``gurobi`` solvers.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from gtsp_bench.solvers.exact.mip import flow
from gtsp_bench.solvers.exact.mip.backends import Backend, LazyMipBackend
from gtsp_bench.solvers.exact.mip.branch_cut import _Search, check_symmetric
from gtsp_bench.solvers.exact.mip.options import MipOptions, restart_tours, upper_bound_tour
from gtsp_bench.solvers.exact.mip.tree_search import _Timer
from gtsp_bench.solvers.exact.prune import prune_heads
from gtsp_bench.solvers.exact.prune import warm_up as prune_warm_up
from gtsp_bench.solvers.heads import optimal_heads
from gtsp_bench.solvers.heuristics import lns_kernels

from gtsp_bench.errors import InputError
from gtsp_bench.instance import Instance
from gtsp_bench.problem import Problem, price
from gtsp_bench.proof.format import write_certificate
from gtsp_bench.solver import Progress, Solution, no_progress

#: Largest share of the time limit that pruning may take.
PRUNE_SHARE = 0.2
#: Share of the time limit for LNS restarts when the root did not prove the incumbent optimal.
RESTART_SHARE = 0.05
#: Share of the time limit after which an unfinished first root loop pauses for the restarts
#: (then goes on): at K = 100 it would otherwise run to the limit with the first tour.
ROOT_SHARE = 0.05
#: A float-cost certificate's cutoff lies this share of the value below the proven bound (room
#: for the rounding between the LP's float bound and the checker's exact one).
CUTOFF_MARGIN = 1e-9


def solve_exact(
    problem: Problem,
    make_backend: Callable[[MipOptions], Backend],
    options: MipOptions,
    *,
    time_limit: float | None = None,
    seed: int = 0,
    initial: np.ndarray | None = None,
    progress: Progress = no_progress,
    certificate: str | os.PathLike[str] | None = None,
) -> Solution:
    """Solve a priced GTSP to proven optimality (or until ``time_limit`` seconds).

    Parameters
    ----------
    problem
        The priced problem (symmetric edge costs).
    make_backend
        Builds an empty backend.
    options
        Shared options.
    time_limit
        Seconds for the whole solve (``None``: no limit).
    seed
        Seed of the upper-bound heuristic.
    initial
        A warm start's tour (problem node ids): the first incumbent, instead of the LNS tour
        (the LNS restarts still run when the root does not prove it optimal).
    progress
        Told each better incumbent's cost and each better bound (the first upper bound's LNS
        included).
    certificate
        Where to write a proof certificate (:mod:`gtsp_bench.proof`) when the solve proves
        optimality; the search then keeps every candidate head (no pruning) and solves node LPs
        without cutoff (each closed node needs its duals). ``stats["certificate_bytes"]`` is the
        file's size, or ``stats["certificate"]`` says why none was written.

    Returns
    -------
    Solution
        Status ``"optimal"`` with ``lower_bound`` when proven, else ``"time_limit"`` with the best
        tour and the best lower bound known (at least :func:`degree_bound`). ``stats`` has seconds per
        phase, rounds, cuts, backend counters and ``root_trace``, a record per root round
        (:meth:`~gtsp_bench.solvers.exact.mip.branch_cut._Search.trace_round`).

    Raises
    ------
    InputError
        A certificate asked of a backend with its own MILP, or of fewer than 3 clusters (solved
        without the model; 3 clusters are enumerated too, but searched with the model when a
        certificate is asked for).
    """
    check_symmetric(problem)
    if certificate is not None and problem.n_clusters < 3:
        raise InputError(f"{problem.instance.name}: a certificate needs at least 3 clusters "
                         f"(this instance has {problem.n_clusters}; its optimum is enumerated)")
    start = time.perf_counter()
    deadline = math.inf if time_limit is None else start + time_limit
    stats: dict[str, Any] = {}

    def result(tour: np.ndarray, status: str, lower: float) -> Solution:
        order, heads = problem.to_solution(tour)
        cost = problem.tour_cost(tour)
        stats["total_s"] = time.perf_counter() - start
        # reduced-cost fixing drops solutions no better than the incumbent, so a bound above
        # the incumbent's cost only says that it is optimal
        bound = None if lower == -math.inf else min(float(lower), cost)
        return Solution(order, heads, objective=cost, status=status, lower_bound=bound, stats=stats)

    if problem.n_clusters <= 3 and certificate is None:  # one cyclic order: its best heads win
        tour, cost = optimal_heads(problem, list(range(problem.instance.n_clusters)))
        return result(tour, "optimal", cost)
    if initial is not None:
        tour = np.asarray(initial, dtype=np.int64)
        stats["warm_start"] = True
    else:
        with _Timer(stats, "heuristic_s"):
            tour = upper_bound_tour(problem, options.lns_trials, seed,
                                    None if time_limit is None else 0.25 * time_limit, progress)
    with _Timer(stats, "prune_s"):
        # pruning is exact after any number of passes; at K = 50 (N = 20) a full run took 138 s
        # of a 300 s limit for 11 % of the nodes, so it gets a fifth of the limit at most
        prune_by = deadline
        if time_limit is not None:
            prune_by = min(deadline, time.perf_counter() + PRUNE_SHARE * time_limit)
        prune = options.prune and certificate is None  # a certificate covers every node
        kept = prune_heads(problem, deadline=prune_by) if prune else problem.clusters
    search = _Search(problem, make_backend(options), options, deadline, tour, kept, stats, progress,
                     certify=certificate is not None)
    if certificate is not None and isinstance(search.lp.backend, LazyMipBackend):
        raise InputError("certificates come from the milp solver's own branch and cut only")
    paused = search.root(None if time_limit is None else start + ROOT_SHARE * time_limit)
    if not search.proven and search.left() > 0:
        # the root did not finish (or paused at half the limit): LNS restarts for a small share
        # of the limit, and the root loop again, against a better incumbent (it fixes more
        # columns by reduced cost) or to go on where it paused
        with _Timer(stats, "heuristic_s"):
            until = None if time_limit is None else min(deadline, time.perf_counter()
                                                         + RESTART_SHARE * time_limit)
            better = restart_tours(problem, search.tour, seed, until)
        if problem.tour_cost(better) < search.ub - search.margin:  # (not a rounding difference)
            stats["restart_gain"] = search.ub - problem.tour_cost(better)
            search.tour, search.ub = better, problem.tour_cost(better)
            search.report()
            paused = True
        if paused:
            search.root()
    if not search.proven and search.left() > 0:
        if isinstance(search.lp.backend, LazyMipBackend):
            search.native_mip()
        else:
            search.branch_and_cut()
    stats["lp_cols"], stats["cuts"] = len(search.lp.cols), len(search.lp.cuts)
    stats["lp_stalls"] = getattr(search.lp.backend, "stalls", 0)
    stats["lp_iterations"] = getattr(search.lp.backend, "iterations", None)
    stats["lp_retries"] = getattr(search.lp.backend, "retries", 0)
    stats["lp_cold_starts"] = getattr(search.lp.backend, "cold_starts", 0)
    if certificate is not None:
        if search.proven:
            with _Timer(stats, "certificate_s"):
                stats["certificate_bytes"] = write_certificate(certificate, _certificate(search))
        else:
            stats["certificate"] = "not written: optimality not proven"
    lower = search.lb
    if search.model.integral_costs and math.isfinite(lower):
        lower = math.ceil(lower - 1e-7)  # every tour costs an integer
    return result(search.tour, "optimal" if search.proven else "time_limit", lower)


def _certificate(search: _Search) -> dict[str, Any]:
    """The certificate of a search that proved its incumbent optimal: the cutoff is the value
    minus 1 with integer costs, else the proven bound less a rounding margin."""
    assert search.log is not None
    ub = search.ub
    if search.model.integral_costs:
        cutoff = ub - 1
    else:
        cutoff = min(search.lb, ub - search.options.abs_gap) - CUTOFF_MARGIN * max(1.0, abs(ub))
    return search.log.certificate(search.problem, search.tour, ub, cutoff, search.open_cids)


class MipSolver:
    """The exact MILP solver on one backend; subclasses name the backend (``milp``, ``gurobi``).

    Parameters
    ----------
    prune
        Remove dominated candidate heads first (exact).
    lns_trials
        Trials of the large neighbourhood search giving the first upper bound (0: greedy and
        local search only).
    root_rounds
        Most rounds of the root LP loop (0: no root cuts).
    core_edges
        Cheapest edges per node in the first LP (0: all edges).
    abs_gap
        Absolute gap under which the optimum counts as proven.
    verbose
        Print the backend's log.
    certificate
        Write a proof certificate of each solve that proves optimality here (see
        :func:`solve_exact`; ``gtsp-bench check-proof`` checks it).
    threads
        LP threads on a model of at least 1,200 nodes (UAV K = 100 and up; ``None``: 2 where
        the cores allow, see :class:`~gtsp_bench.solvers.exact.mip.options.MipOptions`).
    branching
        ``"auto"``, ``"strong"`` or ``"reliability"``: how the branch and cut picks its column
        (see :class:`~gtsp_bench.solvers.exact.mip.options.MipOptions`).
    workers
        Threads of the branch and cut, each with its own LP on one core (``None``: 2 where the
        cores allow, see :class:`~gtsp_bench.solvers.exact.mip.options.MipOptions`).
    """

    def __init__(self, prune: bool = True, lns_trials: int = 1, root_rounds: int = 200,
                 core_edges: int = 10, abs_gap: float = 1e-6, verbose: bool = False,
                 certificate: str | None = None, threads: int | None = None,
                 branching: str = "auto", workers: int | None = None) -> None:
        self.options = MipOptions(prune=prune, lns_trials=lns_trials, root_rounds=root_rounds,
                                  core_edges=core_edges, abs_gap=abs_gap, verbose=verbose,
                                  certificate=None if certificate is None else str(certificate),
                                  threads=threads, branching=branching, workers=workers)
        # compiled or loaded here (a worker's start-up), not in a solve's clock
        flow.warm_up()
        prune_warm_up()
        lns_kernels.warm_up()

    def backend(self, options: MipOptions) -> Backend:
        """A new, empty backend."""
        raise NotImplementedError

    def solve(
        self, instance: Instance, omega: float | None, *, time_limit: float | None = None,
        seed: int = 0, initial: Solution | None = None, progress: Progress = no_progress,
    ) -> Solution:
        """Solve to proven optimality, or return the best tour and bound at ``time_limit``;
        a warm start (``initial``) is the first incumbent; each better incumbent and bound is
        reported to ``progress``."""
        problem = price(instance, omega)
        tour = None if initial is None else problem.to_tour(initial.order, initial.heads)
        return solve_exact(problem, self.backend, self.options, time_limit=time_limit, seed=seed,
                           initial=tour, progress=progress, certificate=self.options.certificate)

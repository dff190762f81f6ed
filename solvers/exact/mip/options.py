"""Options shared by the MILP solvers, and the tour giving the first upper bound."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from gtsp_bench.solvers.heuristics.greedy import greedy_tour
from gtsp_bench.solvers.heuristics.lns import Lns
from gtsp_bench.solvers.heuristics.local_search import anchor_node, improve

from gtsp_bench.checks import check_bool, check_choice, check_float, check_int
from gtsp_bench.errors import InputError
from gtsp_bench.problem import Problem
from gtsp_bench.solver import Progress, allowed_threads, no_progress

#: Threads of a big model's LPs by default (measured on two cores: HiGHS's parallel dual simplex
#: ran 11-20 % more root rounds in the same time at UAV K = 100 and 200, its certified gap lower at
#: every point measured; more threads were not measured).
LP_THREADS = 2
#: Workers of the branch and cut by default, where the cores allow (two cores: one LP each).
TREE_WORKERS = 2
#: Values of :attr:`MipOptions.branching`.
BRANCHINGS = ("auto", "strong", "reliability")


@dataclass(frozen=True)
class MipOptions:
    """Options shared by the MILP solvers (each a constructor keyword of the solvers).

    Attributes
    ----------
    prune
        Remove candidate heads by exact pair dominance first.
    lns_trials
        Trials of the large neighbourhood search giving the first upper bound (0: the greedy
        tour after local search only).
    root_rounds
        Most rounds of the root LP loop (0: no root cuts, all edges).
    core_edges
        Edges per node in the first LP (its cheapest); the others are priced in as needed.
        0: all edges from the start.
    abs_gap
        The optimum counts as proven when upper - lower bound <= abs_gap (with all costs integer,
        a gap below 1 proves it too).
    verbose
        Print the backend's log.
    certificate
        Where a solve that proves optimality writes its proof certificate (``None``: none).
    threads
        Threads of the LP solver on a model of at least ``branch_cut.BIG_ROOT_NODES`` nodes
        (HiGHS's parallel dual simplex, Gurobi's ``Threads``); smaller models solve on one.
        ``None``: :data:`LP_THREADS` where the cores allow
        (:func:`gtsp_bench.solver.allowed_threads`: in a benchmark, the cores over its workers).
    branching
        How the branch and cut picks its column (:mod:`~gtsp_bench.solvers.exact.mip.branching`):
        ``"strong"`` strong-branches the 8 fractional columns closest to 1/2 at every node,
        ``"reliability"`` strong-branches only columns whose pseudo-costs are not yet trusted,
        ``"auto"`` (default) the first until half of the strong LPs stop at their iteration
        limit, then the second.
    workers
        Threads of the branch and cut after the root, each with its own copy of the LP on one
        core (:mod:`~gtsp_bench.solvers.exact.mip.workers`). ``None``: :data:`TREE_WORKERS`
        where the cores allow (:func:`gtsp_bench.solver.allowed_threads`).
    """

    prune: bool = True
    lns_trials: int = 1
    root_rounds: int = 200
    core_edges: int = 10
    abs_gap: float = 1e-6
    verbose: bool = False
    certificate: str | None = None
    threads: int | None = None
    branching: str = "auto"
    workers: int | None = None

    def __post_init__(self) -> None:
        for name in ("prune", "verbose"):
            check_bool(name, getattr(self, name))
        for name in ("lns_trials", "root_rounds", "core_edges"):
            check_int(name, getattr(self, name), 0)
        check_float("abs_gap", self.abs_gap, 0.0, math.inf, open_low=False)
        if self.certificate is not None and not str(self.certificate):
            raise InputError("certificate must be a file path")
        for name in ("threads", "workers"):
            if getattr(self, name) is not None:
                check_int(name, getattr(self, name), 1)
        check_choice("branching", self.branching, BRANCHINGS)

    def lp_threads(self) -> int:
        """Threads of a big model's LPs: ``threads``, else :data:`LP_THREADS` where allowed."""
        return self.threads if self.threads is not None else allowed_threads(LP_THREADS)

    def tree_workers(self) -> int:
        """Workers of the branch and cut: ``workers``, else :data:`TREE_WORKERS` where allowed."""
        return self.workers if self.workers is not None else allowed_threads(TREE_WORKERS)


def upper_bound_tour(problem: Problem, trials: int, seed: int, time_limit: float | None,
                     progress: Progress = no_progress) -> np.ndarray:
    """A good tour, the search's first upper bound.

    Parameters
    ----------
    problem
        The priced problem.
    trials
        Trials of :class:`gtsp_bench.solvers.heuristics.lns.Lns` (0: the greedy tour improved by
        the local search only).
    seed
        Seed of the LNS.
    time_limit
        Seconds for the LNS (``None``: no limit).
    progress
        Told each better tour's cost the LNS finds.

    Returns
    -------
    numpy.ndarray
        Node ids of the tour, one per GTSP cluster (the depot first when there is one).
    """
    if trials == 0:
        tour, cost = improve(problem, greedy_tour(problem, anchor_node(problem)))
        progress(cost)
        return tour
    lns = Lns(trials=trials, stop_at_convergence=True)  # its trials, not the whole time limit
    sol = lns.solve(problem.instance, problem.omega, time_limit=time_limit, seed=seed,
                    progress=progress)
    return problem.to_tour(sol.order, sol.heads)


def restart_tours(problem: Problem, tour: np.ndarray, seed: int, deadline: float | None,
                  trials: int = 3, restarts: int = 3) -> np.ndarray:
    """The best of ``tour`` and LNS restarts with other seeds: a better incumbent for a search
    that the root did not finish.

    Parameters
    ----------
    problem
        The priced problem.
    tour
        The incumbent (problem node ids).
    seed
        The first restart uses ``seed + 1``, the next ``seed + 2``, ...
    deadline
        ``time.perf_counter()`` time after which no restart begins and a running one stops
        (``None``: none).
    trials
        Trials of each LNS run (stopped at convergence).
    restarts
        Most restarts (the first one runs whatever the deadline).

    Returns
    -------
    numpy.ndarray
        The cheapest tour seen.
    """
    lns = Lns(trials=trials, stop_at_convergence=True)
    best, cost = tour, problem.tour_cost(tour)
    k = 0
    while k < restarts and (deadline is None or k == 0 or time.perf_counter() < deadline):
        k += 1
        left = None if deadline is None else max(deadline - time.perf_counter(), 1e-3)
        sol = lns.solve(problem.instance, problem.omega, time_limit=left, seed=seed + k)
        cand = problem.to_tour(sol.order, sol.heads)
        if problem.tour_cost(cand) < cost:
            best, cost = cand, problem.tour_cost(cand)
    return best

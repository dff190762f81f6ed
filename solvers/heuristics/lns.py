"""A GLNS-class large neighbourhood search (after Smith and Imeson, Comput. Oper. Res. 87, 2017).

Each iteration removes some clusters from the current tour and puts them back:

* removal (1 to ``remove_fraction`` of the clusters): **random** clusters, the **worst** ones (the
  largest saving when removed, randomised), a **segment** of consecutive clusters, or the clusters
  whose heads are nearest a random head (**distance**);
* insertion: the pending cluster **cheapest** to insert goes in next, or the **farthest** (dearest),
  or a **random** one, each at its cheapest edge and head; every other iteration adds noise (up to
  ``noise`` times the mean edge cost) to the prices;

then a local search (:mod:`gtsp_bench.solvers.heuristics.lns_kernels`: 2-opt, GLNS's "moveopt" and
"reopt"). The inner loops are compiled with numba. The operators are drawn by roulette on adaptive
weights (each updated with the score of its iterations: new best 3, better than the current 2,
accepted 1, rejected 0). A new tour replaces the current one by simulated-annealing acceptance, the
temperature cooling geometrically over a trial from ``start_temperature`` to ``end_temperature``
times the mean edge cost of the tour. A trial ends after ``iterations`` iterations or ``patience``
without a new trial best; the first trial starts from the greedy tour improved by the local
search, later ones from the best tour so far.

The search has converged after ``trials`` trials. It then goes on with more trials until the time
limit (status ``feasible``: its own criterion was met), unless ``stop_at_convergence`` asks it to
stop there. A run that converges is reproducible for a seed; one cut by the time limit before it
converged has status ``time_limit``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from gtsp_bench.solvers.heuristics import lns_kernels as kernels
from gtsp_bench.solvers.heuristics.greedy import greedy_tour
from gtsp_bench.solvers.heuristics.local_search import anchor_node, deadline_after, is_past

from gtsp_bench.checks import (
    check_bool,
    check_float,
    check_int,
    time_limit_or_default,
)
from gtsp_bench.errors import InputError
from gtsp_bench.instance import Instance
from gtsp_bench.problem import Problem, price
from gtsp_bench.registry import Solution

REMOVALS = kernels.REMOVALS
INSERTIONS = kernels.INSERTIONS
#: Scores of an iteration's operators: new best, better than current, accepted, rejected.
SCORES = (3.0, 2.0, 1.0, 0.0)
#: No operator weight falls below this (each keeps being tried).
MIN_WEIGHT = 0.1
#: Improvements smaller than this share of the tour cost are ignored (rounding noise).
REL_TOL = 1e-9


@dataclass(frozen=True)
class LnsSettings:
    """Validated settings of :class:`Lns` (see there)."""

    iterations: int | None = None
    trials: int = 3
    patience: int | None = None
    remove_fraction: float = 0.3
    start_temperature: float = 0.05
    end_temperature: float = 0.0005
    reaction: float = 0.1
    noise: float = 0.1
    neighbours: int = 10
    stop_at_convergence: bool = False

    def __post_init__(self) -> None:
        if self.iterations is not None:
            check_int("iterations", self.iterations, 1)
        check_int("trials", self.trials, 1)
        if self.patience is not None:
            check_int("patience", self.patience, 1)
        check_float("remove_fraction", self.remove_fraction, 0.0, 1.0)
        check_float("start_temperature", self.start_temperature, 0.0, math.inf, open_low=False)
        check_float("end_temperature", self.end_temperature, 0.0, math.inf, open_low=False)
        if self.end_temperature > self.start_temperature:
            raise InputError(
                f"end_temperature ({self.end_temperature!r}) must not exceed start_temperature "
                f"({self.start_temperature!r})"
            )
        check_float("reaction", self.reaction, 0.0, 1.0)
        check_float("noise", self.noise, 0.0, math.inf, open_low=False)
        check_int("neighbours", self.neighbours, 1)
        check_bool("stop_at_convergence", self.stop_at_convergence)

    def iterations_for(self, n: int) -> int:
        """Iterations per trial for a cycle of ``n`` clusters (default ``max(100, 25 n)``)."""
        return self.iterations if self.iterations is not None else max(100, 25 * n)

    def patience_for(self, n: int) -> int:
        """Iterations without a new trial best that end a trial (default ``max(50, 5 n)``)."""
        return self.patience if self.patience is not None else max(50, 5 * n)


class _Search:
    """State of one LNS run on a priced problem."""

    def __init__(self, problem: Problem, settings: LnsSettings, rng: np.random.Generator) -> None:
        self.p = problem
        self.s = settings
        self.rng = rng
        self.edge = np.ascontiguousarray(problem.edge_cost, dtype=np.float64)
        self.node = np.ascontiguousarray(problem.node_cost, dtype=np.float64)
        self.start = np.array([c[0] for c in problem.clusters] + [problem.n_nodes], dtype=np.int64)
        if not np.array_equal(np.repeat(np.arange(problem.n_clusters), np.diff(self.start)),
                              problem.cluster_of):
            raise ValueError("lns needs nodes numbered cluster by cluster")
        self.cluster_of = np.ascontiguousarray(problem.cluster_of, dtype=np.int64)
        self.near = kernels.neighbours(self.edge, self.start, settings.neighbours)
        n = problem.n_clusters
        self.max_remove = max(1, min(n - 2, math.ceil(settings.remove_fraction * n)))
        self.weights = {"removal": np.ones(len(REMOVALS)), "insertion": np.ones(len(INSERTIONS))}

    def pick(self, kind: str) -> int:
        """An operator index drawn with probability proportional to its weight."""
        cum = np.cumsum(self.weights[kind])
        return min(int(np.searchsorted(cum, self.rng.random() * cum[-1], side="right")), len(cum) - 1)

    def reward(self, kind: str, op: int, score: float) -> None:
        """Blend an iteration's score into the weight of the operator it used."""
        w = self.weights[kind]
        w[op] = max(MIN_WEIGHT, (1.0 - self.s.reaction) * w[op] + self.s.reaction * score)

    def local_search(self, t: np.ndarray) -> tuple[np.ndarray, float]:
        t = np.array(t, dtype=np.int64)
        tol = REL_TOL * max(1.0, abs(kernels.tour_cost(t, self.edge, self.node)))
        cost = kernels.local_search(t, self.edge, self.node, self.start, self.near, self.cluster_of, tol)
        return t, cost

    def run(self, deadline: float | None) -> tuple[np.ndarray, float, dict, bool]:
        """Search until converged (``stop_at_convergence``) or the deadline; returns (tour, cost,
        stats, whether the deadline came before convergence)."""
        p, s = self.p, self.s
        kernels.seed(int(self.rng.integers(2**31 - 1)))
        best, best_cost = self.local_search(greedy_tour(p, anchor_node(p)))
        n = p.n_clusters
        iterations, patience = s.iterations_for(n), s.patience_for(n)
        done = best_at = trials = 0
        # A cycle of at most 3 clusters is fixed by its heads: re-opt solved it, nothing to search.
        converged = exact = n < 4
        timed_out = False
        while not exact and not (converged and (s.stop_at_convergence or deadline is None)):
            if is_past(deadline):
                timed_out = True
                break
            cur, cur_cost = best, best_cost
            trial_best, since = best_cost, 0
            mean_edge = float(np.mean(self.edge[cur, np.roll(cur, -1)]))
            t0 = s.start_temperature * mean_edge
            t1 = s.end_temperature * mean_edge
            for it in range(iterations):
                if is_past(deadline):
                    timed_out = True
                    break
                temp = t0 * (t1 / t0) ** (it / max(1, iterations - 1)) if t0 > 0 and t1 > 0 else t0
                r_op, i_op = self.pick("removal"), self.pick("insertion")
                k = int(self.rng.integers(1, self.max_remove + 1))
                noise = s.noise * mean_edge if self.rng.random() < 0.5 else 0.0
                tol = REL_TOL * max(1.0, abs(cur_cost))
                new, new_cost = kernels.iterate(cur, k, r_op, i_op, noise, self.edge, self.node,
                                                self.start, self.near, self.cluster_of, tol)
                done += 1
                if new_cost < best_cost - tol:
                    score = SCORES[0]
                elif new_cost < cur_cost - tol:
                    score = SCORES[1]
                elif new_cost > cur_cost + tol and temp > 0 and \
                        self.rng.random() < math.exp(-(new_cost - cur_cost) / temp):
                    score = SCORES[2]
                else:
                    score = SCORES[3]
                if score > SCORES[3]:
                    cur, cur_cost = new, new_cost
                if new_cost < best_cost - tol:
                    best, best_cost, best_at = new, new_cost, done
                if new_cost < trial_best - tol:
                    trial_best, since = new_cost, 0
                else:
                    since += 1
                self.reward("removal", r_op, score)
                self.reward("insertion", i_op, score)
                if since >= patience:
                    break
            if timed_out:
                break
            trials += 1
            converged = converged or trials >= s.trials
            if converged and s.stop_at_convergence:
                break
        weights = dict(zip(REMOVALS, self.weights["removal"], strict=True))
        weights.update(zip(INSERTIONS, self.weights["insertion"], strict=True))
        stats = {"iterations": done, "trials": trials, "best_at": best_at, "converged": converged,
                 "weights": {k: round(float(w), 3) for k, w in weights.items()}}
        return best, best_cost, stats, timed_out and not converged


class Lns:
    """GLNS-style large neighbourhood search, compiled inner loops (module docstring).

    Parameters
    ----------
    iterations
        Iterations per trial (default ``max(100, 25 n)``, n = clusters incl. the depot's).
    trials
        Trials until the search counts as converged; each restarts the temperature from the best
        tour so far.
    patience
        Iterations without a new trial best that end a trial (default ``max(50, 5 n)``).
    remove_fraction
        At most this share of the clusters is removed per iteration, in (0, 1].
    start_temperature, end_temperature
        Annealing temperatures as multiples of the tour's mean edge cost (>= 0).
    reaction
        Weight of the newest score in an operator's weight, in (0, 1].
    noise
        Noisy insertions add up to ``noise`` times the mean edge cost to each price (>= 0).
    neighbours
        The local search's moves join a cluster only to its ``neighbours`` nearest clusters.
    stop_at_convergence
        Stop after ``trials`` trials instead of going on with more until the time limit.
    """

    def __init__(
        self, iterations: int | None = None, trials: int = 3, patience: int | None = None,
        remove_fraction: float = 0.3, start_temperature: float = 0.05,
        end_temperature: float = 0.0005, reaction: float = 0.1, noise: float = 0.1,
        neighbours: int = 10, stop_at_convergence: bool = False,
    ) -> None:
        self.settings = LnsSettings(iterations, trials, patience, remove_fraction,
                                    start_temperature, end_temperature, reaction, noise,
                                    neighbours, stop_at_convergence)

    def solve(
        self, instance: Instance, omega: float | None, *, time_limit: float | None = None,
        seed: int = 0,
    ) -> Solution:
        """Search until the time limit (or convergence with ``stop_at_convergence``).

        Without a time limit, :func:`gtsp_bench.checks.default_time_limit` applies. The status is
        ``time_limit`` only when the limit came before the search converged.
        """
        time_limit = time_limit_or_default(time_limit, instance.n_clusters)
        kernels.warm_up()
        deadline = deadline_after(time_limit)
        problem = price(instance, omega)
        search = _Search(problem, self.settings, np.random.default_rng(seed))
        tour, cost, stats, timed_out = search.run(deadline)
        order, heads = problem.to_solution(tour)
        return Solution(order, heads, objective=problem.tour_cost(tour),
                        status="time_limit" if timed_out else "feasible", stats=stats)

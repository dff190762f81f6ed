"""The paper's ACO baseline: an ant system for the GTSP after Yang, Shi, Marchese and Liang (2008).

Each ant starts at the depot (without a depot: at a node drawn uniformly) and, step by step, moves
to a node of a cluster it has not visited yet, node j with probability proportional to
``tau[i, j]**alpha * eta[i, j]**beta``, where ``eta[i, j] = 1 / (edge(i, j) + node(j))`` is the
inverse of the weighted energy that step adds; after the last cluster it returns to its start.
After all ants have built their tours, the pheromone evaporates (``tau *= 1 - rho``) and each ant
deposits ``q / E(tour)`` on the edges of its tour (both directions). The best tour is kept.

The defaults are the paper's settings (section VI): 30 ants, 200 iterations, rho = 0.1,
alpha = 1, beta = 5. The initial pheromone is ``ants * q / E(greedy tour)`` on every edge (the
usual ant-system choice; the paper does not give it). Yang et al.'s mutation and 2-opt steps
are not part of this baseline; ``aco+ls`` adds the project's shared local search to its best tour.

All ants of an iteration move together: one step is a few ``(ants, nodes)`` numpy operations.
"""

from __future__ import annotations

import math

import numpy as np
from gtsp_bench.solvers.heuristics.greedy import greedy_tour
from gtsp_bench.solvers.heuristics.local_search import anchor_node, deadline_after, improved_solution, is_past

from gtsp_bench.checks import check_float, check_int
from gtsp_bench.instance import Instance
from gtsp_bench.problem import Problem, price
from gtsp_bench.solver import Progress, Solution, no_progress

#: Share of the time limit ``aco+ls`` keeps for its local search: the colony stops earlier.
LS_SHARE = 0.2


def aco_search(
    problem: Problem,
    *,
    ants: int,
    iterations: int,
    rho: float,
    alpha: float,
    beta: float,
    q: float,
    rng: np.random.Generator,
    deadline: float | None = None,
    progress: Progress = no_progress,
) -> tuple[np.ndarray, float, int, bool]:
    """Run the ant system on a priced problem, reporting each better tour to ``progress``.

    Returns
    -------
    tour, cost, iterations_done, timed_out
        The best tour the ants found (node ids, starting at the depot when there is one; the
        greedy tour if the deadline stopped the run before the first iteration), its cost, the
        number of completed iterations, and whether the deadline stopped the run early.
    """
    edge, node, cluster_of = problem.edge_cost, problem.node_cost, problem.cluster_of
    m, k = problem.n_nodes, problem.n_clusters
    step = edge + node[None, :]  # weighted energy added by going i -> j
    scale = float(step[step > 0].mean()) if np.any(step > 0) else 1.0
    visibility = (scale / np.maximum(step, 1e-12 * scale)) ** beta
    np.fill_diagonal(visibility, 0.0)
    in_cluster = cluster_of[None, :] == np.arange(k)[:, None]  # (clusters, nodes)

    greedy = greedy_tour(problem, anchor_node(problem))  # sets tau0; the answer if no ant ran
    tau = np.full((m, m), ants * q / max(problem.tour_cost(greedy), 1e-300))

    best_tour, best_cost = greedy, math.inf
    done, timed_out = 0, False
    for _ in range(iterations):
        if is_past(deadline):
            timed_out = True
            break
        weight = (tau if alpha == 1.0 else tau**alpha) * visibility
        tours = np.empty((ants, k), dtype=np.int64)
        if problem.depot is not None:
            tours[:, 0] = problem.depot
        else:
            tours[:, 0] = rng.integers(0, m, size=ants)
        alive = ~in_cluster[cluster_of[tours[:, 0]]]
        for s in range(1, k):
            w = weight[tours[:, s - 1]] * alive
            cum = np.cumsum(w, axis=1)
            total = cum[:, -1]
            stuck = ~(total > 0)  # all weights underflowed: choose uniformly among the allowed
            if np.any(stuck):
                w[stuck] = alive[stuck]
                cum = np.cumsum(w, axis=1)
                total = cum[:, -1]
            # cum is flat over excluded nodes, so the first index whose cum exceeds r is allowed
            r = rng.random(ants) * total * (1.0 - 1e-12)
            nxt = (cum <= r[:, None]).sum(axis=1)
            tours[:, s] = nxt
            alive &= ~in_cluster[cluster_of[nxt]]
        closed = np.roll(tours, -1, axis=1)
        costs = node[tours].sum(axis=1) + edge[tours, closed].sum(axis=1)
        i = int(np.argmin(costs))
        if costs[i] < best_cost:
            best_cost, best_tour = float(costs[i]), tours[i].copy()
            progress(best_cost)
        tau *= 1.0 - rho
        deposit = np.repeat(q / np.maximum(costs, 1e-300), k)
        np.add.at(tau, (tours.ravel(), closed.ravel()), deposit)
        np.add.at(tau, (closed.ravel(), tours.ravel()), deposit)
        done += 1
    if problem.depot is not None:
        best_tour = np.roll(best_tour, -int(np.flatnonzero(best_tour == problem.depot)[0]))
    return best_tour, problem.tour_cost(best_tour), done, timed_out


class Aco:
    """The paper's ant colony baseline (Yang et al. 2008), vectorised over ants.

    Parameters
    ----------
    ants
        Ants per iteration (>= 1).
    iterations
        Number of iterations (>= 1).
    rho
        Pheromone evaporation rate, in (0, 1].
    alpha, beta
        Exponents of the pheromone and of the visibility (>= 0).
    q
        Pheromone an ant deposits, divided by its tour's cost (> 0).
    """

    #: Ants move along directed arcs and tours are priced in their direction (the pheromone is
    #: laid both ways, a choice that is only a heuristic's on asymmetric costs).
    asymmetric = True

    #: Whether the shared local search polishes the best tour (``aco+ls``).
    local_search = False

    def __init__(
        self, ants: int = 30, iterations: int = 200, rho: float = 0.1, alpha: float = 1.0,
        beta: float = 5.0, q: float = 1.0,
    ) -> None:
        self.ants = check_int("ants", ants, 1)
        self.iterations = check_int("iterations", iterations, 1)
        self.rho = check_float("rho", rho, 0.0, 1.0)
        self.alpha = check_float("alpha", alpha, 0.0, math.inf, open_low=False)
        self.beta = check_float("beta", beta, 0.0, math.inf, open_low=False)
        self.q = check_float("q", q, 0.0, math.inf)

    def search(
        self, problem: Problem, *, deadline: float | None, seed: int,
        progress: Progress = no_progress,
    ) -> tuple[np.ndarray, float, int, bool]:
        """:func:`aco_search` with this solver's settings."""
        return aco_search(
            problem, ants=self.ants, iterations=self.iterations, rho=self.rho, alpha=self.alpha,
            beta=self.beta, q=self.q, rng=np.random.default_rng(seed), deadline=deadline,
            progress=progress,
        )

    def solve(
        self, instance: Instance, omega: float | None, *, time_limit: float | None = None,
        seed: int = 0, progress: Progress = no_progress,
    ) -> Solution:
        """Run the colony (then the local search for ``aco+ls``); stop early with status
        ``time_limit`` when the limit passes. Each better tour is reported to ``progress``."""
        deadline = deadline_after(time_limit)
        search_deadline = deadline
        if self.local_search and deadline is not None:  # keep the local search its share
            search_deadline = deadline - LS_SHARE * float(time_limit)  # type: ignore[arg-type]
        problem = price(instance, omega)
        tour, cost, done, timed_out = self.search(problem, deadline=search_deadline, seed=seed,
                                                  progress=progress)
        stats = {"iterations": done}
        if self.local_search:
            return improved_solution(problem, tour, deadline, timed_out=timed_out, stats=stats,
                                     progress=progress)
        order, heads = problem.to_solution(tour)
        return Solution(order, heads, objective=cost,
                        status="time_limit" if timed_out else "feasible", stats=stats)


class AcoLS(Aco):
    """:class:`Aco`, then the shared local search
    (:mod:`gtsp_bench.solvers.heuristics.local_search`) on its best tour, in the time left: the
    colony stops at ``1 - LS_SHARE`` of the time limit, so the local search always gets at least
    ``LS_SHARE`` of it."""

    local_search = True

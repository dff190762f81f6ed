"""A GLNS-class large neighbourhood search (after Smith and Imeson, Comput. Oper. Res. 87, 2017).

Each iteration removes some clusters from the current tour and puts them back:

* removal (1 to ``remove_fraction`` of the clusters): **random** clusters, the **worst** ones (the
  largest saving when removed, randomised), or a **segment** of consecutive clusters;
* insertion: **cheapest** (repeatedly the (cluster, position, head) adding least) or **randomised**
  (clusters in random order, each at its cheapest position and head with some noise);

then the shared local search (:mod:`gtsp_bench.solvers.heuristics.local_search`: 2-opt, or-opt,
optimal heads). The
operators are drawn by roulette on adaptive weights (each updated with the score of its
iterations: new best 3, better than the current 2, accepted 1, rejected 0). A new tour replaces
the current one by simulated-annealing acceptance, with the temperature cooling geometrically
over a trial from ``start_temperature`` to ``end_temperature`` times the mean edge cost of the
tour. A trial ends after ``iterations`` iterations or ``patience`` without a new trial best; the
first trial starts from the greedy tour improved by the local search, later ones from the best.

The run is reproducible for a seed unless the time limit stops it (status ``time_limit``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from gtsp_bench.solvers.heuristics.greedy import greedy_tour
from gtsp_bench.solvers.heuristics.local_search import LocalSearch, anchor_node, deadline_after, is_past

from gtsp_bench.checks import (
    check_float,
    check_int,
    time_limit_or_default,
)
from gtsp_bench.errors import InputError
from gtsp_bench.instance import Instance
from gtsp_bench.problem import Problem, price
from gtsp_bench.registry import Solution

REMOVALS = ("random", "worst", "segment")
INSERTIONS = ("cheapest", "randomised")
#: Scores of an iteration's operators: new best, better than current, accepted, rejected.
SCORES = (3.0, 2.0, 1.0, 0.0)
#: No operator weight falls below this (each keeps being tried).
MIN_WEIGHT = 0.1


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
        self.ls = LocalSearch(problem)
        self.edge, self.node = problem.edge_cost, problem.node_cost
        n_removable = problem.n_clusters - (1 if problem.depot is not None else 2)
        self.max_remove = max(1, min(n_removable, math.ceil(settings.remove_fraction * problem.n_clusters)))
        self.weights = {"removal": np.ones(len(REMOVALS)), "insertion": np.ones(len(INSERTIONS))}

    # ------------------------------------------------------------------ removal
    def remove(self, t: np.ndarray, how: str, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Drop ``k`` clusters from cycle ``t``: returns (remaining cycle, removed clusters)."""
        n = len(t)
        movable = np.ones(n, dtype=bool)
        if self.p.depot is not None:
            movable[t == self.p.depot] = False
        if how == "random":
            drop = self.rng.choice(np.flatnonzero(movable), size=k, replace=False)
        elif how == "worst":
            prev, nxt = np.roll(t, 1), np.roll(t, -1)
            saving = self.edge[prev, t] + self.node[t] + self.edge[t, nxt] - self.edge[prev, nxt]
            key = np.where(movable, saving * self.rng.uniform(0.5, 1.5, size=n), -np.inf)
            drop = np.argsort(-key, kind="stable")[:k]
        else:  # segment
            start = int(self.rng.integers(n))
            run = (start + np.arange(n)) % n
            drop = run[movable[run]][:k]
        keep = np.ones(n, dtype=bool)
        keep[drop] = False
        return t[keep], self.p.cluster_of[t[drop]]

    # ------------------------------------------------------------------ insertion
    def insert(self, t: np.ndarray, clusters: np.ndarray, how: str) -> np.ndarray:
        """Put ``clusters`` back into cycle ``t``, each with a head."""
        tour = list(int(v) for v in t)
        pending = [int(c) for c in clusters]
        if how == "randomised":
            self.rng.shuffle(pending)
            scale = self.s.noise * float(np.mean(self.edge[t, np.roll(t, -1)])) if len(t) > 1 else 0.0
        while pending:
            arr = np.array(tour)
            nxt = np.roll(arr, -1)
            cand = pending if how == "cheapest" else pending[:1]
            nodes = [self.p.clusters[c] for c in cand]
            flat = np.concatenate(nodes)
            bounds = np.cumsum([0] + [len(x) for x in nodes[:-1]])
            add = self.edge[arr][:, flat] + self.edge[nxt][:, flat] + self.node[flat]  # (pos, nodes)
            add -= self.edge[arr, nxt][:, None]
            if how == "randomised" and scale > 0:
                add = add + scale * self.rng.random(add.shape)
            per = np.minimum.reduceat(add, bounds, axis=1)  # (pos, cand)
            pos, which = np.unravel_index(int(np.argmin(per)), per.shape)
            lo = bounds[which]
            hi = bounds[which + 1] if which + 1 < len(bounds) else len(flat)
            head = int(flat[lo + int(np.argmin(add[pos, lo:hi]))])
            tour.insert(int(pos) + 1, head)
            pending.remove(cand[which])
        return np.array(tour, dtype=np.int64)

    # ------------------------------------------------------------------ the search
    def pick(self, kind: str) -> int:
        """An operator index drawn with probability proportional to its weight."""
        cum = np.cumsum(self.weights[kind])
        return min(int(np.searchsorted(cum, self.rng.random() * cum[-1], side="right")), len(cum) - 1)

    def reward(self, kind: str, op: int, score: float) -> None:
        """Blend an iteration's score into the weight of the operator it used."""
        w = self.weights[kind]
        w[op] = max(MIN_WEIGHT, (1.0 - self.s.reaction) * w[op] + self.s.reaction * score)

    def run(self, deadline: float | None) -> tuple[np.ndarray, float, dict, bool]:
        p = self.p
        best, best_cost, timed_out = self.ls.run(greedy_tour(p, anchor_node(p)), deadline)
        n = p.n_clusters
        iterations, patience = self.s.iterations_for(n), self.s.patience_for(n)
        done = best_at = 0
        # A cycle of at most 3 clusters is fixed by its heads: the local search's DP solved it.
        trials = self.s.trials if n >= 4 and not timed_out else 0
        for _trial in range(trials):
            cur, cur_cost = best, best_cost
            trial_best, since = best_cost, 0
            mean_edge = float(np.mean(self.edge[cur, np.roll(cur, -1)]))
            t0 = self.s.start_temperature * mean_edge
            t1 = self.s.end_temperature * mean_edge
            for it in range(iterations):
                if is_past(deadline):
                    timed_out = True
                    break
                temp = t0 * (t1 / t0) ** (it / max(1, iterations - 1)) if t0 > 0 and t1 > 0 else t0
                r_op, i_op = self.pick("removal"), self.pick("insertion")
                k = int(self.rng.integers(1, self.max_remove + 1))
                partial, removed = self.remove(cur, REMOVALS[r_op], k)
                new = self.insert(partial, removed, INSERTIONS[i_op])
                new, new_cost, timed_out = self.ls.run(new, deadline)
                done += 1
                tol = 1e-9 * max(1.0, abs(cur_cost))
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
                if new_cost < best_cost:
                    best, best_cost, best_at = new, new_cost, done
                if new_cost < trial_best - tol:
                    trial_best, since = new_cost, 0
                else:
                    since += 1
                self.reward("removal", r_op, score)
                self.reward("insertion", i_op, score)
                if timed_out or since >= patience:
                    break
            if timed_out:
                break
        weights = dict(zip(REMOVALS, self.weights["removal"], strict=True))
        weights.update(zip(INSERTIONS, self.weights["insertion"], strict=True))
        stats = {"iterations": done, "best_at": best_at,
                 "weights": {k: round(float(w), 3) for k, w in weights.items()}}
        return best, best_cost, stats, timed_out


class Lns:
    """GLNS-style large neighbourhood search with the shared local search (module docstring).

    Parameters
    ----------
    iterations
        Iterations per trial (default ``max(100, 25 n)``, n = clusters incl. the depot's).
    trials
        Trials; each restarts the temperature from the best tour so far.
    patience
        Iterations without a new trial best that end a trial (default ``max(50, 5 n)``).
    remove_fraction
        At most this share of the clusters is removed per iteration, in (0, 1].
    start_temperature, end_temperature
        Annealing temperatures as multiples of the tour's mean edge cost (>= 0).
    reaction
        Weight of the newest score in an operator's weight, in (0, 1].
    noise
        Randomised insertion adds up to ``noise`` times the mean edge cost to each price (>= 0).
    """

    def __init__(
        self, iterations: int | None = None, trials: int = 3, patience: int | None = None,
        remove_fraction: float = 0.3, start_temperature: float = 0.05,
        end_temperature: float = 0.0005, reaction: float = 0.1, noise: float = 0.1,
    ) -> None:
        self.settings = LnsSettings(iterations, trials, patience, remove_fraction,
                                    start_temperature, end_temperature, reaction, noise)

    def solve(
        self, instance: Instance, omega: float | None, *, time_limit: float | None = None,
        seed: int = 0,
    ) -> Solution:
        """Search; stop with status ``time_limit`` (best so far) when the limit passes.

        Without a time limit, :func:`default_time_limit` applies.
        """
        time_limit = time_limit_or_default(time_limit, instance.n_clusters)
        deadline = deadline_after(time_limit)
        problem = price(instance, omega)
        search = _Search(problem, self.settings, np.random.default_rng(seed))
        tour, cost, stats, timed_out = search.run(deadline)
        order, heads = problem.to_solution(tour)
        return Solution(order, heads, objective=cost,
                        status="time_limit" if timed_out else "feasible", stats=stats)

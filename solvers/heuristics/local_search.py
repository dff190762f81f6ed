"""The shared improvement step: 2-opt and or-opt on the cluster order, heads re-optimised.

:func:`improve` takes any feasible tour and returns a local optimum of three neighbourhoods:

* **2-opt**: reverse a run of the cycle; the two clusters at the ends of the reversed run get the
  best head for their new neighbours;
* **or-opt**: move a run of 1, 2 or 3 consecutive clusters elsewhere, in either orientation; a
  moved single cluster gets the best head between its new neighbours, a longer run's outer
  end(s) get the best head for their new outer neighbour (for a run of 2, only the end facing
  the tour before the run, its partner keeping its head);
* **heads**: when no move improves, :func:`gtsp_bench.solvers.heads.optimal_heads` re-optimises all heads for
  the current order (a layered shortest path); if that helps, the moves start again.

Moves are priced exactly and the best one is applied (best improvement), so the cost strictly
decreases and the search ends. Every move's price for all positions at once is a few
``(n, m)`` numpy operations (n clusters in the cycle, m nodes): a minimum over each cluster's nodes
is one ``np.minimum.reduceat`` over the node axis, so clusters of unequal size cost nothing extra.
The tour is a cycle through every GTSP cluster, the depot's one-node cluster included, so the depot
needs no special case. Edge costs must be symmetric (they are for every instance kind).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np
from gtsp_bench.solvers.heads import optimal_heads
from gtsp_bench.solvers.heuristics.greedy import Greedy

from gtsp_bench.checks import check_time_limit
from gtsp_bench.errors import InfeasibleSolutionError
from gtsp_bench.instance import Instance
from gtsp_bench.problem import Problem, price
from gtsp_bench.solver import Progress, Solution, no_progress

#: Improvements smaller than this share of the tour cost are ignored (rounding noise).
REL_TOL = 1e-9
#: Longest run of clusters an or-opt move relocates.
MAX_OR_OPT = 3


@dataclass(frozen=True)
class Move:
    """An improving move found by :meth:`LocalSearch.best_move`.

    Attributes
    ----------
    delta
        Change of the tour cost (negative: better).
    kind
        ``"2opt"`` or ``"oropt"``.
    i
        Position of the first cluster of the run reversed (2-opt) or moved (or-opt).
    length
        2-opt: the run is positions ``i .. i + length``; or-opt: the number of clusters moved.
    p
        Or-opt: the run goes between the clusters now at positions ``p`` and ``p + 1``.
    reverse
        Or-opt: insert the run reversed.
    """

    delta: float
    kind: str
    i: int
    length: int
    p: int = -1
    reverse: bool = False


@dataclass(frozen=True)
class _Geometry:
    """Index arrays that depend only on the cycle length n."""

    n: int
    prev: np.ndarray
    next: np.ndarray
    two_opt_ok: np.ndarray
    or_opt_ok: dict[int, np.ndarray]

    def shift(self, k: int) -> np.ndarray:
        """Indices ``(i + k) mod n``."""
        return (np.arange(self.n) + k) % self.n


@lru_cache(maxsize=64)
def _geometry(n: int) -> _Geometry:
    idx = np.arange(n)
    gap = (idx[None, :] - idx[:, None]) % n
    or_ok = {length: (gap >= length) & (gap <= n - 2) for length in range(1, MAX_OR_OPT + 1)}
    return _Geometry(n, (idx - 1) % n, (idx + 1) % n, (gap >= 2) & (gap <= n - 3), or_ok)


@dataclass(frozen=True)
class _Context:
    """Per-tour arrays shared by the move prices (see :meth:`LocalSearch._context`)."""

    t: np.ndarray
    prev: np.ndarray
    next: np.ndarray
    geometry: _Geometry
    own: np.ndarray  # own[i]: node cost of t[i] plus its two edges
    arc: np.ndarray  # arc[p]: edge t[p] -> t[p + 1]
    first: np.ndarray  # first[i, q]: cluster at i re-headed between t[i + 1] and t[q]
    last: np.ndarray  # last[i, q]: cluster at i re-headed between t[i - 1] and t[q]
    insert: np.ndarray  # insert[i, p]: cluster at i with its best head between t[p], t[p + 1]


class LocalSearch:
    """2-opt, or-opt and optimal heads over one priced problem (see the module docstring).

    Parameters
    ----------
    problem
        The priced problem. Its nodes must be numbered cluster by cluster, as
        :func:`gtsp_bench.problem.price` numbers them.
    """

    def __init__(self, problem: Problem) -> None:
        self.problem = problem
        self.edge = problem.edge_cost
        self.node = problem.node_cost
        self.cluster_of = problem.cluster_of
        self.starts = np.array([c[0] for c in problem.clusters], dtype=np.int64)
        contiguous = all(
            np.array_equal(c, np.arange(c[0], c[0] + len(c))) for c in problem.clusters
        ) and np.all(np.diff(self.starts) > 0)
        if not contiguous:
            raise ValueError("local search needs nodes numbered cluster by cluster")
        self._all_nodes = np.arange(problem.n_nodes)

    # ------------------------------------------------------------------ pricing primitives
    def _check(self, tour: Sequence[int]) -> np.ndarray:
        t = np.asarray(tour, dtype=np.int64).reshape(-1)
        clusters = self.cluster_of[t] if t.size and t.min() >= 0 and t.max() < len(self.node) else None
        if clusters is None or len(t) != self.problem.n_clusters or \
                len(np.unique(clusters)) != self.problem.n_clusters:
            raise InfeasibleSolutionError("tour must hold exactly one node of every cluster")
        return t

    def _context(self, t: np.ndarray) -> _Context:
        """What every move price needs, computed once per tour."""
        n = len(t)
        g = _geometry(n)
        cl = self.cluster_of[t]
        pos = np.empty(self.problem.n_clusters, dtype=np.int64)
        pos[cl] = np.arange(n)
        rows = self.edge[t]  # rows[q, v] = edge(t[q], v)
        prev, nxt = t[g.prev], t[g.next]

        def end_costs(offset: int) -> np.ndarray:
            inner = t[(pos + offset) % n][self.cluster_of]  # every node's inner neighbour
            own = self.node + self.edge[self._all_nodes, inner]
            return np.minimum.reduceat(rows + own, self.starts, axis=1)[:, cl].T

        insert = np.minimum.reduceat(rows + rows[g.next] + self.node, self.starts, axis=1)
        return _Context(
            t=t, prev=prev, next=nxt, geometry=g,
            own=self.edge[prev, t] + self.node[t] + self.edge[t, nxt],
            arc=self.edge[t, nxt], first=end_costs(+1), last=end_costs(-1),
            insert=insert[:, cl].T,
        )

    def insertion_costs(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """``out[q, c]``: min over nodes v of GTSP cluster c of ``node(v) + edge(a[q], v) +
        edge(v, b[q])``, shape ``(len(a), n_clusters)``: the cheapest way to put c between
        ``a[q]`` and ``b[q]``."""
        return np.minimum.reduceat(self.edge[a] + self.edge[b] + self.node, self.starts, axis=1)

    def best_head(self, cluster: int, a: int, b: int) -> int:
        """The node of ``cluster`` with the least ``node(v) + edge(a, v) + edge(v, b)``."""
        nodes = self.problem.clusters[cluster]
        return int(nodes[np.argmin(self.node[nodes] + self.edge[a, nodes] + self.edge[nodes, b])])

    # ------------------------------------------------------------------ move prices
    def two_opt_deltas(self, t: np.ndarray, ctx: _Context | None = None) -> np.ndarray:
        """``out[i, j]``: cost change of reversing positions ``i .. j`` (cyclic), the end clusters
        re-headed; ``inf`` where not a proper move (``(j - i) mod n`` outside ``[2, n - 3]``)."""
        c = ctx or self._context(np.asarray(t, dtype=np.int64))
        g = c.geometry
        # The cluster from j goes to i, between prev[i] and t[j - 1]: last[j, i - 1], transposed;
        # the cluster from i goes to j, between t[i + 1] and next[j]: first[i, j + 1].
        delta = c.last.T[g.prev] + c.first[:, g.next] - c.own[:, None] - c.own[None, :]
        return np.where(g.two_opt_ok, delta, np.inf)

    def or_opt_deltas(
        self, t: np.ndarray, ctx: _Context | None = None
    ) -> dict[tuple[int, bool], np.ndarray]:
        """``out[(length, reverse)][i, p]``: cost change of moving the run of ``length`` clusters
        at positions ``i ..`` between positions ``p`` and ``p + 1``, reversed or not;
        ``inf`` where not a proper move."""
        c = ctx or self._context(np.asarray(t, dtype=np.int64))
        g, e, nd = c.geometry, self.edge, self.node
        n, t = len(c.t), c.t
        out: dict[tuple[int, bool], np.ndarray] = {}
        if n < 4:
            return out
        # One cluster: best head between t[p] and t[p + 1].
        delta = c.insert - c.arc[None, :] + (e[c.prev, c.next] - c.own)[:, None]
        out[(1, False)] = np.where(g.or_opt_ok[1], delta, np.inf)
        for length in range(2, min(MAX_OR_OPT, n - 3) + 1):
            ends = [t[g.shift(k)] for k in range(-1, length + 1)]  # t[i-1], t[i], ..., t[i+L]
            old = e[ends[0], ends[1]] + e[ends[-2], ends[-1]] + nd[ends[1]] + nd[ends[-2]]
            old = old + e[ends[1], ends[2]] + (e[ends[-3], ends[-2]] if length > 2 else 0.0)
            closing = e[ends[0], ends[-1]] - old
            end_rows = c.last[g.shift(length - 1)]  # last[i + L - 1, q]
            if length == 2:  # the partner keeps its head
                fwd = c.first + (nd[ends[2]][:, None] + e[ends[2][:, None], c.next[None, :]])
                rev = end_rows + (nd[ends[1]][:, None] + e[ends[1][:, None], c.next[None, :]])
            else:
                fwd = c.first + end_rows[:, g.next]
                rev = end_rows + c.first[:, g.next]
            for reverse, ins in ((False, fwd), (True, rev)):
                delta = ins - c.arc[None, :] + closing[:, None]
                out[(length, reverse)] = np.where(g.or_opt_ok[length], delta, np.inf)
        return out

    def best_move(self, t: np.ndarray, cost: float | None = None) -> Move | None:
        """The best 2-opt or or-opt move, or ``None`` when none improves."""
        t = np.asarray(t, dtype=np.int64)
        if cost is None:
            cost = self.problem.tour_cost(t)
        tol = REL_TOL * max(1.0, abs(cost))
        if len(t) < 4:
            return None
        ctx = self._context(t)
        best: Move | None = None
        if len(t) >= 5:
            d = self.two_opt_deltas(t, ctx)
            i, j = divmod(int(np.argmin(d)), len(t))
            if d[i, j] < -tol:
                best = Move(float(d[i, j]), "2opt", i, (j - i) % len(t))
        for (length, reverse), d in self.or_opt_deltas(t, ctx).items():
            i, p = divmod(int(np.argmin(d)), len(t))
            if d[i, p] < -tol and (best is None or d[i, p] < best.delta):
                best = Move(float(d[i, p]), "oropt", i, length, p, reverse)
        return best

    def apply(self, t: np.ndarray, move: Move) -> np.ndarray:
        """The tour after ``move`` (heads chosen as :meth:`best_move` priced them)."""
        n, cl = len(t), self.cluster_of
        s = np.roll(t, -move.i)  # the run now starts at 0
        if move.kind == "2opt":
            j = move.length
            run = s[: j + 1][::-1].copy()
            run[0] = self.best_head(int(cl[s[j]]), int(s[-1]), int(s[j - 1]))
            run[-1] = self.best_head(int(cl[s[0]]), int(s[1]), int(s[(j + 1) % n]))
            return np.concatenate([run, s[j + 1:]])
        length = move.length
        run, rest = s[:length].copy(), s[length:]
        at = (move.p - move.i - length) % n  # index in rest of the cluster before the run
        a, b = int(rest[at]), int(rest[(at + 1) % len(rest)])
        if length == 1:
            run[0] = self.best_head(int(cl[run[0]]), a, b)
        else:
            if move.reverse:
                run = run[::-1].copy()
            run[0] = self.best_head(int(cl[run[0]]), int(run[1]), a)
            if length > 2:
                run[-1] = self.best_head(int(cl[run[-1]]), int(run[-2]), b)
        return np.concatenate([rest[: at + 1], run, rest[at + 1:]])

    # ------------------------------------------------------------------ the search
    def reoptimise_heads(self, t: np.ndarray) -> tuple[np.ndarray, float]:
        """Optimal heads for the order of ``t`` (:func:`gtsp_bench.solvers.heads.optimal_heads`)."""
        p = self.problem
        if p.depot is not None:
            start = int(np.flatnonzero(t == p.depot)[0])
            order = self.cluster_of[np.roll(t, -start)[1:]]
        else:
            order = self.cluster_of[t]
        return optimal_heads(p, order)

    def run(self, tour: Sequence[int], deadline: float | None = None,
            progress: Progress = no_progress) -> tuple[np.ndarray, float, bool]:
        """Improve ``tour`` to a local optimum, reporting each cost on the way to ``progress``.

        Returns
        -------
        tour, cost, timed_out
            The tour (starting at the depot when there is one), its cost, and whether the
            deadline (a :func:`time.perf_counter` value) stopped the search early.
        """
        t = self._check(tour)
        cost = self.problem.tour_cost(t)
        timed_out = False
        while True:
            progress(cost)
            if deadline is not None and time.perf_counter() > deadline:
                timed_out = True
                break
            move = self.best_move(t, cost)
            if move is not None:
                t = self.apply(t, move)
                cost = self.problem.tour_cost(t)
                continue
            t_h, c_h = self.reoptimise_heads(t)
            if c_h < cost - REL_TOL * max(1.0, abs(cost)):
                t, cost = t_h, c_h
                continue
            break
        return self.rotate(t), self.problem.tour_cost(t), timed_out

    def rotate(self, t: np.ndarray) -> np.ndarray:
        """``t`` rotated to start at the depot (unchanged without a depot)."""
        if self.problem.depot is None:
            return t
        return np.roll(t, -int(np.flatnonzero(t == self.problem.depot)[0]))


def improve(
    problem: Problem, tour: Sequence[int], *, deadline: float | None = None
) -> tuple[np.ndarray, float]:
    """Improve a tour with 2-opt, or-opt and optimal heads until no move helps.

    Parameters
    ----------
    problem
        The priced problem.
    tour
        Node ids, one per GTSP cluster (the depot's included), in cycle order, any rotation.
    deadline
        A :func:`time.perf_counter` value after which the search stops with the best tour so far.

    Returns
    -------
    tour : numpy.ndarray
        The improved tour, starting at the depot when there is one.
    cost : float
        Its cost, :meth:`Problem.tour_cost`; never above the input tour's.

    Raises
    ------
    InfeasibleSolutionError
        If ``tour`` does not hold exactly one node of every cluster.
    """
    t, cost, _ = LocalSearch(problem).run(tour, deadline)
    return t, cost


def anchor_node(problem: Problem) -> int:
    """Where a constructed tour starts: the depot, else the first node of the smallest cluster."""
    if problem.depot is not None:
        return problem.depot
    return int(min(problem.clusters, key=len)[0])


def deadline_after(time_limit: float | None) -> float | None:
    """A :func:`time.perf_counter` deadline ``time_limit`` seconds from now (``None``: none).

    Raises
    ------
    InputError
        If ``time_limit`` is not a positive number of seconds.
    """
    time_limit = check_time_limit(time_limit)
    return None if time_limit is None else time.perf_counter() + time_limit


def is_past(deadline: float | None) -> bool:
    """Whether ``deadline`` has passed (never for ``None``)."""
    return deadline is not None and time.perf_counter() > deadline


def improved_solution(
    problem: Problem, tour: Sequence[int], deadline: float | None, *, timed_out: bool = False,
    stats: dict | None = None, progress: Progress = no_progress,
) -> Solution:
    """The :class:`Solution` of ``tour`` after :func:`improve` (the ``+ls`` solver variants),
    each better tour on the way reported to ``progress``.

    Its status is ``time_limit`` when ``timed_out`` (the first stage stopped early) or when the
    deadline stops the local search.
    """
    tour, cost, ls_timed_out = LocalSearch(problem).run(tour, deadline, progress)
    order, heads = problem.to_solution(tour)
    return Solution(order, heads, objective=cost,
                    status="time_limit" if timed_out or ls_timed_out else "feasible",
                    stats=dict(stats or {}))


class GreedyLS(Greedy):
    """The paper's greedy (:class:`gtsp_bench.solvers.heuristics.greedy.Greedy`), then
    :func:`improve` on its tour; or, given a warm start (``initial``), :func:`improve` on that."""

    def solve(
        self, instance: Instance, omega: float | None, *, time_limit: float | None = None,
        seed: int = 0, initial: Solution | None = None, progress: Progress = no_progress,
    ) -> Solution:
        """Build the greedy tour (or take ``initial``), then improve it (stopping at the time
        limit), reporting each better tour to ``progress``."""
        deadline = deadline_after(time_limit)
        sol = initial or super().solve(instance, omega, time_limit=time_limit, seed=seed)
        problem = price(instance, omega)
        out = improved_solution(problem, problem.to_tour(sol.order, sol.heads), deadline,
                                progress=progress)
        return out if initial is None else replace(out, stats={**out.stats, "warm_start": True})

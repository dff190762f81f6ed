"""LKH-3 (Helsgaun's Lin-Kernighan-Helsgaun heuristic, through the ``elkai`` wheel) as a peer.

The GTSP becomes an asymmetric TSP by the **Noon-Bean transformation** (the route GLKH takes):

* within each cluster the nodes form a zero-cost cycle ``v0 -> v1 -> ... -> v0``;
* an arc that leaves node ``u`` of a cluster for node ``v`` of another cluster leaves from the
  *predecessor* of ``u`` in that cycle, and costs ``w(u, v) + M`` with
  ``w(u, v) = edge(u, v) + node(u)`` (the node cost of the tail folded in: a tour leaves each
  chosen node once);
* every other arc (inside a cluster, off the cycle) costs ``M``, the forbidden-arc price.

A tour that enters every cluster once walks the whole cycle from its entry node ``u`` to
``pred(u)`` and leaves toward the next cluster: it costs ``K M`` plus exactly the GTSP cost of the
tour through the entry nodes. With ``M`` above the dearest possible GTSP tour, any ATSP tour that
visits a cluster twice, or uses a forbidden arc, costs more than every contiguous one, so the ATSP
optimum is the GTSP optimum. A UAV instance's depot is a cluster of its own (a one-node cycle).

LKH needs integers in a narrow range: elkai hands the matrix over as 32-bit floats and LKH's ATSP
code, multiplying by its ``PRECISION`` (100) in C ``int``, reserves ``INT_MAX / 2 / 100`` (about
1.07e7) for the edges of its own symmetric transformation. Every transformed weight, ``M``
included, is therefore kept at or below :data:`LIMIT` (1e7): whole-number costs (GTSPLIB) are used
as they are when they fit, other costs are scaled so that they do. When the largest arc would get
fewer than :data:`MIN_UNITS` integer units (about ``LIMIT / (K + 1)``: tens of thousands of
clusters) the solver refuses with an :class:`InputError` rather than round the costs away.

LKH's tour is mapped back: the clusters in the order the tour meets them, each cluster's head the
node by which the tour entered it. When the tour is not a contiguous Noon-Bean tour (LKH is a
heuristic: its first tours often are not, e.g. with ``max_trials=1``; with the defaults we have
not seen one) the order it gives is kept and the heads are chosen optimally for it
(:func:`~gtsp_bench.solvers.heads.optimal_heads`); ``stats["repaired"]`` says so. The returned
tour is always priced exactly (:meth:`Problem.tour_cost`).

What is controlled: ``runs``, ``max_trials``, ``subgradient`` (LKH's ``RUNS``, ``MAX_TRIALS``,
``SUBGRADIENT``), the seed (LKH's ``SEED = seed + 1``, modulo 2^31 - 1), and the time limit, shared
by the runs as LKH's per-run ``TIME_LIMIT`` (status ``time_limit`` when the whole solve reaches it).
LKH checks that limit between trials and leaves out its preprocessing (the subgradient ascent that
builds the candidate sets on the 2n-node symmetric graph of the ATSP), which always runs to the end
and produces a first tour: about 0.5 s for n = 400 nodes, 4 s for n = 1000, 25 s for n = 2000 and
about 2 minutes for n = 4000 (K = 200 clusters of 20) on a shared core, so large instances overshoot
a short limit; ``subgradient=False`` cuts it to a fraction of a second. (LKH's ``TOTAL_TIME_LIMIT``
would count the preprocessing, but when it runs out first elkai returns no tour at all.) A limit of
a few milliseconds can still run out before LKH's first tour (elkai then returns none: a 0.01 s
limit at K = 20 did in about 1 of 6 first calls of a process): the solver then returns the warm
start if given, else the paper's greedy tour from the depot (or the smallest cluster), with
``stats["fallback"]`` naming which and status ``time_limit``. A run that stops on its own
(``MAX_TRIALS``, by default n) is reproducible for a seed; one stopped by the limit is not. A warm
start becomes LKH's ``INITIAL_TOUR_FILE``: the Noon-Bean tour of the given GTSP tour
(:func:`atsp_tour`). elkai's LKH keeps that file name for every later call in the process (a later
run without a warm start then fails on the deleted file), so a warm-started run happens in a forked
child process (:func:`_solve_apart`). elkai's public ``DistanceMatrix.solve_tsp`` takes only
``runs``; this solver calls the function it wraps, ``elkai._elkai.solve_problem(params, problem)``,
with a full LKH parameter text.

LKH is free for academic and non-commercial use only (Keld Helsgaun's licence; elkai ships it
under the same restriction). It is an optional extra: ``pip install 'gtsp-bench[lkh]'``.
"""

from __future__ import annotations

import math
import multiprocessing
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from gtsp_bench.solvers.heads import optimal_heads
from gtsp_bench.solvers.heuristics.greedy import greedy_starts, greedy_tour

from gtsp_bench.checks import (
    check_bool,
    check_int,
    time_limit_or_default,
)
from gtsp_bench.errors import InputError, SolverError
from gtsp_bench.instance import Instance
from gtsp_bench.problem import Problem, price
from gtsp_bench.solver import Solution

#: Largest transformed weight, big-M included (LKH reserves INT_MAX / 2 / PRECISION ~ 1.07e7).
LIMIT = 10_000_000
#: Fewest integer units the largest real arc may get before the solver refuses to round.
MIN_UNITS = 100
#: LKH's default ``PRECISION``, written into the parameters so that :data:`LIMIT` holds.
PRECISION = 100

MISSING = "lkh needs the optional package elkai: pip install 'gtsp-bench[lkh]'"


def _import_elkai():
    try:
        from elkai import _elkai
    except ImportError:
        raise InputError(MISSING) from None
    if not hasattr(_elkai, "solve_problem"):
        raise InputError("lkh needs elkai 2.x (elkai._elkai.solve_problem): "
                         "pip install 'gtsp-bench[lkh]'")
    return _elkai


def noon_bean(
    weights: np.ndarray, clusters: Sequence[np.ndarray], big_m: int
) -> np.ndarray:
    """The Noon-Bean ATSP matrix of a GTSP with integer arc weights (node costs folded in).

    Parameters
    ----------
    weights
        ``(n, n)`` integer weights ``w(u, v)`` of leaving the chosen node ``u`` for ``v``.
    clusters
        Node ids of each cluster (they partition ``0..n-1``).
    big_m
        The constant added to every inter-cluster arc and charged for every forbidden arc.

    Returns
    -------
    numpy.ndarray
        ``(n, n)`` int64: 0 on each cluster's cycle (and on the diagonal of a one-node cluster),
        ``w(u, v) + M`` from ``pred(u)`` to ``v`` in another cluster, ``M`` elsewhere.
    """
    n = len(weights)
    pred = np.empty(n, dtype=np.int64)
    cluster_of = np.empty(n, dtype=np.int64)
    for c, nodes in enumerate(clusters):
        nodes = np.asarray(nodes, dtype=np.int64)
        pred[nodes] = np.roll(nodes, 1)
        cluster_of[nodes] = c
    out = np.full((n, n), big_m, dtype=np.int64)
    # Row pred(u) gets u's outgoing weights: ATSP arc pred(u) -> v stands for GTSP arc u -> v.
    inter = cluster_of[:, None] != cluster_of[None, :]
    out[pred] = np.where(inter, weights + big_m, big_m)
    for nodes in clusters:
        nodes = np.asarray(nodes, dtype=np.int64)
        out[np.roll(nodes, 1), nodes] = 0  # pred(u) -> u: the zero-cost cycle
    return out


def atsp_tour(tour: Sequence[int], clusters: Sequence[np.ndarray], cluster_of: np.ndarray) -> np.ndarray:
    """The contiguous Noon-Bean ATSP tour of a GTSP tour (node ids, one per cluster): each
    cluster entered at its node in ``tour``, then walked round its cycle (the inverse of
    :func:`tour_from_atsp`)."""
    runs = []
    for u in tour:
        nodes = np.asarray(clusters[int(cluster_of[u])], dtype=np.int64)
        runs.append(np.roll(nodes, -int(np.flatnonzero(nodes == u)[0])))
    return np.concatenate(runs)


def tour_from_atsp(atsp_tour: Sequence[int], cluster_of: np.ndarray) -> tuple[np.ndarray, bool]:
    """The GTSP tour an ATSP tour stands for, and whether it is a contiguous Noon-Bean tour.

    Each cluster is represented by the node through which the tour first enters it; the clusters
    come in the order the tour first meets them. The tour is contiguous when it meets each
    cluster in exactly one run of consecutive nodes.
    """
    t = np.asarray(atsp_tour, dtype=np.int64)
    labels = cluster_of[t]
    k = int(cluster_of.max()) + 1
    if k == 1:
        return t[:1], True
    # Rotate so that the tour starts at the entry of a run (the cluster changes just before it).
    change = np.flatnonzero(labels != np.roll(labels, 1))
    t, labels = np.roll(t, -int(change[0])), np.roll(labels, -int(change[0]))
    entries = np.flatnonzero(labels != np.roll(labels, 1))
    contiguous = len(entries) == k
    _, first = np.unique(labels[entries], return_index=True)
    return t[entries[np.sort(first)]], contiguous


def scaled_weights(problem: Problem, limit: int | None = None) -> tuple[np.ndarray, int, float]:
    """Integer arc weights ``w(u, v) = edge(u, v) + node(u)`` (shifted, scaled), ``M`` and the scale.

    Inter-cluster weights are shifted so that the cheapest is 0 (every tour uses K of them, so
    the shift is the same for all) and scaled by 1 when they are whole numbers and
    ``M + max w <= limit`` (default :data:`LIMIT`), else so that it just holds. ``M`` is one more
    than the sum over the clusters of the dearest arc leaving each: above any GTSP tour's cost.

    Raises
    ------
    InputError
        When costs are not finite or the largest arc would get fewer than :data:`MIN_UNITS`
        integer units under ``limit``.
    """
    limit = LIMIT if limit is None else limit
    cluster_of = problem.cluster_of
    inter = cluster_of[:, None] != cluster_of[None, :]
    with np.errstate(over="ignore", invalid="ignore"):
        w = problem.edge_cost + problem.node_cost[:, None]
    name = problem.instance.name
    if not np.all(np.isfinite(w[inter])):
        raise InputError(f"lkh: {name} has costs that are not finite numbers; they cannot be "
                         f"scaled to integers")
    w = np.where(inter, w - w[inter].min(), 0.0)
    # The dearest arc leaving each cluster: a GTSP tour costs at most their sum.
    out_max = np.array([w[nodes].max() for nodes in problem.clusters])
    span = float(out_max.sum() + w.max())
    k = problem.n_clusters
    if np.all(w == np.round(w)) and span + 1 <= limit:
        scale = 1.0
    else:  # rounding adds at most 1/2 per cluster to the sum, 1/2 to the largest arc
        scale = (limit - 1 - (k + 1) / 2) / span if span > 0 else 1.0
    top = float(w.max())
    rounds = scale != 1.0  # whole numbers that fit are used as they are, however small
    if rounds and not (math.isfinite(scale) and scale > 0 and top * scale >= MIN_UNITS) and top > 0:
        raise InputError(f"lkh: {name} cannot be scaled to LKH's integer weights: all of them, "
                         f"big-M included, must stay below {limit:.3g}, which leaves its largest "
                         f"arc fewer than {MIN_UNITS} units; use another solver")
    iw = np.round(w * scale).astype(np.int64)
    big_m = int(sum(int(iw[nodes].max()) for nodes in problem.clusters)) + 1
    if big_m + int(iw.max()) > limit:  # cannot happen by construction; never hand LKH a wrong M
        raise SolverError(f"lkh: transformed weights of {name} exceed {limit}")
    return iw, big_m, scale


class LKH:
    """LKH-3 on the Noon-Bean ATSP of the GTSP (see the module docstring).

    Parameters
    ----------
    runs
        LKH's ``RUNS`` (>= 1): independent runs, the best tour kept.
    max_trials
        LKH's ``MAX_TRIALS`` per run (>= 1), or ``None`` for LKH's default (the number of nodes).
    subgradient
        LKH's ``SUBGRADIENT``: ``False`` skips the subgradient ascent (candidate sets from the raw
        weights): much less preprocessing, better on our energy instances, worse on GTSPLIB.
    """

    #: Noon-Bean already makes a directed (ATSP) problem: asymmetric costs go in as they are.
    asymmetric = True
    capped = True  #: given no time limit, run_solver gives it the default one

    def __init__(self, runs: int = 1, max_trials: int | None = None, subgradient: bool = True) -> None:
        self.runs = check_int("runs", runs, 1)
        self.max_trials = None if max_trials is None else check_int("max_trials", max_trials, 1)
        self.subgradient = check_bool("subgradient", subgradient)

    def solve(
        self, instance: Instance, omega: float | None, *, time_limit: float | None = None,
        seed: int = 0, initial: Solution | None = None,
    ) -> Solution:
        """Transform, run LKH once (from the warm start ``initial``, if given), map back and
        price exactly."""
        elkai = _import_elkai()
        time_limit = time_limit_or_default(time_limit, instance.n_clusters)
        start = time.perf_counter()
        problem = price(instance, omega)
        stats: dict = {"lkh": False, "repaired": False}
        if problem.n_nodes < 3 or problem.n_clusters < 2:  # LKH needs 3 nodes; enumerate instead
            tour = _tiny(problem)
        else:
            weights, big_m, scale = scaled_weights(problem)
            stats.update(lkh=True, scale=scale, big_m=big_m)
            matrix = noon_bean(weights, problem.clusters, big_m)
            with tempfile.TemporaryDirectory(prefix="gtsp-lkh-") as folder:
                first = None
                if initial is not None:  # LKH reads an initial tour from a file only
                    first = Path(folder) / "initial.tour"
                    nodes = atsp_tour(problem.to_tour(initial.order, initial.heads), problem.clusters,
                                      problem.cluster_of)
                    first.write_text("TOUR_SECTION\n" + "\n".join(str(v + 1) for v in nodes.tolist())
                                     + "\n-1\nEOF\n", encoding="ascii")
                    stats["warm_start"] = True
                left = max(time_limit - (time.perf_counter() - start), 1e-3)
                params, text = self._params(left, seed, first), _problem_text(matrix)
                found = elkai.solve_problem(params, text) if first is None else _solve_apart(params, text)
                atsp = np.asarray(found, dtype=np.int64) - 1
            spent = time.perf_counter() - start >= time_limit
            partial = len(atsp) > 0 and sorted(atsp.tolist()) != list(range(problem.n_nodes))
            if partial and spent:  # LKH stopped by its limit mid-tour (seen on a loaded machine)
                stats["lkh_partial"] = len(atsp)
                atsp = atsp[:0]
            if len(atsp) == 0:  # the limit ran out before LKH's first tour: a valid tour all the same
                tour = (problem.to_tour(initial.order, initial.heads) if initial is not None
                        else greedy_tour(problem, greedy_starts(problem)[0]))
                stats["fallback"] = "warm_start" if initial is not None else "greedy"
                contiguous = True
            elif partial:
                raise SolverError(f"LKH returned no tour through all nodes of {instance.name}")
            else:
                tour, contiguous = tour_from_atsp(atsp, problem.cluster_of)
                stats["atsp_cost"] = int(matrix[atsp, np.roll(atsp, -1)].sum())
            if not contiguous:  # keep the cyclic order from the depot on, re-choose the heads
                if problem.depot is not None:
                    tour = np.roll(tour, -int(np.flatnonzero(tour == problem.depot)[0]))
                order = [int(c) for c in problem.cluster_of[tour] if c < instance.n_clusters]
                tour = optimal_heads(problem, order)[0]
                stats["repaired"] = True
        order, heads = problem.to_solution(tour)
        seconds = time.perf_counter() - start
        return Solution(order, heads, objective=problem.tour_cost(tour),
                        status="time_limit" if seconds >= time_limit or "fallback" in stats else "feasible",
                        stats=stats)

    def _params(self, seconds: float, seed: int, initial: Path | None = None) -> str:
        """LKH's parameter text: runs, trials, seed, precision, the time left (shared by the
        runs; LKH's ``TIME_LIMIT`` is per run and leaves out the preprocessing) and the initial
        tour's file, if any."""
        lines = [f"RUNS = {self.runs}", f"SEED = {seed % (2**31 - 1) + 1}", f"PRECISION = {PRECISION}",
                 f"TIME_LIMIT = {seconds / self.runs:.6f}",
                 "PROBLEM_FILE = :stdin:"]
        if initial is not None:
            lines.insert(-1, f"INITIAL_TOUR_FILE = {initial}")
        if self.max_trials is not None:
            lines.insert(1, f"MAX_TRIALS = {self.max_trials}")
        if not self.subgradient:
            lines.insert(1, "SUBGRADIENT = NO")
        return "\n".join(lines) + "\n"


def _solve_in_child(params: str, text: str, conn) -> None:
    """A forked child's body (:func:`_solve_apart`): LKH's tour, or its error, sent on ``conn``."""
    try:
        conn.send(("ok", _import_elkai().solve_problem(params, text)))
    except Exception as e:  # sent back whole: the parent raises it
        conn.send(("error", f"{type(e).__name__}: {e}"))
    finally:
        conn.close()


def _solve_apart(params: str, text: str) -> list[int]:
    """``elkai._elkai.solve_problem(params, text)`` in a forked child process, so that what LKH
    keeps between calls (the initial tour's file name) stays out of this process."""
    ctx = multiprocessing.get_context("fork")
    receive, send = ctx.Pipe(duplex=False)
    child = ctx.Process(target=_solve_in_child, args=(params, text, send), daemon=True)
    child.start()
    send.close()
    try:
        kind, value = receive.recv()
    except EOFError:
        raise SolverError(f"LKH's process ended without a tour (exit code {child.exitcode})") from None
    finally:
        receive.close()
        if child.is_alive():
            child.join(timeout=5.0)
            if child.is_alive():
                child.kill()
        child.join()
    if kind != "ok":
        raise SolverError(f"LKH failed: {value}")
    return value


def _problem_text(matrix: np.ndarray) -> str:
    """The TSPLIB text of an ATSP given by a full integer matrix."""
    rows = "\n".join(" ".join(map(str, row)) for row in matrix.tolist())
    return (f"TYPE : ATSP\nDIMENSION : {len(matrix)}\nEDGE_WEIGHT_TYPE : EXPLICIT\n"
            f"EDGE_WEIGHT_FORMAT : FULL_MATRIX\nEDGE_WEIGHT_SECTION\n{rows}\nEOF\n")


def _tiny(problem: Problem) -> np.ndarray:
    """The best tour of a GTSP with one or two clusters, by enumeration."""
    if problem.n_clusters == 1:
        nodes = problem.clusters[0]
        return nodes[[int(np.argmin(problem.node_cost[nodes]))]]
    a, b = problem.clusters
    cost = (problem.node_cost[a][:, None] + problem.node_cost[b][None, :]
            + problem.edge_cost[np.ix_(a, b)] + problem.edge_cost[np.ix_(b, a)].T)  # there and back
    i, j = np.unravel_index(int(np.argmin(cost)), cost.shape)
    return np.array([a[i], b[j]])

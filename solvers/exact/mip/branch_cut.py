"""The exact search: root loop, branch and cut (or the backend's own MILP).

:class:`_Search` holds one solve's state: the root LP loop (pricing, reduced-cost fixing,
separation, purging), the branch and cut with the backend as LP solver or, for a
:class:`~gtsp_bench.solvers.exact.mip.backends.LazyMipBackend`, the backend's own MILP with lazy
subtour rows. With a :class:`~gtsp_bench.solvers.exact.mip.certify.ProofLog` it records every
proof it relies on. :func:`gtsp_bench.solvers.exact.mip.solve.solve_exact` drives it.
"""

from __future__ import annotations

import heapq
import math
import time
from collections.abc import Sequence
from typing import Any

import numpy as np
import scipy.sparse as sp
from gtsp_bench.solvers.exact.mip import branching, columns
from gtsp_bench.solvers.exact.mip.backends import Backend, LazyMipBackend, LpModel, LpResult
from gtsp_bench.solvers.exact.mip.branching import PseudoCosts, StrongResult, choose
from gtsp_bench.solvers.exact.mip.certify import CertificateError, ProofLog
from gtsp_bench.solvers.exact.mip.model import TOL, build_model, core_columns
from gtsp_bench.solvers.exact.mip.options import MipOptions
from gtsp_bench.solvers.exact.mip.separation import Cuts, separate, subtour_cuts
from gtsp_bench.solvers.exact.mip.tree import Node

from gtsp_bench.errors import InputError
from gtsp_bench.problem import Problem
from gtsp_bench.solver import Progress, no_progress

#: Columns priced into the root LP per round, per node.
PRICE_PER_NODE = 2
#: Most dual simplex iterations of a strong-branching LP: one stopped there scores its child by the
#: objective reached (a guide, never a bound). At UAV K = 50 a full strong LP took 3,000-6,000
#: iterations (2-4 s), 16 of them a node.
STRONG_ITERATIONS = 1000
#: A dive stops at a node whose bound is above the best open one by more than this share of the
#: gap between that one and the incumbent (then the best open node is taken).
DIVE_SHARE = 0.3
#: A node taken from the open ones whose column bounds differ from the LP's in more than this many
#: columns (a jump in the tree) has its first LP solved from no basis by the interior point method:
#: UAV K = 50, omega 0.9, 600 s: 6 of 11 such LPs, and 16 of 23 started from the parent's stored
#: basis, stalled in the dual simplex (5,000 iterations, then the interior point method anyway).
JUMP_BOUNDS = 20
#: The root loop ends (tails off) when its LP value rose by less than ``ROOT_TAIL`` of it over its
#: last ``ROOT_TAIL_ROUNDS`` rounds without columns to price in.
ROOT_TAIL, ROOT_TAIL_ROUNDS = 1e-5, 5
#: Also, from round ``ROOT_FLAT_AFTER`` on, when its bound rose by less than ``ROOT_FLAT_SHARE`` of
#: the gap left over its last ``ROOT_FLAT_ROUNDS`` rounds, pricing or not (0 rounds: never; at UAV
#: K = 50 most rounds price). Roots that end sooner (K <= 20, GTSPLIB to 442 nodes) are untouched.
ROOT_FLAT_SHARE, ROOT_FLAT_ROUNDS, ROOT_FLAT_AFTER = 0.05, 10, 100
#: A cut leaves the LP once it was slack at this many LP optima in a row: at the root, and at a
#: node of the search.
ROOT_PURGE_AGE, NODE_PURGE_AGE = 3, 10
#: At the root of a model of at least ``BIG_ROOT_NODES`` nodes (after pruning) a cut leaves once it
#: was slack at ``BIG_ROOT_PURGE_AGE`` optima: there an LP costs thousands of simplex iterations a
#: round (UAV K = 100, about 1,700 nodes: the certified gap at 150 s fell on 9 of 9 points, mean
#: 0.373 -> 0.299 %), where on GTSPLIB up to 442 nodes the root loop took more rounds and most
#: proofs took longer (45ts225 37 -> 46 s). UAV K = 50 has 730-910 nodes. A root of at least
#: ``columns.ROOT_DROP_NODES`` also drops edge columns priced out for long
#: (:func:`columns.drop_root_stale`). A big model's LPs run on ``MipOptions.lp_threads()``.
BIG_ROOT_NODES, BIG_ROOT_PURGE_AGE = 1200, 1


# ---------------------------------------------------------------------- the method
def _is_integral(values: np.ndarray, tol: float = 1e-6) -> bool:
    return bool(np.all(np.abs(values - np.round(values)) <= tol))


def check_symmetric(problem: Problem) -> None:
    """Check that the edge costs are symmetric (the model has one variable per edge).

    Raises
    ------
    InputError
        If they are not (relative tolerance 1e-12).
    """
    if not np.allclose(problem.edge_cost, problem.edge_cost.T, rtol=1e-12, atol=0):
        raise InputError(f"{problem.instance.name}: edge costs are not symmetric; the exact "
                         "solvers need a symmetric GTSP")


def degree_bound(problem: Problem) -> float:
    """A lower bound on the optimum that needs no LP, for cycles through at least 3 clusters.

    In such a cycle every head ``v`` has two different neighbours outside its cluster, so with
    symmetric costs the tour costs ``sum over heads of node[v] + (e(prev, v) + e(v, next)) / 2``,
    at least ``node[v]`` plus half of ``v``'s two cheapest edges to other clusters; the bound
    takes the cheapest node of each cluster by that measure. It is what a solve stopped by its
    time limit before the first LP reports.

    Parameters
    ----------
    problem
        The priced problem (symmetric edge costs, at least 3 GTSP clusters).

    Returns
    -------
    float
        The bound.
    """
    cluster_of = problem.cluster_of
    other = np.where(cluster_of[:, None] != cluster_of[None, :], problem.edge_cost, np.inf)
    per_node = problem.node_cost + 0.5 * np.partition(other, 1, axis=1)[:, :2].sum(axis=1)
    return float(sum(per_node[c].min() for c in problem.clusters))


class _Timer:
    """Accumulates seconds per phase in a stats dict."""

    def __init__(self, stats: dict[str, Any], key: str) -> None:
        self.stats, self.key = stats, key

    def __enter__(self) -> None:
        self.start = time.perf_counter()

    def __exit__(self, *exc: object) -> None:
        self.stats[self.key] = self.stats.get(self.key, 0.0) + time.perf_counter() - self.start


class _Search:
    """State of one exact solve: the incumbent, the bound, the LP and the phases.

    Parameters
    ----------
    problem
        The priced problem.
    backend
        A new, empty backend; the model's core columns are put into it.
    options
        Shared options.
    deadline
        ``time.perf_counter()`` time at which the solve stops.
    tour
        The first incumbent (problem node ids).
    kept
        Candidate heads per GTSP cluster (after pruning).
    stats
        Filled with counters and seconds per phase.
    progress
        Told the incumbent's cost and the bound whenever either improves (:meth:`report`).
    """

    def __init__(self, problem: Problem, backend: Backend, options: MipOptions, deadline: float,
                 tour: np.ndarray, kept: Sequence[np.ndarray], stats: dict[str, Any],
                 progress: Progress = no_progress, certify: bool = False) -> None:
        self.problem, self.options, self.deadline, self.stats = problem, options, deadline, stats
        self.progress = progress
        self.start = time.perf_counter()
        self.model = model = build_model(problem, kept)
        stats["nodes"], stats["edges"] = model.n_nodes, len(model.tail)
        threads = options.lp_threads() if model.n_nodes >= BIG_ROOT_NODES else 1
        if threads > 1:  # its LPs take thousands of simplex iterations: worth a second core
            backend.use_threads(threads)
        stats["lp_threads"] = threads
        self.tour, self.ub = tour, problem.tour_cost(tour)
        self.lb = degree_bound(problem)  # a bound even if no LP is solved in time
        self.gap = max(options.abs_gap, 1 - 1e-6) if model.integral_costs else options.abs_gap
        self.margin = 1e-9 * max(1.0, abs(self.ub))  # against rounding in the LP's duals
        self.lp = LpModel(model, backend, core_columns(model, options.core_edges, tour))
        self.fixed = np.zeros(model.n_cols, dtype=bool)
        self.codes = np.full(model.n_cols, -1, dtype=np.int8)  # the node in the LP, per model column
        self.pinned = np.zeros(model.n_cols, dtype=bool)  # branched on: never dropped
        self.pseudo = PseudoCosts(model.n_cols)
        #: The proofs the search relies on, when it writes a certificate (no LP cutoffs then).
        self.log = ProofLog(model) if certify else None
        self.cid = 0  # the node being solved, in the log
        self.strong_proofs: dict[tuple[int, int], int] = {}  # (backend column, value) -> proof
        self.open_cids: list[int] = []  # nodes left open at the end, closed by their parent's bound
        self.report()

    # -------------------------------------------------------------- helpers
    def record(self, res: LpResult) -> int:
        """Log the duals of the LP just solved (``res``; the backend's Farkas ray when it is
        infeasible); the proof's index (-1 without a log)."""
        if self.log is None:
            return -1
        if res.status == "infeasible":
            ray = self.lp.backend.dual_ray()  # type: ignore[attr-defined]
            if ray is None:
                raise CertificateError("an infeasible LP without a Farkas ray")
            return self.log.proof("farkas", ray, self.lp.cuts, self.lp.cut_ids)
        assert res.duals is not None
        return self.log.proof("dual", res.duals, self.lp.cuts, self.lp.cut_ids)

    def report(self) -> None:
        """Tell ``progress`` the incumbent's cost and the bound (at most that cost: reduced-cost
        fixing may push the bound above an incumbent it has proven optimal)."""
        self.progress(self.ub, min(self.lb, self.ub))

    def left(self) -> float:
        """Seconds left."""
        return self.deadline - time.perf_counter()

    def _root_flat(self, bounds: list[float]) -> bool:
        """Whether the root bound, past round ``ROOT_FLAT_AFTER`` (counting the loop before a pause),
        is flat against the gap left over this loop's last ``ROOT_FLAT_ROUNDS`` rounds."""
        k, done = ROOT_FLAT_ROUNDS, self.stats.get("root_rounds", 0) + len(bounds)
        return (0 < k < len(bounds) and done > ROOT_FLAT_AFTER
                and self.lb - bounds[-1 - k] < ROOT_FLAT_SHARE * (self.ub - self.lb))

    def trace_round(self, objective: float, bound: float) -> None:
        """Add a root round to ``stats["root_trace"]``: seconds since the search began, the LP's
        objective and the round's Lagrangian bound, the LP and separation seconds and simplex
        iterations so far, and the LP's cuts and columns."""
        lp = self.lp
        self.stats.setdefault("root_trace", []).append({
            "time_s": round(time.perf_counter() - self.start, 4), "lp": objective, "bound": bound,
            "lp_s": round(self.stats.get("lp_s", 0.0), 4),
            "separation_s": round(self.stats.get("separation_s", 0.0), 4),
            "iterations": getattr(lp.backend, "iterations", None), "cuts": len(lp.cuts),
            "cols": len(lp.cols)})

    @property
    def proven(self) -> bool:
        """Whether the incumbent is proven optimal (up to the gap and rounding)."""
        return self.ub - self.lb <= self.gap + 8 * np.finfo(float).eps * abs(self.ub)

    def offer(self, values: np.ndarray) -> None:
        """Take an integer solution without subtours as incumbent if it is better."""
        cand = self.model.tour(values)
        cost = self.problem.tour_cost(cand)
        if cost < self.ub:
            self.tour, self.ub = cand, cost
            self.report()

    def solve_lp(self, cutoff: float = math.inf, iterations: int | None = None) -> LpResult:
        """One LP solve, timed (at most ``iterations`` simplex iterations if given)."""
        with _Timer(self.stats, "lp_s"):
            if iterations is None:
                return self.lp.backend.solve_lp(self.left(), cutoff)
            return self.lp.backend.solve_lp(self.left(), cutoff, iterations)

    def separate(self, values: np.ndarray, thorough: bool = True) -> Cuts | None:
        """Cuts at ``values``: subtour rows of an integer point, else the fractional separation."""
        with _Timer(self.stats, "separation_s"):
            if _is_integral(values):
                return subtour_cuts(self.model, values)
            return separate(self.model, values, thorough=thorough, deadline=self.deadline)

    # -------------------------------------------------------------- root
    def root(self, until: float | None = None) -> bool:
        """Root LP loop: price columns in, bound, fix by reduced cost, separate; whether it
        paused at ``until`` (a ``time.perf_counter()`` time) before it finished."""
        model, lp = self.model, self.lp
        purge_age = BIG_ROOT_PURGE_AGE if model.n_nodes >= BIG_ROOT_NODES else ROOT_PURGE_AGE
        drops = model.n_nodes >= columns.ROOT_DROP_NODES
        dropped = np.zeros(model.n_cols, dtype=bool)  # columns this loop took out of the LP
        history: list[float] = []
        bounds: list[float] = []
        rounds = 0
        paused = False
        while rounds < self.options.root_rounds and self.left() > 0:
            if until is not None and time.perf_counter() >= until:
                paused = True
                break
            rounds += 1
            res = self.solve_lp()
            present = np.zeros(model.n_cols, dtype=bool)
            present[lp.cols] = True
            absent = ~present & ~self.fixed
            if res.status == "infeasible" and absent.any():  # the core was too small
                back = absent & dropped  # (or columns dropped below: those first)
                lp.add_cols(np.flatnonzero(back if back.any() else absent))
                dropped[:] = False
                continue
            if res.values is None or res.duals is None or res.reduced_costs is None:
                break
            values = lp.full(res.values)
            rc = np.zeros(model.n_cols)
            rc[lp.cols] = res.reduced_costs
            rc[absent] = lp.reduced_costs(res.duals, np.flatnonzero(absent))
            bound = res.objective + np.minimum(rc[absent], 0).sum()  # Lagrangian bound
            proof = self.record(res)
            if self.log is not None:
                self.log.root_round(bound, proof)
            self.lb = max(self.lb, bound)
            self.report()
            bounds.append(self.lb)
            self.trace_round(res.objective, bound)
            if self.proven or self.left() <= 0 or self._root_flat(bounds):
                break
            if drops:  # edge columns long priced out leave (priced back in when negative)
                gone = columns.drop_root_stale(lp, res.reduced_costs, self.ub - res.objective)
                dropped[gone] = True
                self.stats["root_dropped"] = self.stats.get("root_dropped", 0) + len(gone)
            fix = (bound + rc > self.ub - self.gap + self.margin) & ~self.fixed
            if fix.any():  # fixed columns leave the LP (their nonzeros slow every LP down)
                if self.log is not None:
                    self.log.root_round(bound, proof, np.flatnonzero(fix))
                self.fixed |= fix
                lp.drop_cols(np.flatnonzero(fix[lp.cols]))
            price = np.flatnonzero(absent & ~fix & (rc < -TOL))
            if len(price):  # the most negative columns join; cuts are separated meanwhile
                lp.add_cols(price[np.argsort(rc[price])[:PRICE_PER_NODE * model.n_nodes]])
            else:
                history.append(res.objective)
                last, k = history[-1], ROOT_TAIL_ROUNDS
                if len(history) > k and last - history[-1 - k] < ROOT_TAIL * max(1.0, abs(last)):
                    break  # tailing off
            new = self.separate(values)
            if new is None:
                if not len(price):
                    if _is_integral(values):
                        self.offer(values)  # the LP optimum is a tour: the optimum
                    break
                continue
            if self.left() <= 0:
                break
            lp.purge(values, purge_age)
            lp.add_cuts(new)
        lp.col_age[:] = 0  # the node loop ages columns by its own rule
        self.stats["root_rounds"] = self.stats.get("root_rounds", 0) + rounds  # (over both loops)
        self.stats["root_bound"] = float(self.lb)
        self.stats["root_cuts"] = len(lp.cuts)
        return paused

    def absent(self) -> np.ndarray:
        """Model columns neither in the LP nor fixed to 0 (for the search or at the node)."""
        absent = ~self.fixed & (self.codes != 0)
        absent[self.lp.cols] = False
        return np.flatnonzero(absent)

    # -------------------------------------------------------------- MILP by the backend
    def native_mip(self) -> None:
        """The backend's own branch and cut, subtour rows added lazily."""
        model, lp = self.model, self.lp
        missing = self.absent()  # every column not fixed joins: the search is exact
        if len(missing):
            lp.add_cols(missing)

        def lazy(v: np.ndarray) -> tuple[sp.csr_array, np.ndarray] | None:
            cuts = subtour_cuts(model, lp.full(v))
            if cuts is None:  # a tour: the backend's new incumbent
                self.progress(self.problem.tour_cost(model.tour(lp.full(v))))
                return None
            return cuts.sparse(model, lp.cols), cuts.rhs

        backend = lp.backend
        assert isinstance(backend, LazyMipBackend)
        with _Timer(self.stats, "mip_s"):
            res = backend.solve_mip(self.left(), self.ub - self.gap, self.gap, lazy)
        self.stats.update(res.stats)
        self.lb = max(self.lb, min(res.bound, self.ub))
        if res.values is not None:
            self.offer(lp.full(res.values))
        if res.complete:
            self.lb = max(self.lb, self.ub - self.gap)  # nothing better than ub - gap exists
        self.report()

    # -------------------------------------------------------------- own branch and cut
    def branch_and_cut(self) -> None:
        """Branch and cut with the backend as LP solver: best first, diving into a child while
        its bound stays near the best open one (:data:`DIVE_SHARE`).

        Each node runs the root's cut loop; columns not in the LP are priced in while their
        reduced cost is negative (a node is pruned on its Lagrangian bound before that). It
        fixes columns by reduced cost for its subtree and branches by :meth:`_branching` (strong
        branching among the fractional ``y`` closest to 1/2, else such ``x``). Cuts are
        global; slack ones are purged, and so are columns priced out for long (:mod:`columns`).
        A node taken from the open ones after a jump in the tree (:data:`JUMP_BOUNDS`) has its
        first LP solved from no basis by the interior point method.
        """
        lp = self.lp
        heap: list[Node] = []
        node: Node | None = Node(self.lb, 0, self.codes)  # (the log's root, ``cid`` 0)
        seq = explored = 0
        popped = False  # whether ``node`` came from the heap (a jump), not a dive or the same node
        while node is not None and not self.proven and self.left() > 0:
            if node.bound <= self.ub - self.gap:
                # move the LP's bounds here (codes per model column; absent columns need none)
                change, lower, upper = columns.bound_moves(node.fixes, self.codes, lp.cols, self.fixed)
                if len(change):
                    lp.backend.set_bounds(change, lower, upper)
                if popped and len(change) > JUMP_BOUNDS:  # a jump: the last basis is far away
                    lp.backend.start_cold()
                    self.stats["jumps"] = self.stats.get("jumps", 0) + 1
                self.codes = node.fixes
                self.cid = node.cid
                explored += 1
                outcome = self._node_loop(node.branched)
                if outcome == "stopped":
                    heapq.heappush(heap, node)
                    break
                if isinstance(outcome, tuple) and len(outcome) == 2:  # the same node, one more fix
                    fixes, key = self.codes.copy(), int(lp.cols[outcome[0]])
                    fixes[key], self.pinned[key] = int(outcome[1]), True
                    if self.log is not None:
                        empty_side = self.strong_proofs[(outcome[0], 1 - int(outcome[1]))]
                        self.log.fix_var(node.cid, empty_side, key, int(outcome[1]))
                    node = Node(node.bound, node.seq, fixes, cid=node.cid)
                    continue
                cid, node = node.cid, None
                if isinstance(outcome, tuple) and len(outcome) == 5:
                    bound, col, value, frac, fix = outcome
                    base = self.codes.copy()
                    base[lp.cols[fix]] = 0
                    first, second = (1, 0) if value >= 0.5 else (0, 1)  # dive into ``value``
                    children = []
                    key = int(lp.cols[col])
                    self.pinned[key] = True
                    for v in (first, second):
                        child = base.copy()
                        child[key] = v
                        children.append(child)
                    seq += 2
                    best_other = heap[0].bound if heap else bound
                    cids = (0, 0) if self.log is None else (self.log.child(cid, key, first),
                                                            self.log.child(cid, key, second))
                    heapq.heappush(heap, Node(bound, seq, children[1], (key, second == 1, frac, bound),
                                              cids[1]))
                    node = Node(bound, seq - 1, children[0], (key, first == 1, frac, bound), cids[0])
                    if bound > best_other + DIVE_SHARE * (self.ub - best_other):  # no dive: far up
                        heapq.heappush(heap, node)
                        node = None
            else:
                if self.log is not None:  # its parent's bound closes it
                    self.open_cids.append(node.cid)
                node = None
            popped = node is None and bool(heap)
            if popped:
                node = heapq.heappop(heap)
            # the global bound: the best open node (the incumbent's when none is open)
            best_open = min(heap[0].bound if heap else math.inf,
                            node.bound if node is not None else math.inf)
            self.lb = max(self.lb, min(best_open, self.ub - self.gap))
            self.report()
        self.stats["bc_nodes"] = explored
        self.open_cids += [n.cid for n in heap] + ([node.cid] if node is not None else [])

    def _node_loop(self, branched: tuple[int, bool, float, float] | None = None
                   ) -> tuple[float, int, float, float, np.ndarray] | tuple[int, float] | str | None:
        """Cut loop at a node: ``None`` when pruned, ``"stopped"`` at the time limit,
        (backend column, value) when strong branching showed that the node's solutions below the
        incumbent all have the column at that value, else (bound, backend column, the child's value
        to dive into, the column's LP value, backend columns fixed by reduced cost in the subtree).
        ``branched`` (:attr:`Node.branched`) is recorded in the pseudo-costs at the first LP."""
        lp = self.lp
        history: list[float] = []
        while self.left() > 0:
            absent = self.absent()
            # with columns absent, only the Lagrangian bound (below) may prune: no LP cutoff
            cutoff = self.ub - self.gap if len(absent) == 0 and self.log is None else math.inf
            res = self.solve_lp(cutoff=cutoff)
            self.stats["node_lps"] = self.stats.get("node_lps", 0) + 1
            if res.status == "infeasible" and len(absent):  # only the columns in the LP are
                repair = self._farkas_price(absent)
                if len(repair):
                    lp.add_cols(repair)
                    continue
            if res.status in ("infeasible", "cutoff"):
                return self._leaf(res)
            if res.values is None or res.reduced_costs is None or res.duals is None:
                return "stopped"
            if branched is not None:  # the node's first LP: the branching's gain
                key, up, frac, parent = branched
                self.pseudo.record(key, up, min(res.objective, self.ub) - parent, frac)
                branched = None
            values = lp.full(res.values)
            if len(absent):
                rc = lp.reduced_costs(res.duals, absent)
                if res.objective + np.minimum(rc, 0).sum() > self.ub - self.gap:
                    return self._leaf(res)
                price = rc < -TOL
                if price.any():
                    if _is_integral(values) and subtour_cuts(self.model, values) is None:
                        self.offer(values)
                    lp.add_cols(absent[price][np.argsort(rc[price])[:PRICE_PER_NODE * self.model.n_nodes]])
                    continue
            if res.objective > self.ub - self.gap:
                return self._leaf(res)
            if self.left() <= 0:
                return "stopped"
            history.append(res.objective)
            tailing = len(history) > 3 and history[-1] - history[-4] < 1e-4 * max(1.0, abs(history[-1]))
            new = None if tailing and not _is_integral(values) else self.separate(values, False)
            if new is None:
                if _is_integral(values):
                    self.offer(values)
                    return self._leaf(res)
                proof = self.record(res)  # (before strong branching's LPs)
                rc = res.reduced_costs
                fix = np.flatnonzero((res.objective + rc > self.ub - self.gap + self.margin)
                                     & (res.values < TOL))
                choice = self._branching(res.values, res.objective)
                if choice is None:
                    if self.log is not None:
                        self._both_empty()
                    return None
                col, value, only = choice
                if only:  # the other child is empty: fix the column here and go on
                    return col, value
                if self.log is not None:
                    self.log.fix_rule(self.cid, proof)
                return res.objective, col, value, float(res.values[col]), fix
            gone = columns.drop_stale(lp, res.reduced_costs, self.ub - res.objective,
                                      self.pinned[lp.cols])
            self.stats["cols_dropped"] = self.stats.get("cols_dropped", 0) + len(gone)
            lp.purge(values, NODE_PURGE_AGE)
            lp.add_cuts(new)
        return "stopped"

    def _farkas_price(self, absent: np.ndarray) -> np.ndarray:
        """After an LP infeasible over its columns: the absent columns that could make it feasible
        (negative reduced cost at zero cost under the Farkas ray; all of them when the backend
        gives no ray). None: the ray shows the whole node infeasible."""
        ray_of = getattr(self.lp.backend, "dual_ray", None)
        ray = None if ray_of is None else ray_of()
        if ray is None:
            return absent
        r = self.lp.reduced_costs(ray, absent) - self.model.cost[absent]
        return absent[r < -TOL]

    def _leaf(self, res: LpResult) -> None:
        """The node is closed by ``res`` (its duals or Farkas ray): logged."""
        if self.log is not None:
            self.log.leaf(self.cid, self.record(res))

    def _both_empty(self) -> None:
        """Log the node's closing by strong branching: a column both of whose children are empty."""
        assert self.log is not None
        for (col, v), proof in self.strong_proofs.items():
            other = self.strong_proofs.get((col, 1 - v))
            if v == 0 and other is not None:
                key = int(self.lp.cols[col])
                self.log.leaf(self.log.child(self.cid, key, 0), proof)
                self.log.leaf(self.log.child(self.cid, key, 1), other)
                return
        raise CertificateError("strong branching closed a node without two empty children")

    def _child_is_empty(self, res: LpResult, absent: np.ndarray) -> bool:
        """Whether a strong-branching child's LP shows that it holds nothing below the incumbent
        (its LP covers the columns in the LP only: with columns absent, a Lagrangian bound)."""
        if res.status == "infeasible":
            return len(absent) == 0
        if res.status != "optimal" or res.objective <= self.ub - self.gap or res.duals is None:
            return False
        if len(absent) == 0:
            return True
        rc = self.lp.reduced_costs(res.duals, absent)
        return res.objective + np.minimum(rc, 0).sum() > self.ub - self.gap

    def _strong(self, col: int, objective: float, absent: np.ndarray, restore: bool) -> StrongResult:
        """Both children's LPs of backend column ``col`` (at most :data:`STRONG_ITERATIONS`
        iterations each); the node's basis restored after a stopped run (any run: ``restore``)."""
        backend = self.lp.backend
        child, empty, start = [], [], backend.basis()
        for v in (0.0, 1.0):
            backend.set_bounds(np.array([col]), np.array([v]), np.array([v]))
            res = self.solve_lp(iterations=STRONG_ITERATIONS)
            empty.append(self._child_is_empty(res, absent))
            if empty[-1] and self.log is not None:  # (its ray before the basis is reset)
                self.strong_proofs[(col, int(v))] = self.record(res)
            if restore or res.status == "stopped":
                backend.set_basis(start)
            if res.status == "stopped" and math.isfinite(res.objective):  # a guide only
                self.stats["strong_partial"] = self.stats.get("strong_partial", 0) + 1
                child.append(max(objective, res.objective))
            else:
                child.append(math.inf if res.status == "infeasible" else
                             res.objective if res.status == "optimal" else objective)
        backend.set_bounds(np.array([col]), np.zeros(1), np.ones(1))
        self.stats["strong_lps"] = self.stats.get("strong_lps", 0) + 2
        return StrongResult((child[0], child[1]), (empty[0], empty[1]))

    def _branching(self, values: np.ndarray, objective: float) -> tuple[int, float, bool] | None:
        """Backend column to branch on, the value of the child to dive into, and whether the
        other child is empty (then the column is fixed to that value, no branching); ``None``
        when both children are empty (the node is pruned).

        Candidates: the fractional ``y`` (else ``x``) closest to 1/2, scored by the product of
        the two children's gains (:func:`~gtsp_bench.solvers.exact.mip.branching.choose`): all
        strong-branched while strong-branching LPs mostly finish, else reliability branching
        (the option ``branching`` may fix either).
        """
        self.strong_proofs.clear()
        is_y = self.lp.cols < self.model.n_nodes
        frac = np.abs(values - np.round(values)) > 1e-6
        for group in (is_y, ~is_y):
            cand = np.flatnonzero(group & frac)
            if len(cand):
                break
        else:
            raise AssertionError("no fractional column to branch on")
        mode = self.options.branching
        full = mode == "strong" or (mode == "auto" and not branching.reliability(
            *(self.stats.get(k, 0) for k in ("strong_lps", "strong_partial"))))
        if full:  # full strong branching of the closest few (reliability branching takes them all)
            cand = cand[np.argsort(np.abs(values[cand] - 0.5), kind="stable")[:branching.CANDIDATES]]
        if len(cand) == 1:
            return int(cand[0]), float(round(values[cand[0]])), False
        absent = self.absent()
        with _Timer(self.stats, "branching_s"):
            choice = choose(cand, self.lp.cols[cand], values[cand], objective, self.ub, self.pseudo,
                            lambda c: self._strong(c, objective, absent, not full),
                            stop=lambda: self.left() < 0, reliable=2**62 if full else None,
                            lookahead=len(cand) if full else None,
                            max_strong=len(cand) if full else None)
        if choice is None or choice.only:
            key = "strong_pruned" if choice is None else "strong_fixed"
            self.stats[key] = self.stats.get(key, 0) + 1
        return None if choice is None else (choice.col, choice.value, choice.only)

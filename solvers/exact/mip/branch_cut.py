"""The exact search: root loop, branch and cut (or the backend's own MILP).

:class:`_Search` holds one solve's state: the root LP loop (pricing, reduced-cost fixing,
separation, purging), the branch and cut with the backend as LP solver or, for a
:class:`~gtsp_bench.solvers.exact.mip.backends.LazyMipBackend`, the backend's own MILP with lazy
subtour rows. With a :class:`~gtsp_bench.solvers.exact.mip.certify.ProofLog` it records every
proof it relies on. :func:`gtsp_bench.solvers.exact.mip.solve.solve_exact` drives it.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from typing import Any

import numpy as np
import scipy.sparse as sp
from gtsp_bench.solvers.exact.mip import columns
from gtsp_bench.solvers.exact.mip.backends import Backend, LazyMipBackend, LpModel, LpResult
from gtsp_bench.solvers.exact.mip.branching import PseudoCosts
from gtsp_bench.solvers.exact.mip.certify import CertificateError, ProofLog
from gtsp_bench.solvers.exact.mip.model import TOL, build_model, core_columns
from gtsp_bench.solvers.exact.mip.options import MipOptions
from gtsp_bench.solvers.exact.mip.separation import Cuts, separate, subtour_cuts
from gtsp_bench.solvers.exact.mip.tree_search import PRICE_PER_NODE, TreeSearch, _is_integral, _Timer
from gtsp_bench.solvers.exact.mip.workers import Incumbent

from gtsp_bench.errors import InputError
from gtsp_bench.problem import Problem
from gtsp_bench.solver import Progress, no_progress

#: The root loop ends (tails off) when its LP value rose by less than ``ROOT_TAIL`` of it over its
#: last ``ROOT_TAIL_ROUNDS`` rounds without columns to price in.
ROOT_TAIL, ROOT_TAIL_ROUNDS = 1e-5, 5
#: Also, from round ``ROOT_FLAT_AFTER`` on, when its bound rose by less than ``ROOT_FLAT_SHARE`` of
#: the gap left over its last ``ROOT_FLAT_ROUNDS`` rounds, pricing or not (0 rounds: never; at UAV
#: K = 50 most rounds price). Roots that end sooner (K <= 20, GTSPLIB to 442 nodes) are untouched.
ROOT_FLAT_SHARE, ROOT_FLAT_ROUNDS, ROOT_FLAT_AFTER = 0.05, 10, 100
#: A cut leaves the root's LP once it was slack at this many LP optima in a row (at a node of the
#: search: ``tree_search.NODE_PURGE_AGE``).
ROOT_PURGE_AGE = 3
#: At the root of a model of at least ``BIG_ROOT_NODES`` nodes (after pruning) a cut leaves once it
#: was slack at ``BIG_ROOT_PURGE_AGE`` optima: there an LP costs thousands of simplex iterations a
#: round (UAV K = 100, about 1,700 nodes: the certified gap at 150 s fell on 9 of 9 points, mean
#: 0.373 -> 0.299 %), where on GTSPLIB up to 442 nodes the root loop took more rounds and most
#: proofs took longer (45ts225 37 -> 46 s). UAV K = 50 has 730-910 nodes. A root of at least
#: ``columns.ROOT_DROP_NODES`` also drops edge columns priced out for long
#: (:func:`columns.drop_root_stale`). A big model's LPs run on ``MipOptions.lp_threads()``.
BIG_ROOT_NODES, BIG_ROOT_PURGE_AGE = 1200, 1


# ---------------------------------------------------------------------- the method
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


class _Search(TreeSearch):
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
        # the incumbent and the bound (a bound even if no LP is solved in time), shared by the
        # tree's workers
        self.state = Incumbent(tour, problem.tour_cost(tour), degree_bound(problem), progress)
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
    @property
    def tour(self) -> np.ndarray:
        """The incumbent (problem node ids)."""
        return self.state.tour

    @tour.setter
    def tour(self, tour: np.ndarray) -> None:
        self.state.tour = tour

    @property
    def ub(self) -> float:
        """The incumbent's cost."""
        return self.state.cost

    @ub.setter
    def ub(self, cost: float) -> None:
        self.state.cost = cost

    @property
    def lb(self) -> float:
        """The proven lower bound."""
        return self.state.bound

    @lb.setter
    def lb(self, bound: float) -> None:
        self.state.bound = bound

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
        self.state.report()

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
        self.state.offer(cand, self.problem.tour_cost(cand))

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

"""The branch and cut after the root: best-first search with dives, on one or more workers.

:class:`TreeSearch` is the part of :class:`~gtsp_bench.solvers.exact.mip.branch_cut._Search`
that searches the tree: it takes open nodes (:class:`~gtsp_bench.solvers.exact.mip.workers.OpenNodes`),
runs each node's cut loop (pricing, reduced-cost fixing, separation, purging), branches
(strong or reliability branching, :mod:`~gtsp_bench.solvers.exact.mip.branching`) and logs the
proofs of a certificate. It uses the search's LP, incumbent and helpers (``solve_lp``,
``separate``, ``record``, ``absent``, ``offer``, ``left``, ``report``, ``proven``).
"""

from __future__ import annotations

import copy
import math
import time
from concurrent.futures import ThreadPoolExecutor
from typing import TYPE_CHECKING, Any

import numpy as np
from gtsp_bench.solvers.exact.mip import branching, columns
from gtsp_bench.solvers.exact.mip.backends import LpResult
from gtsp_bench.solvers.exact.mip.branching import StrongResult, choose
from gtsp_bench.solvers.exact.mip.certify import CertificateError
from gtsp_bench.solvers.exact.mip.model import TOL
from gtsp_bench.solvers.exact.mip.separation import subtour_cuts
from gtsp_bench.solvers.exact.mip.tree import Node
from gtsp_bench.solvers.exact.mip.workers import CUT_ID_RANGE, OpenNodes
from threadpoolctl import threadpool_limits

if TYPE_CHECKING:
    from gtsp_bench.solvers.exact.mip.branch_cut import _Search

#: Columns priced into the root LP per round, per node.
PRICE_PER_NODE = 2
#: Most dual simplex iterations of a strong-branching LP: one stopped there scores its child by the
#: objective reached (a guide, never a bound). At UAV K = 50 a full strong LP took 3,000-6,000
#: iterations (2-4 s), 16 of them a node.
STRONG_ITERATIONS = 1000
#: A dive stops at a node whose bound is above the best open one by more than this share of the
#: gap between that one and the incumbent (then the best open node is taken).
DIVE_SHARE = 0.3
#: With two workers or more, one that ends a dive takes the newest open node it made itself whose
#: bound is above the best open one by at most this share of the gap to the incumbent (else the
#: best): it goes on near its LP's last place in the tree, so fewer of its nodes start after a jump.
AFFINITY_SHARE = 0.3
#: A node taken from the open ones whose column bounds differ from the LP's in more than this many
#: columns (a jump in the tree) has its first LP solved from no basis by the interior point method:
#: UAV K = 50, omega 0.9, 600 s: 6 of 11 such LPs, and 16 of 23 started from the parent's stored
#: basis, stalled in the dual simplex (5,000 iterations, then the interior point method anyway).
JUMP_BOUNDS = 20
#: A cut leaves a node's LP once it was slack at this many LP optima in a row.
NODE_PURGE_AGE = 10


def _is_integral(values: np.ndarray, tol: float = 1e-6) -> bool:
    return bool(np.all(np.abs(values - np.round(values)) <= tol))


class _Timer:
    """Accumulates seconds per phase in a stats dict."""

    def __init__(self, stats: dict[str, Any], key: str) -> None:
        self.stats, self.key = stats, key

    def __enter__(self) -> None:
        self.start = time.perf_counter()

    def __exit__(self, *exc: object) -> None:
        self.stats[self.key] = self.stats.get(self.key, 0.0) + time.perf_counter() - self.start


class TreeSearch:
    """The tree search of an exact solve (a base of its ``_Search``, whose state it uses)."""

    def worker(self: _Search, number: int) -> _Search:
        """A copy of this search for tree worker ``number``: its own copy of the LP (cut ids
        from ``number * CUT_ID_RANGE``), node and strong-branching proofs; the incumbent, the
        counters, pseudo-costs, pinned and fixed columns and the proof log shared."""
        twin = copy.copy(self)
        twin.lp = self.lp.copy(number * CUT_ID_RANGE)
        twin.codes = self.codes.copy()
        twin.strong_proofs, twin.open_cids = {}, []
        return twin

    def branch_and_cut(self) -> None:
        """Branch and cut with the backend as LP solver: best first, diving into a child while
        its bound stays near the best open one (:data:`DIVE_SHARE`).

        Each node runs the root's cut loop; columns not in the LP are priced in while their
        reduced cost is negative (a node is pruned on its Lagrangian bound before that). It
        fixes columns by reduced cost for its subtree and branches by :meth:`_branching` (strong
        branching among the fractional ``y`` closest to 1/2, else such ``x``). Cuts are
        global; slack ones are purged, and so are columns priced out for long (:mod:`columns`).
        A node taken from the open ones after a jump in the tree (:data:`JUMP_BOUNDS`) has its
        first LP solved from no basis by the interior point method. With
        ``MipOptions.tree_workers()`` above 1 (and a backend that copies itself) that many
        threads search at once, each with its own copy of the LP on one core
        (:mod:`~gtsp_bench.solvers.exact.mip.workers`), each taking its own open nodes first while
        they are near the best (:data:`AFFINITY_SHARE`).
        """
        tree = OpenNodes(Node(self.lb, 0, self.codes))  # (the log's root, ``cid`` 0)
        workers = self.options.tree_workers() if hasattr(self.lp.backend, "copy") else 1
        self.stats["tree_workers"] = workers
        if workers > 1:
            self.lp.backend.use_threads(1)
            searches = [self] + [self.worker(j) for j in range(1, workers)]
            # one BLAS thread each: calls from two threads into OpenBLAS's own pool of threads
            # queue behind each other (45ts225: no faster than one worker without this cap)
            with threadpool_limits(limits=1, user_api="blas"), \
                    ThreadPoolExecutor(workers, thread_name_prefix="milp-tree") as pool:
                try:
                    done = list(pool.map(lambda j: searches[j].work(tree, j), range(workers)))
                except BaseException:  # (an interrupt, or a worker's error): the others end too
                    tree.close()
                    raise
            for twin in searches[1:]:
                self.open_cids += twin.open_cids
                self.lp.backend.absorb(twin.lp.backend)
        else:
            done = [self.work(tree, 0)]
        self.stats["bc_nodes"] = sum(done)
        self.state.raise_bound(min(tree.bound(), self.ub - self.gap))
        self.report()
        self.open_cids += [n.cid for n in tree.heap]

    def work(self, tree: OpenNodes, worker: int) -> int:
        """Worker ``worker``'s share of :meth:`branch_and_cut`: take the best open node, solve it,
        dive or put the children back, until the tree is done, the incumbent proven or the time
        up (a node in hand goes back to the open ones); the number of nodes it solved."""
        lp = self.lp

        def stop() -> bool:
            return tree.closed or self.proven or self.left() <= 0

        def near(best: float) -> float:
            return best + AFFINITY_SHARE * (self.ub - best)

        prefer = near if self.stats.get("tree_workers", 1) > 1 else None

        explored = 0
        popped = True  # whether ``node`` came from the open ones (a jump), not a dive
        try:
            node = tree.take(worker, stop, prefer)
            while node is not None:
                if stop():
                    tree.put(node)
                    break
                if node.bound <= self.ub - self.gap:
                    # move the LP's bounds here (codes per model column; absent columns need none)
                    change, lower, upper = columns.bound_moves(node.fixes, self.codes, lp.cols,
                                                               self.fixed)
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
                        tree.put(node)
                        break
                    if isinstance(outcome, tuple) and len(outcome) == 2:  # the same node, one more fix
                        fixes, key = self.codes.copy(), int(lp.cols[outcome[0]])
                        fixes[key], self.pinned[key] = int(outcome[1]), True
                        if self.log is not None:
                            empty_side = self.strong_proofs[(outcome[0], 1 - int(outcome[1]))]
                            self.log.fix_var(node.cid, empty_side, key, int(outcome[1]))
                        node = Node(node.bound, node.seq, fixes, cid=node.cid, worker=worker)
                        tree.hold(worker, node)
                        popped = False
                        continue
                    node = self._children(tree, node.cid, outcome, worker)
                else:
                    if self.log is not None:  # its parent's bound closes it
                        self.open_cids.append(node.cid)
                    node = None
                popped = node is None
                if node is None:
                    node = tree.take(worker, stop, prefer)
                else:
                    tree.hold(worker, node)
                # the global bound: the best open or held node (the incumbent's when none is)
                self.state.raise_bound(min(tree.bound(), self.ub - self.gap))
                self.report()
        except BaseException:
            tree.close()  # the other workers end at their next node
            raise
        finally:
            tree.drop(worker)
        return explored

    def _children(self, tree: OpenNodes, cid: int, outcome: Any, worker: int) -> Node | None:
        """Branch as the node loop's ``outcome`` says (or close the node when it is ``None``): one
        child goes to the open nodes, the other is returned to dive into unless its bound is far
        above the best open one (then both go); both marked as made by ``worker``."""
        if not (isinstance(outcome, tuple) and len(outcome) == 5):
            return None
        lp = self.lp
        bound, col, value, frac, fix = outcome
        base = self.codes.copy()
        base[lp.cols[fix]] = 0
        first, second = (1, 0) if value >= 0.5 else (0, 1)  # dive into ``value``
        key = int(lp.cols[col])
        self.pinned[key] = True
        children = []
        for v in (first, second):
            child = base.copy()
            child[key] = v
            children.append(child)
        seqs = (tree.next_seq(), tree.next_seq())
        best_other = tree.top(bound)
        cids = (0, 0) if self.log is None else (self.log.child(cid, key, first),
                                                self.log.child(cid, key, second))
        tree.put(Node(bound, seqs[1], children[1], (key, second == 1, frac, bound), cids[1], worker))
        node = Node(bound, seqs[0], children[0], (key, first == 1, frac, bound), cids[0], worker)
        if bound > best_other + DIVE_SHARE * (self.ub - best_other):  # no dive: far up
            tree.put(node)
            return None
        return node

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

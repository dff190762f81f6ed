"""``milp-textbook``: the GTSP MILP a user writes by hand, modelled in cvxpy and handed whole to a
MILP solver (HiGHS, or Gurobi when it is installed and licensed for the model's size).

This is the kind of exact baseline the paper's Gurobi column is: one compact model, no cuts, no
pricing, no pruning, the solver's own branch and bound. On the priced
:class:`~gtsp_bench.problem.Problem` (node ``v`` in GTSP cluster ``c(v)``, the depot a cluster of
one node, ``n`` clusters in all):

* ``y_v`` in {0, 1}: node ``v`` is its cluster's head; ``x_uv`` in {0, 1} for every directed arc
  between two nodes of different clusters;
* minimise ``sum_v node_cost_v y_v + sum_uv edge_cost_uv x_uv``;
* ``sum_{v in C} y_v = 1`` for every cluster ``C``; ``sum_u x_uv = sum_u x_vu = y_v`` for every
  node (in-degree = out-degree = ``y_v``);
* subtour elimination over the clusters, on the cluster arcs ``z_cd = sum_{u in c, v in d} x_uv``,
  with a root cluster (the depot's; without a depot, the smallest):

  - ``subtour=mtz`` (Miller-Tucker-Zemlin): an order ``1 <= u_c <= n - 1`` per other cluster and
    ``u_c - u_d + (n - 1) z_cd <= n - 2`` for every pair of other clusters;
  - ``subtour=flow`` (single-commodity flow, Gavish-Graves): the root sends one unit to each other
    cluster along the tour, ``0 <= f_cd <= (n - 1) z_cd``;
  - ``subtour=dfj`` (Dantzig-Fulkerson-Johnson, the paper's constraint): ``sum_{c, d in S} z_cd
    <= |S| - 1`` for every set ``S`` of two or more clusters besides the root, all written out
    (``2^(n-1)`` rows: refused beyond :data:`DFJ_MAX_CLUSTERS` clusters).

MTZ and flow are compact (polynomially many rows); all three have weak LP relaxations, because
they act on the clusters and not on the heads. The root LP bound of each is measured against
``milp``'s in ``docs/solvers/exact.md``. The answer is read off the
rounded ``x`` and ``y``, checked to be one cycle through one node of every cluster (else the solve
is reported ``failed``, never as a wrong tour), and re-priced by the registry as every solver's is.

cvxpy is imported inside :meth:`MilpTextbook.solve` only: importing it costs about a second.
"""

from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from gtsp_bench.checks import check_bool, check_choice, check_int
from gtsp_bench.errors import InputError
from gtsp_bench.instance import Instance
from gtsp_bench.problem import Problem, price
from gtsp_bench.solver import Solution

#: Subtour elimination constraints on offer.
SUBTOURS = ("mtz", "flow", "dfj")
#: Most clusters besides the root for ``subtour=dfj`` (it writes a row per set of them).
DFJ_MAX_CLUSTERS = 14
#: MILP solvers on offer (``auto``: Gurobi when it is installed and takes the model, else HiGHS).
BACKENDS = ("highs", "gurobi", "auto")
#: Absolute gap under which the solver's optimum counts as proven (as ``milp``'s ``abs_gap``).
ABS_GAP = 1e-6
#: A rounded variable must lie this close to 0 or 1.
INT_TOL = 1e-4


@dataclass(frozen=True)
class TextbookModel:
    """The cvxpy model of one priced problem.

    Attributes
    ----------
    problem
        The priced problem.
    tail, head
        ``(A,)`` node ids of each directed arc (``x``'s entries).
    root
        The root cluster of the subtour constraints.
    model
        The ``cvxpy.Problem``.
    x, y
        The arc and node variables.
    """

    problem: Problem
    tail: np.ndarray
    head: np.ndarray
    root: int
    model: Any
    x: Any
    y: Any

    @property
    def n_binaries(self) -> int:
        """Binary variables of the model (``x`` and ``y``)."""
        return len(self.tail) + self.problem.n_nodes


def arcs(problem: Problem) -> tuple[np.ndarray, np.ndarray]:
    """``(tail, head)``: every directed arc between two nodes of different clusters."""
    c = problem.cluster_of
    tail, head = np.nonzero(c[:, None] != c[None, :])
    return tail.astype(np.int64), head.astype(np.int64)


def n_binaries(problem: Problem) -> int:
    """Binary variables the model of ``problem`` has, counted without building it."""
    sizes = np.array([len(c) for c in problem.clusters], dtype=np.int64)
    m = int(sizes.sum())
    return m * (m - 1) - int((sizes * (sizes - 1)).sum()) + m


def root_cluster(problem: Problem) -> int:
    """The depot's cluster, or without a depot the smallest cluster (the first of equals)."""
    if problem.depot is not None:
        return int(problem.cluster_of[problem.depot])
    return int(np.argmin([len(c) for c in problem.clusters]))


def build(problem: Problem, subtour: str = "dfj", *, relax: bool = False) -> TextbookModel:
    """The cvxpy model of ``problem`` (``relax``: its LP relaxation, ``0 <= x, y <= 1``)."""
    import cvxpy as cp

    check_choice("subtour", subtour, SUBTOURS)
    n, m = problem.n_clusters, problem.n_nodes
    if subtour == "dfj" and n - 1 > DFJ_MAX_CLUSTERS:
        raise InputError(f"milp-textbook -p subtour=dfj writes a row per set of clusters: at most "
                         f"{DFJ_MAX_CLUSTERS} besides the root, {problem.instance.name} has {n - 1}; "
                         f"use subtour=mtz or flow")
    tail, head = arcs(problem)
    a = len(tail)
    root = root_cluster(problem)
    cols = np.arange(a)
    ones_a = np.ones(a)
    out_deg = sp.csr_array((ones_a, (tail, cols)), shape=(m, a))
    in_deg = sp.csr_array((ones_a, (head, cols)), shape=(m, a))
    members = sp.csr_array((np.ones(m), (problem.cluster_of, np.arange(m))), shape=(n, m))
    if relax:
        x, y = cp.Variable(a, nonneg=True), cp.Variable(m, nonneg=True)
        rows = [x <= 1, y <= 1]
    else:
        x, y = cp.Variable(a, boolean=True), cp.Variable(m, boolean=True)
        rows = []
    rows += [members @ y == 1, out_deg @ x == y, in_deg @ x == y]
    ct, ch = problem.cluster_of[tail], problem.cluster_of[head]
    pair = ct * n + ch  # the cluster arc (c, d) of each node arc, as c * n + d
    if n > 2:
        if subtour == "mtz":
            others = np.array([c for c in range(n) if c != root])
            cd = np.array([(c, d) for c in others for d in others if c != d])
            index = np.full(n * n, -1)
            index[cd[:, 0] * n + cd[:, 1]] = np.arange(len(cd))
            keep = np.flatnonzero(index[pair] >= 0)
            agg = sp.csr_array((np.ones(len(keep)), (index[pair[keep]], keep)), shape=(len(cd), a))
            slot = np.full(n, -1)
            slot[others] = np.arange(len(others))
            r = np.arange(len(cd))
            diff = sp.csr_array((np.r_[np.ones(len(cd)), -np.ones(len(cd))],
                                 (np.r_[r, r], np.r_[slot[cd[:, 0]], slot[cd[:, 1]]])),
                                shape=(len(cd), len(others)))
            order = cp.Variable(len(others))
            rows += [order >= 1, order <= n - 1, diff @ order + (n - 1) * (agg @ x) <= n - 2]
        elif subtour == "dfj":
            others = np.array([c for c in range(n) if c != root])
            cd = np.array([(i, j) for i in range(n - 1) for j in range(n - 1) if i != j])
            index = np.full(n * n, -1)
            index[others[cd[:, 0]] * n + others[cd[:, 1]]] = np.arange(len(cd))
            keep = np.flatnonzero(index[pair] >= 0)
            agg = sp.csr_array((np.ones(len(keep)), (index[pair[keep]], keep)), shape=(len(cd), a))
            masks = np.arange(1, 1 << (n - 1), dtype=np.int64)
            size = np.array([mask.bit_count() for mask in masks.tolist()])
            masks, size = masks[size >= 2], size[size >= 2]
            inside = ((masks[:, None] >> cd[:, 0]) & (masks[:, None] >> cd[:, 1]) & 1).astype(bool)
            sets = sp.csr_array(inside.astype(np.float64))
            z = cp.Variable(len(cd))  # arcs between clusters, so that a set's row is short
            rows += [z == agg @ x, sets @ z <= size - 1]
        else:
            cd = np.array([(c, d) for c in range(n) for d in range(n) if c != d])
            index = np.full(n * n, -1)
            index[cd[:, 0] * n + cd[:, 1]] = np.arange(len(cd))
            agg = sp.csr_array((ones_a, (index[pair], cols)), shape=(len(cd), a))
            r = np.arange(len(cd))
            balance = sp.csr_array((np.r_[np.ones(len(cd)), -np.ones(len(cd))],
                                    (np.r_[cd[:, 1], cd[:, 0]], np.r_[r, r])), shape=(n, len(cd)))
            others = np.array([c for c in range(n) if c != root])
            flow = cp.Variable(len(cd), nonneg=True)  # each cluster but the root keeps one unit
            rows += [flow <= (n - 1) * (agg @ x), (balance @ flow)[others] == 1]
    cost = problem.node_cost @ y + problem.edge_cost[tail, head] @ x
    return TextbookModel(problem, tail, head, root, cp.Problem(cp.Minimize(cost), rows), x, y)


def extract_tour(tm: TextbookModel) -> np.ndarray | None:
    """The tour of the model's integer solution, the root cluster's node first; ``None`` when
    the values are not integral or do not form one cycle through one node of every cluster."""
    problem = tm.problem
    if tm.x.value is None or tm.y.value is None:
        return None
    xv, yv = np.asarray(tm.x.value, dtype=float), np.asarray(tm.y.value, dtype=float)
    if not (np.isfinite(xv).all() and np.isfinite(yv).all()):
        return None
    if max(np.abs(xv - np.round(xv)).max(initial=0.0), np.abs(yv - np.round(yv)).max()) > INT_TOL:
        return None
    chosen = np.flatnonzero(yv > 0.5)
    if len(chosen) != problem.n_clusters or len(np.unique(problem.cluster_of[chosen])) != len(chosen):
        return None
    used = np.flatnonzero(xv > 0.5)
    tails, heads = tm.tail[used], tm.head[used]
    if len(used) != len(chosen) and len(chosen) > 1:
        return None
    if not (np.isin(tails, chosen).all() and np.isin(heads, chosen).all()):
        return None
    if len(chosen) == 1:
        return chosen
    succ = dict(zip(tails.tolist(), heads.tolist(), strict=True))
    if len(succ) != len(chosen) or len(set(succ.values())) != len(chosen):
        return None
    start = int(chosen[problem.cluster_of[chosen] == tm.root][0])
    tour, v = [start], succ[start]
    while v != start and len(tour) <= len(chosen):
        tour.append(v)
        v = succ[v]
    return np.array(tour, dtype=np.int64) if len(tour) == len(chosen) else None


class MilpTextbook:
    """The textbook GTSP MILP in cvxpy, solved whole by HiGHS or Gurobi.

    Parameters
    ----------
    subtour
        ``"mtz"`` (Miller-Tucker-Zemlin orders over the clusters), ``"flow"`` (single-commodity
        flow over the clusters) or ``"dfj"`` (a subtour row per set of clusters, all written out;
        the default: it proves the most of the three, see ``docs/solvers/exact.md``, but is
        refused beyond :data:`DFJ_MAX_CLUSTERS` clusters besides the root).
    backend
        ``"highs"``, ``"gurobi"`` (gurobipy must be installed and licensed for the model's size)
        or ``"auto"``: Gurobi when that holds, else HiGHS; ``stats["backend"]`` says which ran.
    max_binaries
        Refuse an instance whose model has more binary variables than this.
    threads
        Threads the MILP solver may use.
    verbose
        Print the solver's log.
    """

    def __init__(self, subtour: str = "dfj", backend: str = "auto", max_binaries: int = 200_000,
                 threads: int = 1, verbose: bool = False) -> None:
        self.subtour = check_choice("subtour", subtour, SUBTOURS)
        self.backend = check_choice("backend", backend, BACKENDS)
        self.max_binaries = check_int("max_binaries", max_binaries, 1)
        self.threads = check_int("threads", threads, 1)
        self.verbose = check_bool("verbose", verbose)

    def solve(
        self, instance: Instance, omega: float | None, *, time_limit: float | None = None,
        seed: int = 0,
    ) -> Solution:
        """Solve to proven optimality, or return the best tour and bound at ``time_limit``."""
        start = time.perf_counter()
        problem = price(instance, omega)
        need = n_binaries(problem)
        if need > self.max_binaries:
            raise InputError(f"milp-textbook: {instance.name} needs {need} binary variables, above "
                             f"its limit of {self.max_binaries} (-p max_binaries); use 'milp'")
        if problem.n_clusters == 1:  # no arc at all: the cheapest node is the tour
            tour = np.array([int(np.argmin(problem.node_cost))])
            return self._answer(problem, tour, "optimal", problem.tour_cost(tour), {})
        tm = build(problem, self.subtour)
        stats: dict[str, Any] = {"subtour": self.subtour, "binaries": tm.n_binaries,
                                 "build_s": time.perf_counter() - start}
        left = None if time_limit is None else max(time_limit - (time.perf_counter() - start), 0.01)
        if self.backend in ("gurobi", "auto") and _gurobi_runs(tm, self, left, stats):
            pass
        else:
            _run_highs(tm, self, left, stats)
        stats["total_s"] = time.perf_counter() - start
        bound = stats.get("bound")
        if not stats["has_solution"]:  # dp's convention: greedy with optimal heads, marked as such
            stats["tour"] = "greedy"
            stats["note"] = "time limit: the model found no tour; greedy tour with optimal heads"
            return self._answer(problem, greedy_tour(problem), "time_limit", bound, stats)
        tour = extract_tour(tm)
        if tour is None:
            stats["note"] = "the solver's solution is not one tour through every cluster"
            return Solution((), (), objective=math.inf, status="failed", stats=stats)
        stats["tour"] = "model"
        return self._answer(problem, tour, "optimal" if stats["proven"] else "time_limit", bound, stats)

    @staticmethod
    def _answer(problem: Problem, tour: np.ndarray, status: str, bound: float | None,
                stats: dict[str, Any]) -> Solution:
        order, heads = problem.to_solution(tour)
        cost = problem.tour_cost(tour)
        if status == "optimal" or bound is not None:  # a bound above the tour only proves it
            bound = cost if bound is None else min(bound, cost)
        return Solution(order, heads, objective=cost, status=status, lower_bound=bound, stats=stats)


def greedy_tour(problem: Problem) -> np.ndarray:
    """The greedy order with optimal heads: the answer when the model found no tour in time."""
    from gtsp_bench.solvers.heads import optimal_heads
    from gtsp_bench.solvers.heuristics.greedy import Greedy

    greedy = Greedy().solve(problem.instance, problem.omega)
    return optimal_heads(problem, greedy.order)[0]


def _finite(value: Any) -> float | None:
    try:
        v = float(value)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def _run_highs(tm: TextbookModel, solver: MilpTextbook, left: float | None,
               stats: dict[str, Any]) -> None:
    """Solve with HiGHS through cvxpy; fill ``stats`` (backend, proven, has_solution, bound)."""
    import cvxpy as cp

    opts: dict[str, Any] = {"mip_rel_gap": 0.0, "mip_abs_gap": ABS_GAP, "threads": solver.threads,
                            "random_seed": 0}
    if left is not None:
        opts["time_limit"] = float(left)
    try:
        with warnings.catch_warnings():  # "may be inaccurate" at a time limit: stats say what holds
            warnings.simplefilter("ignore", UserWarning)
            tm.model.solve(solver=cp.HIGHS, verbose=solver.verbose, **opts)
    except cp.error.SolverError as e:
        raise RuntimeError(f"milp-textbook: HiGHS failed: {e}") from None
    if tm.model.status not in (cp.OPTIMAL, cp.USER_LIMIT):
        raise RuntimeError(f"milp-textbook: HiGHS ended with status {tm.model.status}")
    info = tm.model.solver_stats.extra_stats
    stats["backend"] = "highs"
    stats["solver_status"] = tm.model.status
    stats["has_solution"] = bool(getattr(info, "primal_solution_status", 0) == 2)
    stats["proven"] = tm.model.status == cp.OPTIMAL
    stats["bound"] = _finite(getattr(info, "mip_dual_bound", None))
    stats["bb_nodes"] = int(getattr(info, "mip_node_count", 0))
    stats["solve_s"] = tm.model.solver_stats.solve_time


#: Variables and rows Gurobi's size-limited (pip) licence allows.
GUROBI_FREE_SIZE = 2000


def _size_limited(gp: Any, env: Any) -> bool:
    """Whether the Gurobi licence is the size-limited one (it refuses a model just above it)."""
    probe = gp.Model(env=env)
    try:
        probe.addVars(GUROBI_FREE_SIZE + 1)
        probe.optimize()
    except gp.GurobiError as e:
        return "size-limited" in str(e)
    finally:
        probe.dispose()
    return False


def _gurobi_runs(tm: TextbookModel, solver: MilpTextbook, left: float | None,
                 stats: dict[str, Any]) -> bool:
    """Solve with Gurobi through cvxpy when it can; ``False`` (for ``auto``) when gurobipy is
    missing or its licence refuses the model's size. ``backend=gurobi`` raises instead."""
    import cvxpy as cp

    try:
        import gurobipy as gp
    except ImportError:
        if solver.backend == "gurobi":
            raise InputError("milp-textbook -p backend=gurobi needs gurobipy, which is not "
                             "installed: pip install gurobipy (or make install)") from None
        return False
    env = gp.Env(empty=True)
    env.setParam("OutputFlag", int(solver.verbose))
    env.start()
    opts: dict[str, Any] = {"MIPGap": 0.0, "MIPGapAbs": ABS_GAP, "Threads": solver.threads,
                            "Seed": 0, "env": env}
    if left is not None:
        opts["TimeLimit"] = float(left)
    try:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", UserWarning)
                tm.model.solve(solver=cp.GUROBI, verbose=solver.verbose, **opts)
        except (gp.GurobiError, cp.error.SolverError) as e:
            if not _size_limited(gp, env):  # cvxpy hides Gurobi's own message: ask the licence
                raise RuntimeError(f"milp-textbook: Gurobi failed: {e}") from None
            if solver.backend == "gurobi":
                raise InputError(f"milp-textbook: Gurobi's size-limited licence refuses the model "
                                 f"({tm.n_binaries} binary variables); use -p backend=highs") from None
            stats["gurobi"] = "size-limited licence refused the model"
            return False
        model = tm.model.solver_stats.extra_stats
        if model.Status not in (gp.GRB.OPTIMAL, gp.GRB.TIME_LIMIT):
            raise RuntimeError(f"milp-textbook: Gurobi ended with status {model.Status}")
        stats["backend"] = "gurobi"
        stats["solver_status"] = tm.model.status
        stats["has_solution"] = bool(model.SolCount > 0)
        stats["proven"] = tm.model.status == cp.OPTIMAL
        stats["bound"] = _finite(model.ObjBound)
        stats["bb_nodes"] = int(model.NodeCount)
        stats["solve_s"] = model.Runtime
        model.dispose()
        return True
    finally:
        env.dispose()

"""LP/MIP backends: the protocol the search needs, the model held in one, HiGHS and Gurobi.

A backend is a thin wrapper of an LP library that knows nothing of the GTSP (columns in [0, 1]
and rows, numbered in the order added); :class:`LpModel` keeps a
:class:`~gtsp_bench.solvers.exact.mip.model.GtspModel` and its cuts in one. highspy and gurobipy
are imported when a backend is built, never when this module is imported (highspy cannot share a
process with ortools; gurobipy is an optional extra).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np
import scipy.sparse as sp
from gtsp_bench.solvers.exact.mip import flow
from gtsp_bench.solvers.exact.mip.model import TOL, GtspModel
from gtsp_bench.solvers.exact.mip.options import MipOptions
from gtsp_bench.solvers.exact.mip.separation import Cuts

from gtsp_bench.errors import InputError

#: Fewest simplex iterations after which a HiGHS run counts as stalled (see
#: :meth:`HighsBackend.solve_lp`). UAV K = 50, omega 0.9: of 198 LPs that finished, the median took
#: 860 iterations, the slowest 7,309; a stalled one ran 10,000 (10-14 s) and its cold solve 1-2 s.
STALL_ITERATIONS = 5_000
#: ... or this many per row and column, if more.
STALL_PER_LINE = 0.5
#: gurobipy's error code for a model above the size-limited licence.
_SIZE_LIMIT_ERROR = 10010


# ---------------------------------------------------------------------- results and protocols
@dataclass(frozen=True)
class LpResult:
    """An LP solve.

    Attributes
    ----------
    status
        ``"optimal"``, ``"infeasible"``, ``"cutoff"`` (the bound passed the cutoff) or
        ``"stopped"`` (time limit or other).
    objective
        The LP optimum (``inf`` unless optimal).
    values, reduced_costs
        Per backend column; ``None`` unless optimal.
    duals
        Per row; ``None`` unless optimal.
    """

    status: str
    objective: float = math.inf
    values: np.ndarray | None = None
    duals: np.ndarray | None = None
    reduced_costs: np.ndarray | None = None


@dataclass(frozen=True)
class MipResult:
    """A MILP solve under a cutoff.

    Attributes
    ----------
    values
        The best solution found below the cutoff (per backend column), or ``None``.
    bound
        A proven lower bound on every solution below the cutoff.
    complete
        True when the search finished (nothing better than ``values``, up to the gap, exists
        below the cutoff); False when it stopped at the time limit.
    stats
        Backend statistics (nodes, ...), summed over solves by the caller.
    """

    values: np.ndarray | None
    bound: float
    complete: bool
    stats: dict[str, Any] = field(default_factory=dict)


class Backend(Protocol):
    """A thin wrapper of an LP library: what the search needs (HiGHS, Gurobi).

    It starts empty. Columns are bounded in [0, 1] and numbered in the order added; rows are
    numbered in the order added (deleting rows renumbers the later ones). A
    :class:`LazyMipBackend` also solves the MILP itself; for any other,
    :func:`gtsp_bench.solvers.exact.mip.solve.solve_exact` branches, with the backend as LP
    solver.
    """

    def add_cols(self, cost: np.ndarray, entries: sp.csc_array) -> None:
        """Append columns with these costs and coefficients in the current rows."""
        ...

    def add_rows(self, matrix: sp.csr_array, lower: np.ndarray, upper: np.ndarray) -> None:
        """Append rows ``lower <= matrix @ v <= upper`` over the current columns."""
        ...

    def delete_rows(self, rows: np.ndarray) -> None:
        """Delete rows by index."""
        ...

    def delete_cols(self, cols: np.ndarray) -> None:
        """Delete columns by index (later ones are renumbered)."""
        ...

    def set_bounds(self, cols: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> None:
        """Change column bounds."""
        ...

    def basis(self) -> Any:
        """The current basis (opaque), for :meth:`set_basis`."""
        ...

    def set_basis(self, basis: Any) -> None:
        """Start the next solve from ``basis`` (taken since by :meth:`basis` with the same rows
        and columns)."""
        ...

    def start_cold(self) -> None:
        """Solve the next LP that has no iteration limit from no basis (HiGHS: by the interior
        point method, once an LP has stalled), not from the last one: after a jump in the tree it
        is far away."""
        ...

    def use_threads(self, threads: int) -> None:
        """Solve with ``threads`` threads from now on (set before the first solve; the search
        asks it of big models only)."""
        ...

    def solve_lp(self, time_limit: float, cutoff: float = math.inf,
                 iterations: int | None = None) -> LpResult:
        """Solve the LP relaxation; it may stop early once its bound passes ``cutoff``, and
        stops after ``iterations`` simplex iterations if given (status ``"stopped"``; the
        objective, if finite, is the solver's value there: a guide, not a bound)."""
        ...


@runtime_checkable
class LazyMipBackend(Backend, Protocol):
    """A backend whose MILP search takes lazy constraints (Gurobi)."""

    def solve_mip(
        self, time_limit: float, cutoff: float, gap: float,
        lazy: Callable[[np.ndarray], tuple[sp.csr_array, np.ndarray] | None],
    ) -> MipResult:
        """Solve with every column binary, for solutions below ``cutoff``, to absolute ``gap``.

        It calls ``lazy`` on each integer solution and adds the rows ``matrix @ v <= upper`` it
        returns.
        """
        ...


# ---------------------------------------------------------------------- the model in a backend
class LpModel:
    """The GTSP model held in a backend: which model columns it has, and the cuts in it.

    Rows are the model's base rows, then the cuts in the order added (purging deletes some);
    backend column ``k`` is model column ``cols[k]``.

    Parameters
    ----------
    model
        The model.
    backend
        A new, empty backend.
    cols
        The model columns it starts with.
    """

    def __init__(self, model: GtspModel, backend: Backend, cols: np.ndarray) -> None:
        self.model, self.backend = model, backend
        self.cols = np.zeros(0, dtype=np.int64)
        self.cuts = Cuts.empty(model.n_nodes)
        self.slack_age = np.zeros(0, dtype=np.int64)
        self.col_age = np.zeros(0, dtype=np.int64)  # LPs with a large reduced cost (columns.py)
        self.cut_ids = np.zeros(0, dtype=np.int64)  # a number per cut row, never reused
        self._next_id = 0
        base, rhs = model.base_rows(np.zeros(0, dtype=np.int64))
        backend.add_rows(base.tocsr(), rhs, rhs)
        self.add_cols(cols)

    def copy(self, first_id: int) -> LpModel:
        """A copy in a copy of the backend (:meth:`HighsBackend.copy`), its new cuts numbered
        from ``first_id`` on (a tree worker's own range: the proof log keeps a cut by its id)."""
        twin = copy.copy(self)
        twin.backend = self.backend.copy()  # type: ignore[attr-defined]
        for name in ("cols", "slack_age", "col_age", "cut_ids"):
            setattr(twin, name, getattr(self, name).copy())
        twin._next_id = max(self._next_id, first_id)
        return twin

    def add_cols(self, cols: np.ndarray) -> None:
        """Add model columns ``cols`` with their coefficients in the base rows and cuts."""
        base, _ = self.model.base_rows(cols)
        cut_part = self.cuts.sparse(self.model, cols)
        self.backend.add_cols(self.model.cost[cols], sp.vstack([base, cut_part], format="csc"))
        self.cols = np.concatenate([self.cols, cols])
        self.col_age = np.concatenate([self.col_age, np.zeros(len(cols), dtype=np.int64)])

    def add_cuts(self, cuts: Cuts) -> None:
        """Add cut rows over the columns present (each side in its sparser form over them)."""
        cuts = cuts.sparsest(self.model, self.cols)
        matrix = cuts.sparse(self.model, self.cols)
        self.backend.add_rows(matrix, np.full(len(cuts), -np.inf), cuts.rhs)
        self.cuts = Cuts.stack([self.cuts, cuts])
        self.cut_ids = np.concatenate([self.cut_ids, self._next_id + np.arange(len(cuts))])
        self._next_id += len(cuts)
        self.slack_age = np.concatenate([self.slack_age, np.zeros(len(cuts), dtype=np.int64)])

    def purge(self, values: np.ndarray, age: int) -> None:
        """Delete cuts slack at ``values`` for ``age`` rounds in a row."""
        slack = self.cuts.slack(self.model, values) > TOL
        self.slack_age = np.where(slack, self.slack_age + 1, 0)
        old = self.slack_age >= age
        if old.any():
            self.backend.delete_rows(self.model.n_base_rows + np.flatnonzero(old))
            self.cuts, self.slack_age = self.cuts.select(~old), self.slack_age[~old]
            self.cut_ids = self.cut_ids[~old]

    def drop_cols(self, positions: np.ndarray) -> None:
        """Delete backend columns ``positions`` (fixed to 0 or priced out: the search prices every
        model column absent from the LP, so nothing is lost; their nonzeros leave the LP)."""
        if len(positions):
            self.backend.delete_cols(positions)
            self.cols = np.delete(self.cols, positions)
            self.col_age = np.delete(self.col_age, positions)

    def fix_zero(self, positions: np.ndarray) -> None:
        """Fix backend columns to 0."""
        k = len(positions)
        self.backend.set_bounds(positions, np.zeros(k), np.zeros(k))

    def full(self, values: np.ndarray) -> np.ndarray:
        """A backend column vector as a model column vector (absent columns 0)."""
        out = np.zeros(self.model.n_cols)
        out[self.cols] = values
        return out

    def reduced_costs(self, duals: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Reduced costs of model columns ``cols`` for the row duals of an LP solve."""
        model = self.model
        n, m = model.n_nodes, model.n_clusters
        pi_cluster, pi_deg, mu = duals[:m], duals[m:m + n], duals[m + n:]
        is_y = cols < n
        ys, es = cols[is_y], cols[~is_y] - n
        on_edge, on_y = self.cuts.dual_weights(model, mu, es)
        out = np.empty(len(cols))
        out[is_y] = model.cost[ys] - pi_cluster[model.cluster[ys]] + 2 * pi_deg[ys] - on_y[ys]
        out[~is_y] = flow.edge_reduced_costs(es, model.cost[n:], model.tail, model.head, pi_deg,
                                             on_edge)
        return out


# ---------------------------------------------------------------------- HiGHS
#: HiGHS's ``simplex_strategy`` values: its serial dual simplex (the default), its parallel one.
SERIAL_DUAL, PAMI = 1, 2
#: The threads of HiGHS's task scheduler, one per process, as the last run of a backend here left
#: it (``None``: no run yet): a run whose ``threads`` option differs from the scheduler's fails, so
#: a backend on other threads than the last one's restarts it first.
_SCHEDULER: dict[str, int | None] = {"threads": None}


class HighsBackend:
    """A ``highspy.Highs`` object behind the :class:`Backend` protocol.

    It is an LP solver only: highspy has no working lazy constraints, so
    :func:`gtsp_bench.solvers.exact.mip.solve.solve_exact` branches itself (HiGHS's own MILP, re-solved
    after each subtour solution, stalled on instances whose root gap stayed open).
    """

    def __init__(self, options: MipOptions) -> None:
        import highspy

        self._hs = highspy
        self.options = options
        self.h = highspy.Highs()
        self.h.setOptionValue("output_flag", options.verbose)
        self.use_threads(1)
        self.stalls = 0  # runs stopped by the iteration limit and restarted
        self.retries = 0  # runs that ended otherwise than solved, infeasible, cut off or out of time
        self.cold_starts = 0  # LPs solved from no basis by request (:meth:`start_cold`)
        self.iterations = 0  # simplex iterations over all runs
        self._cold = False

    def add_cols(self, cost: np.ndarray, entries: sp.csc_array) -> None:
        """Append [0, 1] columns."""
        k = len(cost)
        e = sp.csc_array(entries)
        e.sort_indices()
        self.h.addCols(k, np.asarray(cost, float), np.zeros(k), np.ones(k), e.nnz,
                       e.indptr[:-1].astype(np.int32), e.indices.astype(np.int32),
                       e.data.astype(np.float64))

    def add_rows(self, matrix: sp.csr_array, lower: np.ndarray, upper: np.ndarray) -> None:
        """Append rows."""
        a = sp.csr_array(matrix)
        a.eliminate_zeros()
        a.sort_indices()
        self.h.addRows(a.shape[0], np.asarray(lower, float), np.asarray(upper, float), a.nnz,
                       a.indptr[:-1].astype(np.int32), a.indices.astype(np.int32),
                       a.data.astype(np.float64))

    def delete_rows(self, rows: np.ndarray) -> None:
        """Delete rows by index."""
        self.h.deleteRows(len(rows), np.asarray(rows, dtype=np.int32))

    def delete_cols(self, cols: np.ndarray) -> None:
        """Delete columns by index."""
        self.h.deleteCols(len(cols), np.asarray(cols, dtype=np.int32))

    def set_bounds(self, cols: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> None:
        """Change column bounds."""
        self.h.changeColsBounds(len(cols), np.asarray(cols, dtype=np.int32),
                                np.asarray(lower, float), np.asarray(upper, float))

    def copy(self) -> HighsBackend:
        """A new backend holding the same LP, its basis and options (its counters at 0)."""
        twin = type(self)(self.options)
        twin.h.passModel(self.h.getLp())
        twin.h.setBasis(self.h.getBasis())
        twin.use_threads(self.threads)
        return twin

    def absorb(self, other: HighsBackend) -> None:
        """Add the counters of ``other`` (a copy that has done its work) to this one's."""
        self.stalls += other.stalls
        self.retries += other.retries
        self.cold_starts += other.cold_starts
        self.iterations += other.iterations

    def use_threads(self, threads: int) -> None:
        """From 2 threads, the LPs by HiGHS's parallel dual simplex (PAMI) on that many; on 1,
        its serial dual simplex."""
        self.threads = threads
        self.h.setOptionValue("threads", threads)
        self.h.setOptionValue("simplex_strategy", PAMI if threads > 1 else SERIAL_DUAL)
        self._scheduler()

    def _scheduler(self) -> None:
        """Restart HiGHS's task scheduler (one per process) on this backend's threads if the last
        run left it on others: a run on other threads than the scheduler's fails. Tree workers
        change threads before they start, never while another backend runs."""
        if _SCHEDULER["threads"] != self.threads:
            self._hs.Highs.resetGlobalScheduler(True)
            _SCHEDULER["threads"] = self.threads

    def basis(self) -> Any:
        """The current ``HighsBasis``."""
        return self.h.getBasis()

    def set_basis(self, basis: Any) -> None:
        """Start the next solve from ``basis``."""
        self.h.setBasis(basis)

    def start_cold(self) -> None:
        """Solve the next LP without iteration limit by the interior point method, from no basis,
        once a run has stalled (:meth:`solve_lp`) in this object: where none does (GTSPLIB up to
        442 nodes) the dual simplex from the last basis is fast, and other starting bases change
        the search (31pr152 took 65 s instead of 13 s)."""
        self._cold = self.stalls > 0

    def _set_time_limit(self, seconds: float) -> None:
        # HiGHS compares time_limit with the object's run time summed over all its runs
        self.h.setOptionValue("time_limit", self.h.getRunTime() + float(seconds))

    def _run(self, iteration_limit: int) -> Any:
        self._scheduler()  # HiGHS's threads are one pool per process
        self.h.setOptionValue("simplex_iteration_limit", int(iteration_limit))
        self.h.run()
        self.iterations += self.h.getInfo().simplex_iteration_count
        return self.h.getModelStatus()

    def _interior(self) -> Any:
        """Solve from no basis by the interior point method and crossover; HiGHS's choice after."""
        self.h.clearSolver()
        self.h.setOptionValue("solver", "ipm")
        try:
            return self._run(2**31 - 1)
        finally:
            self.h.setOptionValue("solver", "choose")

    def dual_ray(self) -> np.ndarray | None:
        """After an infeasible LP: a Farkas ray over the rows (``w`` with ``b'w + sum_j min(-a_j'w
        l_j, -a_j'w u_j) > 0``), or ``None`` when HiGHS has none."""
        _, has, ray = self.h.getDualRay()
        return np.array(ray) if has else None

    def solve_lp(self, time_limit: float, cutoff: float = np.inf,
                 iterations: int | None = None) -> LpResult:
        """Solve the LP relaxation (from the previous basis); stopped after ``iterations`` simplex
        iterations if given (status ``"stopped"``, objective the dual simplex's value there).

        A run that takes more than :data:`STALL_ITERATIONS` (or :data:`STALL_PER_LINE` per row and
        column) simplex iterations is stopped and solved from no basis by the interior point method
        with crossover (which leaves an optimal basis for the next warm start). At UAV K = 50 a
        hot-started branch-and-cut LP ran 245,000 iterations (490 s) where the same LP and basis read
        from files took 4,600 (3 s); some stalled from their start basis too, with HiGHS's state
        cleared, and took 14,000-17,500 dual simplex iterations (24-31 s) from no basis, 1-2 s by the
        interior point method. After :meth:`start_cold` the next such solve goes to the interior point
        method at once.
        """
        self._set_time_limit(time_limit)
        self.h.setOptionValue("objective_bound", float(cutoff))
        limit = int(max(STALL_ITERATIONS, STALL_PER_LINE * (self.h.getNumRow() + self.h.getNumCol())))
        if iterations is not None:
            limit = min(limit, iterations)
        stopped = self._hs.HighsModelStatus.kIterationLimit
        if self._cold and iterations is None:
            self._cold = False
            self.cold_starts += 1
            status = self._interior()
        else:
            status = self._run(limit)
            if status == stopped and iterations is not None and iterations <= limit:
                return LpResult("stopped", self.h.getInfo().objective_function_value)
            if status == stopped:
                self.stalls += 1
                status = self._interior()
        done = (self._hs.HighsModelStatus.kOptimal, self._hs.HighsModelStatus.kInfeasible,
                self._hs.HighsModelStatus.kObjectiveBound, self._hs.HighsModelStatus.kTimeLimit)
        if status not in done and iterations is None:  # (seen once at K = 50): again from no basis
            self.retries += 1
            self.h.clearSolver()
            self.h.setBasis()
            status = self._run(2**31 - 1)
        if status == self._hs.HighsModelStatus.kInfeasible:
            return LpResult("infeasible")
        if status == self._hs.HighsModelStatus.kObjectiveBound:
            return LpResult("cutoff")
        if status != self._hs.HighsModelStatus.kOptimal:
            return LpResult("stopped")
        sol = self.h.getSolution()
        return LpResult("optimal", self.h.getInfo().objective_function_value,
                        np.array(sol.col_value), np.array(sol.row_dual), np.array(sol.col_dual))


# ---------------------------------------------------------------------- Gurobi
def import_gurobipy() -> Any:
    """The gurobipy module, imported now.

    Raises
    ------
    InputError
        If gurobipy is not installed (the message says how to install it).
    """
    try:
        import gurobipy
    except ImportError:
        raise InputError("solver 'gurobi' needs gurobipy, which is not installed: "
                         "pip install gurobipy (or make install)") from None
    return gurobipy


class GurobiBackend:
    """A gurobipy model behind the :class:`LazyMipBackend` protocol."""

    def __init__(self, options: MipOptions) -> None:
        gp = self.gp = import_gurobipy()
        self.env = gp.Env(empty=True)
        self.env.setParam("OutputFlag", int(options.verbose))
        self.env.start()
        self.m = gp.Model(env=self.env)
        self.m.Params.Threads = 1
        self.vars: list[Any] = []
        self.rows: list[Any] = []

    def use_threads(self, threads: int) -> None:
        """Gurobi's ``Threads``."""
        self.m.Params.Threads = threads

    def add_cols(self, cost: np.ndarray, entries: sp.csc_array) -> None:
        """Append [0, 1] columns."""
        gp = self.gp
        e = sp.csc_array(entries)
        for j, c in enumerate(cost):
            lo, hi = e.indptr[j], e.indptr[j + 1]
            column = gp.Column(e.data[lo:hi].tolist(), [self.rows[i] for i in e.indices[lo:hi]])
            self.vars.append(self.m.addVar(lb=0.0, ub=1.0, obj=float(c), column=column))

    def add_rows(self, matrix: sp.csr_array, lower: np.ndarray, upper: np.ndarray) -> None:
        """Append rows (equalities or ``<=`` rows)."""
        a = sp.csr_array(matrix)
        for i in range(a.shape[0]):
            lo, hi = a.indptr[i], a.indptr[i + 1]
            expr = self.gp.LinExpr(a.data[lo:hi].tolist(), [self.vars[j] for j in a.indices[lo:hi]])
            if lower[i] == upper[i]:
                self.rows.append(self.m.addLConstr(expr, "=", float(upper[i])))
            else:
                self.rows.append(self.m.addLConstr(expr, "<", float(upper[i])))

    def delete_rows(self, rows: np.ndarray) -> None:
        """Delete rows by index."""
        gone = set(int(r) for r in rows)
        self.m.remove([self.rows[r] for r in gone])
        self.rows = [c for i, c in enumerate(self.rows) if i not in gone]

    def delete_cols(self, cols: np.ndarray) -> None:
        """Delete columns by index."""
        gone = set(int(c) for c in cols)
        self.m.remove([self.vars[c] for c in gone])
        self.vars = [v for i, v in enumerate(self.vars) if i not in gone]

    def set_bounds(self, cols: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> None:
        """Change column bounds."""
        vs = [self.vars[c] for c in cols]
        self.m.setAttr("LB", vs, [float(v) for v in lower])
        self.m.setAttr("UB", vs, [float(v) for v in upper])

    def basis(self) -> Any:
        """Nothing: Gurobi starts from its last basis itself (and solves the MILP itself)."""
        return None

    def set_basis(self, basis: Any) -> None:
        """Nothing (see :meth:`basis`)."""

    def start_cold(self) -> None:
        """Nothing (Gurobi chooses its own start; it solves the MILP itself)."""

    def _optimize(self, callback: Callable[..., None] | None = None) -> None:
        try:
            self.m.optimize(callback)
        except self.gp.GurobiError as e:
            if e.errno == _SIZE_LIMIT_ERROR:
                raise InputError(
                    f"the model ({len(self.vars)} variables, {len(self.rows)} rows) is too large "
                    "for Gurobi's size-limited licence (2000 each); use 'milp'") from None
            raise

    def solve_lp(self, time_limit: float, cutoff: float = np.inf,
                 iterations: int | None = None) -> LpResult:
        """Solve the LP relaxation (at most ``iterations`` simplex iterations if given)."""
        grb = self.gp.GRB
        self.m.Params.TimeLimit = min(max(time_limit, 0.0), 1e100)  # left() may be just below 0
        self.m.Params.IterationLimit = grb.INFINITY if iterations is None else float(iterations)
        self.m.Params.Cutoff = cutoff if np.isfinite(cutoff) else grb.INFINITY
        self._optimize()
        status = self.m.Status
        if status == grb.INFEASIBLE:
            return LpResult("infeasible")
        if status == grb.CUTOFF:
            return LpResult("cutoff")
        if status != grb.OPTIMAL:
            return LpResult("stopped")
        return LpResult("optimal", self.m.ObjVal, np.array(self.m.getAttr("X", self.vars)),
                        np.array(self.m.getAttr("Pi", self.rows)),
                        np.array(self.m.getAttr("RC", self.vars)))

    def solve_mip(
        self, time_limit: float, cutoff: float, gap: float,
        lazy: Callable[[np.ndarray], tuple[sp.csr_array, np.ndarray] | None],
    ) -> MipResult:
        """Solve the MILP below ``cutoff``, adding ``lazy``'s rows at each integer solution."""
        gp, grb, m = self.gp, self.gp.GRB, self.m
        m.setAttr("VType", self.vars, [grb.BINARY] * len(self.vars))
        m.Params.TimeLimit = min(max(time_limit, 0.0), 1e100)  # left() may be just below 0
        m.Params.Cutoff = cutoff
        m.Params.MIPGap = 0.0
        m.Params.MIPGapAbs = gap
        m.Params.LazyConstraints = 1

        def callback(model: Any, where: int) -> None:
            if where != grb.Callback.MIPSOL:
                return
            rows = lazy(np.array(model.cbGetSolution(self.vars)))
            if rows is None:
                return
            a, rhs = sp.csr_array(rows[0]), rows[1]
            for i in range(a.shape[0]):
                lo, hi = a.indptr[i], a.indptr[i + 1]
                model.cbLazy(gp.LinExpr(a.data[lo:hi].tolist(),
                                        [self.vars[j] for j in a.indices[lo:hi]]) <= float(rhs[i]))

        self._optimize(callback)
        stats = {"mip_nodes": int(m.NodeCount)}
        status = m.Status
        values = np.array(m.getAttr("X", self.vars)) if m.SolCount > 0 else None
        if status == grb.OPTIMAL:
            return MipResult(values, m.ObjBound, True, stats)
        if status in (grb.INFEASIBLE, grb.CUTOFF):  # nothing below the cutoff
            return MipResult(None, cutoff, True, stats)
        if status in (grb.TIME_LIMIT, grb.INTERRUPTED):
            return MipResult(values, m.ObjBound, False, stats)
        raise RuntimeError(f"Gurobi stopped with status {status}")


"""``gurobi``: the GTSP MILP of :mod:`gtsp_bench.solvers.exact.gtsp_mip` solved exactly with
Gurobi (gurobipy).

The model, the root loop (pricing, cuts, reduced-cost fixing) and the separation are the ones
``milp`` uses; only the LP/MIP calls differ. Gurobi has lazy constraints, so after the root it
solves the MILP itself and adds subtour rows from a ``MIPSOL`` callback.

gurobipy is an optional extra (``pip install gurobipy``, installed by ``make install``); its
free licence is limited to 2000 variables and 2000 rows, which covers small instances only (a
larger model is refused with a clear error). Without gurobipy, building the solver fails with a
clear error.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.sparse as sp
from gtsp_bench.solvers.exact.gtsp_mip import LpResult, MipOptions, MipResult, MipSolver

from gtsp_bench.errors import InputError

#: gurobipy's error code for a model above the size-limited licence.
_SIZE_LIMIT_ERROR = 10010


def import_gurobipy() -> Any:
    """gurobipy, or :class:`InputError` saying how to install it."""
    try:
        import gurobipy
    except ImportError:
        raise InputError("solver 'gurobi' needs gurobipy, which is not installed: "
                         "pip install gurobipy (or make install)") from None
    return gurobipy


class GurobiBackend:
    """A gurobipy model behind the :class:`gtsp_bench.solvers.exact.gtsp_mip.LazyMipBackend` protocol."""

    def __init__(self, options: MipOptions) -> None:
        gp = self.gp = import_gurobipy()
        self.env = gp.Env(empty=True)
        self.env.setParam("OutputFlag", int(options.verbose))
        self.env.start()
        self.m = gp.Model(env=self.env)
        self.m.Params.Threads = 1
        self.vars: list[Any] = []
        self.rows: list[Any] = []

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

    def set_bounds(self, cols: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> None:
        """Change column bounds."""
        vs = [self.vars[c] for c in cols]
        self.m.setAttr("LB", vs, [float(v) for v in lower])
        self.m.setAttr("UB", vs, [float(v) for v in upper])

    def _optimize(self, callback: Callable[..., None] | None = None) -> None:
        try:
            self.m.optimize(callback)
        except self.gp.GurobiError as e:
            if e.errno == _SIZE_LIMIT_ERROR:
                raise InputError(
                    f"the model ({len(self.vars)} variables, {len(self.rows)} rows) is too large "
                    "for Gurobi's size-limited licence (2000 each); use 'milp'") from None
            raise

    def solve_lp(self, time_limit: float, cutoff: float = np.inf) -> LpResult:
        """Solve the LP relaxation."""
        grb = self.gp.GRB
        self.m.Params.TimeLimit = min(max(time_limit, 0.0), 1e100)  # left() may be just below 0
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


class Gurobi(MipSolver):
    """Exact GTSP by MILP with Gurobi (options: :class:`gtsp_bench.solvers.exact.gtsp_mip.MipSolver`).

    Raises :class:`InputError` at once when gurobipy is not installed.
    """

    def __init__(self, prune: bool = True, lns_trials: int = 1, root_rounds: int = 200,
                 core_edges: int = 10, abs_gap: float = 1e-6, verbose: bool = False) -> None:
        import_gurobipy()
        super().__init__(prune, lns_trials, root_rounds, core_edges, abs_gap, verbose)

    def backend(self, options: MipOptions) -> GurobiBackend:
        """A new, empty Gurobi backend."""
        return GurobiBackend(options)

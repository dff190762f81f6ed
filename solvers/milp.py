"""``milp``: the GTSP MILP of :mod:`solvers.gtsp_mip` solved exactly with HiGHS (highspy).

highspy 1.15.1 has no working lazy-constraint callback, so subtour rows are added in the root LP
loop and, when the MILP's solution still has subtours, by solving it again with their rows. The
heuristic's tour value is passed as a cutoff (``objective_bound``), not as a MIP start (a start
made HiGHS restart and run slower). ``mip_rel_gap`` is 0: "optimal" means proven.

highspy is imported inside :meth:`Milp.solve` only (it cannot share a process with ortools).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.sparse as sp

from solvers.gtsp_mip import LpResult, MipOptions, MipResult, MipSolver


class HighsBackend:
    """A ``highspy.Highs`` object behind the :class:`solvers.gtsp_mip.Backend` protocol.

    It has no lazy constraints: :func:`solvers.gtsp_mip.solve_exact` branches itself and uses
    HiGHS as LP solver (HiGHS's own MIP, re-solved after each subtour solution, stalled on
    instances whose root gap was not closed).
    """

    lazy_constraints = False

    def __init__(self, options: MipOptions) -> None:
        import highspy

        self._hs = highspy
        self.h = highspy.Highs()
        self.h.setOptionValue("output_flag", options.verbose)
        self._integral = False

    @property
    def n_cols(self) -> int:
        """Number of columns."""
        return self.h.getNumCol()

    def add_cols(self, cost: np.ndarray, entries: sp.csc_array) -> None:
        """Append [0, 1] columns."""
        k = len(cost)
        e = sp.csc_array(entries)
        e.sort_indices()
        self.h.addCols(k, np.asarray(cost, float), np.zeros(k), np.ones(k), e.nnz,
                       e.indptr[:-1].astype(np.int32), e.indices.astype(np.int32),
                       e.data.astype(np.float64))
        if self._integral:
            self._set_integral(True, np.arange(self.n_cols - k, self.n_cols))

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

    def set_bounds(self, cols: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> None:
        """Change column bounds."""
        self.h.changeColsBounds(len(cols), np.asarray(cols, dtype=np.int32),
                                np.asarray(lower, float), np.asarray(upper, float))

    def _set_time_limit(self, seconds: float) -> None:
        # HiGHS compares time_limit with the object's run time summed over all its runs
        self.h.setOptionValue("time_limit", self.h.getRunTime() + float(seconds))

    def _set_integral(self, integral: bool, cols: np.ndarray | None = None) -> None:
        self._integral = integral
        cols = np.arange(self.n_cols) if cols is None else cols
        kind = self._hs.HighsVarType.kInteger if integral else self._hs.HighsVarType.kContinuous
        self.h.changeColsIntegrality(len(cols), cols.astype(np.int32),
                                     np.full(len(cols), int(kind), dtype=np.uint8))

    def solve_lp(self, time_limit: float, cutoff: float = np.inf) -> LpResult:
        """Solve the LP relaxation (from the previous basis)."""
        if self._integral:
            self._set_integral(False)
        self._set_time_limit(time_limit)
        self.h.setOptionValue("objective_bound", float(cutoff))
        self.h.run()
        status = self.h.getModelStatus()
        if status == self._hs.HighsModelStatus.kInfeasible:
            return LpResult("infeasible")
        if status == self._hs.HighsModelStatus.kObjectiveBound:
            return LpResult("cutoff")
        if status != self._hs.HighsModelStatus.kOptimal:
            return LpResult("stopped")
        sol = self.h.getSolution()
        return LpResult("optimal", self.h.getInfo().objective_function_value,
                        np.array(sol.col_value), np.array(sol.row_dual), np.array(sol.col_dual))

    def solve_mip(
        self, time_limit: float, cutoff: float, gap: float,
        lazy: Callable[[np.ndarray], Any],
    ) -> MipResult:
        """Solve the MILP below ``cutoff`` (``lazy`` is not used: no lazy constraints)."""
        status_of = self._hs.HighsModelStatus
        h = self.h
        if not self._integral:
            self._set_integral(True)
        self._set_time_limit(time_limit)
        h.setOptionValue("objective_bound", float(cutoff))
        h.setOptionValue("mip_rel_gap", 0.0)
        h.setOptionValue("mip_abs_gap", float(gap))
        h.run()
        status = h.getModelStatus()
        info = h.getInfo()
        stats: dict[str, Any] = {"mip_nodes": int(info.mip_node_count)}
        values = None
        if info.primal_solution_status == 2:  # kSolutionStatusFeasible
            values = np.array(h.getSolution().col_value)
        if status == status_of.kOptimal:
            return MipResult(values, info.mip_dual_bound, True, stats)
        if status == status_of.kInfeasible:  # nothing below the cutoff
            return MipResult(None, cutoff, True, stats)
        if status in (status_of.kTimeLimit, status_of.kInterrupt):
            return MipResult(values, info.mip_dual_bound, False, stats)
        raise RuntimeError(f"HiGHS stopped with status {h.modelStatusToString(status)}")


class Milp(MipSolver):
    """Exact GTSP by MILP with HiGHS (options: :class:`solvers.gtsp_mip.MipSolver`)."""

    def backend(self, options: MipOptions) -> HighsBackend:
        """A new, empty HiGHS backend."""
        return HighsBackend(options)

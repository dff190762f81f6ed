"""``milp``: the GTSP MILP of :mod:`gtsp_bench.solvers.exact.gtsp_mip` solved exactly, with HiGHS
as LP solver.

highspy 1.15.1 has no working lazy-constraint callback (it exists but never fires, and its input
cannot add rows), and HiGHS's own MILP, re-solved after each solution with subtours, stalled on
instances whose root gap stayed open. So HiGHS solves LPs only: the root loop and the branch and
cut of :func:`gtsp_bench.solvers.exact.gtsp_mip.solve_exact` add the cuts, price the columns and
branch. "optimal"
means proven to ``abs_gap`` (1e-6; with integer costs, to below 1).

highspy is imported when a backend is built only (it cannot share a process with ortools).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from gtsp_bench.solvers.exact.gtsp_mip import LpResult, MipOptions, MipSolver


class HighsBackend:
    """A ``highspy.Highs`` object behind the :class:`gtsp_bench.solvers.exact.gtsp_mip.Backend` protocol.

    It is an LP solver only: highspy has no working lazy constraints, so
    :func:`gtsp_bench.solvers.exact.gtsp_mip.solve_exact` branches itself (HiGHS's own MILP, re-solved
    after each subtour solution, stalled on instances whose root gap stayed open).
    """

    def __init__(self, options: MipOptions) -> None:
        import highspy

        self._hs = highspy
        self.h = highspy.Highs()
        self.h.setOptionValue("output_flag", options.verbose)

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

    def set_bounds(self, cols: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> None:
        """Change column bounds."""
        self.h.changeColsBounds(len(cols), np.asarray(cols, dtype=np.int32),
                                np.asarray(lower, float), np.asarray(upper, float))

    def _set_time_limit(self, seconds: float) -> None:
        # HiGHS compares time_limit with the object's run time summed over all its runs
        self.h.setOptionValue("time_limit", self.h.getRunTime() + float(seconds))

    def solve_lp(self, time_limit: float, cutoff: float = np.inf) -> LpResult:
        """Solve the LP relaxation (from the previous basis)."""
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


class Milp(MipSolver):
    """Exact GTSP by MILP with HiGHS (options: :class:`gtsp_bench.solvers.exact.gtsp_mip.MipSolver`)."""

    def backend(self, options: MipOptions) -> HighsBackend:
        """A new, empty HiGHS backend."""
        return HighsBackend(options)

"""``milp``: the GTSP MILP of :mod:`gtsp_bench.solvers.exact.mip` solved exactly, with HiGHS
as LP solver.

highspy 1.15.1 has no working lazy-constraint callback (it exists but never fires, and its input
cannot add rows), and HiGHS's own MILP, re-solved after each solution with subtours, stalled on
instances whose root gap stayed open. So HiGHS solves LPs only: the root loop and the branch and
cut of :func:`gtsp_bench.solvers.exact.mip.solve.solve_exact` add the cuts, price the columns
and branch. "optimal" means proven to ``abs_gap`` (1e-6; with integer costs, to below 1).

highspy is imported when a backend is built only (it cannot share a process with ortools); the
backend is :class:`gtsp_bench.solvers.exact.mip.backends.HighsBackend`.
"""

from __future__ import annotations

from gtsp_bench.solvers.exact.mip.backends import HighsBackend
from gtsp_bench.solvers.exact.mip.options import MipOptions
from gtsp_bench.solvers.exact.mip.solve import MipSolver


class Milp(MipSolver):
    """Exact GTSP by MILP with HiGHS (options: :class:`gtsp_bench.solvers.exact.mip.solve.MipSolver`)."""

    def backend(self, options: MipOptions) -> HighsBackend:
        """A new, empty HiGHS backend."""
        return HighsBackend(options)

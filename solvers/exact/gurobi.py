"""``gurobi``: the GTSP MILP of :mod:`gtsp_bench.solvers.exact.mip` solved exactly with
Gurobi (gurobipy).

The model, the root loop (pricing, cuts, reduced-cost fixing) and the separation are the ones
``milp`` uses; only the LP/MIP calls differ
(:class:`gtsp_bench.solvers.exact.mip.backends.GurobiBackend`). Gurobi has lazy constraints, so
after the root it solves the MILP itself and adds subtour rows from a ``MIPSOL`` callback.

gurobipy is an optional extra (``pip install gurobipy``, installed by ``make install``); its
free licence is limited to 2000 variables and 2000 rows, which covers small instances only (a
larger model is refused with a clear error). Without gurobipy, building the solver fails with a
clear error.
"""

from __future__ import annotations

from gtsp_bench.solvers.exact.mip.backends import GurobiBackend, import_gurobipy
from gtsp_bench.solvers.exact.mip.options import MipOptions
from gtsp_bench.solvers.exact.mip.solve import MipSolver


class Gurobi(MipSolver):
    """Exact GTSP by MILP with Gurobi (options: :class:`gtsp_bench.solvers.exact.mip.solve.MipSolver`).

    Raises :class:`InputError` at once when gurobipy is not installed.
    """

    def __init__(self, prune: bool = True, lns_trials: int = 1, root_rounds: int = 200,
                 core_edges: int = 10, abs_gap: float = 1e-6, verbose: bool = False,
                 certificate: str | None = None, threads: int | None = None,
                 branching: str = "auto", workers: int | None = None) -> None:
        import_gurobipy()
        # (a certificate is refused at the solve: Gurobi's own search logs no proof; after the
        # root Gurobi branches itself, so ``branching`` and ``workers`` are checked but not used)
        super().__init__(prune, lns_trials, root_rounds, core_edges, abs_gap, verbose, certificate,
                         threads, branching, workers)

    def backend(self, options: MipOptions) -> GurobiBackend:
        """A new, empty Gurobi backend."""
        return GurobiBackend(options)

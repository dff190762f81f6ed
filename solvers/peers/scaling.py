"""Integer arc costs for the peer solvers whose libraries take integer matrices (PyVRP, OR-Tools).

Node costs are folded into the edges, half of each end's node cost on every edge (a closed tour uses
two edges at every node, so its folded length is exactly its cost; the matrix stays symmetric). The
folded costs are used as they are when they are all whole numbers of at most :data:`MAX_EXACT`
(GTSPLIB), else scaled so that the largest is about ``resolution`` units and rounded. A tour of
K + 1 edges then stays below :data:`MAX_TOUR_UNITS`, far inside int64, or the costs are refused
with a one-line :class:`~gtsp_bench.errors.InputError`: costs that are not finite, a scale that is
not finite (a subnormal largest cost, whose tours could not be told apart), or sums that could wrap.

The last case is out of reach of the instances this project accepts: the largest scaled cost is
at most 2^40 (whole numbers up to :data:`MAX_EXACT`, or ``resolution`` <= 2^40), so (K + 1) of them
stay below 2^60 for K < 2^20 clusters (GTSPLIB's largest has 17,180), and the loader's bound on a
tour's cost (:data:`gtsp_bench.checks.MAX_TOUR_COST`, 2^53) keeps far-apart coordinates (up to
:data:`gtsp_bench.checks.MAX_COORD`) well inside it too.

Scaling does round: arcs are kept to about 1 / ``resolution`` of the largest one, so tours whose
costs differ by less than K + 1 such units may be ranked wrongly inside the library (the answer is
re-priced exactly; on GTSPLIB, whole numbers, nothing is rounded).
"""

from __future__ import annotations

import math

import numpy as np

from gtsp_bench.errors import InputError
from gtsp_bench.problem import Problem

#: Integer scale target: the largest folded edge cost becomes about this many units.
RESOLUTION = 1e7
#: Largest cost that is used as is when all folded costs are whole numbers.
MAX_EXACT = 2**40
#: Largest scaled cost of a whole tour: the libraries add int64 costs, so this leaves room for
#: their sums (OR-Tools' guided local search adds penalties on top, with saturating arithmetic).
MAX_TOUR_UNITS = 2**60


def folded_costs(
    problem: Problem, resolution: float = RESOLUTION, *, solver: str, library: str
) -> tuple[np.ndarray, float]:
    """Integer edge costs with the node costs folded in, and the scale used.

    ``out[i, j] = round(scale * (edge(i, j) + (node(i) + node(j)) / 2))`` off the diagonal, 0 on it.

    Parameters
    ----------
    problem
        The priced GTSP.
    resolution
        The largest folded cost becomes about this many units (unless all are whole numbers).
    solver, library
        The solver's registered name and the library's name, for the error messages.

    Raises
    ------
    InputError
        One line: costs that are not finite, or whose scaling would overflow the library's sums.
    """
    with np.errstate(over="ignore", invalid="ignore"):
        cost = problem.edge_cost + 0.5 * (problem.node_cost[:, None] + problem.node_cost[None, :])
    np.fill_diagonal(cost, 0.0)
    if not np.all(np.isfinite(cost)):
        raise InputError(f"{solver}: {problem.instance.name} has costs that are not finite numbers; "
                         f"they cannot be scaled to integers")
    top = float(np.abs(cost).max()) if cost.size else 0.0
    if np.all(cost == np.round(cost)) and top <= MAX_EXACT:
        scale = 1.0
    else:
        scale = resolution / top if top > 0 else 1.0
    if not math.isfinite(scale):  # a subnormal largest cost: no unit is small enough
        raise InputError(f"{solver}: the costs of {problem.instance.name} (up to {top:.6g}) are too "
                         f"small to scale to integers that tell tours apart; use another solver")
    # A tour sums K + 1 edges: its scaled cost must stay far inside int64, or the sums wrap.
    if not (problem.n_clusters + 1) * top * scale <= MAX_TOUR_UNITS:
        owner = library + ("'" if library.endswith("s") else "'s")
        raise InputError(f"{solver}: the costs of {problem.instance.name} (up to {top:.6g}) scaled to "
                         f"integers would overflow {owner} 64-bit sums; use another solver")
    return np.round(cost * scale).astype(np.int64), scale

"""The open nodes of the branch and cut: their bound, column fixes and the branching that made them.

A node's column fixes are per model column (-1 free, else the value the column is fixed to), so
that columns leaving and joining the LP leave them unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(order=True)
class Node:
    """An open branch-and-cut node (ordered by bound, then by ``seq``).

    Attributes
    ----------
    bound
        Its parent's LP bound.
    seq
        Creation order (ties).
    fixes
        Per model column, -1 (free) or the value it is fixed to.
    branched
        The branching that made it (model column, up, the column's LP value and the LP bound in
        the parent), for the pseudo-costs.
    cid
        Its number in the search's proof log (0 without one).
    worker
        The tree worker that made it (:meth:`~gtsp_bench.solvers.exact.mip.workers.OpenNodes.take`
        gives a worker its own nodes first while their bounds are near the best).
    """

    bound: float
    seq: int
    fixes: np.ndarray = field(compare=False)
    branched: tuple[int, bool, float, float] | None = field(default=None, compare=False)
    cid: int = field(default=0, compare=False)
    worker: int = field(default=0, compare=False)

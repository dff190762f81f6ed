"""Columns leaving the branch and cut's LP: those whose reduced cost has stayed large.

Columns priced into the LP stayed there for the rest of the search (only those fixed to 0 by
reduced cost for the whole search left it), so every LP grew with the search. A column whose
reduced cost has been above :data:`DROP_SHARE` of the node's gap (incumbent minus LP value) for
:data:`DROP_AGE` rounds of a node's cut loop in a row (ages go on across nodes) leaves the LP.
Nothing is lost: the search prices every column absent from the LP (and not fixed to 0 at the
node) at every node LP before it uses the LP's value as a bound, so a dropped column comes back
as soon as its reduced cost is negative. Columns that have been branched on are never dropped (a
node fixing one must find it in the LP). A column's reduced cost is positive only while it is
nonbasic at 0, so dropping it leaves the LP's basis valid.

The nodes' column codes (-1 free, else the value a column is fixed to) are kept per model column,
so that dropping and adding LP columns leaves every open node's fixes unchanged.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from gtsp_bench.solvers.exact.mip.backends import LpModel

#: Rounds of the node cut loop in a row with a large reduced cost after which a column leaves the
#: LP (0: never). UAV K = 50, omega 0.9: node LPs of a median 5,400 columns instead of 7,600.
DROP_AGE = 3
#: A reduced cost counts as large above this share of the node's gap (incumbent minus LP value).
DROP_SHARE = 1.0
#: At a root of at least ``ROOT_DROP_NODES`` model nodes, an edge column leaves the LP once its
#: reduced cost stayed above ``ROOT_DROP_SHARE`` of the gap for ``ROOT_DROP_AGE`` rounds in a row.
#: At UAV K = 200 (3,660-3,840 nodes) the root never finishes in 600 s, and its LP grew to 39,000
#: columns (half of them above 2 % of the gap): with the rule 23,000, and the bound rose faster
#: (`exact-frontier-uav`, its nine K = 200 solves: certified gap 0.631 -> 0.532 %). At K = 100
#: (1,620-1,870 nodes) the root too rose faster (150 s: lower gap on 4 of 4 points) but ended
#: sooner with a lower bound, and at 600 s two points were worse (0.078 -> 0.133 %, 0.069 ->
#: 0.173 %), hence the size.
ROOT_DROP_NODES, ROOT_DROP_SHARE, ROOT_DROP_AGE = 3000, 0.02, 3


def age_columns(age: np.ndarray, reduced_costs: np.ndarray, gap: float,
                share: float | None = None) -> np.ndarray:
    """The LP columns' new ages: one more where the reduced cost is large, else 0.

    Parameters
    ----------
    age
        Per LP column, the LPs in a row it has had a large reduced cost.
    reduced_costs
        Per LP column, its reduced cost at the LP just solved.
    gap
        The incumbent's value minus the LP's (at least 0).
    share
        A reduced cost is large above this share of ``gap`` (default :data:`DROP_SHARE`).

    Returns
    -------
    numpy.ndarray
        The new ages.
    """
    large = reduced_costs > (DROP_SHARE if share is None else share) * max(gap, 0.0)
    return np.where(large & (reduced_costs > 0), age + 1, 0)


def stale_columns(age: np.ndarray, keep: np.ndarray, limit: int | None = None) -> np.ndarray:
    """LP columns (positions) that leave the LP: aged ``limit`` (default :data:`DROP_AGE`) or more
    and not kept.

    Parameters
    ----------
    age
        Per LP column, from :func:`age_columns`.
    keep
        Per LP column, whether it must stay (branched on).
    limit
        The age from which a column leaves (0: none leaves).

    Returns
    -------
    numpy.ndarray
        Their positions, increasing (none when the limit is 0).
    """
    limit = DROP_AGE if limit is None else limit
    if limit <= 0:
        return np.zeros(0, dtype=np.int64)
    return np.flatnonzero((age >= limit) & ~keep)


def drop_stale(lp: LpModel, reduced_costs: np.ndarray, gap: float, keep: np.ndarray,
               share: float | None = None, limit: int | None = None) -> np.ndarray:
    """Age the LP's columns by the LP just solved and drop the stale ones.

    Parameters
    ----------
    lp
        The model in the backend, its basis that of the LP just solved.
    reduced_costs
        Per LP column, its reduced cost at that LP.
    gap
        The incumbent's value minus the LP's.
    keep
        Per LP column, whether it must stay in the LP (at a node: branched on).
    share, limit
        As in :func:`age_columns` and :func:`stale_columns` (defaults: the node loop's rule).

    Returns
    -------
    numpy.ndarray
        The model columns that left the LP.
    """
    lp.col_age = age_columns(lp.col_age, reduced_costs, gap, share)
    stale = stale_columns(lp.col_age, keep, limit)
    gone = lp.cols[stale]
    lp.drop_cols(stale)
    return gone


def drop_root_stale(lp: LpModel, reduced_costs: np.ndarray, gap: float) -> np.ndarray:
    """:func:`drop_stale` by the big root's rule (:data:`ROOT_DROP_SHARE`,
    :data:`ROOT_DROP_AGE`): edge columns only, the ``y`` columns stay."""
    return drop_stale(lp, reduced_costs, gap, lp.cols < lp.model.n_nodes, ROOT_DROP_SHARE,
                      ROOT_DROP_AGE)


def bound_moves(target: np.ndarray, applied: np.ndarray, cols: np.ndarray, fixed: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The LP column bounds to change to go from one node's codes to another's.

    Parameters
    ----------
    target, applied
        Per model column, the codes of the node to go to and of the node in the LP (-1 free,
        else the value the column is fixed to).
    cols
        The model column of each LP column.
    fixed
        Per model column, whether it is fixed to 0 for the whole search (then its upper bound
        when free is 0).

    Returns
    -------
    tuple of numpy.ndarray
        LP column positions whose code differs, and their new lower and upper bounds.
    """
    change = np.flatnonzero(target[cols] != applied[cols])
    code = target[cols[change]]
    upper0 = np.where(fixed[cols[change]], 0.0, 1.0)
    return change, np.maximum(code, 0).astype(float), np.where(code < 0, upper0, code).astype(float)

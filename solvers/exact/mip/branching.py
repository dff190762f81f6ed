"""Branching of the branch and cut: pseudo-costs and reliability branching.

Strong branching solves both children's LPs of every candidate column: at UAV K = 50 a node
spent 16 LPs of up to 1,000 simplex iterations on it. :class:`PseudoCosts` keeps, per model
column, the mean bound gain per unit of change seen when the column was rounded down (to 0) or
up (to 1), from strong-branching LPs and from the first LP of every child node.
:func:`choose` (reliability branching) strong-branches a candidate only while its pseudo-costs
rest on fewer than ``reliable`` observations in either direction, and stops strong branching after
``lookahead`` candidates in a row that did not beat the best score; the others are scored by
their pseudo-costs. The score is the product of the two children's gains (as before).

The branching decision is a guide only: any column and either child keep the search exact. A
child is declared empty (column fixed, or node pruned) only by the caller's ``strong`` function,
on an LP that proves it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

#: Candidates considered at a node: the fractional columns closest to 1/2.
CANDIDATES = 8
#: Share of strong-branching LPs stopped by their iteration limit (of at least two nodes' worth)
#: from which the search uses reliability branching; below it, every candidate is strong-branched
#: (on 31pr152 reliability branching took 19,304 nodes and 63 s, strong branching 296 and 14 s; at
#: UAV K = 50, where most strong LPs stop at the limit, it let the search reach 2-3x the nodes).
PARTIAL_SHARE = 0.5
#: Observations per direction after which a column's pseudo-costs are trusted.
RELIABLE = 1
#: Strong-branched candidates in a row without a better score after which strong branching stops
#: (reliability branching).
LOOKAHEAD = 2
#: Most candidates strong-branched at one node (reliability branching). UAV K = 50, seed 1, omega
#: 0.9, 600 s, one other job beside: with 8 and a look-ahead of 4, 29 nodes and bound 2,896.83;
#: with 4 and 2, 69 nodes and 2,897.13 (2 and 1: 70 nodes, 2,896.95).
MAX_STRONG = 4
#: Relative floor of a gain in the product score (a child that gains nothing still counts).
GAIN_FLOOR = 1e-6


@dataclass(frozen=True)
class StrongResult:
    """What strong branching on one column showed.

    Attributes
    ----------
    objective
        Each child's LP value (down = 0, up = 1): ``inf`` when infeasible, the dual simplex's
        value when the LP was stopped early (a guide), the node's value when unknown.
    empty
        Whether each child is proven to hold nothing below the incumbent.
    """

    objective: tuple[float, float]
    empty: tuple[bool, bool]


@dataclass(frozen=True)
class Choice:
    """A branching decision.

    Attributes
    ----------
    col
        The candidate's index (as given to :func:`choose`).
    value
        The child to dive into (0.0 or 1.0); when ``only``, the one child that is not empty.
    only
        The other child is empty: fix the column to ``value`` at the node, no branching.
    """

    col: int
    value: float
    only: bool = False


class PseudoCosts:
    """Per-column mean bound gain per unit of change, down (to 0) and up (to 1).

    Parameters
    ----------
    n_cols
        Number of model columns.
    """

    def __init__(self, n_cols: int) -> None:
        self.sums = np.zeros((2, n_cols))
        self.counts = np.zeros((2, n_cols), dtype=np.int64)

    def record(self, col: int, up: bool, gain: float, frac: float) -> None:
        """One observation: rounding column ``col`` (at ``frac`` in the parent's LP) up (or down)
        raised the LP bound by ``gain`` (negative gains count as 0; non-finite ones and integral
        ``frac`` are ignored)."""
        change = 1.0 - frac if up else frac
        if not math.isfinite(gain) or change <= 1e-9:
            return
        d = int(up)
        self.sums[d, col] += max(gain, 0.0) / change
        self.counts[d, col] += 1

    def mean(self, up: bool) -> float:
        """The mean per-unit gain over all observations in one direction (1.0 when none)."""
        d = int(up)
        total = self.counts[d].sum()
        return float(self.sums[d].sum() / total) if total else 1.0

    def per_unit(self, cols: np.ndarray) -> np.ndarray:
        """Per-unit gains, shape (2, len(cols)): the column's mean, else the direction's mean."""
        counts, sums = self.counts[:, cols], self.sums[:, cols]
        fallback = np.array([[self.mean(False)], [self.mean(True)]])
        return np.where(counts > 0, sums / np.maximum(counts, 1), fallback)

    def estimate(self, cols: np.ndarray, fracs: np.ndarray) -> np.ndarray:
        """Estimated gains of the two children, shape (2, len(cols))."""
        unit = self.per_unit(cols)
        return unit * np.vstack([fracs, 1.0 - fracs])

    def reliable(self, cols: np.ndarray, at_least: int) -> np.ndarray:
        """Whether each column has ``at_least`` observations in both directions."""
        return self.counts[:, cols].min(axis=0) >= at_least


def reliability(strong_lps: int, partial: int) -> bool:
    """Whether to use reliability branching after ``strong_lps`` strong-branching LPs, ``partial``
    of them stopped by their iteration limit: from two nodes' worth of LPs on, when at least
    :data:`PARTIAL_SHARE` of them stopped (strong branching is then both costly and a guide)."""
    return strong_lps >= 2 * CANDIDATES and partial >= PARTIAL_SHARE * strong_lps


def score(gain_down: float, gain_up: float, objective: float) -> float:
    """The product score of two children's gains, each floored at a small share of the bound."""
    floor = GAIN_FLOOR * max(1.0, abs(objective))
    return max(gain_down, floor) * max(gain_up, floor)


def choose(cands: np.ndarray, keys: np.ndarray, fracs: np.ndarray, objective: float, ub: float,
           pseudo: PseudoCosts, strong: Callable[[int], StrongResult], *,
           reliable: int | None = None, lookahead: int | None = None, max_strong: int | None = None,
           stop: Callable[[], bool] = lambda: False) -> Choice | None:
    """Reliability branching: the candidate to branch on, or ``None`` when strong branching
    showed both children of some candidate empty (the node is pruned).

    Parameters
    ----------
    cands
        Candidate indices (the caller's columns), handed back in :attr:`Choice.col` and to
        ``strong``.
    keys
        Each candidate's model column (the pseudo-costs' index).
    fracs
        Each candidate's fractional LP value.
    objective
        The node's LP value.
    ub
        The incumbent's cost (gains are capped there).
    pseudo
        The pseudo-costs; strong-branching results are recorded in them.
    strong
        Solves both children of a candidate.
    reliable, lookahead, max_strong
        See :data:`RELIABLE`, :data:`LOOKAHEAD`, :data:`MAX_STRONG` (their values when ``None``).
    stop
        Whether to stop strong branching now (the time limit).

    Returns
    -------
    Choice or None
        The column with the best score (strong-branched ones by their LPs, the others by their
        pseudo-costs) and the child of lower estimated value to dive into; a column with one
        child shown empty is returned at once with ``only``.
    """
    if len(cands) == 0:
        raise ValueError("no candidate to branch on")
    reliable = RELIABLE if reliable is None else reliable
    lookahead = LOOKAHEAD if lookahead is None else lookahead
    max_strong = MAX_STRONG if max_strong is None else max_strong
    est = np.minimum(pseudo.estimate(keys, fracs), max(ub - objective, 0.0))
    est_score = np.array([score(d, u, objective) for d, u in est.T])
    # best estimated first; among equal estimates (no observations yet) the most fractional
    order = np.lexsort((np.abs(fracs - 0.5), -est_score))
    trusted = pseudo.reliable(keys, reliable)
    best, pick = -1.0, None
    strong_done = since_better = 0
    for i in order:
        if not trusted[i] and strong_done < max_strong and since_better < lookahead and not stop():
            res = strong(int(cands[i]))
            strong_done += 1
            if res.empty[0] and res.empty[1]:
                return None
            if res.empty[0] or res.empty[1]:
                return Choice(int(cands[i]), 1.0 if res.empty[0] else 0.0, True)
            gains = [min(c, ub) - objective for c in res.objective]
            for up in (False, True):
                pseudo.record(int(keys[i]), up, gains[int(up)], float(fracs[i]))
            s = score(gains[0], gains[1], objective)
            down_first = res.objective[0] <= res.objective[1]
            if s > best:
                best, pick, since_better = s, Choice(int(cands[i]), 0.0 if down_first else 1.0), 0
            else:
                since_better += 1
        else:
            s = float(est_score[i])
            if s > best:
                down_first = est[0, i] <= est[1, i]
                best, pick = s, Choice(int(cands[i]), 0.0 if down_first else 1.0)
    assert pick is not None
    return pick

"""Exact bounds from dual values: the Lagrangian bound of a dual vector, and Farkas proofs.

For the model ``min c'v`` over tours ``v`` (binary ``y`` and ``x``), rows ``A v (=, <=) b`` valid
for every tour (cluster and degree equalities, cuts) and a domain ``l <= v <= u`` (variables fixed
by branching), any dual ``w`` with ``w_k <= 0`` on the ``<=`` rows gives, for every tour ``v`` in
the domain, ``c'v >= c'v - w'(Av - b) = b'w + r'v >= b'w + sum_j min(r_j l_j, r_j u_j)`` with
``r = c - A'w``. No optimality of ``w`` is needed, so floats read as exact rationals give a sound
bound. A Farkas proof is the same with ``c = 0``: a positive value shows that no tour lies in the
domain.

Duals are integers scaled by ``2**bits``; the scaled ``A'w`` of every column is computed in int64
(over the edge columns in one compiled loop, :mod:`gtsp_bench.proof.pairs`: the subtour rows'
part ``M' diag(w) M`` over their member masks as sums over member pairs) and
the costs are compared and summed exactly (scaled integers for integer costs, fractions
otherwise).
"""

from __future__ import annotations

import functools
import itertools
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np
import scipy.sparse as sp

from gtsp_bench.checks import all_ints, is_int
from gtsp_bench.problem import Problem
from gtsp_bench.proof.families import Blossom, Cut, Gsec, member_y_coef
from gtsp_bench.proof.pairs import edge_sums

#: Largest magnitude of any scaled sum (int64 with room).
_LIMIT = 2**62


@dataclass(frozen=True)
class Space:
    """The model's columns and costs for a priced problem.

    Attributes
    ----------
    cluster_of
        Cluster of each node.
    node_cost, edge_cost
        ``(n,)`` and ``(n, n)`` costs (float64, read as exact rationals).
    edge
        ``(n, n)`` bool: ``(i, j)`` is a column (``i < j``, two clusters).
    integral
        Whether every cost is an integer (then sums are scaled integers).
    """

    cluster_of: np.ndarray
    node_cost: np.ndarray
    edge_cost: np.ndarray
    edge: np.ndarray
    integral: bool

    @staticmethod
    def of(problem: Problem) -> Space:
        """The space of a priced problem."""
        c = problem.cluster_of
        n = len(c)
        edge = np.triu(c[:, None] != c[None, :], 1)
        node, cost = np.asarray(problem.node_cost, float), np.asarray(problem.edge_cost, float)
        integral = bool(np.all(node == np.round(node)) and np.all(cost[edge] == np.round(cost[edge])))
        return Space(c, node, cost, edge, integral and n > 0)

    @functools.cached_property
    def max_cost(self) -> float:
        """The largest magnitude of a column's cost (a node's or an edge column's)."""
        return max(float(np.abs(self.edge_cost[self.edge]).max(initial=0)),
                   float(np.abs(self.node_cost).max(initial=0)))

    @property
    def n_nodes(self) -> int:
        """Number of nodes."""
        return len(self.cluster_of)

    @property
    def n_clusters(self) -> int:
        """Number of clusters."""
        return int(self.cluster_of.max()) + 1


@dataclass
class Domain:
    """Fixed variables: per column -1 (free in [0, 1]) or its value.

    Attributes
    ----------
    y
        ``(n,)`` int8.
    x
        ``(n, n)`` int8 (entries ``i < j`` of edge columns are used).
    """

    y: np.ndarray
    x: np.ndarray

    @staticmethod
    def free(space: Space) -> Domain:
        """Every variable free."""
        n = space.n_nodes
        return Domain(np.full(n, -1, np.int8), np.full((n, n), -1, np.int8))

    def copy(self) -> Domain:
        """An independent copy."""
        return Domain(self.y.copy(), self.x.copy())

    def get(self, i: int, j: int) -> int:
        """State of ``y[i]`` (``j < 0``) or ``x[i, j]``."""
        return int(self.y[i] if j < 0 else self.x[i, j])

    def set(self, i: int, j: int, value: int) -> None:
        """Fix ``y[i]`` (``j < 0``) or ``x[i, j]`` to ``value`` (-1: free)."""
        if j < 0:
            self.y[i] = value
        else:
            self.x[i, j] = value


def _sparse(entries: Any, size: int, what: str) -> tuple[np.ndarray, np.ndarray]:
    """Indices and integer values of ``[[index, value], ...]``."""
    if not isinstance(entries, list):
        raise ValueError(f"{what} must be a list of [index, value] pairs")
    plain = (set(map(type, entries)) <= {list} and set(map(len, entries)) <= {2}
             and all_ints(list(itertools.chain.from_iterable(entries)))
             and all(0 <= e[0] < size for e in entries))  # a JSON file's pairs, in a few passes
    for e in () if plain else entries:  # else each entry, to name the first bad one
        if not (isinstance(e, list) and len(e) == 2 and is_int(e[0]) and is_int(e[1])
                and 0 <= e[0] < size):
            raise ValueError(f"{what}: {e!r} is not [index in [0, {size}), integer]")
    try:
        pairs = np.array(entries, dtype=np.int64).reshape(-1, 2)
    except OverflowError:
        raise ValueError(f"{what}: a dual value is too large") from None
    idx, val = pairs[:, 0], pairs[:, 1]
    if len(np.unique(idx)) != len(idx):
        raise ValueError(f"{what}: an index is repeated")
    if ((val >= _LIMIT // 8) | (val <= -(_LIMIT // 8))).any():
        raise ValueError(f"{what}: a dual value is too large")
    return idx, val


def _nonzero(mask: np.ndarray) -> tuple[np.ndarray, ...]:
    """``np.nonzero(mask)`` (the same arrays, row-major order), through the flat array: for a
    2-D mask about ten times faster than numpy's own."""
    flat = np.flatnonzero(mask)
    return tuple(np.unravel_index(flat, mask.shape)) if mask.ndim > 1 else (flat,)


def _gsec_sums(rows: list[Gsec], weights: np.ndarray, cluster_of: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``A'w`` of subtour rows with int64 ``weights`` over the y columns, exactly (``(n,)``, an
    integer sparse product: no float rounding), and the rows' members as CSR ``indices`` and
    ``indptr`` for the edge columns' part (:func:`~gtsp_bench.proof.pairs.edge_sums`)."""
    nodes = [r.nodes for r in rows]
    counts = np.array([len(q) for q in nodes], dtype=np.int64)
    indices = np.concatenate(nodes).astype(np.int64, copy=False)
    indptr = np.concatenate([[0], np.cumsum(counts)])
    row_of = np.repeat(np.arange(len(rows)), counts)
    c1 = np.array([r.c1 for r in rows])[row_of]
    c2 = np.array([r.c2 for r in rows])[row_of]
    y_coef = member_y_coef(cluster_of[indices], c1, c2)
    aw_y = sp.csr_array((y_coef, indices, indptr), shape=(len(rows), len(cluster_of))).T @ weights
    return np.asarray(aw_y, dtype=np.int64), indices, indptr


@dataclass(frozen=True)
class Priced:
    """The reduced costs of one dual vector, scaled by ``2**bits``, over a space.

    ``r = c - A'w`` per column; exact values come from :meth:`exact`.
    """

    space: Space
    scale: int
    farkas: bool
    rhs: int  # b'w, scaled
    aw_y: np.ndarray  # (n,) int64: A'w of the y columns, scaled
    aw_x: np.ndarray  # (n, n) int64: A'w of the edge columns (entries i < j), scaled

    def approx(self, x: bool) -> tuple[np.ndarray, float]:
        """Float reduced costs of the y (``x`` false) or edge columns and a bound on the error of
        every one (computed once: do not change them)."""
        return self._approx_x if x else self._approx_y

    @functools.cached_property
    def _approx_x(self) -> tuple[np.ndarray, float]:
        return self._approx(True)

    @functools.cached_property
    def _approx_y(self) -> tuple[np.ndarray, float]:
        return self._approx(False)

    def _approx(self, x: bool) -> tuple[np.ndarray, float]:
        # one rounding to float of A'w (the scale is a power of 2) and one of the difference:
        # |error| <= (|c| + |A'w| + |r|) 2**-53 <= 2 (max |c| + max |A'w|) 2**-53 per column, a
        # column's cost being a node's or an edge column's (other entries of the (n, n) arrays are
        # never read as columns); one bound for all, in a few passes over the array
        aw = self.aw_x if x else self.aw_y
        r = aw * (1.0 / self.scale)
        c_max = 0.0
        if self.farkas:
            np.negative(r, out=r)
        else:
            np.subtract(self.space.edge_cost if x else self.space.node_cost, r, out=r)
            c_max = self.space.max_cost
        aw_max = max(int(aw.max(initial=0)), -int(aw.min(initial=0))) / self.scale
        return r, (c_max + aw_max) * 2.0**-48 + 2.0**-1000

    def exact(self, i: np.ndarray, j: np.ndarray | None) -> list[Fraction]:
        """Exact reduced costs of y columns ``i`` (``j`` None) or edge columns ``(i, j)``."""
        aw = self.aw_y[i] if j is None else self.aw_x[i, j]
        if self.farkas:
            return [Fraction(-int(a), self.scale) for a in aw]
        c = self.space.node_cost[i] if j is None else self.space.edge_cost[i, j]
        if self.space.integral:
            return [Fraction(round(cc) * self.scale - int(a), self.scale)
                    for cc, a in zip(c, aw, strict=True)]
        return [Fraction(float(cc)) - Fraction(int(a), self.scale) for cc, a in zip(c, aw, strict=True)]

    @functools.cached_property
    def _negative(self) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray]]:
        """The y columns (a mask) and the edge columns (index arrays) whose reduced cost may be
        below 0."""
        (ry, ey), (rx, ex) = self.approx(False), self.approx(True)
        return ry < ey, _nonzero(self.space.edge & (rx < ex))

    def _exact_sum(self, i: np.ndarray, j: np.ndarray | None, clip: bool) -> Fraction:
        """The exact sum of the reduced costs of y columns ``i`` (``j`` None) or edge columns
        ``(i, j)``, each taken at most 0 if ``clip``: in int64 numerators over the scale where
        the costs are integers (no Fraction per column), else as fractions."""
        if not (self.farkas or self.space.integral):
            return sum((min(v, 0) if clip else v for v in self.exact(i, j)), Fraction(0))
        aw = self.aw_y[i] if j is None else self.aw_x[i, j]
        if self.farkas:
            num = -aw
        else:  # |cost * scale| < 2**60 (price_duals) and |A'w| < 2**60: no overflow
            c = self.space.node_cost[i] if j is None else self.space.edge_cost[i, j]
            num = np.rint(c).astype(np.int64) * self.scale - aw
        if clip:
            num = np.minimum(num, 0)
        return Fraction(sum(num.tolist()), self.scale)

    def bound(self, domain: Domain) -> Fraction:
        """``b'w + sum_j min(r_j l_j, r_j u_j)`` over the domain, exactly."""
        total = Fraction(self.rhs, self.scale)
        neg_y, neg_x = self._negative
        y, x = domain.y, domain.x
        total += self._exact_sum(np.flatnonzero(y == 1), None, False)
        total += self._exact_sum(np.flatnonzero(neg_y & (y == -1)), None, True)
        i, j = _nonzero(x == 1)
        keep = self.space.edge[i, j]
        total += self._exact_sum(i[keep], j[keep], False)
        i, j = neg_x
        free = x[i, j] == -1
        return total + self._exact_sum(i[free], j[free], True)

    def fixable(self, domain: Domain, room: Fraction) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray]]:
        """Free columns whose reduced cost exceeds ``room``: fixed to 1 they raise the bound by
        more than ``room``. Returns the y nodes and the edge index arrays."""
        out: list[Any] = []
        t = float(room)
        tol = abs(t) * 2.0**-50 + 2.0**-1000
        for is_x, state in ((False, domain.y), (True, domain.x)):
            r, err = self.approx(is_x)
            valid = self.space.edge if is_x else np.ones(len(state), dtype=bool)
            free = valid & (state == -1)
            sure = free & (r - err > t + tol)
            unsure = _nonzero(free & ~sure & (r + err >= t - tol))
            vals = self.exact(unsure[0], unsure[1] if is_x else None)
            more = np.array([v > room for v in vals], dtype=bool)
            sure[tuple(u[more] for u in unsure)] = True
            out.append(_nonzero(sure) if is_x else np.flatnonzero(sure))
        return out[0], out[1]


def price_duals(space: Space, cuts: list[Cut], proof: dict[str, Any], bits: int) -> Priced:
    """The reduced costs of one proof's dual vector.

    Raises
    ------
    ValueError
        A malformed proof, a cut dual above 0 (``<=`` rows need duals at most 0), or values so
        large that the int64 sums could overflow.
    """
    kind = proof.get("kind") if isinstance(proof, dict) else None
    if kind not in ("dual", "farkas"):
        raise ValueError(f"kind {kind!r} (valid: dual, farkas)")
    n, m = space.n_nodes, space.n_clusters
    cu, cv = _sparse(proof.get("cluster", []), m, "cluster duals")
    di, dv = _sparse(proof.get("degree", []), n, "degree duals")
    ki, kv = _sparse(proof.get("cuts", []), len(cuts), "cut duals")
    if (kv > 0).any():
        k = int(ki[np.argmax(kv)])
        raise ValueError(f"the dual of cut {k} is positive (a <= row needs a dual at most 0)")
    u = np.zeros(m, np.int64)
    u[cu] = cv
    pi = np.zeros(n, np.int64)
    pi[di] = dv
    if 4 * (int(np.abs(u).max(initial=0)) + 2 * int(np.abs(pi).max(initial=0))
            + 2 * sum(map(abs, kv.tolist()))) >= _LIMIT:  # Python ints: no wrap
        raise ValueError("dual values too large to sum exactly")
    aw_y = u[space.cluster_of] - 2 * pi
    rhs = int(cv.sum())
    rows = [cuts[r] for r in ki.tolist()]
    g_idx = [k for k, c in enumerate(rows) if isinstance(c, Gsec)]
    weights = np.ascontiguousarray(kv[g_idx], dtype=np.int64)
    indices, indptr = np.zeros(0, np.int64), np.zeros(1, np.int64)
    if g_idx:
        gy, indices, indptr = _gsec_sums([rows[k] for k in g_idx], weights, space.cluster_of)
        aw_y += gy
    pair = np.zeros((m, m), np.int64)
    for c, w in zip(rows, kv.tolist(), strict=True):
        if isinstance(c, Blossom):
            h = np.flatnonzero(c.handle)
            pair[np.ix_(h, h)] += w
            pair[c.teeth[:, 0], c.teeth[:, 1]] += w
            pair[c.teeth[:, 1], c.teeth[:, 0]] += w
            rhs += w * c.rhs
    aw_x = edge_sums(pi, pair, space.cluster_of.astype(np.int64, copy=False), indices, indptr, weights)
    scale = 2**bits
    big = space.max_cost * scale >= _LIMIT // 4
    if kind != "farkas" and space.integral and big:
        raise ValueError("costs too large for the dual scale")
    return Priced(space, scale, kind == "farkas", rhs, aw_y, aw_x)

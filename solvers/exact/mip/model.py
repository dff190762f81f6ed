"""The GTSP MILP over the kept candidate heads: columns, base rows, integer points, core columns.

Column ``i < n_nodes`` is ``y_i`` (local node ``i`` is its cluster's head); column
``n_nodes + e`` is ``x_e`` of edge ``e = (tail[e], head[e])`` between two clusters. The base rows
are ``Cluster(C)``: ``y(C) = 1`` and ``Degree(i)``: ``x(delta(i)) = 2 y_i``; cuts live in
:mod:`gtsp_bench.solvers.exact.mip.separation`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from gtsp_bench.problem import Problem

#: Values above this count as 1 in an integer solution.
HALF = 0.5
#: Values above this are in the support graph.
ZERO = 1e-9
#: A cut is added only when violated by more than this; a column priced in below -this.
TOL = 1e-6


@dataclass(frozen=True, eq=False)
class GtspModel:
    """The MILP over the kept candidate heads.

    Column ``i < n_nodes`` is ``y`` of local node ``i``; column ``n_nodes + e`` is ``x`` of edge
    ``e = (tail[e], head[e])``.

    Attributes
    ----------
    problem
        The priced problem.
    nodes
        Problem node id of each local node.
    cluster
        GTSP cluster of each local node (nondecreasing).
    tail, head
        Local end nodes of each edge (different clusters, ``tail < head``).
    cost
        Objective coefficient of each column.
    """

    problem: Problem
    nodes: np.ndarray
    cluster: np.ndarray
    tail: np.ndarray
    head: np.ndarray
    cost: np.ndarray

    @property
    def n_nodes(self) -> int:
        """Number of y columns."""
        return len(self.nodes)

    @property
    def n_clusters(self) -> int:
        """Number of GTSP clusters (the depot's included)."""
        return int(self.cluster[-1]) + 1

    @property
    def n_cols(self) -> int:
        """Number of columns (y and x)."""
        return len(self.cost)

    @property
    def n_base_rows(self) -> int:
        """Number of ``Cluster`` and ``Degree`` rows."""
        return self.n_clusters + self.n_nodes

    @property
    def integral_costs(self) -> bool:
        """Whether every cost is an integer (then a gap below 1 proves optimality)."""
        return bool(np.all(self.cost == np.round(self.cost)))

    def edge_ids(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Edge numbers of the node pairs ``(a, b)``, ``a < b`` in different clusters.

        The edges are :func:`build_model`'s: every pair of nodes of different clusters, in
        ``(tail, head)`` order, so edge ``(i, j)`` is number ``first[i] + j - after[i]``, with
        ``after[i]`` the node after ``i``'s cluster and ``first[i]`` the number of ``i``'s first edge.
        """
        after = np.searchsorted(self.cluster, self.cluster, side="right")
        first = np.concatenate([[0], np.cumsum(self.n_nodes - after)[:-1]])
        if first[-1] + self.n_nodes - after[-1] != len(self.tail):
            raise ValueError("edge numbers need build_model's edges (every pair between clusters)")
        return first[a] + b - after[a]

    def split(self, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(y, x)`` parts of a column vector."""
        return values[:self.n_nodes], values[self.n_nodes:]

    def base_rows(self, cols: np.ndarray) -> tuple[sp.csc_array, np.ndarray]:
        """``Cluster(C)`` then ``Degree(i)`` rows over columns ``cols``: (matrix, right-hand side).

        Both families are equalities.
        """
        n, m = self.n_nodes, self.n_clusters
        is_y = cols < n
        ys, es = cols[is_y], cols[~is_y] - n
        pos = np.arange(len(cols))
        row = np.concatenate([self.cluster[ys], m + ys, m + self.tail[es], m + self.head[es]])
        col = np.concatenate([pos[is_y], pos[is_y], pos[~is_y], pos[~is_y]])
        val = np.concatenate([np.ones(len(ys)), np.full(len(ys), -2.0), np.ones(2 * len(es))])
        matrix = sp.csc_array((val, (row, col)), shape=(m + n, len(cols)))
        return matrix, np.concatenate([np.ones(m), np.zeros(n)])

    def components(self, values: np.ndarray) -> list[np.ndarray]:
        """Local nodes of each cycle of an integer solution."""
        y, x = self.split(values)
        used = x > HALF
        graph = sp.coo_array((np.ones(int(used.sum())), (self.tail[used], self.head[used])),
                             shape=(self.n_nodes, self.n_nodes))
        _, label = connected_components(graph, directed=False)
        chosen = np.flatnonzero(y > HALF)
        return [chosen[label[chosen] == c] for c in np.unique(label[chosen])]

    def tour(self, values: np.ndarray) -> np.ndarray:
        """Problem node ids of the tour of an integer solution without subtours."""
        y, x = self.split(values)
        neighbours: dict[int, list[int]] = {}
        for e in np.flatnonzero(x > HALF):
            a, b = int(self.tail[e]), int(self.head[e])
            neighbours.setdefault(a, []).append(b)
            neighbours.setdefault(b, []).append(a)
        start = int(np.flatnonzero(y > HALF)[0])
        path, prev, cur = [start], -1, start
        while True:
            nxt = next(v for v in neighbours[cur] if v != prev)
            if nxt == start:
                return self.nodes[np.array(path)]
            path.append(nxt)
            prev, cur = cur, nxt


def build_model(problem: Problem, kept: Sequence[np.ndarray]) -> GtspModel:
    """The MILP over candidate heads ``kept``.

    Parameters
    ----------
    problem
        The priced problem.
    kept
        Node ids of the candidate heads of each GTSP cluster, in cluster order.

    Returns
    -------
    GtspModel
        One ``y`` column per kept node, one ``x`` column per pair of kept nodes in different
        clusters, with their costs.
    """
    nodes = np.concatenate([np.asarray(k, dtype=np.int64) for k in kept])
    cluster = np.repeat(np.arange(len(kept)), [len(k) for k in kept])
    tail, head = np.triu_indices(len(nodes), 1)
    between = cluster[tail] != cluster[head]
    tail, head = tail[between].astype(np.int64), head[between].astype(np.int64)
    cost = np.concatenate([problem.node_cost[nodes], problem.edge_cost[nodes[tail], nodes[head]]])
    return GtspModel(problem, nodes, cluster, tail, head, cost)


def core_columns(model: GtspModel, per_node: int, tour: np.ndarray | None,
                 block: int = 4_000_000) -> np.ndarray:
    """The columns of the first LP: a core of cheap edges (the others are priced in later).

    Parameters
    ----------
    model
        The model.
    per_node
        Cheapest edges kept at each node (0: every column); on equal costs, those to later
        nodes first, then to earlier ones, each in node order.
    tour
        Problem node ids of a tour whose edges join (keeping the LP feasible), or ``None``;
        ignored when it uses a node the model does not have.
    block
        Node pairs looked at a time (memory: a few arrays of this many entries).

    Returns
    -------
    numpy.ndarray
        Model columns, increasing: all ``y`` columns, then the edges kept.
    """
    n = model.n_nodes
    if per_node == 0:
        return np.arange(model.n_cols)
    keep = np.zeros(len(model.tail), dtype=bool)
    # rows of the (n, n) matrix of edge costs (inf within a cluster), a block of rows at a time:
    # the per_node-th cost of each row, then the ties at it in the order above (one lexsort of
    # both ends of every edge took 7-12 s at UAV K = 200)
    step = max(1, block // max(1, n))
    cols = np.arange(n)
    for r0 in range(0, n, step):
        rows = np.arange(r0, min(n, r0 + step))
        cost = np.full((len(rows), n), np.inf)
        other = model.cluster[None, :] != model.cluster[rows, None]
        lo, hi = np.minimum(rows[:, None], cols), np.maximum(rows[:, None], cols)
        cost[other] = model.cost[n + model.edge_ids(lo[other], hi[other])]
        kth = per_node - 1
        if kth < n:
            limit = np.partition(cost, kth, axis=1)[:, kth:kth + 1]
        else:
            limit = np.full((len(rows), 1), np.inf)
        chosen = cost < limit
        tie = (cost == limit) & np.isfinite(cost)
        later = cols[None, :] > rows[:, None]
        ahead = np.cumsum(tie & later, axis=1)  # ties to later nodes, up to and at each column
        rank = np.where(later, ahead, ahead[:, -1:] + np.cumsum(tie & ~later, axis=1)) - 1
        chosen |= tie & (rank < per_node - chosen.sum(axis=1, keepdims=True))
        i, j = np.nonzero(chosen)
        keep[model.edge_ids(np.minimum(rows[i], j), np.maximum(rows[i], j))] = True
    if tour is not None:
        local = np.full(model.problem.n_nodes, -1)
        local[model.nodes] = np.arange(n)
        t = local[tour]
        if np.all(t >= 0):  # (the tour may use pruned nodes)
            a, b = np.minimum(t, np.roll(t, -1)), np.maximum(t, np.roll(t, -1))
            keep[model.edge_ids(a, b)] = True
    return np.concatenate([np.arange(n), n + np.flatnonzero(keep)])

"""The exact solvers' GTSP MILP, written once for every LP/MIP library.

Formulation over the candidate heads left by :func:`gtsp_bench.solvers.exact.prune.prune_heads` (node ``i`` in
GTSP cluster ``c(i)``; the depot, when there is one, is a cluster of one node):

* ``y_i`` in {0, 1}: node ``i`` is its cluster's head; ``x_e`` in {0, 1} for every edge
  ``e = {i, j}`` with ``c(i) != c(j)`` (symmetric: one variable per edge);
* minimise ``sum_i node_cost_i y_i + sum_e edge_cost_e x_e``;
* ``Cluster(C)``: ``y(C) = 1`` for every cluster;
* ``Degree(i)``: ``x(delta(i)) = 2 y_i``;
* ``Subtour(S, C)``, added as cuts: ``x(delta(S)) >= 2 y(S & C)`` for a node set ``S`` that
  misses a whole cluster and any cluster ``C``. With the degree rows it is written over the edges
  inside the smaller of the two sides (fewer nonzeros): ``x(E(S)) <= y(S - C)`` or
  ``x(E(T)) <= y(T) + y(T & C) - 1`` with ``T = V - S``. Every cut is thus
  ``x(E(side)) + sum_i a_i y_i <= b``: a :class:`Cuts` block stores ``side``, ``a`` and ``b``.

A tour through three or fewer clusters needs no model: one cyclic order exists, and
:func:`gtsp_bench.solvers.heads.optimal_heads` gives its optimal heads (one cluster: a single node; two: an
edge used twice).

:func:`solve_exact` runs the method on any :class:`Backend` (a thin LP/MIP wrapper that knows
nothing of the GTSP):

1. an upper bound from the large neighbourhood search
   :class:`gtsp_bench.solvers.heuristics.lns.Lns` (one trial);
2. exact pruning of candidate heads;
3. a root loop on the LP relaxation over a core of cheap edges: columns of negative reduced cost
   are priced in, columns whose reduced cost exceeds the gap to the upper bound are fixed to 0,
   and violated cuts are separated at the fractional solution: node-cluster rows
   ``x(i : D) <= y_i`` by enumeration, lifted subtour cuts by one max-flow per cluster, and
   blossoms of the tour over the clusters by the odd-component heuristic; slack cuts are purged;
4. unless the root proved the upper bound optimal, branch and cut with the backend as LP solver:
   best first with diving, the same cuts, pricing and reduced-cost fixing at every node,
   branching on ``y`` first. A backend with lazy constraints (Gurobi) solves the MILP itself
   instead, over every column not fixed, adding subtour rows from a callback.

Branching ourselves replaced re-solving HiGHS's MILP after each subtour solution: on a K = 20
instance whose root gap stayed open, HiGHS spent 110 s on 3 nodes without finishing (it can
neither separate subtours inside its search nor take lazy rows in highspy 1.15.1), where the
branch and cut here proves it in about 20 s.
"""

from __future__ import annotations

import heapq
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np
import scipy.sparse as sp
from gtsp_bench.solvers.exact.prune import prune_heads
from gtsp_bench.solvers.heads import optimal_heads
from gtsp_bench.solvers.heuristics.greedy import greedy_tour
from gtsp_bench.solvers.heuristics.lns import Lns
from gtsp_bench.solvers.heuristics.local_search import anchor_node, improve
from scipy.sparse.csgraph import breadth_first_order, connected_components, maximum_flow

from gtsp_bench.checks import check_float, check_int
from gtsp_bench.errors import InputError
from gtsp_bench.instance import Instance
from gtsp_bench.problem import Problem, price
from gtsp_bench.registry import Solution

#: Values above this count as 1 in an integer solution.
_HALF = 0.5
#: Values above this are in the support graph.
_ZERO = 1e-9
#: Capacities are scaled to integers for scipy's max-flow.
_FLOW_SCALE = 1_000_000
#: A cut is added only when violated by more than this; a column priced in below -this.
_TOL = 1e-6
#: Columns priced into the root LP per round, per node.
PRICE_PER_NODE = 2


# ---------------------------------------------------------------------- options
@dataclass(frozen=True)
class MipOptions:
    """Options shared by the MILP solvers (each a constructor keyword of the solvers).

    Attributes
    ----------
    prune
        Remove candidate heads by exact pair dominance first.
    lns_trials
        Trials of the large neighbourhood search giving the first upper bound (0: the greedy
        tour after local search only).
    root_rounds
        Most rounds of the root LP loop (0: no root cuts, all edges).
    core_edges
        Edges per node in the first LP (its cheapest); the others are priced in as needed.
        0: all edges from the start.
    abs_gap
        The optimum counts as proven when upper - lower bound <= abs_gap (with all costs integer,
        a gap below 1 proves it too).
    verbose
        Print the backend's log.
    """

    prune: bool = True
    lns_trials: int = 1
    root_rounds: int = 200
    core_edges: int = 10
    abs_gap: float = 1e-6
    verbose: bool = False

    def __post_init__(self) -> None:
        for name in ("prune", "verbose"):
            if not isinstance(getattr(self, name), bool):
                raise InputError(f"{name} must be true or false, got {getattr(self, name)!r}")
        for name in ("lns_trials", "root_rounds", "core_edges"):
            check_int(name, getattr(self, name), 0)
        check_float("abs_gap", self.abs_gap, 0.0, math.inf, open_low=False)


def upper_bound_tour(problem: Problem, trials: int, seed: int, time_limit: float | None) -> np.ndarray:
    """A good tour: :class:`gtsp_bench.solvers.heuristics.lns.Lns` with ``trials`` trials
    (0: greedy + local search)."""
    if trials == 0:
        return improve(problem, greedy_tour(problem, anchor_node(problem)))[0]
    sol = Lns(trials=trials).solve(problem.instance, problem.omega, time_limit=time_limit, seed=seed)
    return problem.to_tour(sol.order, sol.heads)


# ---------------------------------------------------------------------- model
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
        used = x > _HALF
        graph = sp.coo_array((np.ones(int(used.sum())), (self.tail[used], self.head[used])),
                             shape=(self.n_nodes, self.n_nodes))
        _, label = connected_components(graph, directed=False)
        chosen = np.flatnonzero(y > _HALF)
        return [chosen[label[chosen] == c] for c in np.unique(label[chosen])]

    def tour(self, values: np.ndarray) -> np.ndarray:
        """Problem node ids of the tour of an integer solution without subtours."""
        y, x = self.split(values)
        neighbours: dict[int, list[int]] = {}
        for e in np.flatnonzero(x > _HALF):
            a, b = int(self.tail[e]), int(self.head[e])
            neighbours.setdefault(a, []).append(b)
            neighbours.setdefault(b, []).append(a)
        start = int(np.flatnonzero(y > _HALF)[0])
        path, prev, cur = [start], -1, start
        while True:
            nxt = next(v for v in neighbours[cur] if v != prev)
            if nxt == start:
                return self.nodes[np.array(path)]
            path.append(nxt)
            prev, cur = cur, nxt


def build_model(problem: Problem, kept: Sequence[np.ndarray]) -> GtspModel:
    """The MILP over candidate heads ``kept`` (node ids per GTSP cluster, in cluster order)."""
    nodes = np.concatenate([np.asarray(k, dtype=np.int64) for k in kept])
    cluster = np.repeat(np.arange(len(kept)), [len(k) for k in kept])
    tail, head = np.triu_indices(len(nodes), 1)
    between = cluster[tail] != cluster[head]
    tail, head = tail[between].astype(np.int64), head[between].astype(np.int64)
    cost = np.concatenate([problem.node_cost[nodes], problem.edge_cost[nodes[tail], nodes[head]]])
    return GtspModel(problem, nodes, cluster, tail, head, cost)


# ---------------------------------------------------------------------- cuts
@dataclass(frozen=True)
class Cuts:
    """Cut rows ``sum_{k: row_k = r} x(E(side_k)) + ycoef_r . y <= rhs_r``.

    Most rows have one side; a blossom has its handle and each tooth as sides.

    Attributes
    ----------
    side
        ``(S, n_nodes)`` bool: the edges with both ends in ``side_k`` get coefficient 1 in row
        ``row[k]`` (summed over a row's sides).
    row
        ``(S,)`` row of each side.
    ycoef
        ``(R, n_nodes)`` coefficients of the y columns.
    rhs
        ``(R,)`` right-hand sides.
    """

    side: np.ndarray
    row: np.ndarray
    ycoef: np.ndarray
    rhs: np.ndarray

    def __len__(self) -> int:
        return len(self.rhs)

    @staticmethod
    def empty(n_nodes: int) -> Cuts:
        """No cuts."""
        return Cuts(np.zeros((0, n_nodes), bool), np.zeros(0, np.int64), np.zeros((0, n_nodes)),
                    np.zeros(0))

    @staticmethod
    def one(sides: np.ndarray, ycoef: np.ndarray, rhs: float) -> Cuts:
        """One row from its sides ``(k, n_nodes)`` (or a single side ``(n_nodes,)``)."""
        sides = np.atleast_2d(sides)
        return Cuts(sides.copy(), np.zeros(len(sides), np.int64), ycoef[None, :].astype(float),
                    np.array([float(rhs)]))

    @staticmethod
    def stack(blocks: Sequence[Cuts]) -> Cuts:
        """All cuts in one block."""
        offsets = np.cumsum([0] + [len(b) for b in blocks[:-1]])
        return Cuts(np.concatenate([b.side for b in blocks]),
                    np.concatenate([b.row + o for b, o in zip(blocks, offsets, strict=True)]),
                    np.concatenate([b.ycoef for b in blocks]), np.concatenate([b.rhs for b in blocks]))

    def select(self, mask: np.ndarray) -> Cuts:
        """The cuts where ``mask`` (one entry per row) is true."""
        renumber = np.cumsum(mask) - 1
        keep = mask[self.row]
        return Cuts(self.side[keep], renumber[self.row[keep]], self.ycoef[mask], self.rhs[mask])

    def _per_row(self, per_side: np.ndarray) -> np.ndarray:
        """Sum ``per_side`` (first axis: sides) over each row's sides."""
        if len(self.row) == len(self) and np.array_equal(self.row, np.arange(len(self))):
            return per_side
        out = np.zeros((len(self), *per_side.shape[1:]))
        np.add.at(out, self.row, per_side)
        return out

    def matrix(self, model: GtspModel, cols: np.ndarray) -> np.ndarray:
        """Dense ``(R, len(cols))`` coefficients over columns ``cols``."""
        n = model.n_nodes
        is_y = cols < n
        out = np.empty((len(self), len(cols)))
        out[:, is_y] = self.ycoef[:, cols[is_y]]
        es = cols[~is_y] - n
        out[:, ~is_y] = self._per_row(self.side[:, model.tail[es]] & self.side[:, model.head[es]])
        return out

    def slack(self, model: GtspModel, values: np.ndarray) -> np.ndarray:
        """``rhs - lhs`` at a full column vector (negative: violated)."""
        y, x = model.split(values)
        s = self.side.astype(float)
        # x(E(side)) = 1/2 sum_{i, j in side} X_ij with X the symmetric edge-value matrix
        xm = sp.csr_array((np.concatenate([x, x]), (np.concatenate([model.tail, model.head]),
                                                    np.concatenate([model.head, model.tail]))),
                          shape=(model.n_nodes, model.n_nodes))
        inside = 0.5 * np.einsum("sn,sn->s", (xm @ s.T).T, s)
        return self.rhs - self._per_row(inside) - self.ycoef @ y

    def dual_weights(
        self, model: GtspModel, duals: np.ndarray, edges: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """For row duals ``duals``: the dual weight on each of ``edges`` and on each y column."""
        nz = np.flatnonzero(np.abs(duals[self.row]) > 1e-12)
        rows = np.flatnonzero(np.abs(duals) > 1e-12)
        on_y = duals[rows] @ self.ycoef[rows]
        s = self.side[nz]
        if len(edges) * len(nz) < model.n_nodes**2 * 4:  # few edges: side by side
            both = s[:, model.tail[edges]] & s[:, model.head[edges]]
            return duals[self.row[nz]] @ both, on_y
        sf = s.astype(float)
        pair = (sf * duals[self.row[nz], None]).T @ sf  # (n, n): duals of the sides holding i, j
        return pair[model.tail[edges], model.head[edges]], on_y


def subtour_cut(model: GtspModel, sink_side: np.ndarray, c: int) -> Cuts:
    """``Subtour(S, C)`` for ``S = sink_side``, over the side with fewer inside edges.

    ``S`` must miss a whole cluster. Over ``S``: ``x(E(S)) - y(S - C) <= 0`` (when ``S`` holds
    all of ``C``: ``x(E(S)) - y(S) <= -1``); over ``T = V - S``: ``x(E(T)) - y(T) - y(T & C)
    <= -1``.
    """
    in_c = model.cluster == c
    s, t = sink_side, ~sink_side
    edges_s = np.count_nonzero(s[model.tail] & s[model.head])
    edges_t = np.count_nonzero(t[model.tail] & t[model.head])
    if edges_s <= edges_t:
        if not (in_c & t).any():
            return Cuts.one(s, -s.astype(float), -1.0)
        return Cuts.one(s, -(s & ~in_c).astype(float), 0.0)
    return Cuts.one(t, -t.astype(float) - (t & in_c), -1.0)


def lifted_cut(model: GtspModel, sink_side: np.ndarray, y: np.ndarray) -> Cuts:
    """The strongest-looking ``Subtour(S', C)`` at ``y`` for a cut with sink side ``S``.

    Nodes with ``y_i = 0`` have no edges at the current point, so moving them does not change
    ``x(delta(S))`` there: every cluster whose chosen nodes all lie in ``S`` joins ``S`` whole,
    which makes the right-hand side 2. Otherwise ``C`` is the cluster with the largest
    ``y(S & C)``.
    """
    m = model.n_clusters
    outside = np.bincount(model.cluster[(y > _ZERO) & ~sink_side], minlength=m)
    s = sink_side | (outside[model.cluster] == 0)
    full = np.flatnonzero(outside == 0)
    if len(full):
        return subtour_cut(model, s, int(full[0]))
    inside = np.bincount(model.cluster, weights=np.where(s, y, 0.0), minlength=m)
    return subtour_cut(model, s, int(np.argmax(inside)))


def subtour_cuts(model: GtspModel, values: np.ndarray) -> Cuts | None:
    """Cuts removing an integer solution with subtours (``None`` if it is one tour).

    For every cycle but the largest, with ``W`` the clusters it visits and ``S`` all candidate
    heads of ``W``: ``x(E(S)) <= |W| - 1``.
    """
    comps = model.components(values)
    if len(comps) == 1:
        return None
    comps.sort(key=len)
    return Cuts.stack([subtour_cut(model, np.isin(model.cluster, model.cluster[comp]),
                                   int(model.cluster[comp[0]])) for comp in comps[:-1]])


def node_cluster_cuts(model: GtspModel, values: np.ndarray) -> Cuts | None:
    """Violated ``x(i : D) <= y_i`` rows: a head has at most one edge to a cluster ``D``.

    This is ``Subtour(S, D)`` for ``S = D + {i}``, found by enumeration (vectorised). The flow
    separation finds at most two cuts per cluster and round; these are the ones that stop the LP
    from spreading each head over many nodes, and they cut the number of rounds by 3-4x.
    """
    y, x = model.split(values)
    n, m = model.n_nodes, model.n_clusters
    ends = np.concatenate([model.tail, model.head])
    key = ends * m + np.concatenate([model.cluster[model.head], model.cluster[model.tail]])
    load = np.bincount(key, weights=np.concatenate([x, x]), minlength=n * m)
    viol = np.flatnonzero(load - np.repeat(y, m) > _TOL)
    if len(viol) == 0:
        return None
    node, other = viol // m, viol % m
    r = np.arange(len(viol))
    side = model.cluster[None, :] == other[:, None]
    side[r, node] = True
    ycoef = np.zeros((len(viol), n))
    ycoef[r, node] = -1.0
    return Cuts(side, r, ycoef, np.zeros(len(viol)))


def _min_cut_sides(graph: sp.csr_array, source: int, sink: int) -> tuple[float, list[np.ndarray]]:
    """Max-flow value and the sink sides of the two extreme minimum cuts (masks over nodes)."""
    flow = maximum_flow(graph, source, sink, method="dinic")
    residual = (graph - flow.flow).tocsr()
    residual.data[residual.data < 0] = 0
    residual.eliminate_zeros()
    n = graph.shape[0]
    from_source = np.zeros(n, dtype=bool)
    from_source[breadth_first_order(residual, source, directed=True, return_predecessors=False)] = True
    to_sink = np.zeros(n, dtype=bool)
    to_sink[breadth_first_order(residual.T.tocsr(), sink, directed=True, return_predecessors=False)] = True
    return float(flow.flow_value), [~from_source, to_sink]


def flow_cuts(model: GtspModel, values: np.ndarray) -> Cuts | None:
    """Violated ``Subtour(S, C)`` cuts at a fractional solution, by one max-flow per cluster.

    For cluster ``C``, a source cluster ``D != C`` (the smallest: the depot when there is one) is
    tied to the source and each node ``i`` of ``C`` to the sink with capacity ``2 y_i``; edges
    carry ``x_e`` both ways. A cut of value below 2 is a violated cut: ``x(delta(S)) + 2 y(C - S)
    < 2`` with ``S`` the sink side, which misses ``D``. Cuts from both extreme minimum cuts are
    returned, lifted by :func:`lifted_cut`.
    """
    y, x = model.split(values)
    n, m = model.n_nodes, model.n_clusters
    src, snk = n, n + 1
    sup = x > _ZERO
    cap = np.round(x[sup] * _FLOW_SCALE).astype(np.int64)
    a, b = model.tail[sup], model.head[sup]
    by_size = np.argsort(np.bincount(model.cluster, minlength=m), kind="stable")
    big = 4 * _FLOW_SCALE * (m + 1)
    found: list[Cuts] = []
    seen: set[bytes] = set()
    for c in range(m):
        in_c = np.flatnonzero((model.cluster == c) & (y > _ZERO))
        if len(in_c) == 0:
            continue
        d = int(by_size[0] if by_size[0] != c else by_size[1])
        in_d = np.flatnonzero(model.cluster == d)
        rows = np.concatenate([a, b, np.full(len(in_d), src), in_c])
        cols = np.concatenate([b, a, in_d, np.full(len(in_c), snk)])
        caps = np.concatenate([cap, cap, np.full(len(in_d), big),
                               np.round(2 * y[in_c] * _FLOW_SCALE).astype(np.int64)])
        graph = sp.csr_array((caps.astype(np.int32), (rows, cols)), shape=(n + 2, n + 2))
        graph.sum_duplicates()
        graph.sort_indices()
        value, sides = _min_cut_sides(graph, src, snk)
        if value >= (2 - _TOL) * _FLOW_SCALE:
            continue
        for side in sides:
            s = side[:n]
            key = bytes(np.packbits(s)) + c.to_bytes(4, "little")
            if key in seen or not s.any():
                continue
            seen.add(key)
            cut = lifted_cut(model, s, y)
            inside = cut.side[0]  # one side
            lhs = x[inside[model.tail] & inside[model.head]].sum() + cut.ycoef[0] @ y
            if lhs > cut.rhs[0] + _TOL:
                found.append(cut)
    return Cuts.stack(found) if found else None


def blossom_cuts(model: GtspModel, values: np.ndarray) -> Cuts | None:
    """Violated blossoms of the tour over clusters, by the odd-component heuristic.

    ``z_CD = x(C : D)`` is a Hamiltonian cycle over the clusters, so the 2-matching (blossom)
    inequalities of the TSP hold for it: for a handle ``H`` (clusters) and an odd number of
    pairwise disjoint teeth ``T`` (cluster pairs with one end in ``H``),
    ``z(E(H)) + z(T) <= |H| + (|T| - 1) / 2``. Handles are the connected components of the
    fractional ``z``; teeth the pairs with ``z = 1`` leaving them (an outside cluster on two
    teeth joins the handle). They close the half-integral root gaps the subtour cuts leave.
    """
    _, x = model.split(values)
    m = model.n_clusters
    z = np.zeros((m, m))
    np.add.at(z, (model.cluster[model.tail], model.cluster[model.head]), x)
    z += z.T
    frac = (z > _TOL) & (z < 1 - _TOL)
    n_comp, label = connected_components(sp.csr_array(frac.astype(float)), directed=False)
    found = []
    for comp in range(n_comp):
        handle = label == comp
        if handle.sum() < 2:
            continue
        while True:
            inner, outer = np.nonzero(handle[:, None] & ~handle[None, :] & (z > 1 - _TOL))
            shared = np.flatnonzero(np.bincount(outer, minlength=m) > 1)
            if len(shared) == 0:
                break
            handle[shared] = True
        k = len(inner)
        if k % 2 == 0 or handle.all() or len(np.unique(inner)) < k:  # teeth must be disjoint
            continue
        lhs = z[np.ix_(handle, handle)].sum() / 2 + z[inner, outer].sum()
        rhs = handle.sum() + (k - 1) / 2
        if lhs > rhs + _TOL:
            sides = [np.isin(model.cluster, np.flatnonzero(handle))]
            sides += [np.isin(model.cluster, [i, j]) for i, j in zip(inner, outer, strict=True)]
            found.append(Cuts.one(np.array(sides), np.zeros(model.n_nodes), rhs))
    return Cuts.stack(found) if found else None


def separate(model: GtspModel, values: np.ndarray, *, thorough: bool = True) -> Cuts | None:
    """Violated cuts at an LP solution: node-cluster rows and blossoms (cheap), then max-flow.

    With ``thorough`` false the max-flows run only when the cheap families find nothing.
    """
    found = [c for c in (node_cluster_cuts(model, values), blossom_cuts(model, values))
             if c is not None]
    if thorough or not found:
        flows = flow_cuts(model, values)
        if flows is not None:
            found.append(flows)
    return Cuts.stack(found) if found else None


# ---------------------------------------------------------------------- backends
@dataclass(frozen=True)
class LpResult:
    """An LP solve.

    ``status`` is ``"optimal"``, ``"infeasible"``, ``"cutoff"`` (the bound passed the cutoff) or
    ``"stopped"`` (time limit or other); ``values`` and ``reduced_costs`` (per backend column) and
    ``duals`` (per row) are ``None`` unless optimal.
    """

    status: str
    objective: float = math.inf
    values: np.ndarray | None = None
    duals: np.ndarray | None = None
    reduced_costs: np.ndarray | None = None


@dataclass(frozen=True)
class MipResult:
    """A MILP solve under a cutoff.

    Attributes
    ----------
    values
        The best solution found below the cutoff (per backend column), or ``None``.
    bound
        A proven lower bound on every solution below the cutoff.
    complete
        True when the search finished (nothing better than ``values``, up to the gap, exists
        below the cutoff); False when it stopped at the time limit.
    stats
        Backend statistics (nodes, ...), summed over solves by the caller.
    """

    values: np.ndarray | None
    bound: float
    complete: bool
    stats: dict[str, Any] = field(default_factory=dict)


class Backend(Protocol):
    """A thin wrapper of an LP library: what :func:`solve_exact` needs (HiGHS, Gurobi).

    It starts empty. Columns are bounded in [0, 1] and numbered in the order added; rows are
    numbered in the order added (deleting rows renumbers the later ones). A
    :class:`LazyMipBackend` also solves the MILP itself; for any other, :func:`solve_exact`
    branches, with the backend as LP solver.
    """

    def add_cols(self, cost: np.ndarray, entries: sp.csc_array) -> None:
        """Append columns with these costs and coefficients in the current rows."""
        ...

    def add_rows(self, matrix: sp.csr_array, lower: np.ndarray, upper: np.ndarray) -> None:
        """Append rows ``lower <= matrix @ v <= upper`` over the current columns."""
        ...

    def delete_rows(self, rows: np.ndarray) -> None:
        """Delete rows by index."""
        ...

    def set_bounds(self, cols: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> None:
        """Change column bounds."""
        ...

    def solve_lp(self, time_limit: float, cutoff: float = math.inf) -> LpResult:
        """Solve the LP relaxation; it may stop early once its bound passes ``cutoff``."""
        ...


@runtime_checkable
class LazyMipBackend(Backend, Protocol):
    """A backend whose MILP search takes lazy constraints (Gurobi)."""

    def solve_mip(
        self, time_limit: float, cutoff: float, gap: float,
        lazy: Callable[[np.ndarray], tuple[sp.csr_array, np.ndarray] | None],
    ) -> MipResult:
        """Solve with every column binary, for solutions below ``cutoff``, to absolute ``gap``.

        It calls ``lazy`` on each integer solution and adds the rows ``matrix @ v <= upper`` it
        returns.
        """
        ...


class _Lp:
    """The GTSP model held in a backend: which model columns it has, and the cuts in it."""

    def __init__(self, model: GtspModel, backend: Backend, cols: np.ndarray) -> None:
        self.model, self.backend = model, backend
        self.cols = np.zeros(0, dtype=np.int64)
        self.cuts = Cuts.empty(model.n_nodes)
        self.slack_age = np.zeros(0, dtype=np.int64)
        base, rhs = model.base_rows(np.zeros(0, dtype=np.int64))
        backend.add_rows(base.tocsr(), rhs, rhs)
        self.add_cols(cols)

    def add_cols(self, cols: np.ndarray) -> None:
        """Add model columns ``cols`` with their coefficients in the base rows and cuts."""
        base, _ = self.model.base_rows(cols)
        cut_part = sp.csc_array(self.cuts.matrix(self.model, cols))
        self.backend.add_cols(self.model.cost[cols], sp.vstack([base, cut_part], format="csc"))
        self.cols = np.concatenate([self.cols, cols])

    def add_cuts(self, cuts: Cuts) -> None:
        """Add cut rows over the columns present."""
        matrix = sp.csr_array(cuts.matrix(self.model, self.cols))
        self.backend.add_rows(matrix, np.full(len(cuts), -np.inf), cuts.rhs)
        self.cuts = Cuts.stack([self.cuts, cuts])
        self.slack_age = np.concatenate([self.slack_age, np.zeros(len(cuts), dtype=np.int64)])

    def purge(self, values: np.ndarray, age: int) -> None:
        """Delete cuts slack at ``values`` for ``age`` rounds in a row."""
        slack = self.cuts.slack(self.model, values) > _TOL
        self.slack_age = np.where(slack, self.slack_age + 1, 0)
        old = self.slack_age >= age
        if old.any():
            self.backend.delete_rows(self.model.n_base_rows + np.flatnonzero(old))
            self.cuts, self.slack_age = self.cuts.select(~old), self.slack_age[~old]

    def fix_zero(self, positions: np.ndarray) -> None:
        """Fix backend columns to 0."""
        k = len(positions)
        self.backend.set_bounds(positions, np.zeros(k), np.zeros(k))

    def full(self, values: np.ndarray) -> np.ndarray:
        """A backend column vector as a model column vector (absent columns 0)."""
        out = np.zeros(self.model.n_cols)
        out[self.cols] = values
        return out

    def reduced_costs(self, duals: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Reduced costs of model columns ``cols`` for the row duals of an LP solve."""
        model = self.model
        n, m = model.n_nodes, model.n_clusters
        pi_cluster, pi_deg, mu = duals[:m], duals[m:m + n], duals[m + n:]
        is_y = cols < n
        ys, es = cols[is_y], cols[~is_y] - n
        on_edge, on_y = self.cuts.dual_weights(model, mu, es)
        out = np.empty(len(cols))
        out[is_y] = model.cost[ys] - pi_cluster[model.cluster[ys]] + 2 * pi_deg[ys] - on_y[ys]
        out[~is_y] = (model.cost[n + es] - pi_deg[model.tail[es]] - pi_deg[model.head[es]]
                      - on_edge)
        return out


def core_columns(model: GtspModel, per_node: int, tour: np.ndarray | None) -> np.ndarray:
    """All y columns, each node's ``per_node`` cheapest edges and the edges of ``tour``."""
    n = model.n_nodes
    if per_node == 0:
        return np.arange(model.n_cols)
    e = np.arange(len(model.tail))
    ends = np.concatenate([model.tail, model.head])
    order = np.lexsort((np.concatenate([model.cost[n:], model.cost[n:]]), ends))
    rank = np.empty(len(order), dtype=np.int64)
    start = np.searchsorted(ends[order], np.arange(n))
    rank[order] = np.arange(len(order)) - np.repeat(start, np.bincount(ends, minlength=n))
    keep = np.zeros(len(e), dtype=bool)
    keep[np.concatenate([e, e])[rank < per_node]] = True
    if tour is not None:
        local = np.full(model.problem.n_nodes, -1)
        local[model.nodes] = np.arange(n)
        t = local[tour]
        if np.all(t >= 0):  # (the tour may use pruned nodes)
            a, b = np.minimum(t, np.roll(t, -1)), np.maximum(t, np.roll(t, -1))
            keys = model.tail * n + model.head  # sorted: edges come in (tail, head) order
            keep[np.searchsorted(keys, a * n + b)] = True
    return np.concatenate([np.arange(n), n + np.flatnonzero(keep)])


# ---------------------------------------------------------------------- the method
def _is_integral(values: np.ndarray, tol: float = 1e-6) -> bool:
    return bool(np.all(np.abs(values - np.round(values)) <= tol))


def check_symmetric(problem: Problem) -> None:
    """Raise :class:`InputError` unless the edge costs are symmetric (the model assumes it)."""
    if not np.allclose(problem.edge_cost, problem.edge_cost.T, rtol=1e-12, atol=0):
        raise InputError(f"{problem.instance.name}: edge costs are not symmetric; the exact "
                         "solvers need a symmetric GTSP")


def degree_bound(problem: Problem) -> float:
    """A lower bound on the optimum that needs no LP, for cycles through at least 3 clusters.

    In such a cycle every head ``v`` has two different neighbours outside its cluster, so with
    symmetric costs the tour costs ``sum over heads of node[v] + (e(prev, v) + e(v, next)) / 2``,
    at least ``node[v]`` plus half of ``v``'s two cheapest edges to other clusters; the bound
    takes the cheapest node of each cluster by that measure. It is what a solve stopped by its
    time limit before the first LP reports.
    """
    cluster_of = problem.cluster_of
    other = np.where(cluster_of[:, None] != cluster_of[None, :], problem.edge_cost, np.inf)
    per_node = problem.node_cost + 0.5 * np.partition(other, 1, axis=1)[:, :2].sum(axis=1)
    return float(sum(per_node[c].min() for c in problem.clusters))


class _Timer:
    """Accumulates seconds per phase in a stats dict."""

    def __init__(self, stats: dict[str, Any], key: str) -> None:
        self.stats, self.key = stats, key

    def __enter__(self) -> None:
        self.start = time.perf_counter()

    def __exit__(self, *exc: object) -> None:
        self.stats[self.key] = self.stats.get(self.key, 0.0) + time.perf_counter() - self.start


def _padded(fixes: np.ndarray, n: int) -> np.ndarray:
    """Node column codes for ``n`` columns: columns added since the node was made are free."""
    if len(fixes) == n:
        return fixes
    return np.concatenate([fixes, np.full(n - len(fixes), -1, dtype=np.int8)])


@dataclass(order=True)
class _Node:
    """An open branch-and-cut node: its parent's bound and, per backend column, -1 (free) or
    the value it is fixed to."""

    bound: float
    seq: int
    fixes: np.ndarray = field(compare=False)


class _Search:
    """State of one exact solve: the incumbent, the bound, the LP and the phases."""

    def __init__(self, problem: Problem, backend: Backend, options: MipOptions, deadline: float,
                 tour: np.ndarray, kept: Sequence[np.ndarray], stats: dict[str, Any]) -> None:
        self.problem, self.options, self.deadline, self.stats = problem, options, deadline, stats
        self.model = model = build_model(problem, kept)
        stats["nodes"], stats["edges"] = model.n_nodes, len(model.tail)
        self.tour, self.ub = tour, problem.tour_cost(tour)
        self.lb = degree_bound(problem)  # a bound even if no LP is solved in time
        self.gap = max(options.abs_gap, 1 - 1e-6) if model.integral_costs else options.abs_gap
        self.margin = 1e-9 * max(1.0, abs(self.ub))  # against rounding in the LP's duals
        self.lp = _Lp(model, backend, core_columns(model, options.core_edges, tour))
        self.fixed = np.zeros(model.n_cols, dtype=bool)

    # -------------------------------------------------------------- helpers
    def left(self) -> float:
        """Seconds left."""
        return self.deadline - time.perf_counter()

    @property
    def proven(self) -> bool:
        """Whether the incumbent is proven optimal (up to the gap and rounding)."""
        return self.ub - self.lb <= self.gap + 8 * np.finfo(float).eps * abs(self.ub)

    def offer(self, values: np.ndarray) -> None:
        """Take an integer solution without subtours as incumbent if it is better."""
        cand = self.model.tour(values)
        cost = self.problem.tour_cost(cand)
        if cost < self.ub:
            self.tour, self.ub = cand, cost

    def solve_lp(self, cutoff: float = math.inf) -> LpResult:
        """One LP solve, timed."""
        with _Timer(self.stats, "lp_s"):
            return self.lp.backend.solve_lp(self.left(), cutoff)

    def separate(self, values: np.ndarray, thorough: bool = True) -> Cuts | None:
        """Cuts at ``values``: subtour rows of an integer point, else the fractional separation."""
        with _Timer(self.stats, "separation_s"):
            if _is_integral(values):
                return subtour_cuts(self.model, values)
            return separate(self.model, values, thorough=thorough)

    # -------------------------------------------------------------- root
    def root(self) -> None:
        """Root LP loop: price columns in, bound, fix by reduced cost, separate."""
        model, lp = self.model, self.lp
        history: list[float] = []
        rounds = 0
        while rounds < self.options.root_rounds and self.left() > 0:
            rounds += 1
            res = self.solve_lp()
            present = np.zeros(model.n_cols, dtype=bool)
            present[lp.cols] = True
            absent = ~present & ~self.fixed
            if res.status == "infeasible" and absent.any():  # the core was too small
                lp.add_cols(np.flatnonzero(absent))
                continue
            if res.values is None or res.duals is None or res.reduced_costs is None:
                break
            values = lp.full(res.values)
            rc = np.zeros(model.n_cols)
            rc[lp.cols] = res.reduced_costs
            rc[absent] = lp.reduced_costs(res.duals, np.flatnonzero(absent))
            bound = res.objective + np.minimum(rc[absent], 0).sum()  # Lagrangian bound
            self.lb = max(self.lb, bound)
            if self.proven:
                break
            fix = (bound + rc > self.ub - self.gap + self.margin) & ~self.fixed
            if fix.any():
                self.fixed |= fix
                lp.fix_zero(np.flatnonzero(fix[lp.cols]))
            price = np.flatnonzero(absent & ~fix & (rc < -_TOL))
            if len(price):  # the most negative columns join; cuts are separated meanwhile
                lp.add_cols(price[np.argsort(rc[price])[:PRICE_PER_NODE * model.n_nodes]])
            else:
                history.append(res.objective)
                if len(history) > 5 and history[-1] - history[-6] < 1e-5 * max(1.0, abs(history[-1])):
                    break  # tailing off
            new = self.separate(values)
            if new is None:
                if not len(price):
                    if _is_integral(values):
                        self.offer(values)  # the LP optimum is a tour: the optimum
                    break
                continue
            lp.purge(values, 3)
            lp.add_cuts(new)
        self.stats["root_rounds"], self.stats["root_bound"] = rounds, float(self.lb)
        self.stats["root_cuts"] = len(lp.cuts)

    def absent(self) -> np.ndarray:
        """Model columns neither in the LP nor fixed to 0."""
        absent = ~self.fixed
        absent[self.lp.cols] = False
        return np.flatnonzero(absent)

    # -------------------------------------------------------------- MILP by the backend
    def native_mip(self) -> None:
        """The backend's own branch and cut, subtour rows added lazily."""
        model, lp = self.model, self.lp
        missing = self.absent()  # every column not fixed joins: the search is exact
        if len(missing):
            lp.add_cols(missing)

        def lazy(v: np.ndarray) -> tuple[sp.csr_array, np.ndarray] | None:
            cuts = subtour_cuts(model, lp.full(v))
            if cuts is None:
                return None
            return sp.csr_array(cuts.matrix(model, lp.cols)), cuts.rhs

        backend = lp.backend
        assert isinstance(backend, LazyMipBackend)
        with _Timer(self.stats, "mip_s"):
            res = backend.solve_mip(self.left(), self.ub - self.gap, self.gap, lazy)
        self.stats.update(res.stats)
        self.lb = max(self.lb, min(res.bound, self.ub))
        if res.values is not None:
            self.offer(lp.full(res.values))
        if res.complete:
            self.lb = max(self.lb, self.ub - self.gap)  # nothing better than ub - gap exists

    # -------------------------------------------------------------- own branch and cut
    def branch_and_cut(self) -> None:
        """Branch and cut with the backend as LP solver: best first, diving into a child.

        Each node runs the root's cut loop; columns not in the LP are priced in while their
        reduced cost is negative (a node is pruned on its Lagrangian bound before that). It
        fixes columns by reduced cost for its subtree and branches on the fractional ``y``
        closest to 1/2 (``y = 1`` fixes a cluster's head), else on such an ``x``. Cuts are
        global; slack ones are purged.
        """
        lp = self.lp
        heap: list[_Node] = []
        free = np.full(len(lp.cols), -1, dtype=np.int8)
        node: _Node | None = _Node(self.lb, 0, free)
        applied = free
        seq = explored = 0
        while node is not None and not self.proven and self.left() > 0:
            if node.bound <= self.ub - self.gap:
                # move the LP's bounds here (columns priced in later are free in older nodes)
                fixes, applied = _padded(node.fixes, len(lp.cols)), _padded(applied, len(lp.cols))
                change = np.flatnonzero(fixes != applied)
                if len(change):
                    code = fixes[change]
                    upper0 = np.where(self.fixed[lp.cols[change]], 0.0, 1.0)
                    lp.backend.set_bounds(change, np.maximum(code, 0).astype(float),
                                          np.where(code < 0, upper0, code).astype(float))
                applied = fixes
                explored += 1
                outcome = self._node_loop()
                if outcome == "stopped":
                    heapq.heappush(heap, node)
                    break
                node = None
                if isinstance(outcome, tuple):
                    bound, col, value, fix = outcome
                    base = _padded(applied, len(lp.cols))
                    base[fix] = 0
                    first, second = (1, 0) if value >= 0.5 else (0, 1)
                    children = []
                    for v in (first, second):
                        child = base.copy()
                        child[col] = v
                        children.append(child)
                    seq += 2
                    heapq.heappush(heap, _Node(bound, seq, children[1]))
                    node = _Node(bound, seq - 1, children[0])  # dive
            else:
                node = None
            if node is None and heap:
                node = heapq.heappop(heap)
            # the global bound: the best open node (the incumbent's when none is open)
            best_open = min(heap[0].bound if heap else math.inf,
                            node.bound if node is not None else math.inf)
            self.lb = max(self.lb, min(best_open, self.ub - self.gap))
        self.stats["bc_nodes"] = explored

    def _node_loop(self) -> tuple[float, int, float, np.ndarray] | str | None:
        """Cut loop at a node: ``None`` when pruned, ``"stopped"`` at the time limit, else
        (bound, backend column and its value to branch on, backend columns fixed by reduced
        cost in the subtree)."""
        lp = self.lp
        history: list[float] = []
        while self.left() > 0:
            absent = self.absent()
            # with columns absent, only the Lagrangian bound (below) may prune: no LP cutoff
            res = self.solve_lp(cutoff=self.ub - self.gap if len(absent) == 0 else math.inf)
            if res.status in ("infeasible", "cutoff"):
                return None
            if res.values is None or res.reduced_costs is None or res.duals is None:
                return "stopped"
            values = lp.full(res.values)
            if len(absent):
                rc = lp.reduced_costs(res.duals, absent)
                if res.objective + np.minimum(rc, 0).sum() > self.ub - self.gap:
                    return None
                price = rc < -_TOL
                if price.any():
                    if _is_integral(values) and subtour_cuts(self.model, values) is None:
                        self.offer(values)
                    lp.add_cols(absent[price][np.argsort(rc[price])[:PRICE_PER_NODE * self.model.n_nodes]])
                    continue
            if res.objective > self.ub - self.gap:
                return None
            history.append(res.objective)
            tailing = len(history) > 3 and history[-1] - history[-4] < 1e-4 * max(1.0, abs(history[-1]))
            new = None if tailing and not _is_integral(values) else self.separate(values, False)
            if new is None:
                if _is_integral(values):
                    self.offer(values)
                    return None
                rc = res.reduced_costs
                fix = np.flatnonzero((res.objective + rc > self.ub - self.gap + self.margin)
                                     & (res.values < _TOL))
                return res.objective, *self._branching(res.values), fix
            lp.purge(values, 10)
            lp.add_cuts(new)
        return "stopped"

    def _branching(self, values: np.ndarray) -> tuple[int, float]:
        """Backend column to branch on and its value: the fractional y closest to 1/2, else x."""
        is_y = self.lp.cols < self.model.n_nodes
        frac = np.abs(values - np.round(values)) > 1e-6
        for group in (is_y, ~is_y):
            cand = np.flatnonzero(group & frac)
            if len(cand):
                col = int(cand[np.argmin(np.abs(values[cand] - 0.5))])
                return col, float(values[col])
        raise AssertionError("no fractional column to branch on")


def solve_exact(
    problem: Problem,
    make_backend: Callable[[MipOptions], Backend],
    options: MipOptions,
    *,
    time_limit: float | None = None,
    seed: int = 0,
) -> Solution:
    """Solve a priced GTSP to proven optimality (or until ``time_limit`` seconds).

    Parameters
    ----------
    problem
        The priced problem (symmetric edge costs).
    make_backend
        Builds an empty backend.
    options
        Shared options.
    time_limit
        Seconds for the whole solve (``None``: no limit).
    seed
        Seed of the upper-bound heuristic.

    Returns
    -------
    Solution
        Status ``"optimal"`` with ``lower_bound`` when proven, else ``"time_limit"`` with the best
        tour and the best lower bound known (at least :func:`degree_bound`). ``stats`` has seconds per
        phase, rounds, cuts and backend counters.
    """
    check_symmetric(problem)
    start = time.perf_counter()
    deadline = math.inf if time_limit is None else start + time_limit
    stats: dict[str, Any] = {}

    def result(tour: np.ndarray, status: str, lower: float) -> Solution:
        order, heads = problem.to_solution(tour)
        cost = problem.tour_cost(tour)
        stats["total_s"] = time.perf_counter() - start
        # reduced-cost fixing drops solutions no better than the incumbent, so a bound above
        # the incumbent's cost only says that it is optimal
        bound = None if lower == -math.inf else min(float(lower), cost)
        return Solution(order, heads, objective=cost, status=status, lower_bound=bound, stats=stats)

    if problem.n_clusters <= 3:  # one cyclic order: its optimal heads are the optimum
        tour, cost = optimal_heads(problem, list(range(problem.instance.n_clusters)))
        return result(tour, "optimal", cost)
    with _Timer(stats, "heuristic_s"):
        tour = upper_bound_tour(problem, options.lns_trials, seed,
                                None if time_limit is None else 0.25 * time_limit)
    with _Timer(stats, "prune_s"):
        kept = prune_heads(problem, deadline=deadline) if options.prune else problem.clusters
    search = _Search(problem, make_backend(options), options, deadline, tour, kept, stats)
    search.root()
    if not search.proven and search.left() > 0:
        if isinstance(search.lp.backend, LazyMipBackend):
            search.native_mip()
        else:
            search.branch_and_cut()
    stats["lp_cols"], stats["cuts"] = len(search.lp.cols), len(search.lp.cuts)
    lower = search.lb
    if search.model.integral_costs and math.isfinite(lower):
        lower = math.ceil(lower - 1e-7)  # every tour costs an integer
    return result(search.tour, "optimal" if search.proven else "time_limit", lower)


class MipSolver:
    """The exact MILP solver on one backend; subclasses name the backend (``milp``, ``gurobi``).

    Parameters
    ----------
    prune
        Remove dominated candidate heads first (exact).
    lns_trials
        Trials of the large neighbourhood search giving the first upper bound (0: greedy and
        local search only).
    root_rounds
        Most rounds of the root LP loop (0: no root cuts).
    core_edges
        Cheapest edges per node in the first LP (0: all edges).
    abs_gap
        Absolute gap under which the optimum counts as proven.
    verbose
        Print the backend's log.
    """

    def __init__(self, prune: bool = True, lns_trials: int = 1, root_rounds: int = 200,
                 core_edges: int = 10, abs_gap: float = 1e-6, verbose: bool = False) -> None:
        self.options = MipOptions(prune=prune, lns_trials=lns_trials, root_rounds=root_rounds,
                                  core_edges=core_edges, abs_gap=abs_gap, verbose=verbose)

    def backend(self, options: MipOptions) -> Backend:
        """A new, empty backend."""
        raise NotImplementedError

    def solve(
        self, instance: Instance, omega: float | None, *, time_limit: float | None = None,
        seed: int = 0,
    ) -> Solution:
        """Solve to proven optimality, or return the best tour and bound at ``time_limit``."""
        return solve_exact(price(instance, omega), self.backend, self.options,
                           time_limit=time_limit, seed=seed)

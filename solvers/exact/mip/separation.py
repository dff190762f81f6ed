"""Cut rows and their separation: subtour rows of an integer point, generalized subtour cuts by
max-flow, node-cluster rows and blossoms at a fractional one.

Every cut is ``x(E(side)) + sum_i a_i y_i <= b`` (a blossom sums ``x(E(side))`` over its handle
and teeth); a :class:`Cuts` block stores sides, ``a`` and ``b`` and turns them into matrix rows
over any columns of a :class:`~gtsp_bench.solvers.exact.mip.model.GtspModel`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from gtsp_bench.solvers.exact.mip import flow
from gtsp_bench.solvers.exact.mip.model import TOL, ZERO, GtspModel
from scipy.sparse.csgraph import breadth_first_order, connected_components

#: Capacities are scaled to integers for scipy's max-flow.
_FLOW_SCALE = 1_000_000
#: Up to this many nodes :meth:`Cuts.dual_weights` takes the dense node x node product (8 ms a
#: call at 89pcb442, 432 nodes, one BLAS thread; the split form 5.5 ms): its sums in their own
#: order keep the searches of GTSPLIB to 442 nodes and UAV K = 20 as they were (in the split
#: form's order, the branch and cut of 89pcb442, 45ts225 and 31pr152 took 6-24 % longer).
DENSE_NODES = 500


@dataclass(frozen=True)
class Cuts:
    """Cut rows ``sum_{k: row_k = r} x(E(side_k)) + ycoef_r . y <= rhs_r``.

    Most rows have one side; a blossom has its handle and each tooth as sides. A side may be
    written over the edges crossing it instead (``cross``): with the degree rows ``x(delta(i)) =
    2 y_i``, ``x(E(S)) = y(S) - x(delta(S)) / 2``, so the side contributes ``-x(delta(S)) / 2``
    and ``y(S)`` is part of ``ycoef`` (the same row on the LP's feasible set; fewer nonzeros when
    ``S`` holds many of the LP's edges, see :meth:`sparsest`).

    Attributes
    ----------
    side
        ``(S, n_nodes)`` bool: the edges with both ends in ``side_k`` get coefficient 1 in row
        ``row[k]`` (summed over a row's sides), or with ``cross[k]``, the edges with one end in
        it get -1/2.
    row
        ``(S,)`` row of each side.
    ycoef
        ``(R, n_nodes)`` coefficients of the y columns.
    rhs
        ``(R,)`` right-hand sides.
    cross
        ``(S,)`` bool: the side is written over its crossing edges (``None``: none is).
    """

    side: np.ndarray
    row: np.ndarray
    ycoef: np.ndarray
    rhs: np.ndarray
    cross: np.ndarray = None  # type: ignore[assignment]  # set in __post_init__

    def __post_init__(self) -> None:
        if self.cross is None:
            object.__setattr__(self, "cross", np.zeros(len(self.row), dtype=bool))

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
                    np.array([float(rhs)]), np.zeros(len(sides), dtype=bool))

    @staticmethod
    def stack(blocks: Sequence[Cuts]) -> Cuts:
        """All cuts in one block."""
        offsets = np.cumsum([0] + [len(b) for b in blocks[:-1]])
        return Cuts(np.concatenate([b.side for b in blocks]),
                    np.concatenate([b.row + o for b, o in zip(blocks, offsets, strict=True)]),
                    np.concatenate([b.ycoef for b in blocks]), np.concatenate([b.rhs for b in blocks]),
                    np.concatenate([b.cross for b in blocks]))

    def select(self, mask: np.ndarray) -> Cuts:
        """The cuts where ``mask`` (one entry per row) is true."""
        renumber = np.cumsum(mask) - 1
        keep = mask[self.row]
        return Cuts(self.side[keep], renumber[self.row[keep]], self.ycoef[mask], self.rhs[mask],
                    self.cross[keep])

    def _edge_coef(self, sides: np.ndarray, tails: np.ndarray, heads: np.ndarray) -> np.ndarray:
        """Coefficients ``(len(sides), len(tails))`` of edges ``(tails, heads)`` per side
        (indices into the sides)."""
        s = self.side[sides]
        st, sh = s[:, tails], s[:, heads]
        cross = self.cross[sides]
        if not cross.any():
            return st & sh
        return np.where(cross[:, None], -0.5 * (st ^ sh), st & sh)

    def sparsest(self, model: GtspModel, cols: np.ndarray) -> Cuts:
        """The same rows, each side (not yet crossing) written over its crossing edges where that
        has fewer nonzeros over columns ``cols`` (its inside edges against its crossing edges and
        the y entries it adds)."""
        n = model.n_nodes
        es = cols[cols >= n] - n
        inside, crossing = flow.side_edges(self.side, model.tail[es], model.head[es])
        y_now = self.ycoef[self.row] != 0
        y_after = (self.ycoef[self.row] + self.side) != 0
        extra = y_after.sum(axis=1) - y_now.sum(axis=1)
        turn = ~self.cross & (crossing + extra < inside)
        if not turn.any():
            return self
        ycoef = self.ycoef.copy()
        np.add.at(ycoef, self.row[turn], self.side[turn].astype(float))
        return Cuts(self.side, self.row, ycoef, self.rhs, self.cross | turn)

    def _per_row(self, per_side: np.ndarray) -> np.ndarray:
        """Sum ``per_side`` (first axis: sides) over each row's sides."""
        if len(self.row) == len(self) and np.array_equal(self.row, np.arange(len(self))):
            return per_side
        # a sparse sum (``np.add.at`` over a sides x columns matrix took 0.1 s a call at K = 100)
        rows = sp.csr_array((np.ones(len(self.row)), (self.row, np.arange(len(self.row)))),
                            shape=(len(self), len(self.row)))
        return np.asarray(rows @ per_side.astype(float))

    def matrix(self, model: GtspModel, cols: np.ndarray) -> np.ndarray:
        """Dense ``(R, len(cols))`` coefficients over columns ``cols``."""
        n = model.n_nodes
        is_y = cols < n
        out = np.empty((len(self), len(cols)))
        out[:, is_y] = self.ycoef[:, cols[is_y]]
        es = cols[~is_y] - n
        every = np.arange(len(self.row))
        out[:, ~is_y] = self._per_row(self._edge_coef(every, model.tail[es], model.head[es]))
        return out

    def sparse(self, model: GtspModel, cols: np.ndarray) -> sp.csr_array:
        """:meth:`matrix` as a sparse array (its entries found by :func:`flow.cut_rows`, never a
        dense ``(R, len(cols))`` array: all the columns of 217vm1084, 587,000, took more than 24
        GiB that way)."""
        indptr, indices, data = flow.cut_rows(self.side, self.row, self.cross, self.ycoef,
                                              np.asarray(cols, dtype=np.int64), model.tail, model.head)
        return sp.csr_array((data, indices, indptr), shape=(len(self), len(cols)))

    def slack(self, model: GtspModel, values: np.ndarray) -> np.ndarray:
        """``rhs - lhs`` at a full column vector (negative: violated)."""
        y, x = model.split(values)
        # x(E(side)) over the support only (an LP point has a few edges per node, the model up
        # to millions: over every edge this took 3.7 s a call at K = 100)
        sup = np.flatnonzero(x)
        inside = self._edge_coef(np.arange(len(self.row)), model.tail[sup], model.head[sup]) @ x[sup]
        return self.rhs - self._per_row(inside) - self.ycoef @ y

    def dual_weights(
        self, model: GtspModel, duals: np.ndarray, edges: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """For row duals ``duals``: the dual weight on each of ``edges`` and on each y column.

        With many edges (and more than :data:`DENSE_NODES` nodes), each side is split into the
        clusters it holds whole (``W``) and its other nodes (``P``, a few at most in most cuts).
        The weight of edge ``(i, j)``, ``sum_k d_k s_k[i] s_k[j]`` less half the crossing sides'
        duals at ``i`` and at ``j``, is then a clusters x clusters product (``W W``), a nodes x
        clusters one (``W P``, the halves added) and a sparse one over the few node pairs in a
        ``P`` (``P P``), summed per edge by
        :func:`~gtsp_bench.solvers.exact.mip.flow.edge_weights`. At UAV K = 200 (3,663 nodes,
        2,756 sides with a dual, 6,135 of their nodes outside whole clusters) the dense ``(n,
        n)`` product over nodes took 2.8 s a call, this 0.4 s.
        """
        nz = np.flatnonzero(np.abs(duals[self.row]) > 1e-12)
        rows = np.flatnonzero(np.abs(duals) > 1e-12)
        on_y = duals[rows] @ self.ycoef[rows]
        d = duals[self.row[nz]]
        if len(edges) * len(nz) < model.n_nodes**2 * 4:  # few edges: side by side
            return d @ self._edge_coef(nz, model.tail[edges], model.head[edges]), on_y
        if model.n_nodes <= DENSE_NODES:  # (n, n): duals of the sides holding i and j
            sf = self.side[nz].astype(float)
            pair = (sf * d[:, None]).T @ sf
            cross = self.cross[nz]  # a crossing side's -1/2 (s_i + s_j) + s_i s_j
            half = -0.5 * (d[cross] @ sf[cross]) if cross.any() else np.zeros(model.n_nodes)
            t, h = model.tail[edges], model.head[edges]
            return pair[t, h] + half[t] + half[h], on_y
        sides, cl = self.side[nz], model.cluster
        starts = np.flatnonzero(np.r_[True, cl[1:] != cl[:-1]])
        whole = np.logical_and.reduceat(sides, starts, axis=1)  # (sides, clusters)
        indptr, indices = flow.loose_nodes(sides, whole, cl)
        part = sp.csr_array((np.ones(len(indices), dtype=bool), indices, indptr),
                            shape=sides.shape)  # (sides, nodes): nodes outside whole clusters
        wd = whole * d[:, None]
        pair = wd.T @ whole.astype(float)  # W W
        node_cluster = np.ascontiguousarray(part.T @ wd) if part.nnz else np.zeros((len(cl), len(starts)))
        cross = self.cross[nz]
        if cross.any():  # the crossing sides' -1/2 at each end: one end's at each (node, cluster)
            node_cluster += (-0.5 * (d[cross] @ sides[cross]))[:, None]
        extra = np.zeros(0)
        pp = sp.coo_array(part.T @ sp.csr_array(part.multiply(d[:, None])))  # P P
        a, b = pp.coords
        on = (a < b) & (cl[a] != cl[b])
        if on.any():
            extra = np.zeros(len(model.tail))
            np.add.at(extra, model.edge_ids(a[on], b[on]), pp.data[on])
        return flow.edge_weights(np.asarray(edges, dtype=np.int64), model.tail, model.head, cl,
                                 pair, node_cluster, extra), on_y


def subtour_cuts(model: GtspModel, values: np.ndarray) -> Cuts | None:
    """Cuts removing an integer solution with subtours (``None`` if it is one tour).

    For every cycle but the largest, with ``W`` the clusters it visits and ``S`` all candidate
    heads of ``W``: ``x(E(S)) <= |W| - 1``.

    Parameters
    ----------
    model
        The model.
    values
        An integer point (a full model column vector).

    Returns
    -------
    Cuts or None
        One row per cycle but the largest, smallest cycle first.
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

    Parameters
    ----------
    model
        The model.
    values
        A point (a full model column vector).

    Returns
    -------
    Cuts or None
        Every violated row, by node then cluster; ``None`` when none is.
    """
    y, x = model.split(values)
    n, m = model.n_nodes, model.n_clusters
    sup = np.flatnonzero(x)  # (over every edge this took 0.6 s a call at UAV K = 200)
    t, h = model.tail[sup], model.head[sup]
    key = np.concatenate([t, h]) * m + np.concatenate([model.cluster[h], model.cluster[t]])
    load = np.bincount(key, weights=np.concatenate([x[sup], x[sup]]), minlength=n * m)
    viol = np.flatnonzero(load - np.repeat(y, m) > TOL)
    if len(viol) == 0:
        return None
    node, other = viol // m, viol % m
    r = np.arange(len(viol))
    side = model.cluster[None, :] == other[:, None]
    side[r, node] = True
    ycoef = np.zeros((len(viol), n))
    ycoef[r, node] = -1.0
    return Cuts(side, r, ycoef, np.zeros(len(viol)))


def subtour_cut(model: GtspModel, sink_side: np.ndarray, c: int, d: int | None = None) -> Cuts:
    """``Subtour(S, C, D)`` for ``S = sink_side``, over the side with fewer inside edges.

    The generalized subtour inequality ``x(delta(S)) >= 2 (y(S & C) + y(D - S) - 1)`` for any
    node set ``S`` and clusters ``C != D`` (a tour with its heads of ``C`` inside and of ``D``
    outside crosses ``S`` twice). With the degree rows, over ``S``: ``x(E(S)) - y(S - C) -
    y(S & D) <= 0`` (when ``S`` holds all of ``C``: ``x(E(S)) - y(S) - y(S & D) <= -1``); over
    ``T = V - S``: ``x(E(T)) - y(T) - y(T & C) + y(T & D) <= 0`` (when ``T`` holds all of ``D``:
    ``x(E(T)) - y(T) - y(T & C) <= -1``). When ``S`` misses a whole cluster ``D`` this is
    ``x(delta(S)) >= 2 y(S & C)``.

    Parameters
    ----------
    model
        The model.
    sink_side
        ``(n_nodes,)`` bool mask of ``S``.
    c
        The cluster ``C``.
    d
        The cluster ``D`` (``None``: ``S`` must miss a whole cluster, which is taken).

    Returns
    -------
    Cuts
        One row.
    """
    m = model.n_clusters
    s, t = sink_side, ~sink_side
    in_s = np.bincount(model.cluster[s], minlength=m)
    if d is None:
        d = int(np.flatnonzero(in_s == 0)[0])
    in_c, in_d = model.cluster == c, model.cluster == d
    # edges with both ends in a side: its node pairs minus those inside one cluster
    in_t = np.bincount(model.cluster[t], minlength=m)
    edges_s = int(in_s.sum()) ** 2 - int((in_s**2).sum())
    edges_t = int(in_t.sum()) ** 2 - int((in_t**2).sum())
    if edges_s <= edges_t:
        both = -(s & in_d).astype(float)
        if not (in_c & t).any():
            return Cuts.one(s, both - s, -1.0)
        return Cuts.one(s, both - (s & ~in_c), 0.0)
    if not (in_d & s).any():
        return Cuts.one(t, -t.astype(float) - (t & in_c), -1.0)
    return Cuts.one(t, -t.astype(float) - (t & in_c) + (t & in_d), 0.0)


@dataclass(frozen=True)
class _Network:
    """A flow network laid out once as CSR, every arc with its reverse arc also present.

    Attributes
    ----------
    indptr, indices
        CSR structure over ``size`` nodes (rows sorted by column).
    row
        Tail node of each arc (CSR position).
    rev
        CSR position of each arc's reverse.
    """

    indptr: np.ndarray
    indices: np.ndarray
    row: np.ndarray
    rev: np.ndarray

    @staticmethod
    def build(tails: np.ndarray, heads: np.ndarray, size: int) -> tuple[_Network, np.ndarray]:
        """The network of arcs ``tails -> heads`` and their reverses (none may be given twice);
        also the CSR position of each given arc."""
        rows, cols = np.concatenate([tails, heads]), np.concatenate([heads, tails])
        order = np.lexsort((cols, rows))
        where = np.empty(len(order), dtype=np.int64)
        where[order] = np.arange(len(order))
        g = len(tails)
        rev = np.empty(len(order), dtype=np.int64)
        rev[where] = where[np.concatenate([np.arange(g, 2 * g), np.arange(g)])]
        indptr = np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=size))]).astype(np.int64)
        return _Network(indptr, cols[order].astype(np.int64), rows[order].astype(np.int64), rev), where[:g]

    def min_cut_sides(self, cap: np.ndarray, source: int, sink: int) -> tuple[float, list[np.ndarray]]:
        """Max-flow value for capacities ``cap`` (per CSR position) and the sink sides of the
        two extreme minimum cuts (masks over nodes)."""
        value, f = flow.max_flow(self.indptr, self.indices, self.row, self.rev, cap, source, sink)
        residual = cap - f
        from_source = flow.reach(self.indptr, self.indices, self.rev, residual, source, False)
        to_sink = flow.reach(self.indptr, self.indices, self.rev, residual, sink, True)
        return float(value), [~from_source, to_sink]


def _best_pair(share: np.ndarray) -> tuple[int, int, float]:
    """Clusters ``C != D`` maximising ``y(S & C) - y(D & S)`` for ``share[k] = y(S & k)``."""
    order = np.argsort(share, kind="stable")
    hi, lo = int(order[-1]), int(order[0])
    return hi, lo, float(share[hi] - share[lo])


def flow_cuts(model: GtspModel, values: np.ndarray, deadline: float = math.inf) -> Cuts | None:
    """Violated generalized subtour cuts at a fractional solution, one max-flow per cluster.

    On the support graph (nodes with ``y > 0``; edges carry ``x_e`` both ways), for cluster
    ``C`` the nodes of a source cluster ``D`` (the one with the largest ``y``, the depot when
    there is one) are tied to the source and those of ``C`` to the sink, each with capacity
    ``2 y_i``. A cut of value ``x(delta(S)) + 2 y(C - S) + 2 y(D & S)`` below 2 (``S`` the sink
    side) is a violated ``Subtour(S, C, D)``: the separation is exact for that pair. From both
    extreme minimum cuts, the pair ``C, D`` most violated for ``S`` is taken and ``S`` is lifted:
    nodes with ``y = 0`` have no edges at the point, so those of ``C`` and of clusters whose
    chosen nodes all lie in ``S`` join ``S``.

    Parameters
    ----------
    model
        The model.
    values
        A fractional point (a full model column vector).
    deadline
        ``time.perf_counter()`` time after which no further max-flow starts.

    Returns
    -------
    Cuts or None
        The cuts still violated, cluster by cluster (each ``S, C, D`` once); ``None`` when none is.
    """
    y, x = model.split(values)
    n, m = model.n_nodes, model.n_clusters
    on = np.flatnonzero(y > ZERO)
    k = len(on)
    local = np.full(n, -1)
    local[on] = np.arange(k)
    sup = (x > ZERO) & (local[model.tail] >= 0) & (local[model.head] >= 0)
    a, b, xs = local[model.tail[sup]], local[model.head[sup]], x[sup]
    clus, ys = model.cluster[on], y[on]
    src, snk = k, k + 1
    # support edges both ways, source -> node and node -> sink (capacities set per cluster),
    # laid out once so that each max-flow only swaps the capacities
    net, where = _Network.build(np.concatenate([a, np.full(k, src), np.arange(k)]),
                                np.concatenate([b, np.arange(k), np.full(k, snk)]), k + 2)
    e = len(a)
    base = np.zeros(len(net.indices), dtype=np.int64)
    base[where[:e]] = base[net.rev[where[:e]]] = np.round(xs * _FLOW_SCALE).astype(np.int64)
    at_src, at_snk = where[e:e + k], where[e + k:]
    ycap = np.round(2 * ys * _FLOW_SCALE).astype(np.int64)
    top = np.zeros(m)
    np.maximum.at(top, clus, ys)
    found: list[Cuts] = []
    seen: set[bytes] = set()
    for c in np.unique(clus):
        if time.perf_counter() > deadline:
            break
        in_c = np.flatnonzero(clus == c)
        others = top.copy()
        others[c] = -1.0
        d = int(np.argmax(others))
        in_d = np.flatnonzero(clus == d)
        cap = base.copy()
        cap[at_src[in_d]] = ycap[in_d]
        cap[at_snk[in_c]] = ycap[in_c]
        value, sides = net.min_cut_sides(cap, src, snk)
        if value >= (2 - TOL) * _FLOW_SCALE:
            continue
        for side in sides:
            s = side[:k]
            if not s.any() or s.all():
                continue
            share = np.bincount(clus, weights=np.where(s, ys, 0.0), minlength=m)
            hi, lo, diff = _best_pair(share)
            if 2 * diff - xs[s[a] != s[b]].sum() <= TOL:
                continue
            full = np.zeros(n, dtype=bool)
            full[on[s]] = True
            full |= (y <= ZERO) & ((model.cluster == hi) | (share[model.cluster] >= 1 - ZERO))
            full &= ~((model.cluster == lo) & (y <= ZERO))
            s = full[on]  # (unchanged but for nodes of y at most ZERO)
            if 2 * (share[hi] - share[lo]) - xs[s[a] != s[b]].sum() <= TOL:
                continue
            key = bytes(np.packbits(full)) + hi.to_bytes(4, "little") + lo.to_bytes(4, "little")
            if key not in seen:
                seen.add(key)
                found.append(subtour_cut(model, full, hi, lo))
    return Cuts.stack(found) if found else None


#: Largest handle grown from one cluster by :func:`blossom_cuts` (clusters).
MAX_HANDLE = 40


def _best_teeth(z: np.ndarray, handle: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """The odd tooth set ``F`` (edges leaving ``handle``) of the most violated blossom.

    ``z(delta(H) - F) + sum_F (1 - z_e) >= 1`` for every odd ``F`` (a tour crosses ``H`` an even
    number of times); ``F`` takes the edges with ``z_e > 1/2``, parity mended by the edge whose
    ``z_e`` is closest to 1/2. Returns the violation (positive: violated;
    computed by :func:`flow.teeth_violation`) and ``F``'s ends.
    """
    violation, mend_i, mend_j = flow.teeth_violation(z, handle)
    teeth = (z > 0.5) & handle[:, None] & ~handle[None, :]
    if mend_i >= 0:
        teeth[mend_i, mend_j] = not teeth[mend_i, mend_j]
    inner, outer = np.nonzero(teeth)
    return violation, inner, outer


def blossom_cuts(model: GtspModel, values: np.ndarray, grow: bool = True,
                 deadline: float = math.inf) -> Cuts | None:
    """Violated blossoms of the tour over clusters: handles grown along the fractional ``z``.

    ``z_CD = x(C : D)`` is a Hamiltonian cycle over the clusters, so the 2-matching (blossom)
    inequalities of the TSP hold for it: for a handle ``H`` (clusters) and an odd set ``F`` of
    cluster pairs with one end in ``H`` (edge teeth; a tour crosses ``H`` an even number of
    times, so they need not be disjoint), ``z(E(H)) + z(F) <= |H| + (|F| - 1) / 2``. Handles
    tried: each connected component of the fractional ``z`` and, with ``grow``, the
    breadth-first prefixes (3 clusters up to :data:`MAX_HANDLE`, and less than the component) of
    the component grown from each of its clusters; teeth by :func:`_best_teeth`. Half-integral
    root points, whose fractional edges form one large component with an even number of 1-edges
    leaving it, need the prefixes; they cost tens of milliseconds a call, so the branch and cut
    (31pr152: more nodes, a better bound in 120 s without them) leaves them out.

    Parameters
    ----------
    model
        The model.
    values
        A fractional point (a full model column vector).
    grow
        Also try the grown handles.
    deadline
        ``time.perf_counter()`` time after which no further handle is tried.

    Returns
    -------
    Cuts or None
        One row per violated blossom (sides: the handle, then each tooth); ``None`` when none is.
    """
    _, x = model.split(values)
    m = model.n_clusters
    z = np.zeros((m, m))
    sup = np.flatnonzero(x)  # (over every edge, ``np.add.at`` took 0.1 s a call at K = 100)
    np.add.at(z, (model.cluster[model.tail[sup]], model.cluster[model.head[sup]]), x[sup])
    z += z.T
    frac = (z > TOL) & (z < 1 - TOL)
    graph = sp.csr_array(frac.astype(float))
    n_comp, label = connected_components(graph, directed=False)
    found = []
    seen: set[bytes] = set()
    for comp in range(n_comp):
        members = np.flatnonzero(label == comp)
        if len(members) < 2:
            continue
        handles = [label == comp]
        for start in members if grow else ():
            order = breadth_first_order(graph, int(start), directed=False, return_predecessors=False)
            for size in range(3, min(len(order), MAX_HANDLE + 1)):
                h = np.zeros(m, dtype=bool)
                h[order[:size]] = True
                handles.append(h)
        for handle in handles:
            if handle.all() or time.perf_counter() > deadline:
                continue
            key = bytes(np.packbits(handle))
            if key in seen:
                continue
            seen.add(key)
            if flow.teeth_violation(z, handle)[0] <= TOL:  # (compiled: tens of thousands a round)
                continue
            violation, inner, outer = _best_teeth(z, handle)
            if violation > TOL:
                sides = [np.isin(model.cluster, np.flatnonzero(handle))]
                sides += [np.isin(model.cluster, [i, j]) for i, j in zip(inner, outer, strict=True)]
                found.append(Cuts.one(np.array(sides), np.zeros(model.n_nodes),
                                      handle.sum() + (len(inner) - 1) / 2))
    return Cuts.stack(found) if found else None


def separate(model: GtspModel, values: np.ndarray, *, thorough: bool = True,
             deadline: float = math.inf) -> Cuts | None:
    """Violated cuts at an LP solution: node-cluster rows and blossoms (cheap), then max-flow.

    Parameters
    ----------
    model
        The model.
    values
        A fractional point (a full model column vector).
    thorough
        Run the max-flows always and grow blossom handles (the root); when false (branch and cut
        nodes), max-flows only if the cheap families find nothing, blossom handles not grown.
    deadline
        ``time.perf_counter()`` time after which the max-flows and blossom handles stop (the
        cuts found by then are returned).

    Returns
    -------
    Cuts or None
        Node-cluster rows, then blossoms, then flow cuts; ``None`` when none is violated.
    """
    found = [c for c in (node_cluster_cuts(model, values),
                         blossom_cuts(model, values, thorough, deadline)) if c is not None]
    if thorough or not found:
        flows = flow_cuts(model, values, deadline)
        if flows is not None:
            found.append(flows)
    return Cuts.stack(found) if found else None

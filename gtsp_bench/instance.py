"""The common instance format: clusters of 2-D nodes, an optional depot, and how edges are priced.

An :class:`Instance` is what a file holds. Two kinds share it:

* a UAV instance (``params`` is an :class:`~gtsp_bench.params.EnergyParams`): nodes are IoT
  devices in metres, the depot is the base station, and the energy model prices it for a weight
  ``omega`` (see :mod:`gtsp_bench.energy`);
* a distance-only GTSP (``params is None``), e.g. a GTSPLIB file: edge weights follow the TSPLIB95
  rule named by ``edge_weight_type`` and there are no node costs.

Nodes are numbered globally in cluster order (cluster 0's nodes first); a solution names, for each
cluster, the index of its head *inside* that cluster.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from types import MappingProxyType
from typing import Any

import numpy as np

from gtsp_bench.checks import check_memory, is_int
from gtsp_bench.errors import InfeasibleSolutionError, InputError
from gtsp_bench.params import EnergyParams

#: Edge-weight rules: exact Euclidean (UAV instances) and the TSPLIB95 rules GTSPLIB uses.
EDGE_WEIGHT_TYPES = ("EUCLIDEAN", "EUC_2D", "CEIL_2D", "ATT", "GEO", "GEOM", "EXPLICIT")


def _frozen_array(a: Any, dtype: type = np.float64) -> np.ndarray:
    arr = np.array(a, dtype=dtype)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Instance:
    """An immutable GTSP instance.

    Parameters
    ----------
    name
        Instance name.
    clusters
        One ``(N_k, 2)`` array of node coordinates per cluster (sizes may differ).
    depot
        ``(2,)`` coordinates of the depot (base station) where the tour starts and ends, or
        ``None`` for a closed tour without a depot.
    params
        Energy parameters for a UAV instance, or ``None`` for a distance-only GTSP.
    edge_weight_type
        ``"EUCLIDEAN"`` (exact distances, required for UAV instances) or a TSPLIB95 rule.
    weights
        For ``"EXPLICIT"`` only: the full ``(n, n)`` weight matrix in global node order;
        ``weights[i, j]`` is the cost of going from node i to node j.
    meta
        Free-form metadata (seed, generator settings, source file, ...).
    symmetric
        ``False`` for an asymmetric GTSP (a GTSPLIB ``TYPE : AGTSP`` file): only then may the
        (``"EXPLICIT"``) weight matrix differ from its transpose, and a tour is priced in its
        direction. A symmetric instance's matrix must equal its transpose exactly.
    """

    name: str
    clusters: tuple[np.ndarray, ...]
    depot: np.ndarray | None = None
    params: EnergyParams | None = field(default_factory=EnergyParams)
    edge_weight_type: str = "EUCLIDEAN"
    weights: np.ndarray | None = None
    meta: Mapping[str, Any] = field(default_factory=dict)
    symmetric: bool = True

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise InputError("instance name must be a non-empty string")
        if self.edge_weight_type not in EDGE_WEIGHT_TYPES:
            raise InputError(
                f"unknown edge weight type {self.edge_weight_type!r} "
                f"(valid: {', '.join(EDGE_WEIGHT_TYPES)})"
            )
        if self.params is not None and self.edge_weight_type != "EUCLIDEAN":
            raise InputError("a UAV instance (with energy parameters) must use EUCLIDEAN distances")
        explicit = self.edge_weight_type == "EXPLICIT"
        if len(self.clusters) == 0:
            raise InputError("an instance needs at least one cluster")
        arrays = []
        for k, pts in enumerate(self.clusters):
            arr = np.asarray(pts, dtype=np.float64)
            if arr.size == 0:
                raise InputError(f"cluster {k} is empty")
            if arr.ndim != 2 or arr.shape[1] != 2:
                raise InputError(f"cluster {k} must be a list of [x, y] pairs")
            arrays.append(arr)
        # One copy the instance owns (read-only); the clusters are views of it, in order.
        coords = np.concatenate(arrays)
        if not explicit and not np.all(np.isfinite(coords)):
            bad = np.flatnonzero(~np.isfinite(coords).all(axis=1))[0]
            k = int(np.searchsorted(np.cumsum([len(a) for a in arrays]), bad, side="right"))
            raise InputError(f"cluster {k} has a NaN or infinite coordinate")
        coords.setflags(write=False)
        ends = np.cumsum([len(a) for a in arrays])[:-1]
        object.__setattr__(self, "clusters", tuple(np.split(coords, ends)))
        self.__dict__["coords"] = coords  # the cached property, already at hand
        if self.depot is not None:
            depot = _frozen_array(self.depot)
            if depot.shape != (2,):
                raise InputError("depot must be a pair [x, y]")
            if not np.all(np.isfinite(depot)):
                raise InputError("depot has a NaN or infinite coordinate")
            object.__setattr__(self, "depot", depot)
        if explicit:
            if self.weights is None:
                raise InputError("EXPLICIT edge weights need a weight matrix")
            if self.depot is not None:
                raise InputError("EXPLICIT edge weights do not support a depot")
            w = _frozen_array(self.weights)
            n = self.n_nodes
            if w.shape != (n, n):
                raise InputError(f"weight matrix must be {n} x {n}, got {w.shape}")
            if not np.all(np.isfinite(w)):
                raise InputError("weight matrix has a NaN or infinite entry")
            if self.symmetric and not np.array_equal(w, w.T):
                raise InputError("weight matrix is not symmetric (an asymmetric instance says "
                                 "symmetric=False; in a GTSPLIB file, TYPE : AGTSP)")
            object.__setattr__(self, "weights", w)
        elif self.weights is not None:
            raise InputError("a weight matrix is only allowed with EXPLICIT edge weights")
        if self.symmetric is not True:
            if self.symmetric is not False:
                raise InputError(f"symmetric must be True or False, got {self.symmetric!r}")
            if not explicit:
                raise InputError("only EXPLICIT edge weights can be asymmetric")
        object.__setattr__(self, "meta", MappingProxyType(dict(self.meta)))

    # ------------------------------------------------------------------ shape
    @property
    def n_clusters(self) -> int:
        """K, the number of clusters (the depot not counted)."""
        return len(self.clusters)

    @cached_property
    def sizes(self) -> np.ndarray:
        """Number of nodes of each cluster, ``(K,)``."""
        return _frozen_array([len(c) for c in self.clusters], np.int64)

    @property
    def n_nodes(self) -> int:
        """Number of nodes in all clusters (the depot not counted)."""
        return int(self.sizes.sum())

    @cached_property
    def offsets(self) -> np.ndarray:
        """Global id of each cluster's first node, ``(K,)``."""
        return _frozen_array(np.concatenate([[0], np.cumsum(self.sizes)[:-1]]), np.int64)

    @cached_property
    def coords(self) -> np.ndarray:
        """All node coordinates in global order, ``(n, 2)``."""
        return _frozen_array(np.concatenate(self.clusters))

    @cached_property
    def node_points(self) -> np.ndarray:
        """The coordinates of every node of the cost matrix, the depot (when there is one) last:
        ``(n[+1], 2)``, read-only."""
        return self.coords if self.depot is None else _frozen_array(np.vstack([self.coords, self.depot]))

    @cached_property
    def cluster_of(self) -> np.ndarray:
        """Cluster of each global node, ``(n,)``."""
        return _frozen_array(np.repeat(np.arange(self.n_clusters), self.sizes), np.int64)

    @property
    def is_uav(self) -> bool:
        """True for an energy-priced UAV instance, False for a distance-only GTSP."""
        return self.params is not None

    # ------------------------------------------------------------------ solutions
    def check_solution(
        self, order: Sequence[int], heads: Sequence[int]
    ) -> tuple[np.ndarray, np.ndarray]:
        """Validate a solution and return it as integer arrays.

        Parameters
        ----------
        order
            Cluster indices in visiting order (depot excluded); each cluster exactly once.
        heads
            ``heads[k]`` is the index of cluster k's head inside that cluster.

        Raises
        ------
        InfeasibleSolutionError
            Naming the first problem found.
        """
        order_arr = _as_int_array(order, "order")
        heads_arr = _as_int_array(heads, "heads")
        k = self.n_clusters
        if len(order_arr) != k:
            raise InfeasibleSolutionError(
                f"order lists {len(order_arr)} clusters but the instance has {k}"
            )
        if len(heads_arr) != k:
            raise InfeasibleSolutionError(
                f"heads has {len(heads_arr)} entries but the instance has {k} clusters"
            )
        bad = order_arr[(order_arr < 0) | (order_arr >= k)]
        if bad.size:
            raise InfeasibleSolutionError(f"order names cluster {bad[0]}, valid are 0..{k - 1}")
        counts = np.bincount(order_arr, minlength=k)
        if np.any(counts != 1):
            c = int(np.flatnonzero(counts != 1)[0])
            what = "is never visited" if counts[c] == 0 else f"is visited {counts[c]} times"
            raise InfeasibleSolutionError(f"cluster {c} {what}")
        out = (heads_arr < 0) | (heads_arr >= self.sizes)
        if np.any(out):
            c = int(np.flatnonzero(out)[0])
            raise InfeasibleSolutionError(
                f"heads[{c}] = {heads_arr[c]} is not a node of cluster {c} "
                f"(it has {self.sizes[c]} nodes)"
            )
        return order_arr, heads_arr


def _as_int_array(values: Sequence[int], what: str) -> np.ndarray:
    try:
        seq = list(values)
    except TypeError:
        raise InfeasibleSolutionError(f"{what} must be a list of integers") from None
    for v in seq:
        if not is_int(v):
            raise InfeasibleSolutionError(f"{what} must be a list of integers, got {v!r}")
    try:
        return np.asarray(seq, dtype=np.int64).reshape(-1)
    except OverflowError:
        raise InfeasibleSolutionError(f"{what} holds an integer far outside any index") from None


# ---------------------------------------------------------------------- distances
def pair_distances(a: np.ndarray, b: np.ndarray, edge_weight_type: str) -> np.ndarray:
    """Distances between points ``a[..., :]`` and ``b[..., :]`` by an edge-weight rule.

    Parameters
    ----------
    a, b
        Broadcastable arrays of shape ``(..., 2)``.
    edge_weight_type
        ``"EUCLIDEAN"`` (exact) or ``"EUC_2D"``, ``"CEIL_2D"``, ``"ATT"``, ``"GEO"`` as defined by
        TSPLIB95 (nint(x) = floor(x + 0.5); GEO takes whole degrees by truncation, as Concorde), or
        ``"GEOM"`` as LKH and Concorde define it (exact degrees, metres on a sphere).

    Returns
    -------
    numpy.ndarray
        The broadcast shape without the last axis.
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if edge_weight_type == "GEO":
        return _geo_distances(a, b)
    if edge_weight_type == "GEOM":
        return _geom_distances(a, b)
    # the two squares added in the order of a sum over the last axis: the same floats, without
    # an (..., 2) temporary
    d2 = (a[..., 0] - b[..., 0]) ** 2 + (a[..., 1] - b[..., 1]) ** 2
    if edge_weight_type == "EUCLIDEAN":
        return np.sqrt(d2)
    if edge_weight_type == "EUC_2D":
        return np.floor(np.sqrt(d2) + 0.5)
    if edge_weight_type == "CEIL_2D":
        return np.ceil(np.sqrt(d2))
    if edge_weight_type == "ATT":
        r = np.sqrt(d2 / 10.0)
        t = np.floor(r + 0.5)
        return np.where(t < r, t + 1.0, t)
    raise InputError(f"no coordinate rule for edge weight type {edge_weight_type!r}")


def _geo_radians(x: np.ndarray) -> np.ndarray:
    deg = np.trunc(x)
    return 3.141592 * (deg + 5.0 * (x - deg) / 3.0) / 180.0


def _geo_distances(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    lat_a, lon_a = _geo_radians(a[..., 0]), _geo_radians(a[..., 1])
    lat_b, lon_b = _geo_radians(b[..., 0]), _geo_radians(b[..., 1])
    q1 = np.cos(lon_a - lon_b)
    q2 = np.cos(lat_a - lat_b)
    q3 = np.cos(lat_a + lat_b)
    arg = np.clip(0.5 * ((1.0 + q1) * q2 - (1.0 - q1) * q3), -1.0, 1.0)
    return np.floor(6378.388 * np.arccos(arg) + 1.0)


def _geom_distances(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """GEOM: great-circle metres on a sphere of radius 6378388 m, (latitude, longitude) in
    degrees; the rounding of LKH and Concorde, (int)(d + 1)."""
    lat_a, lon_a = np.pi * (a[..., 0] / 180.0), np.pi * (a[..., 1] / 180.0)
    lat_b, lon_b = np.pi * (b[..., 0] / 180.0), np.pi * (b[..., 1] / 180.0)
    dlon = lon_a - lon_b
    q1 = np.cos(lat_b) * np.sin(dlon)
    q3 = np.sin(dlon / 2.0)
    q4 = np.cos(dlon / 2.0)
    q2 = np.sin(lat_b - lat_a) * q4 * q4 + np.sin(lat_a + lat_b) * q3 * q3
    q5 = np.cos(lat_a - lat_b) * q4 * q4 - np.cos(lat_a + lat_b) * q3 * q3
    return np.floor(6378388.0 * np.arctan2(np.sqrt(q1 * q1 + q2 * q2), q5) + 1.0)


#: Most nodes (the depot included) whose full ``(m, m)`` cost matrix :func:`node_distance_matrix`
#: builds: 32,000 nodes take about 7.6 GiB of float64. Larger instances (GTSPLIB's largest have
#: 33,810 to 85,900 nodes) are refused with one line before anything is allocated.
MAX_MATRIX_NODES = 32_000
#: Rows computed at once from coordinates (bounds the temporary arrays to a few tens of MB).
_CHUNK_BYTES = 2**26
#: Rules that :func:`planar_rows` computes in place, and the bytes of a row block it works on (a
#: block that stays in the cache: a 15,112-node matrix takes about 1 s instead of 10 s).
PLANAR_RULES = ("EUCLIDEAN", "EUC_2D", "CEIL_2D")
_PLANAR_CHUNK_BYTES = 2**20


def planar_rows(pts: np.ndarray, lo: int, rule: str, out: np.ndarray) -> None:
    """Rows ``lo, lo + 1, ...`` of the distance matrix of ``pts`` into ``out`` (``(rows, m)``) by a
    planar rule (:data:`PLANAR_RULES`), without temporaries of the block's size beyond two: the
    same numbers as :func:`pair_distances` (the same operations in the same order)."""
    block = pts[lo:lo + len(out)]
    dx = np.subtract.outer(block[:, 0], pts[:, 0])
    np.multiply(dx, dx, out=dx)
    np.subtract.outer(block[:, 1], pts[:, 1], out=out)
    np.multiply(out, out, out=out)
    np.add(dx, out, out=out)
    np.sqrt(out, out=out)
    if rule == "EUC_2D":
        out += 0.5
        np.floor(out, out=out)
    elif rule == "CEIL_2D":
        np.ceil(out, out=out)


def check_matrix_size(instance: Instance) -> None:
    """:class:`InputError` when the full node-to-node matrix of ``instance`` is too large to build:
    more than :data:`MAX_MATRIX_NODES` nodes, or more memory than this process has."""
    m = instance.n_nodes + (instance.depot is not None)
    need = 8.0 * m * m
    if m > MAX_MATRIX_NODES:
        raise InputError(f"{instance.name} has {m:,} nodes: its full cost matrix would need "
                         f"{need / 2**30:.3g} GiB, and matrices are built up to {MAX_MATRIX_NODES:,} "
                         f"nodes; this solver works on the full matrix, so the instance is too "
                         f"large for it")
    check_memory(f"the {m:,} x {m:,} cost matrix of {instance.name}", need, "use a smaller instance")


def node_distance_matrix(instance: Instance) -> np.ndarray:
    """Distances between all nodes, the depot last when there is one: ``(n[+1], n[+1])``.

    ``out[i, j]`` is the cost of going from node i to node j (the transpose of it too unless the
    instance is asymmetric). The diagonal is zero. For UAV instances this is the horizontal
    flight distance in metres.

    Raises
    ------
    InputError
        When the matrix is too large (:func:`check_matrix_size`).
    """
    check_matrix_size(instance)
    if instance.edge_weight_type == "EXPLICIT":
        w = np.array(instance.weights, dtype=np.float64)
    else:
        pts = instance.node_points
        m = len(pts)
        w = np.empty((m, m))
        rule = instance.edge_weight_type
        if rule in PLANAR_RULES:
            step = max(1, _PLANAR_CHUNK_BYTES // (8 * max(m, 1)))
            for lo in range(0, m, step):
                planar_rows(pts, lo, rule, w[lo:lo + step])
        else:
            step = max(1, _CHUNK_BYTES // (16 * max(m, 1)))
            for lo in range(0, m, step):
                w[lo:lo + step] = pair_distances(pts[lo:lo + step, None, :], pts[None, :, :], rule)
    np.fill_diagonal(w, 0.0)
    return w


def tour_length(instance: Instance, order: np.ndarray, heads: np.ndarray) -> float:
    """Length of the closed tour depot -> heads in ``order`` -> depot (no depot: a cycle).

    Priced in its direction: ``order[i] -> order[i + 1]``, then the closing edge from the last
    head back to the first (``weights[from, to]``; the same both ways on a symmetric instance).

    ``order`` and ``heads`` must already be checked (:meth:`Instance.check_solution`).
    """
    nodes = instance.offsets[order] + heads[order]
    if instance.edge_weight_type == "EXPLICIT":
        return float(instance.weights[nodes, np.roll(nodes, -1)].sum())
    pts = instance.coords[nodes]
    if instance.depot is not None:
        pts = np.vstack([instance.depot, pts])
    legs = pair_distances(pts, np.roll(pts, -1, axis=0), instance.edge_weight_type)
    return float(math.fsum(legs))

"""Edge costs for the compiled loops of :mod:`gtsp_bench.solvers.heuristics.lns`: a matrix, or points.

The kernels read the cost of the edge from node ``a`` to node ``b`` as ``ec(edge, a, b)``, where
``edge`` is either

* the ``(m, m)`` matrix of :attr:`gtsp_bench.problem.Problem.edge_cost`, or
* **points**: a tuple ``(xy, rule, scale)`` of the ``(m, 2)`` node coordinates (the depot last),
  a planar rule (:data:`RULES`) and a factor, from :func:`points_of`. Each cost is then computed
  where it is needed, with the same operations as :func:`gtsp_bench.instance.pair_distances` and
  :func:`gtsp_bench.problem.price`, so the same number as the matrix holds.

numba compiles each kernel once per kind (both kinds are in its cache; the cache is keyed on each
kernel's own file, so after editing this module delete ``solvers/heuristics/__pycache__/*.nbi``).
On a large instance the points are the faster kind: a 15,112-node matrix takes 1.8 GB, and the
search reads it at scattered rows, nearly every read a cache miss; the coordinates fit in the
cache, and the matrix is never built.
"""

from __future__ import annotations

import numpy as np
from numba import types
from numba.extending import overload, register_jitable

from gtsp_bench.problem import Problem

#: Planar rules the points kind computes, by code (0 is not used: it would read as "no rule").
RULES = {"EUCLIDEAN": 1, "EUC_2D": 2, "CEIL_2D": 3}
#: Problems of at least this many nodes are searched on points when their rule allows it (below,
#: the matrix is cheap to build and fits in the cache).
POINTS_FROM = 2000

Points = tuple[np.ndarray, int, float]


@register_jitable
def _squared(xy: np.ndarray, a: int, b: int) -> float:
    dx = xy[a, 0] - xy[b, 0]
    dy = xy[a, 1] - xy[b, 1]
    return dx * dx + dy * dy


@register_jitable
def _rounded_root(key: float, rule: int, scale: float) -> float:
    r = np.sqrt(key)
    if rule == 2:
        return scale * np.floor(r + 0.5)
    if rule == 3:
        return scale * np.ceil(r)
    return scale * r


def ec_key(edge: np.ndarray | Points, a: int, b: int) -> float:
    """A key that orders edges as their costs do: the matrix entry, or the squared distance (the
    least cost of many edges is then ``ec_of_key(edge, least key)``, one root and rounding)."""
    if isinstance(edge, np.ndarray):
        return float(edge[a, b])
    return _squared(edge[0], a, b)


def ec_of_key(edge: np.ndarray | Points, key: float) -> float:
    """The cost of an edge whose :func:`ec_key` is ``key``: the key itself on a matrix, else the
    factor times the rule's rounding of its root."""
    if isinstance(edge, np.ndarray):
        return key
    return float(_rounded_root(key, edge[1], edge[2]))


@overload(ec_key)
def _ec_key(edge, a, b):
    if isinstance(edge, types.Array):
        return lambda edge, a, b: edge[a, b]
    return lambda edge, a, b: _squared(edge[0], a, b)


@overload(ec_of_key)
def _ec_of_key(edge, key):
    if isinstance(edge, types.Array):
        return lambda edge, key: key
    return lambda edge, key: _rounded_root(key, edge[1], edge[2])


@register_jitable
def ec(edge: np.ndarray | Points, a: int, b: int) -> float:
    """The cost of the edge from node ``a`` to node ``b``: a matrix entry, or computed from points
    (compiled inside the kernels that call it, or plain Python)."""
    return ec_of_key(edge, ec_key(edge, a, b))


def points_of(problem: Problem) -> Points | None:
    """``(xy, rule, scale)`` for ``problem``, or ``None`` when its costs are not a planar rule
    times a factor (explicit weights, ATT, GEO, GEOM)."""
    inst = problem.instance
    rule = RULES.get(inst.edge_weight_type)
    if rule is None:
        return None
    return inst.node_points, rule, float(problem.edge_scale)  # float64, contiguous, read-only


def kernel_costs(problem: Problem, points: bool | None = None) -> np.ndarray | Points:
    """What the kernels take as ``edge`` for ``problem``: its points when ``points`` (default:
    from :data:`POINTS_FROM` nodes) and the rule allows, else its matrix."""
    if points is None:
        points = problem.n_nodes >= POINTS_FROM
    found = points_of(problem) if points else None
    if found is not None:
        return found
    return np.ascontiguousarray(problem.edge_cost, dtype=np.float64)


def cluster_arrays(problem: Problem) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """What the kernels take as ``node``, ``start`` and ``cluster_of`` for ``problem``: the node
    costs, the first node of each cluster followed by the number of nodes, and each node's cluster.

    Raises
    ------
    ValueError
        When the nodes are not numbered cluster by cluster (the kernels index clusters by ranges).
    """
    start = np.array([c[0] for c in problem.clusters] + [problem.n_nodes], dtype=np.int64)
    cluster_of = np.ascontiguousarray(problem.cluster_of, dtype=np.int64)
    sizes = np.diff(start)
    if (sizes < 1).any() or not np.array_equal(np.repeat(np.arange(problem.n_clusters), sizes),
                                                cluster_of):
        raise ValueError("the kernels need nodes numbered cluster by cluster")
    return np.ascontiguousarray(problem.node_cost, dtype=np.float64), start, cluster_of

"""A GTSP priced for one omega: what most solvers work on.

:func:`price` turns an :class:`~gtsp_bench.instance.Instance` and a weight ``omega`` into a
:class:`Problem`: a cost per node and a cost per edge, ``edge_cost[i, j]`` for going from i to j
(symmetric unless the instance is asymmetric: :attr:`Problem.symmetric`), with the depot (when
there is one) as an extra one-node cluster. The cost of a closed tour through one node per cluster,

    sum of node costs + sum of edge costs,

equals the evaluator's objective (:func:`gtsp_bench.energy.evaluate`) for the same solution:

* UAV instance: node cost = omega * ground energy of that head + (1 - omega) * E_{c_k};
  edge cost = (1 - omega) * P_move / v_UAV * distance;
* distance-only GTSP: node cost 0, edge cost = the TSPLIB weight.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from gtsp_bench.checks import check_omega
from gtsp_bench.energy import cluster_hover_energy, node_ground_energy
from gtsp_bench.errors import InfeasibleSolutionError
from gtsp_bench.instance import (
    PLANAR_RULES,
    Instance,
    check_matrix_size,
    node_distance_matrix,
    pair_distances,
    planar_rows,
)


@dataclass(frozen=True, eq=False)
class Problem:
    """A priced GTSP.

    Attributes
    ----------
    instance
        The instance it was priced from.
    omega
        The weight used (``None`` for a distance-only GTSP).
    node_cost
        ``(m,)`` cost of choosing each node; node ids are the instance's global ids, and the
        depot, if any, is node ``m - 1`` with cost 0.
    clusters
        Node ids of each GTSP cluster: the K instance clusters in order, then ``[depot]``.
    depot
        Node id of the depot, or ``None``.
    edge_scale
        Each edge costs this times the distance between its nodes
        (:func:`gtsp_bench.instance.node_distance_matrix`).
    """

    instance: Instance
    omega: float | None
    node_cost: np.ndarray
    clusters: tuple[np.ndarray, ...]
    depot: int | None
    edge_scale: float = 1.0

    @cached_property
    def edge_cost(self) -> np.ndarray:
        """``(m, m)`` edge costs, zero diagonal, read-only: ``edge_cost[i, j]`` is the cost of going
        from node i to node j, equal to ``edge_cost[j, i]`` unless :attr:`symmetric` is false.
        Built on first use (a solver that computes its costs from the coordinates never builds it)."""
        dist = node_distance_matrix(self.instance)
        out = dist if self.edge_scale == 1.0 else self.edge_scale * dist
        out.setflags(write=False)
        return out

    @property
    def symmetric(self) -> bool:
        """Whether ``edge_cost`` equals its transpose (false for an asymmetric instance, e.g. a
        GTSPLIB ``AGTSP`` file: a tour and its reverse may then cost differently)."""
        return self.instance.symmetric

    @property
    def n_nodes(self) -> int:
        """Number of nodes, the depot included."""
        return len(self.node_cost)

    @property
    def n_clusters(self) -> int:
        """Number of GTSP clusters, the depot's included."""
        return len(self.clusters)

    @cached_property
    def cluster_of(self) -> np.ndarray:
        """GTSP cluster of each node, ``(m,)``."""
        out = np.empty(self.n_nodes, dtype=np.int64)
        for c, nodes in enumerate(self.clusters):
            out[nodes] = c
        return out

    def tour_cost(self, tour: Sequence[int]) -> float:
        """Cost of the closed tour through ``tour`` (node ids, one per cluster, any rotation), in
        its direction: ``tour[i] -> tour[i + 1]``, then ``tour[-1] -> tour[0]``."""
        t = np.asarray(tour, dtype=np.int64)
        return float(self.node_cost[t].sum() + self.edge_costs(t, np.roll(t, -1)).sum())

    def edge_costs(self, tails: np.ndarray, heads: np.ndarray) -> np.ndarray:
        """The costs of the edges ``tails[i] -> heads[i]`` (see :meth:`edge_row`)."""
        if self._from_matrix:
            return self.edge_cost[tails, heads]
        pts = self.instance.node_points
        dist = pair_distances(pts[tails], pts[heads], self.instance.edge_weight_type)
        dist[tails == heads] = 0.0
        return dist if self.edge_scale == 1.0 else self.edge_scale * dist

    def edge_block(self, nodes: np.ndarray) -> np.ndarray:
        """The costs of the edges among ``nodes``, ``(len(nodes), len(nodes))``, row = tail: the
        same numbers as :meth:`edge_costs` of every pair, by one broadcast over the coordinates on
        a planar rule (no gathered copy of every pair's points)."""
        nodes = np.asarray(nodes, dtype=np.int64)
        if self._from_matrix:
            return self.edge_cost[np.ix_(nodes, nodes)]
        pts = self.instance.node_points[nodes]
        dist = pair_distances(pts[:, None, :], pts[None, :, :], self.instance.edge_weight_type)
        dist[nodes[:, None] == nodes[None, :]] = 0.0
        return dist if self.edge_scale == 1.0 else self.edge_scale * dist

    def edge_row(self, i: int) -> np.ndarray:
        """``edge_cost[i]``: read from :attr:`edge_cost` once it is built or when the rule is not
        planar, else computed from the coordinates (the same numbers as the matrix holds: the same
        operations), without building the matrix."""
        if self._from_matrix:
            return self.edge_cost[i]
        pts = self.instance.node_points
        dist = np.empty((1, len(pts)))
        planar_rows(pts, i, self.instance.edge_weight_type, dist)
        dist[0, i] = 0.0
        return dist[0] if self.edge_scale == 1.0 else self.edge_scale * dist[0]

    @property
    def _from_matrix(self) -> bool:
        return "edge_cost" in self.__dict__ or self.instance.edge_weight_type not in PLANAR_RULES

    def to_tour(self, order: Sequence[int], heads: Sequence[int]) -> np.ndarray:
        """Node ids of a solution's tour, starting at the depot when there is one."""
        order_arr, heads_arr = self.instance.check_solution(order, heads)
        nodes = self.instance.offsets[order_arr] + heads_arr[order_arr]
        if self.depot is not None:
            nodes = np.concatenate([[self.depot], nodes])
        return nodes

    def to_solution(self, tour: Sequence[int]) -> tuple[tuple[int, ...], tuple[int, ...]]:
        """Turn a closed tour of node ids (one per cluster) into ``(order, heads)``.

        The tour is rotated so that the depot comes first; the depot is then dropped.

        Raises
        ------
        InfeasibleSolutionError
            If the tour does not hold exactly one node of every cluster.
        """
        t = np.asarray(tour, dtype=np.int64).reshape(-1)
        if t.size and (t.min() < 0 or t.max() >= self.n_nodes):
            raise InfeasibleSolutionError("tour names a node that does not exist")
        clusters = self.cluster_of[t]
        if len(t) != self.n_clusters or len(np.unique(clusters)) != self.n_clusters:
            raise InfeasibleSolutionError("tour must hold exactly one node of every cluster")
        if self.depot is not None:
            start = int(np.flatnonzero(t == self.depot)[0])
            t = np.roll(t, -start)[1:]
        order = self.instance.cluster_of[t]
        heads = np.empty(self.instance.n_clusters, dtype=np.int64)
        heads[order] = t - self.instance.offsets[order]
        return tuple(int(c) for c in order), tuple(int(h) for h in heads)


def price(instance: Instance, omega: float | None) -> Problem:
    """Price an instance for a weight ``omega`` (ignored for a distance-only GTSP).

    Raises
    ------
    InputError
        If ``omega`` is not in [0, 1] for a UAV instance, or the instance is too large for a full
        cost matrix (:func:`gtsp_bench.instance.check_matrix_size`).
    """
    check_matrix_size(instance)
    n = instance.n_nodes
    if instance.params is None:
        w = None
        node_cost = np.zeros(n + (instance.depot is not None))
        scale = 1.0
    else:
        w = check_omega(omega)
        hover = cluster_hover_energy(instance)[instance.cluster_of]
        node_cost = w * node_ground_energy(instance) + (1.0 - w) * hover
        if instance.depot is not None:
            node_cost = np.append(node_cost, 0.0)
        scale = (1.0 - w) * instance.params.flight_energy_per_m
    clusters = [np.arange(o, o + s) for o, s in zip(instance.offsets, instance.sizes, strict=True)]
    depot = None
    if instance.depot is not None:
        depot = n
        clusters.append(np.array([n]))
    for a in (node_cost, *clusters):
        a.setflags(write=False)
    return Problem(instance, w, node_cost, tuple(clusters), depot, scale)

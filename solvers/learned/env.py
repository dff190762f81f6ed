"""The batch environment of the learned policies: instances priced for one omega each, tour
costs, the two head rules and the features a model reads.

The environment prices tours with the quantities of the one evaluator: node costs from
:func:`gtsp_bench.energy.cluster_ground_energy` and :meth:`EnergyParams.hover_energy`, flight at
:attr:`EnergyParams.flight_energy_per_m` per metre, so that

    cost = sum of node costs of the heads + (1 - omega) * flight_energy_per_m * tour length

equals :func:`gtsp_bench.energy.evaluate` (a test checks it on random tours). Models see
coordinates divided by :data:`AREA_SCALE` (the generator's 1000 m square becomes the unit
square) and omega; the scale is fixed, not per instance, because the energy model is not
scale-free (d_0, flight energy per metre).

Everything here imports torch; nothing in ``gtsp_bench`` imports this module at start-up.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import torch

from gtsp_bench.checks import check_choice, check_omega
from gtsp_bench.energy import cluster_ground_energy
from gtsp_bench.errors import InputError
from gtsp_bench.instance import Instance
from gtsp_bench.params import EnergyParams

#: Coordinates are divided by this (m) before they enter a model.
AREA_SCALE = 1000.0
#: Costs enter losses in kJ (rewards of a few thousand J otherwise dominate Adam's first steps).
COST_SCALE = 1000.0
#: Relative ground energy of a node inside its cluster is divided by this (J) as a model feature.
GROUND_SCALE = 50.0


# ---------------------------------------------------------------------- environment
@dataclass(frozen=True)
class EnvBatch:
    """A batch of UAV instances with equal K and N, priced for one omega each (float64).

    Attributes
    ----------
    coords
        ``(B, K, N, 2)`` node coordinates (m).
    depot
        ``(B, 2)`` depot coordinates (m).
    omega
        ``(B,)`` weights.
    node_cost
        ``(B, K, N)``: omega * ground energy + (1 - omega) * E_{c_k} of each candidate head.
    ground
        ``(B, K, N)``: unweighted ground energy of each candidate head.
    edge_per_m
        ``(B,)``: (1 - omega) * flight energy per metre.
    """

    coords: torch.Tensor
    depot: torch.Tensor
    omega: torch.Tensor
    node_cost: torch.Tensor
    ground: torch.Tensor
    edge_per_m: torch.Tensor

    @property
    def shape(self) -> tuple[int, int, int]:
        """(B, K, N)."""
        b, k, n, _ = self.coords.shape
        return b, k, n

    def _tensors(self) -> tuple[torch.Tensor, ...]:
        return (self.coords, self.depot, self.omega, self.node_cost, self.ground, self.edge_per_m)

    def rows(self, start: int, stop: int) -> EnvBatch:
        """Instances ``start .. stop - 1``."""
        return EnvBatch(*(t[start:stop] for t in self._tensors()))

    def repeat(self, times: int) -> EnvBatch:
        """Each instance ``times`` times in a row (instance i becomes rows i*times .. )."""
        return EnvBatch(*(t.repeat_interleave(times, dim=0) for t in self._tensors()))


def make_env(
    coords: np.ndarray,
    omega: float | np.ndarray,
    params: EnergyParams | None = None,
    depot: np.ndarray | Sequence[float] = (500.0, 0.0),
    *,
    ground: np.ndarray | None = None,
) -> EnvBatch:
    """Price a batch of coordinates ``(B, K, N, 2)`` with the shared evaluator's quantities.

    Parameters
    ----------
    coords
        Node coordinates in m (e.g. from :func:`gtsp_bench.generator.generate_batch`).
    omega
        Scalar or ``(B,)`` weights in [0, 1].
    params
        Energy parameters (defaults if ``None``).
    depot
        ``(2,)`` or ``(B, 2)`` depot coordinates.
    ground
        Optional precomputed :func:`cluster_ground_energy` of ``coords``.
    """
    params = params or EnergyParams()
    coords = np.asarray(coords, dtype=np.float64)
    b, _, n, _ = coords.shape
    w = np.broadcast_to(np.asarray(omega, dtype=np.float64), (b,)).copy()
    if np.any(~((w >= 0) & (w <= 1))):
        raise InputError("omega must be in [0, 1]")
    if ground is None:
        ground = cluster_ground_energy(coords, params)
    node_cost = w[:, None, None] * ground + (1 - w)[:, None, None] * params.hover_energy(n)
    dep = np.broadcast_to(np.asarray(depot, dtype=np.float64), (b, 2))
    t = torch.from_numpy
    return EnvBatch(t(coords), t(dep.copy()), t(w), t(node_cost), t(np.ascontiguousarray(ground)),
                    t((1 - w) * params.flight_energy_per_m))


def env_from_instances(instances: Sequence[Instance], omegas: Sequence[float]) -> EnvBatch:
    """Price UAV instances for a policy; clusters of unequal size are padded.

    Node costs are those of :func:`gtsp_bench.problem.price` (omega * ground energy +
    (1 - omega) * E_{c_k}), computed per cluster without the full distance matrix. A cluster
    smaller than the largest is padded with copies of its node 0 (same position and cost), and a
    head index past its real size maps back to node 0, so padding never changes the optimum.

    Raises
    ------
    InputError
        For a distance-only instance, one without a depot, or instances of different K.
    """
    if not instances:
        raise InputError("no instances to solve")
    if len({inst.n_clusters for inst in instances}) != 1:
        raise InputError("a batch of instances must have one number of clusters")
    n = max(int(inst.sizes.max()) for inst in instances)
    coords, depots, node_cost, ground, edge, ws = [], [], [], [], [], []
    for inst, omega in zip(instances, omegas, strict=True):
        params = inst.params
        if params is None or inst.depot is None:
            raise InputError(f"{inst.name}: learned policies need a UAV instance with a depot "
                             "(energy parameters and a base station)")
        w = check_omega(omega)
        hover = np.array([params.hover_energy(int(size)) for size in inst.sizes])
        if np.all(inst.sizes == n):
            xy = np.stack(inst.clusters)
            g = cluster_ground_energy(xy, params)
        else:
            idx = [np.where(np.arange(n) < size, np.arange(n), 0) for size in inst.sizes]
            xy = np.stack([c[i] for c, i in zip(inst.clusters, idx, strict=True)])
            g = np.stack([cluster_ground_energy(c, params)[i]
                          for c, i in zip(inst.clusters, idx, strict=True)])
        coords.append(xy)
        ground.append(g)
        node_cost.append(w * g + (1 - w) * hover[:, None])
        depots.append(inst.depot)
        edge.append((1 - w) * params.flight_energy_per_m)
        ws.append(w)
    t = torch.from_numpy
    return EnvBatch(t(np.stack(coords)), t(np.stack(depots)), t(np.array(ws)), t(np.stack(node_cost)),
                    t(np.stack(ground)), t(np.array(edge)))


def unpad_heads(heads: Sequence[int], sizes: Sequence[int]) -> tuple[int, ...]:
    """Heads of a policy's (padded) clusters as the instance's node indices: a padded copy of a
    cluster's node 0 (an index past the cluster's size) is node 0."""
    return tuple(int(x) if x < size else 0 for x, size in zip(heads, sizes, strict=True))


def mirror(env: EnvBatch) -> EnvBatch:
    """The batch mirrored about the vertical line through each depot: every cost is unchanged."""
    coords = env.coords.clone()
    coords[..., 0] = 2 * env.depot[:, None, None, 0] - coords[..., 0]
    return dataclasses.replace(env, coords=coords)


def _rows(b: int) -> torch.Tensor:
    return torch.arange(b)[:, None]


def tour_points(env: EnvBatch, order: torch.Tensor, heads: torch.Tensor) -> torch.Tensor:
    """``(B, K + 2, 2)``: depot, the heads in visiting order, depot."""
    b, k, _ = env.shape
    head_xy = env.coords[_rows(b), torch.arange(k)[None, :], heads]  # (B, K, 2) by cluster
    path = head_xy[_rows(b), order]
    dep = env.depot[:, None, :]
    return torch.cat([dep, path, dep], dim=1)


def tour_cost(env: EnvBatch, order: torch.Tensor, heads: torch.Tensor) -> torch.Tensor:
    """Objective of each tour ``(B,)`` in J: the torch form of :func:`gtsp_bench.energy.evaluate`.

    Parameters
    ----------
    env
        The batch.
    order
        ``(B, K)`` cluster indices in visiting order.
    heads
        ``(B, K)`` head index inside each cluster, indexed by cluster.
    """
    b, k, _ = env.shape
    path = tour_points(env, order, heads)
    distance = (path[:, 1:] - path[:, :-1]).pow(2).sum(-1).sqrt().sum(1)
    nodes = env.node_cost[_rows(b), torch.arange(k)[None, :], heads].sum(1)
    return nodes + env.edge_per_m * distance


def paper_head_step(env: EnvBatch, prev: torch.Tensor, cluster: torch.Tensor,
                    ) -> tuple[torch.Tensor, torch.Tensor]:
    """One step of the paper's head rule (eq. "chselection") for every instance of the batch.

    Entering ``cluster`` ``(B,)`` from the point ``prev`` ``(B, 2)`` (the previous head, or the
    depot), the head is the node with the least weighted energy from there: edge cost to it plus
    its node cost.

    Returns
    -------
    head : torch.Tensor
        ``(B,)`` the chosen node's index inside its cluster.
    xy : torch.Tensor
        ``(B, 2)`` its coordinates (m): where the UAV hovers next.
    """
    rows = torch.arange(len(cluster))
    xy = env.coords[rows, cluster]  # (B, N, 2)
    j = rule_entry(env, prev, xy, env.node_cost[rows, cluster])[1]
    return j, xy[rows, j]


def rule_entry(env: EnvBatch, prev: torch.Tensor, xy: torch.Tensor, node_cost: torch.Tensor,
               ) -> tuple[torch.Tensor, torch.Tensor]:
    """The paper's rule entering candidate nodes ``xy`` ``(B, ..., N, 2)`` from ``prev`` ``(B, 2)``.

    Returns the least weighted energy (edge cost from ``prev`` plus ``node_cost``, shaped like
    ``xy`` without its last axis) and the node reaching it, both ``(B, ...)``: the rule's choice
    for one cluster (``xy`` ``(B, N, 2)``) or for every cluster at once (``(B, K, N, 2)``).
    """
    lead = (prev.shape[0],) + (1,) * (xy.dim() - 2)
    dist = (xy - prev.view(*lead, 2)).pow(2).sum(-1).sqrt()
    return (env.edge_per_m.view(lead) * dist + node_cost).min(-1)


def paper_heads(env: EnvBatch, order: torch.Tensor) -> torch.Tensor:
    """The paper's head rule (eq. "chselection") along ``order``, ``(B, K)`` indexed by cluster.

    :func:`paper_head_step` for each cluster in visiting order, from the depot.
    """
    b, k, _ = env.shape
    rows = torch.arange(b)
    prev = env.depot
    heads = torch.empty((b, k), dtype=torch.long)
    for t in range(k):
        c = order[:, t]
        heads[rows, c], prev = paper_head_step(env, prev, c)
    return heads


def optimal_heads_batch(env: EnvBatch, order: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Best heads for fixed cluster orders: a shortest path through the layers, batched.

    The batched form of :func:`gtsp_bench.solvers.heads.optimal_heads`; O(B K N^2).

    Returns
    -------
    heads : torch.Tensor
        ``(B, K)`` head index inside each cluster, indexed by cluster.
    cost : torch.Tensor
        ``(B,)`` the cost of the resulting tours.
    """
    b, k, _ = env.shape
    rows = torch.arange(b)
    xy = env.coords[_rows(b), order]  # (B, K, N, 2) in visiting order
    nc = env.node_cost[_rows(b), order]  # (B, K, N)
    w = env.edge_per_m[:, None, None]
    cost = w[:, :, 0] * (xy[:, 0] - env.depot[:, None]).pow(2).sum(-1).sqrt() + nc[:, 0]
    back = []
    for t in range(1, k):
        d = torch.cdist(xy[:, t - 1], xy[:, t], compute_mode="donot_use_mm_for_euclid_dist")
        best, arg = (cost[:, :, None] + w * d).min(1)
        cost = best + nc[:, t]
        back.append(arg)
    cost = cost + w[:, :, 0] * (xy[:, -1] - env.depot[:, None]).pow(2).sum(-1).sqrt()
    total, j = cost.min(1)
    in_order = torch.empty((b, k), dtype=torch.long)
    in_order[:, k - 1] = j
    for t in range(k - 1, 0, -1):
        j = back[t - 1][rows, j]
        in_order[:, t - 1] = j
    heads = torch.empty_like(in_order)
    heads.scatter_(1, order, in_order)
    return heads, total


def _optimal_heads(env: EnvBatch, order: torch.Tensor) -> torch.Tensor:
    return optimal_heads_batch(env, order)[0]


#: The head rules by name: ``paper`` (eq. "chselection", :func:`paper_heads`) and ``optimal``
#: (the best heads for the order, :func:`optimal_heads_batch`).
HEAD_RULES: dict[str, Callable[[EnvBatch, torch.Tensor], torch.Tensor]] = {
    "paper": paper_heads,
    "optimal": _optimal_heads,
}


def choose_heads(env: EnvBatch, order: torch.Tensor, rule: str) -> torch.Tensor:
    """Heads ``(B, K)`` for ``order`` by the head rule named ``rule`` (a key of :data:`HEAD_RULES`).

    Raises
    ------
    InputError
        For an unknown rule, listing the valid ones.
    """
    return HEAD_RULES[check_choice("heads", rule, tuple(HEAD_RULES))](env, order)


# ---------------------------------------------------------------------- model features
def element_features(env: EnvBatch) -> tuple[torch.Tensor, torch.Tensor]:
    """Per-node features ``(B, K, N, 4)`` and depot features ``(B, 3)`` (float32).

    A node: x, y (scaled to the unit square), omega, and its ground energy above the cluster's
    cheapest head / :data:`GROUND_SCALE`. The depot: x, y, omega.
    """
    b, k, n = env.shape
    xy = env.coords / AREA_SCALE
    rel = (env.ground - env.ground.min(-1, keepdim=True).values) / GROUND_SCALE
    w = env.omega[:, None, None, None].expand(b, k, n, 1)
    nodes = torch.cat([xy, w, rel[..., None]], dim=-1).float()
    depot = torch.cat([env.depot / AREA_SCALE, env.omega[:, None]], dim=-1).float()
    return nodes, depot



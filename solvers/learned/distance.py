"""Distance-only instances (GTSPLIB's planar files) for the local-view policy.

The policy was trained on UAV instances: a depot, node costs, one omega. A planar GTSP without
them is the special case omega = 0 with every node cost zero and one edge cost per metre, except
that it has no depot: its tour is a cycle through every cluster. So one node of the smallest
cluster (the anchor) stands in for the depot and the other K - 1 clusters are decoded from it;
every node of the anchor cluster is tried (one batch row each) and the best closed tour, priced
by the one evaluator (GTSPLIB's own rounding of distances), is kept. Heads of the other clusters
are the optimal ones for the decoded order under plain Euclidean distances.
"""

from __future__ import annotations

import numpy as np
import torch
from gtsp_bench.solvers.learned.env import EnvBatch, optimal_heads_batch, unpad_heads

from gtsp_bench.energy import evaluate
from gtsp_bench.errors import InputError
from gtsp_bench.instance import PLANAR_RULES, Instance
from gtsp_bench.solver import Solution


def anchor_env(instance: Instance) -> tuple[EnvBatch, int, list[int]]:
    """One batch row per node of the anchor cluster (the smallest, the first of equal ones):
    that node as the depot, the other clusters (padded with copies of their node 0) as the
    instance, omega 0, no node costs, edge cost 1 per unit of distance.

    Returns
    -------
    env : EnvBatch
        ``(A, K - 1, N)``, A the anchor cluster's size.
    anchor : int
        The anchor cluster.
    others : list[int]
        The other clusters, in the env's cluster order.

    Raises
    ------
    InputError
        If the instance's distances are not planar (EXPLICIT, GEO, ATT) or it has under 3
        clusters.
    """
    if instance.edge_weight_type not in PLANAR_RULES:
        raise InputError(f"{instance.name}: the local policy needs planar distances "
                         f"({', '.join(PLANAR_RULES)}), not {instance.edge_weight_type}")
    if instance.n_clusters < 3:
        raise InputError(f"{instance.name}: the local policy needs at least 3 clusters")
    anchor = int(np.argmin(instance.sizes))
    others = [c for c in range(instance.n_clusters) if c != anchor]
    n = max(int(instance.sizes[c]) for c in others)
    xy = np.stack([np.asarray(instance.clusters[c], dtype=np.float64)[
        np.where(np.arange(n) < len(instance.clusters[c]), np.arange(n), 0)] for c in others])
    depots = np.asarray(instance.clusters[anchor], dtype=np.float64)
    a = len(depots)
    coords = torch.from_numpy(np.broadcast_to(xy, (a, *xy.shape)).copy())
    zeros = torch.zeros(coords.shape[:3], dtype=torch.float64)
    env = EnvBatch(coords, torch.from_numpy(depots.copy()), torch.zeros(a, dtype=torch.float64),
                   zeros, zeros.clone(), torch.ones(a, dtype=torch.float64))
    return env, anchor, others


def solve_distance(model: torch.nn.Module, instance: Instance, starts: int) -> Solution:
    """Greedy decodes (``starts`` rotated frames per anchor node) of a distance-only instance;
    the best tour by the evaluator."""
    env, anchor, others = anchor_env(instance)
    a = env.shape[0]
    with torch.inference_mode():
        order, _ = model.decode(env, "greedy", starts=starts,
                                flight_per_m=torch.ones(a, dtype=torch.float64))
        heads = optimal_heads_batch(env.repeat(starts), order)[0]
    sizes = instance.sizes
    best: Solution | None = None
    for row in range(a * starts):
        full = [anchor] + [others[int(c)] for c in order[row]]
        h = np.zeros(instance.n_clusters, dtype=np.int64)
        h[anchor] = row // starts
        h[others] = unpad_heads(heads[row].tolist(), [sizes[c] for c in others])
        value = evaluate(instance, None, full, h.tolist()).objective
        if best is None or value < best.objective:
            best = Solution(tuple(full), tuple(int(x) for x in h), objective=value,
                            status="feasible", stats={"heads": "optimal", "anchor": anchor})
    assert best is not None
    return best

"""Exact oracles on a batch environment, for validation and benchmarks (small K only).

:func:`exact_by_enumeration` is the optimum (every order, optimal heads): the trainer's
validation gap for K <= 6. :func:`paper_rule_optimum` is the best any visiting order reaches
when heads follow the paper's rule: no policy that keeps that rule can do better.
"""

from __future__ import annotations

import itertools
import math

import torch
from gtsp_bench.solvers.learned.env import EnvBatch, optimal_heads_batch


def exact_by_enumeration(env: EnvBatch, chunk: int = 1 << 16) -> torch.Tensor:
    """Exact optimum ``(B,)`` by trying every order with optimal heads (small K only)."""
    b, k, _ = env.shape
    perms = torch.tensor(list(itertools.permutations(range(k))), dtype=torch.long)
    best = torch.full((b,), math.inf, dtype=torch.float64)
    per = max(1, chunk // len(perms))
    for i in range(0, b, per):
        sub = env.rows(i, i + per)
        m = sub.shape[0]
        rep = sub.repeat(len(perms))
        _, cost = optimal_heads_batch(rep, perms.repeat(m, 1))
        best[i:i + m] = cost.view(m, len(perms)).min(1).values
    return best


def paper_rule_optimum(env: EnvBatch) -> torch.Tensor:
    """Best objective ``(B,)`` over all visiting orders when heads follow the paper's rule.

    The rule fixes each head from the previous one, so a tour's future depends only on the set
    of visited clusters, the last cluster and its head: a Held-Karp recursion over those
    ``2^K K N`` states gives the optimum exactly, O(2^K K^2 N) per instance. It bounds what any
    policy with :func:`paper_heads` can reach (small K only: memory is ``B 2^K K N`` floats).
    """
    b, k, n = env.shape
    w = env.edge_per_m
    flat = env.coords.reshape(b, k * n, 2)
    d = torch.cdist(flat, flat, compute_mode="donot_use_mm_for_euclid_dist").view(b, k, n, k, n)
    # from head (p, h) into cluster c: the rule's cost and head, (B, K, N, K) each
    step, nxt = (w[:, None, None, None, None] * d + env.node_cost[:, None, None]).min(-1)
    back = w[:, None, None] * (env.coords - env.depot[:, None, None]).pow(2).sum(-1).sqrt()
    first, j0 = (back + env.node_cost).min(-1)  # from the depot, (B, K)
    full = (1 << k) - 1
    cost = torch.full((b, full + 1, k, n), math.inf, dtype=torch.float64)
    rows = torch.arange(b)
    for c in range(k):
        cost[rows, 1 << c, c, j0[:, c]] = first[:, c]
    for mask in range(1, full):  # supersets come later in numeric order
        for p in (p for p in range(k) if mask >> p & 1):
            cur = cost[:, mask, p]  # (B, N)
            if torch.isinf(cur).all():
                continue
            for c in (c for c in range(k) if not mask >> c & 1):
                cost[:, mask | 1 << c, c].scatter_reduce_(1, nxt[:, p, :, c], cur + step[:, p, :, c],
                                                         reduce="amin")
    return (cost[:, full] + back).reshape(b, -1).min(1).values


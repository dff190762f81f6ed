"""Beyond the paper: an attention-model policy (Kool et al. 2019) with POMO multiple starts.

Cluster encoder: every node's (x, y, omega, relative ground energy) goes through a small MLP,
and a cluster is the mean and the max of its nodes' vectors (permutation-invariant, any N, clusters
of unequal size are padded); the depot has its own embedding of (x, y, omega). A 3-layer
transformer encoder (8 heads, D = 128) mixes the K + 1 elements. The decoder is Kool et al.'s:
a query from [graph mean, depot, last cluster], an 8-head glimpse over the unvisited clusters, then
single-head logits clipped to 10 tanh(.). POMO (Kwon et al. 2020): every instance is decoded from
each of its K first clusters; training uses the mean cost of those K tours as the baseline, and
inference keeps the best of the K greedy tours. Heads: optimal for the decoded order by default
(the policy picks the order only), or the paper's rule.
"""

from __future__ import annotations

import math
from typing import Any

import torch
from gtsp_bench.solvers.learned.decoding import choose
from gtsp_bench.solvers.learned.env import AREA_SCALE, EnvBatch, element_features
from torch import nn


class AttentionPolicy(nn.Module):
    """Transformer encoder + pointer decoder over clusters, POMO multi-start.

    Parameters
    ----------
    dim
        Embedding width D.
    n_heads
        Attention heads.
    n_layers
        Encoder layers.
    ff
        Width of the encoder's feed-forward layers.
    local
        Add a learned bias f(d(last, j), d(j, depot)) of centroid distances to the logits: a
        nearest-neighbour-like prior that does not depend on K (it helps K-generalisation).
    """

    #: Training baselines it supports (:mod:`gtsp_bench.solvers.learned.baselines`).
    baselines = ("pomo",)

    def __init__(self, dim: int = 128, n_heads: int = 8, n_layers: int = 3, ff: int = 512,
                 local: bool = True) -> None:
        super().__init__()
        self.config: dict[str, Any] = {"model": "am", "dim": dim, "n_heads": n_heads,
                                       "n_layers": n_layers, "ff": ff, "local": local}
        self.local = nn.Sequential(nn.Linear(3, 32), nn.ReLU(), nn.Linear(32, 1)) if local else None
        self.n_heads = n_heads
        self.node = nn.Sequential(nn.Linear(4, dim), nn.ReLU(), nn.Linear(dim, dim))
        self.pool = nn.Linear(2 * dim, dim)
        self.depot = nn.Linear(3, dim)
        layer = nn.TransformerEncoderLayer(dim, n_heads, ff, dropout=0.0, batch_first=True)
        self.encoder = nn.TransformerEncoder(layer, n_layers, enable_nested_tensor=False)
        self.project_kv = nn.Linear(dim, 3 * dim, bias=False)
        self.project_graph = nn.Linear(dim, dim, bias=False)
        self.project_step = nn.Linear(2 * dim, dim, bias=False)
        self.project_out = nn.Linear(dim, dim, bias=False)

    def encode(self, env: EnvBatch) -> torch.Tensor:
        """``(B, K + 1, D)`` element embeddings, the depot first."""
        nodes, depot = element_features(env)
        hn = self.node(nodes)  # (B, K, N, D)
        clusters = self.pool(torch.cat([hn.mean(2), hn.max(2).values], dim=-1))
        return self.encoder(torch.cat([self.depot(depot)[:, None], clusters], dim=1))

    @staticmethod
    def _centroid_distances(env: EnvBatch) -> torch.Tensor:
        """``(B, K + 1, K + 1)`` distances between the depot and cluster centroids (unit square)."""
        pts = torch.cat([env.depot[:, None], env.coords.mean(2)], dim=1) / AREA_SCALE
        return (pts[:, :, None] - pts[:, None, :]).pow(2).sum(-1).sqrt().float()

    def decode(self, env: EnvBatch, mode: str = "greedy", *, generator: torch.Generator | None = None,
               ) -> tuple[torch.Tensor, torch.Tensor]:
        """Decode K tours per instance, the t-th starting at cluster t (POMO).

        Returns
        -------
        order : torch.Tensor
            ``(B * K, K)``: rows ``i * K .. i * K + K - 1`` are instance i's tours.
        logp : torch.Tensor
            ``(B * K,)`` log-probability of each tour after its forced first step.
        """
        h = self.encode(env)
        b, m, d = h.shape
        dist = self._centroid_distances(env) if self.local is not None else None
        k = m - 1
        r = b * k
        h = h.repeat_interleave(k, dim=0)  # (R, M, D)
        rows = torch.arange(r)
        hd = d // self.n_heads
        kg, vg, kl = self.project_kv(h).chunk(3, dim=-1)
        kg = kg.view(r, m, self.n_heads, hd).transpose(1, 2)  # (R, H, M, hd)
        vg = vg.view(r, m, self.n_heads, hd).transpose(1, 2)
        fixed = self.project_graph(h.mean(1))  # (R, D)
        depot = h[:, 0]
        act = torch.arange(k).repeat(b) + 1  # forced first cluster of each tour
        visited = torch.zeros((r, m), dtype=torch.bool)
        visited[:, 0] = True
        visited[rows, act] = True
        actions, logp = [act], h.new_zeros(r)
        for _ in range(k - 1):
            q = fixed + self.project_step(torch.cat([depot, h[rows, act]], dim=-1))
            qh = q.view(r, self.n_heads, 1, hd)
            compat = (qh @ kg.transpose(-1, -2)) / math.sqrt(hd)  # (R, H, 1, M)
            compat = compat.masked_fill(visited[:, None, None, :], -math.inf)
            glimpse = (torch.softmax(compat, -1) @ vg).reshape(r, d)
            logits = (self.project_out(glimpse)[:, None, :] * kl).sum(-1) / math.sqrt(d)
            if dist is not None:
                inst = rows // k
                w = env.omega[inst].float()[:, None].expand(r, m)
                feats = torch.stack([dist[inst, act], dist[inst, 0], w], dim=-1)  # (R, M, 3)
                logits = logits + self.local(feats).squeeze(-1)
            act, step_logp, visited = choose(logits, visited, mode, generator)
            logp = logp + step_logp
            actions.append(act)
        return torch.stack(actions, 1) - 1, logp

"""Beyond the paper: a local-view policy that re-encodes its neighbourhood at every step.

Why: a policy that embeds all K clusters once (``drl``, ``am``) sees a different input
distribution at every K, and its decisions drift as K grows. The policies that generalise in the
learned-routing literature (INViT, ELG: local nearest-neighbour views; LEHD, BQ-NCO: a heavy
decoder that re-encodes the remaining state each step) see a state whose form and scale do not
depend on K. This one does both in a small way:

* **The view** (:class:`Walk`, :class:`View`): at each step, the ``k`` unvisited clusters whose
  centroids are nearest to the UAV's current point ``p``. For each candidate, the rule's entry
  node from ``p`` (the node with the least weighted energy from ``p``: edge cost plus node cost,
  the paper's head rule) and the cluster centroid, both relative to ``p`` and divided by the
  local scale ``s`` (the distance to the farthest candidate's centroid); the entry node's node
  cost above the cluster's cheapest node in metres of flight (cost / edge cost per metre) over
  ``s``; and the candidate's distance to the depot. The context token: omega, the fraction of
  clusters left, the unit direction to the depot and to the centre of mass of the unvisited
  clusters and their distances over ``s`` (as ``log1p``). Node costs (ground energy weighted by
  omega, :func:`gtsp_bench.problem.price`) thus enter through the entry rule and the excess
  feature. Nothing in the state grows with K.
* **The decoder** (:class:`LocalPolicy`): a small transformer over the ``k + 1`` tokens,
  re-run at every step (the whole state is re-encoded each step, as LEHD's heavy decoder), and
  a score per candidate; greedy takes the best.
* **Starts**: the problem is invariant under rotations and reflections of the plane, and every
  input vector is relative, so each of ``starts`` decodings sees the view turned by its own
  rotation (odd starts also mirrored): POMO-style instance augmentation, the best tour kept.
* **Heads**: the policy picks the order; the heads are the optimal ones for that order
  (:func:`~gtsp_bench.solvers.learned.env.optimal_heads_batch`) or the paper's rule.

The model is trained by imitation of near-optimal tours (:mod:`~.imitation`), not REINFORCE.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import torch
from gtsp_bench.solvers.learned.env import EnvBatch
from torch import nn

#: Scalars per candidate token and per context token; 2-D vectors per candidate and context.
CAND_SCALARS, CTX_SCALARS, CAND_VECTORS, CTX_VECTORS = 2, 3, 2, 2
#: The node-cost excess feature (metres of flight over the local scale) is clipped to this.
EXCESS_CLIP = 5.0
#: Edge cost per metre is floored at this fraction of the UAV's flight energy per metre before
#: dividing node costs by it (omega = 1 makes flight free).
MIN_EDGE_FRACTION = 0.05


@dataclass(frozen=True)
class View:
    """The local view of ``R`` walks at one step (float32 features).

    Attributes
    ----------
    cand_vec
        ``(R, k, 2, 2)``: entry node and centroid of each candidate, relative to the current
        point, over the local scale.
    cand_sc
        ``(R, k, 2)``: node-cost excess of the entry node (metres of flight over the local scale,
        clipped) and ``log1p`` of the candidate's centroid-to-depot distance over the scale.
    ctx_vec
        ``(R, 2, 2)``: unit directions to the depot and to the unvisited clusters' centre of mass.
    ctx_sc
        ``(R, 3)``: omega, the fraction of clusters left, ``log1p`` of the depot's distance over
        the scale.
    mask
        ``(R, k)``: which candidates exist (fewer than ``k`` clusters may be left).
    cluster
        ``(R, k)``: cluster index of each candidate.
    entry_xy
        ``(R, k, 2)``: the entry node's coordinates (m), float64.
    """

    cand_vec: torch.Tensor
    cand_sc: torch.Tensor
    ctx_vec: torch.Tensor
    ctx_sc: torch.Tensor
    mask: torch.Tensor
    cluster: torch.Tensor
    entry_xy: torch.Tensor


class Walk:
    """``S`` walks per instance of a batch through its clusters, from the depot.

    Parameters
    ----------
    env
        The batch (B instances).
    starts
        Walks per instance (rows ``i * starts .. i * starts + starts - 1`` are instance i's).
    k
        Candidates in the view.
    flight_per_m
        The UAV's flight energy per metre (J/m) of the instances, for the floor on the edge cost.
    shrink
        Whether a view has fewer than ``k`` candidates once fewer clusters are left (in every
        row): cheaper, and the scores are the same, since candidates that do not exist are
        masked out of the attention. Off, every view has ``k`` (training stacks views).
    """

    def __init__(self, env: EnvBatch, starts: int, k: int, flight_per_m: torch.Tensor,
                 shrink: bool = False) -> None:
        b, n_clusters, _ = env.shape
        self.env = env
        self.inst = torch.arange(b).repeat_interleave(starts)
        self.r = b * starts
        self.n_clusters = n_clusters
        self.k = k
        self.cent = env.coords.mean(2)  # (B, K, 2)
        self.cent_rows = self.cent[self.inst]  # (R, K, 2)
        self.depot = env.depot[self.inst]  # (R, 2)
        self.pos = self.depot.clone()
        self.visited = torch.zeros((self.r, n_clusters), dtype=torch.bool)
        w = env.edge_per_m[self.inst]
        self.edge = w  # (R,)
        self.per_m = torch.maximum(w, MIN_EDGE_FRACTION * flight_per_m[self.inst])
        self.omega = env.omega[self.inst]
        self.rows = torch.arange(self.r)
        self.shrink = shrink
        #: Clusters of the (sub)problem, for the context's fraction left (a re-constructed
        #: segment is a problem of its own size).
        self.size = n_clusters
        # Per cluster, flattened to (B * K, ...) so that one index picks a row's candidates.
        _, _, n_nodes, _ = env.coords.shape
        self._flat_xy = env.coords.reshape(b * n_clusters, n_nodes, 2)
        self._flat_nc = env.node_cost.reshape(b * n_clusters, n_nodes)
        self._flat_nc_min = self._flat_nc.min(-1).values
        self._flat_cent = self.cent.reshape(b * n_clusters, 2)
        self._row_base = (self.inst * n_clusters)[:, None]  # (R, 1) first flat index of a row

    def view(self) -> View:
        """The view from the current points."""
        cent = self.cent_rows
        d2 = _sq_norm(cent - self.pos[:, None]).masked_fill_(self.visited, math.inf)
        width = self.k
        if self.shrink:  # only as many tokens as the row with most clusters left needs
            width = max(1, min(self.k, int((~self.visited).sum(1).max())))
        d2, cluster = d2.topk(min(width, self.n_clusters), dim=1, largest=False)
        if width > self.n_clusters:  # fewer clusters than candidates: pad (masked below)
            extra = width - self.n_clusters
            d2 = torch.cat([d2, d2.new_full((self.r, extra), math.inf)], 1)
            cluster = torch.cat([cluster, cluster.new_zeros((self.r, extra))], 1)
        mask = torch.isfinite(d2)
        full = bool(mask.all())
        if not full:
            cluster = torch.where(mask, cluster, cluster[:, :1])
            d2 = d2.masked_fill(~mask, 0.0)
        scale = d2.amax(1).sqrt_().clamp_min_(1.0)  # (R,) the farthest candidate's distance
        flat = self._row_base + cluster  # (R, k) flat cluster index
        xy = self._flat_xy[flat]  # (R, k, N, 2)
        nc = self._flat_nc[flat]  # (R, k, N)
        rel_xy = xy - self.pos[:, None, None]
        reach = _sq_norm(rel_xy).sqrt_()
        j = torch.addcmul(nc, self.edge[:, None, None], reach).argmin(-1, keepdim=True)  # (R, k, 1)
        pick = j[..., None].expand(-1, -1, 1, 2)
        rel_entry = rel_xy.gather(2, pick)[:, :, 0]
        entry_xy = xy.gather(2, pick)[:, :, 0]
        s = scale[:, None]
        excess = nc.gather(2, j)[..., 0] - self._flat_nc_min[flat]
        excess = (excess / (self.per_m[:, None] * s)).clamp_(0.0, EXCESS_CLIP)
        c_xy = self._flat_cent[flat]  # (R, k, 2)
        home = _sq_norm(c_xy - self.depot[:, None]).sqrt_() / s
        rel = torch.stack([rel_entry, c_xy - self.pos[:, None]], 2)
        cand_vec = rel / s[..., None, None]
        cand_sc = torch.stack([excess, torch.log1p(home)], -1)
        left = ~self.visited
        n_left = left.sum(1).clamp_min(1)
        mass = torch.bmm(left[:, None].to(cent.dtype), cent)[:, 0] / n_left[:, None]
        to_depot = self.depot - self.pos
        to_mass = mass - self.pos
        dd = to_depot.norm(dim=-1)
        ctx_vec = torch.stack([to_depot / dd.clamp_min(1e-6)[:, None],
                               to_mass / to_mass.norm(dim=-1).clamp_min(1e-6)[:, None]], 1)
        ctx_sc = torch.stack([self.omega, n_left / self.size, torch.log1p(dd / scale)], -1)
        if not full:
            zero = ~mask
            cand_vec = cand_vec.masked_fill(zero[..., None, None], 0.0)
            cand_sc = cand_sc.masked_fill(zero[..., None], 0.0)
        return View(cand_vec.float(), cand_sc.float(), ctx_vec.float(), ctx_sc.float(), mask,
                    cluster, entry_xy)

    def goto(self, cluster: torch.Tensor) -> None:
        """Visit ``cluster`` ``(R,)`` (any unvisited one) through its entry node from the
        current point: how a known tour is walked (imitation) to the same states as decoding."""
        ii = self.inst
        xy = self.env.coords[ii, cluster]  # (R, N, 2)
        nc = self.env.node_cost[ii, cluster]
        reach = (xy - self.pos[:, None]).pow(2).sum(-1).sqrt()
        j = (self.edge[:, None] * reach + nc).argmin(-1)
        self.pos = xy[self.rows, j]
        self.visited = self.visited.clone()
        self.visited[self.rows, cluster] = True

    def move(self, view: View, choice: torch.Tensor) -> torch.Tensor:
        """Visit candidate ``choice`` ``(R,)`` of ``view``; returns the clusters visited ``(R,)``."""
        cluster = view.cluster[self.rows, choice]
        self.pos = view.entry_xy[self.rows, choice]
        self.visited = self.visited.clone()
        self.visited[self.rows, cluster] = True
        return cluster


def _sq_norm(v: torch.Tensor) -> torch.Tensor:
    """Squared length of 2-D vectors ``(..., 2)``: x * x + y * y (as a sum over the last axis
    gives, much faster than a reduction over an axis of length 2)."""
    x, y = v[..., 0], v[..., 1]
    return torch.addcmul(x * x, y, y)


def frame(starts: int) -> torch.Tensor:
    """``(starts, 2, 2)`` orthogonal maps: rotations by 2 pi j / starts, odd j also mirrored."""
    mats = []
    for j in range(starts):
        a = 2 * math.pi * j / starts
        rot = torch.tensor([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
        if j % 2:
            rot = rot @ torch.tensor([[-1.0, 0.0], [0.0, 1.0]])
        mats.append(rot)
    return torch.stack(mats)


def turn(v: View | tuple[torch.Tensor, ...], maps: torch.Tensor) -> tuple[torch.Tensor, ...]:
    """The view's features with every 2-D vector mapped by ``maps`` ``(R, 2, 2)`` (one per row):
    ``(cand_vec, cand_sc, ctx_vec, ctx_sc)``."""
    cand_vec, cand_sc, ctx_vec, ctx_sc = ((v.cand_vec, v.cand_sc, v.ctx_vec, v.ctx_sc)
                                          if isinstance(v, View) else v[:4])
    m = maps.transpose(1, 2)
    return (cand_vec @ m[:, None], cand_sc, ctx_vec @ m, ctx_sc)


class LocalPolicy(nn.Module):
    """A transformer over the local view, re-run each step; one score per candidate.

    Parameters
    ----------
    dim
        Token width.
    n_heads
        Attention heads.
    n_layers
        Transformer layers.
    ff
        Feed-forward width.
    k
        Candidates in the view.
    """

    #: Not trained by REINFORCE (no baseline): :mod:`~.imitation` trains it.
    baselines: tuple[str, ...] = ()

    def __init__(self, dim: int = 64, n_heads: int = 4, n_layers: int = 2, ff: int = 128,
                 k: int = 16) -> None:
        super().__init__()
        self.config: dict[str, Any] = {"model": "local", "dim": dim, "n_heads": n_heads,
                                       "n_layers": n_layers, "ff": ff, "k": k}
        self.k = k
        self.cand = nn.Linear(2 * CAND_VECTORS + CAND_SCALARS, dim)
        self.ctx = nn.Linear(2 * CTX_VECTORS + CTX_SCALARS, dim)
        layer = nn.TransformerEncoderLayer(dim, n_heads, ff, dropout=0.0, batch_first=True)
        self.encoder = nn.TransformerEncoder(layer, n_layers, enable_nested_tensor=False)
        self.score = nn.Sequential(nn.Linear(2 * dim, dim), nn.ReLU(), nn.Linear(dim, 1))

    def scores(self, cand_vec: torch.Tensor, cand_sc: torch.Tensor, ctx_vec: torch.Tensor,
               ctx_sc: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
        """Logits ``(R, k)`` of the candidates (-inf where ``mask`` is false)."""
        r, k = mask.shape
        tc = self.cand(torch.cat([cand_vec.reshape(r, k, -1), cand_sc], -1))
        tx = self.ctx(torch.cat([ctx_vec.reshape(r, -1), ctx_sc], -1))[:, None]
        # no padding mask while every candidate exists (most steps): a plain softmax is faster
        full = bool(mask.all())
        pad = None if full else torch.cat([mask.new_zeros((r, 1)), ~mask], 1)
        x = torch.cat([tx, tc], 1)
        if torch.is_grad_enabled():
            h = self.encoder(x, src_key_padding_mask=pad)
        else:  # decoding: the same layers as plain operations, without the module's checks
            for layer in self.encoder.layers:
                x = encoder_layer(layer, x, pad)
            h = x
        # the score MLP's first layer on [candidate, context] as two products: the context's once
        first, act, last = self.score
        d = h.shape[-1]
        w = first.weight
        ctx_part = torch.addmm(first.bias, h[:, 0], w[:, d:].t())  # (R, dim)
        hidden = act(nn.functional.linear(h[:, 1:], w[:, :d]).add_(ctx_part[:, None]))
        logits = last(hidden).squeeze(-1)
        return logits if full else logits.masked_fill(~mask, -math.inf)

    def decode(self, env: EnvBatch, mode: str = "greedy", *, generator: torch.Generator | None = None,
               starts: int = 1, flight_per_m: torch.Tensor | None = None,
               ) -> tuple[torch.Tensor, torch.Tensor]:
        """Decode ``starts`` tours per instance, each in its own rotated frame (:func:`frame`).

        Returns
        -------
        order : torch.Tensor
            ``(B * starts, K)``: rows ``i * starts ..`` are instance i's tours.
        logp : torch.Tensor
            ``(B * starts,)`` log-probability of each tour.
        """
        if flight_per_m is None:
            flight_per_m = _flight_per_m(env)
        walk = Walk(env, starts, self.k, flight_per_m, shrink=True)
        maps = frame(starts).repeat(env.shape[0], 1, 1)
        steps, logp = [], torch.zeros(walk.r)
        for step in range(walk.n_clusters):
            v = walk.view()
            if mode == "greedy" and step == walk.n_clusters - 1:  # one cluster left: log p = 0
                steps.append(walk.move(v, v.mask.int().argmax(-1)))
                continue
            # one start: its frame is the identity, and turning the view would change nothing
            features = turn(v, maps) if starts > 1 else (v.cand_vec, v.cand_sc, v.ctx_vec, v.ctx_sc)
            logits = self.scores(*features, v.mask)
            lp = torch.log_softmax(logits, -1)
            if mode == "greedy":
                choice = logits.argmax(-1)
            else:
                choice = torch.multinomial(lp.exp(), 1, generator=generator)[:, 0]
            logp = logp + lp[walk.rows, choice]
            steps.append(walk.move(v, choice))
        return torch.stack(steps, 1), logp


def encoder_layer(layer: nn.TransformerEncoderLayer, x: torch.Tensor,
                  pad: torch.Tensor | None = None) -> torch.Tensor:
    """One post-norm ReLU encoder layer (as :class:`LocalPolicy` builds it) as plain operations.

    The same function as ``layer(x, src_key_padding_mask=pad)`` without dropout (the outputs of
    padded tokens aside, which no score reads). Decoding re-encodes a small batch at every step,
    where the module's own checks of its configuration and hooks took about a fifth of the
    time; this form also runs the products as ``addmm`` over all tokens at once.

    Parameters
    ----------
    layer
        A trained layer: ``batch_first``, ``norm_first`` false, ReLU.
    x
        ``(R, T, D)`` tokens.
    pad
        ``(R, T)`` true where a token is padding (is not attended to), or ``None``.
    """
    attn = layer.self_attn
    r, t, d = x.shape
    heads = attn.num_heads
    flat = x.reshape(r * t, d)
    qkv = torch.addmm(attn.in_proj_bias, flat, attn.in_proj_weight.t())
    q, k, v = qkv.view(r, t, 3, heads, d // heads).permute(2, 0, 3, 1, 4)
    mask = None if pad is None else ~pad[:, None, None, :]
    o = nn.functional.scaled_dot_product_attention(q, k, v, attn_mask=mask)
    o = torch.addmm(attn.out_proj.bias, o.transpose(1, 2).reshape(r * t, d), attn.out_proj.weight.t())
    n1, n2 = layer.norm1, layer.norm2
    flat = nn.functional.layer_norm(o.add_(flat), (d,), n1.weight, n1.bias, n1.eps)
    ff = torch.addmm(layer.linear1.bias, flat, layer.linear1.weight.t()).relu_()
    ff = torch.addmm(layer.linear2.bias, ff, layer.linear2.weight.t())
    return nn.functional.layer_norm(ff.add_(flat), (d,), n2.weight, n2.bias, n2.eps).view(r, t, d)


def _flight_per_m(env: EnvBatch) -> torch.Tensor:
    """The UAV's flight energy per metre per instance, from the batch (edge cost / (1 - omega));
    the default parameters' where omega is 1."""
    from gtsp_bench.params import EnergyParams

    default = EnergyParams().flight_energy_per_m
    free = 1.0 - env.omega
    out = torch.full_like(env.edge_per_m, default)
    ok = free > 1e-9
    out[ok] = env.edge_per_m[ok] / free[ok]
    return out

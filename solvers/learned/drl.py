"""The paper's policy (section IV): a Seq2Seq pointer network trained by REINFORCE with a critic.

Encoder: one linear embedding per element of C = {b0, G_1, ..., G_K} into D = 128. A cluster is
the vector of its N node coordinates (scaled to the unit square) plus omega, so the model is tied
to the N it was trained with (other N: a clear error); the depot has its own embedding of
(x, y, omega). Omega is an input, so one model serves every omega (the paper trains one model per
omega). Decoder: an LSTM cell of 128 units fed the embedding of the element chosen last (the depot
first). Attention (eqs. "u_k" to "u_kp"): u = v_a tanh(W1 e + W2 h), a = softmax(u),
g = sum a e, logits = v_g tanh(W3 e + W4 g), clipped to C_L tanh(.) with C_L = 10, visited
elements masked. The paper's u_k runs over every element; with ``glimpse="unvisited"`` (how
``gtsp-bench train`` and the shipped checkpoint train it) visited elements are masked in the
glimpse too, so g summarises what is left to visit, which the LSTM state alone must otherwise
track: a policy trained on K = 4 then generalises much better to K = 10 (`gtsp-bench bench learned`).
Beyond the paper's equations, ``local`` adds to each pointer logit a learned term of K-free
numbers read from the UAV's location (the paper's state includes it; ``energy`` adds the rule's
next step into each cluster), and ``damp`` weights the pointer's own logits by
min(1, K_train / clusters left) beyond the training K; the shipped checkpoint has all three.
Heads: the paper's rule (eq. "chselection") by default, or optimal heads for the
decoded order. The critic: an attention-weighted sum of its own embeddings -> dense + ReLU ->
dense -> the expected cost (kJ).
"""

from __future__ import annotations

import math
from typing import Any

import torch
from gtsp_bench.solvers.learned.decoding import choose, step_logprobs
from gtsp_bench.solvers.learned.env import (
    AREA_SCALE,
    COST_SCALE,
    EnvBatch,
    element_features,
    paper_head_step,
    rule_entry,
)
from torch import nn

from gtsp_bench.checks import check_bool, check_choice, check_int
from gtsp_bench.errors import InputError

#: Elements the glimpse attends to: all of C (as eq. "u_k" reads) or the unvisited ones only.
GLIMPSES = ("all", "unvisited")


class _Embedding(nn.Module):
    """Linear embedding of the depot and of each cluster's flattened coordinates (+ omega)."""

    def __init__(self, n_nodes: int, dim: int) -> None:
        super().__init__()
        self.n_nodes = n_nodes
        self.depot = nn.Linear(3, dim)
        self.cluster = nn.Linear(2 * n_nodes + 1, dim)

    def forward(self, env: EnvBatch) -> torch.Tensor:
        b, k, n = env.shape
        if n != self.n_nodes:
            raise InputError(f"the drl model was trained on clusters of {self.n_nodes} nodes and "
                             f"cannot embed clusters of {n} (use 'am', which takes any size)")
        nodes, depot = element_features(env)
        flat = torch.cat([nodes[..., :2].reshape(b, k, 2 * n), nodes[:, :, 0, 2:3]], dim=-1)
        return torch.cat([self.depot(depot)[:, None], self.cluster(flat)], dim=1)  # (B, K+1, D)


class Critic(nn.Module):
    """Baseline V(C): attention-weighted sum of embeddings -> two dense layers -> scalar (kJ)."""

    def __init__(self, n_nodes: int, dim: int) -> None:
        super().__init__()
        self.embed = _Embedding(n_nodes, dim)
        self.w = nn.Linear(dim, dim)
        self.v = nn.Linear(dim, 1, bias=False)
        self.head = nn.Sequential(nn.Linear(dim, dim), nn.ReLU(), nn.Linear(dim, 1))

    def forward(self, env: EnvBatch) -> torch.Tensor:
        """Predicted cost ``(B,)`` in kJ."""
        e = self.embed(env)
        a = torch.softmax(self.v(torch.tanh(self.w(e))).squeeze(-1), dim=-1)
        return self.head((a[..., None] * e).sum(1)).squeeze(-1)


class PointerPolicy(nn.Module):
    """The paper's Seq2Seq actor (and its critic, used only in training, by the ``critic``
    baseline; its weights are part of the policy file).

    Parameters
    ----------
    n_nodes
        N, the cluster size it embeds.
    dim
        D, embedding and LSTM width (paper: 128).
    glimpse
        ``all``: the glimpse attends to every element; ``unvisited``: visited ones are masked
        in the glimpse as in the pointer.
    local
        Add a learned term ``f(d(UAV, c_k), d(c_k, b0), omega)`` to each element's pointer logit:
        ``d`` are distances from the UAV's location (the head it hovers above, chosen by the
        paper's rule as the order is decoded; the depot first) and to the depot, ``c_k`` the
        centroid of cluster k, ``f`` a 3 -> 32 -> 1 MLP. The paper's state includes the UAV's
        location (section IV-C); this is where it enters the decision. ``False``: the paper's
        pointer alone.
    damp
        With ``local``: weight the pointer's own logits by ``min(1, damp / n)``, ``n`` the
        clusters left to visit, before the local term is added. The trainer sets it to the
        training K, so no training step sees a weight below 1; at larger K the pointer, which
        has only learned to choose among at most ``damp`` clusters, then shares the first
        decisions with the K-free local term. 0: off.
    energy
        With ``local``: two more features per cluster for ``f``: the weighted energy of
        entering it from the UAV's location (the value eq. "chselection" minimises, in kJ) and
        the distance from the head that rule would pick there to the depot.
    """

    #: Training baselines it supports (:mod:`gtsp_bench.solvers.learned.baselines`).
    baselines = ("critic",)

    def __init__(self, n_nodes: int = 20, dim: int = 128, glimpse: str = "all",
                 local: bool = False, damp: int = 0, energy: bool = False) -> None:
        super().__init__()
        check_choice("drl glimpse", glimpse, GLIMPSES)
        check_bool("drl local", local)
        damp = check_int("drl damp", damp, 0)
        check_bool("drl energy", energy)
        if damp and not local:
            raise InputError("drl damp needs the local term (local=True)")
        if energy and not local:
            raise InputError("drl energy needs the local term (local=True)")
        self.config: dict[str, Any] = {"model": "drl", "n_nodes": n_nodes, "dim": dim}
        if glimpse != "all":
            self.config["glimpse"] = glimpse
        if local:
            self.config["local"] = True
        if damp:
            self.config["damp"] = damp
        if energy:
            self.config["energy"] = True
        self.damp = damp
        self.energy = energy
        width = 5 if energy else 3
        self.local = nn.Sequential(nn.Linear(width, 32), nn.ReLU(), nn.Linear(32, 1)) if local else None
        self.mask_glimpse = glimpse == "unvisited"
        self.embed = _Embedding(n_nodes, dim)
        self.lstm = nn.LSTMCell(dim, dim)
        self.w1 = nn.Linear(dim, dim, bias=False)
        self.w2 = nn.Linear(dim, dim)
        self.v_a = nn.Linear(dim, 1, bias=False)
        self.w3 = nn.Linear(dim, dim, bias=False)
        self.w4 = nn.Linear(dim, dim)
        self.v_g = nn.Linear(dim, 1, bias=False)
        self.critic = Critic(n_nodes, dim)

    def glimpse(self, e: torch.Tensor, k1: torch.Tensor, h: torch.Tensor, visited: torch.Tensor,
                ) -> tuple[torch.Tensor, torch.Tensor]:
        """Glimpse ``g = sum a e`` ``(B, D)`` and its weights ``a = softmax(u)`` ``(B, K + 1)``.

        ``k1`` is ``W1 e``; visited elements get zero weight when the glimpse is ``unvisited``.
        """
        u = self.v_a(torch.tanh(k1 + self.w2(h)[:, None])).squeeze(-1)
        if self.mask_glimpse:
            u = u.masked_fill(visited, -math.inf)
        a = torch.softmax(u, dim=-1)
        return (a[..., None] * e).sum(1), a

    def decode(self, env: EnvBatch, mode: str = "greedy", *, generator: torch.Generator | None = None,
               forced: torch.Tensor | None = None) -> tuple[torch.Tensor, torch.Tensor]:
        """Decode a visiting order per instance, or score ``forced`` ``(B, T)``: 0-based orders,
        or their first T <= K steps (then only those are decoded).

        Returns
        -------
        order : torch.Tensor
            ``(B, K)`` cluster indices (0-based, depot excluded).
        logp : torch.Tensor
            ``(B,)`` log-probability of the order under the policy.
        """
        order, logp, _ = self.decode_first(env, mode, generator=generator, forced=forced)
        return order, logp

    def decode_first(self, env: EnvBatch, mode: str = "greedy", *,
                     generator: torch.Generator | None = None, forced: torch.Tensor | None = None,
                     ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """:meth:`decode`, and the log-probabilities ``(B, K)`` of the first step's choice of
        each cluster (from the depot): the first step of every order at once, e.g. of a tour
        and of its reverse, at no extra cost."""
        e, k1, k3, ctx = self._start(env)
        b, m, d = e.shape
        rows = torch.arange(b)
        visited = torch.zeros((b, m), dtype=torch.bool)
        visited[:, 0] = True  # pi_0 = b0
        h = c = e.new_zeros((b, d))
        x = e[:, 0]
        where = env.depot  # the UAV's location (m)
        actions, logp, first = [], e.new_zeros(b), e.new_zeros((b, 0))
        for t in range(m - 1 if forced is None else forced.shape[1]):
            h, c = self.lstm(x, (h, c))
            logits = self._logits(env, e, k1, k3, h, visited, where, ctx)
            if t == 0:
                first = step_logprobs(logits, visited)[:, 1:]
            act, step_logp, visited = choose(logits, visited, mode, generator,
                                             None if forced is None else forced[:, t] + 1)
            logp = logp + step_logp
            actions.append(act)
            x = e[rows, act]
            if self.local is not None:
                where = paper_head_step(env, where, act - 1)[1]
        return torch.stack(actions, 1) - 1, logp, first

    def _start(self, env: EnvBatch) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor,
                                             tuple[torch.Tensor, ...]]:
        """Embeddings ``e``, ``W1 e``, ``W3 e`` and the local term's fixed inputs."""
        e = self.embed(env)
        ctx: tuple[torch.Tensor, ...] = ()
        if self.local is not None:  # centroids (depot first), their distances to the depot, omega
            pts = torch.cat([env.depot[:, None], env.coords.mean(2)], dim=1) / AREA_SCALE
            home = (pts - pts[:, :1]).pow(2).sum(-1).sqrt()
            ctx = (pts, home, env.omega[:, None].expand(e.shape[0], e.shape[1]))
        return e, self.w1(e), self.w3(e), ctx

    def _logits(self, env: EnvBatch, e: torch.Tensor, k1: torch.Tensor, k3: torch.Tensor,
                h: torch.Tensor, visited: torch.Tensor, where: torch.Tensor,
                ctx: tuple[torch.Tensor, ...]) -> torch.Tensor:
        """Raw pointer logits ``(B, K + 1)`` at decoder state ``h``, the UAV at ``where`` (m)."""
        g = self.glimpse(e, k1, h, visited)[0]
        logits = self.v_g(torch.tanh(k3 + self.w4(g)[:, None])).squeeze(-1)
        if self.damp:
            left = (~visited).sum(1, keepdim=True)  # clusters left to visit, >= 1
            logits = logits * (self.damp / left).clamp(max=1.0)
        if self.local is not None:
            pts, home, omega = ctx
            near = (pts - where[:, None] / AREA_SCALE).pow(2).sum(-1).sqrt()
            cols = [near, home, omega]
            if self.energy:
                cols += self._rule_features(env, where)
            feats = torch.stack(cols, dim=-1).float()  # (B, K + 1, 3 or 5)
            logits = logits + self.local(feats).squeeze(-1)
        return logits

    @staticmethod
    def _rule_features(env: EnvBatch, where: torch.Tensor) -> list[torch.Tensor]:
        """``(B, K + 1)`` each, the depot's column 0: the paper rule's energy of entering each
        cluster from ``where`` (kJ), and the distance from the head it picks to the depot."""
        b = env.shape[0]
        enter, j = rule_entry(env, where, env.coords, env.node_cost)  # (B, K)
        xy = env.coords.gather(2, j[:, :, None, None].expand(-1, -1, 1, 2))[:, :, 0]  # (B, K, 2)
        back = (xy - env.depot[:, None]).pow(2).sum(-1).sqrt() / AREA_SCALE
        zero = enter.new_zeros((b, 1))
        return [torch.cat([zero, enter / COST_SCALE], 1), torch.cat([zero, back], 1)]

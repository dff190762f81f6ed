"""Shared pieces of the learned policies (``drl``, ``am``): batched environment, heads, decoding,
checkpoints and the solver classes.

Everything here imports torch; nothing in ``gtsp_bench`` imports this module at start-up.

The environment prices tours with the quantities of the one evaluator: node costs from
:func:`gtsp_bench.energy.cluster_ground_energy` and :meth:`EnergyParams.hover_energy`, flight at
:attr:`EnergyParams.flight_energy_per_m` per metre, so that

    cost = sum of node costs of the heads + (1 - omega) * flight_energy_per_m * tour length

equals :func:`gtsp_bench.energy.evaluate` (a test checks it on random tours). Models see
coordinates divided by :data:`AREA_SCALE` (the generator's 1000 m square becomes the unit
square) and omega; the scale is fixed, not per instance, because the energy model is not
scale-free (d_0, flight energy per metre).
"""

from __future__ import annotations

import dataclasses
import hashlib
import itertools
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import nn

from gtsp_bench.checks import check_int, check_omega
from gtsp_bench.energy import cluster_ground_energy
from gtsp_bench.errors import InputError
from gtsp_bench.instance import Instance
from gtsp_bench.io import atomic_write_bytes
from gtsp_bench.params import EnergyParams
from gtsp_bench.registry import Solution

#: Coordinates are divided by this (m) before they enter a model.
AREA_SCALE = 1000.0
#: Costs enter losses in kJ (rewards of a few thousand J otherwise dominate Adam's first steps).
COST_SCALE = 1000.0
#: Relative ground energy of a node inside its cluster is divided by this (J) as a model feature.
GROUND_SCALE = 50.0
#: Logit clipping C_L (paper, after Bello et al.).
CLIP = 10.0
#: Where the shipped checkpoints live.
CHECKPOINT_DIR = Path(__file__).resolve().parent / "checkpoints"
#: Head-selection rules.
HEAD_RULES = ("paper", "optimal")
#: Marker of a policy file.
FILE_KIND = "gtsp-bench-policy"


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


def choose_heads(env: EnvBatch, order: torch.Tensor, rule: str) -> torch.Tensor:
    """Heads for ``order`` by ``rule`` (``"paper"`` or ``"optimal"``)."""
    if rule == "paper":
        return paper_heads(env, order)
    return optimal_heads_batch(env, order)[0]


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


def _clipped(logits: torch.Tensor, visited: torch.Tensor) -> torch.Tensor:
    return (CLIP * torch.tanh(logits)).masked_fill(visited, -math.inf)


def step_logprobs(logits: torch.Tensor, visited: torch.Tensor) -> torch.Tensor:
    """Log-probabilities ``(R, M)`` of one step: raw logits clipped to C_L tanh(.), visited
    elements masked (-inf)."""
    return torch.log_softmax(_clipped(logits, visited), -1)


def choose(logits: torch.Tensor, visited: torch.Tensor, mode: str,
           generator: torch.Generator | None, forced: torch.Tensor | None = None,
           ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """One decoding step from raw logits ``(R, M)``.

    The logits are clipped to C_L tanh(.), visited elements set to -inf, then the action is the
    argmax (``mode="greedy"``), a sample, or ``forced`` ``(R,)`` when given (to score a known
    order).

    Returns
    -------
    action : torch.Tensor
        ``(R,)`` chosen elements.
    logp : torch.Tensor
        ``(R,)`` their log-probabilities.
    visited : torch.Tensor
        The new visited mask (a copy; autograd needs the old one).
    """
    logits = _clipped(logits, visited)
    logprob = torch.log_softmax(logits, -1)
    if forced is not None:
        action = forced
    elif mode == "greedy":
        action = logits.argmax(-1)
    else:
        action = torch.multinomial(logprob.exp(), 1, generator=generator)[:, 0]
    rows = torch.arange(len(action))
    visited = visited.clone()
    visited[rows, action] = True
    return action, logprob[rows, action], visited


# ---------------------------------------------------------------------- checkpoints
def build_model(config: dict[str, Any]) -> nn.Module:
    """The policy described by ``config`` (its ``"model"`` key names the class)."""
    from gtsp_bench.solvers.learned.am import AttentionPolicy
    from gtsp_bench.solvers.learned.drl import PointerPolicy

    classes = {"drl": PointerPolicy, "am": AttentionPolicy}
    name = config.get("model")
    if name not in classes:
        raise InputError(f"unknown model {name!r} (valid: {', '.join(classes)})")
    kwargs = {k: v for k, v in config.items() if k != "model"}
    try:
        return classes[name](**kwargs)
    except TypeError as e:
        raise InputError(f"bad model config {config!r}: {e}") from None


def save_policy(model: nn.Module, path: str | Path) -> None:
    """Write a policy file (config + state_dict) atomically."""
    import io

    buf = io.BytesIO()
    torch.save({"kind": FILE_KIND, "config": model.config, "state_dict": model.state_dict()}, buf)
    atomic_write_bytes(path, buf.getvalue())


def load_policy(path: str | Path, model_name: str | None = None) -> nn.Module:
    """Load a policy file written by :func:`save_policy` (weights only, never pickled code).

    Raises
    ------
    InputError
        One line naming the file: missing, unreadable or corrupt, not a policy, a different
        model than ``model_name``, or weights whose shapes do not fit the config.
    """
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: no such checkpoint file")
    try:
        data = torch.load(p, map_location="cpu", weights_only=True)
    except Exception:  # torch raises many kinds (and long texts) on a corrupt or foreign file
        raise InputError(
            f"{p}: not a readable checkpoint (not a file written by 'gtsp-bench train', or damaged)"
        ) from None
    if not isinstance(data, dict) or data.get("kind") != FILE_KIND:
        raise InputError(f"{p}: not a gtsp-bench policy checkpoint")
    config = data.get("config")
    if not isinstance(config, dict):
        raise InputError(f"{p}: checkpoint has no model config")
    if model_name is not None and config.get("model") != model_name:
        raise InputError(f"{p}: checkpoint holds a {config.get('model')!r} model, not {model_name!r}")
    try:
        model = build_model(config)
    except InputError as e:
        raise InputError(f"{p}: {e}") from None
    try:
        model.load_state_dict(data["state_dict"])
    except (RuntimeError, KeyError, TypeError) as e:
        first = str(e).strip().splitlines()
        reason = " ".join(line.strip() for line in first[:2])[:160]
        raise InputError(f"{p}: weights do not fit the model config ({reason})") from None
    model.eval()
    return model


# ---------------------------------------------------------------------- solvers
class LearnedSolver:
    """Common body of the learned solvers: load a policy, decode batches, build solutions.

    Parameters
    ----------
    checkpoint
        Policy file; default: the shipped ``solvers/learned/checkpoints/<model>.pt``.
    heads
        ``"paper"`` (the paper's rule, eq. "chselection") or ``"optimal"`` (the best heads for the
        decoded order, a shortest path).
    samples
        Sampled tours per instance in addition to the greedy ones (0: greedy only).
    threads
        torch threads for inference.
    augment
        Also decode the mirror image of each instance (x -> 2 x_depot - x; same costs) and keep
        the better tour.
    reverse
        Also price every decoded tour flown backwards and keep the better direction. Only the
        paper's head rule can tell the two apart (it picks each head from the previous one);
        with optimal heads both cost the same.
    """

    model_name = ""
    default_heads = "paper"

    def __init__(self, checkpoint: str | None = None, heads: str | None = None, samples: int = 0,
                 threads: int = 1, augment: bool = False, reverse: bool = False) -> None:
        heads = heads or self.default_heads
        if heads not in HEAD_RULES:
            raise InputError(f"heads must be one of {', '.join(HEAD_RULES)}, got {heads!r}")
        samples = check_int("samples", samples, 0)
        threads = check_int("threads", threads, 1)
        self.checkpoint = Path(checkpoint) if checkpoint else CHECKPOINT_DIR / f"{self.model_name}.pt"
        self.heads = heads
        self.samples = samples
        for name, flag in (("augment", augment), ("reverse", reverse)):
            if not isinstance(flag, bool):
                raise InputError(f"{name} must be true or false, got {flag!r}")
        self.threads = threads
        self.augment = augment
        self.reverse = reverse
        self._model: nn.Module | None = None

    @classmethod
    def revision(cls) -> str:
        """A hash of the default checkpoint's bytes (the runner re-solves when it changes)."""
        path = CHECKPOINT_DIR / f"{cls.model_name}.pt"
        if not path.is_file():
            return "missing"
        return hashlib.sha256(path.read_bytes()).hexdigest()[:12]

    @property
    def model(self) -> nn.Module:
        """The policy, loaded on first use."""
        if self._model is None:
            self._model = load_policy(self.checkpoint, self.model_name)
        return self._model

    def candidates(self, env: EnvBatch, generator: torch.Generator) -> torch.Tensor:
        """``(B, R, K)`` candidate orders per instance (greedy first, then samples, then each of
        them reversed if ``reverse``)."""
        b, _, _ = env.shape
        views = [env, mirror(env)] if self.augment else [env]
        orders = [self.model.decode(v, "greedy")[0].view(b, -1, env.shape[1]) for v in views]
        if self.samples:
            rep = env.repeat(self.samples)
            sampled, _ = self.model.decode(rep, "sample", generator=generator)
            orders.append(sampled.view(b, -1, env.shape[1]))
        cand = torch.cat(orders, dim=1)
        return torch.cat([cand, cand.flip(-1)], dim=1) if self.reverse else cand

    def solve_env(self, env: EnvBatch, seed: int = 0) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Best candidate per instance: ``order (B, K)``, ``heads (B, K)``, ``cost (B,)``."""
        torch.set_num_threads(self.threads)
        generator = torch.Generator().manual_seed(int(seed))
        with torch.inference_mode():
            cand = self.candidates(env, generator)  # (B, R, K)
            b, r, k = cand.shape
            rep = env.repeat(r)
            flat = cand.reshape(b * r, k)
            heads = choose_heads(rep, flat, self.heads)
            cost = tour_cost(rep, flat, heads).view(b, r)
            best = cost.argmin(1)
            rows = torch.arange(b)
            return cand[rows, best], heads.view(b, r, k)[rows, best], cost[rows, best]

    def solve_batch(self, instances: Sequence[Instance], omegas: Sequence[float], *,
                    seed: int = 0) -> list[Solution]:
        """Solve many instances of one K at once (what the benchmark times)."""
        start = time.perf_counter()
        env = env_from_instances(instances, omegas)
        order, heads, cost = self.solve_env(env, seed)
        out = []
        for i, inst in enumerate(instances):
            o = tuple(int(c) for c in order[i])
            h = tuple(int(x) if x < size else 0  # padded copies of node 0 are node 0
                      for x, size in zip(heads[i].tolist(), inst.sizes, strict=True))
            # tour_cost is the evaluator's objective (tested to 1e-12); run_solver re-checks it
            out.append(Solution(o, h, objective=float(cost[i]), status="feasible",
                                stats={"heads": self.heads, "batch": len(instances)}))
        stats = {"batch_wall_s": time.perf_counter() - start}
        return [dataclasses.replace(sol, stats={**sol.stats, **stats}) for sol in out]

    def solve(self, instance: Instance, omega: float | None, *, time_limit: float | None = None,
              seed: int = 0) -> Solution:
        """Decode one instance (a batch of one); ``time_limit`` is not needed (milliseconds)."""
        if omega is None:
            raise InputError(f"{instance.name}: learned policies need a UAV instance and omega")
        return self.solve_batch([instance], [omega], seed=seed)[0]

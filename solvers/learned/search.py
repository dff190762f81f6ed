"""The ``local-search`` solver: the local-view policy (:mod:`~.local`) as a search, in a time budget.

One greedy decode is the policy's best guess; a search spends more time for a better tour:

1. **Multi-start**: ``starts`` greedy decodes, each in its own rotated (odd: mirrored) frame
   (POMO-style instance augmentation); the best tour, optimal heads.
2. **Local search** (``ls``, default on): the shared 2-opt / or-opt / heads search
   (:mod:`gtsp_bench.solvers.heuristics.local_search`) to its local optimum.
3. **Re-construction by the policy** (LEHD's random re-construct): each round draws one segment
   length, cuts the current tour into consecutive segments of that length from a random offset
   (:func:`partition`) and re-decodes every segment ``max(1, width // segments)`` times, all in
   one batch (:func:`reconstruct`): each copy greedily with the policy as a small problem of its
   own (the UAV starts where the tour enters the segment, the segment's clusters are the
   unvisited ones, and the point where the tour leaves it stands in for the depot, the policy's
   "return home"), in its own random rotated frame, half of them flown backwards. The
   candidates are priced with optimal heads; every segment whose best copy is better replaces
   its old run at once (the merged tour is kept if it beats the best single candidate), then
   ``ls`` again. Rounds go on until the time is spent (the last round is cut to the length that
   fits, judged by the previous round's seconds per step) or ``patience`` rounds in a row found
   nothing better.
4. **Kicks** (the last ``kick_share`` of the budget, and whatever the rounds left; none below 8
   clusters, where the search ends after its rounds): the iterated local search of
   :func:`gtsp_bench.solvers.heuristics.ils.kick` from the best tour (double-bridge kicks, each
   followed by the lns kernels' local search). ``greedy+ils`` runs the same from the greedy tour:
   the learned benchmark's control for what the policy adds.

The budget is ``seconds_per_cluster`` * K (default 0.01 s: 1 s at K = 100, 2 s at K = 200), or
the runner's time limit where smaller; the rounds end at ``1 - kick_share`` of it, the kicks
:data:`~gtsp_bench.solvers.heuristics.ils.MARGIN` of it early, so that the final pricing ends
within it. The search is seeded (the segments, frames and kicks); on a loaded machine fewer
rounds and kicks fit in the budget, so results depend on the machine's speed.
"""

from __future__ import annotations

import math
import time

import numpy as np
import torch
from gtsp_bench.solvers.heuristics import lns_kernels as kernels
from gtsp_bench.solvers.heuristics.ils import MARGIN, kick
from gtsp_bench.solvers.heuristics.local_search import LocalSearch
from gtsp_bench.solvers.learned.env import (
    EnvBatch,
    env_from_instances,
    optimal_heads_batch,
    unpad_heads,
)
from gtsp_bench.solvers.learned.local import LocalPolicy, Walk, _flight_per_m, turn
from gtsp_bench.solvers.learned.solver import LearnedSolver

from gtsp_bench.checks import check_bool, check_float, check_int
from gtsp_bench.energy import evaluate
from gtsp_bench.errors import InputError
from gtsp_bench.instance import Instance
from gtsp_bench.problem import price
from gtsp_bench.solver import Progress, Solution, no_progress

#: Improvements smaller than this share of the tour cost are ignored (rounding noise).
REL_TOL = 1e-9
#: Default ``kick_share``.
KICK_SHARE = 0.5


def random_maps(n: int, generator: torch.Generator) -> torch.Tensor:
    """``(n, 2, 2)`` random rotations, half of them mirrored (the problem's symmetries)."""
    a = torch.rand(n, generator=generator, dtype=torch.float64) * 2 * math.pi
    c, s = torch.cos(a), torch.sin(a)
    rot = torch.stack([torch.stack([c, -s], -1), torch.stack([s, c], -1)], -2)
    flip = torch.where(torch.rand(n, generator=generator) < 0.5, -1.0, 1.0).double()
    rot[:, :, 0] = rot[:, :, 0] * flip[:, None]
    return rot.float()


def reconstruct(model: LocalPolicy, env: EnvBatch, order: torch.Tensor, heads: torch.Tensor,
                starts: np.ndarray, length: int, backwards: np.ndarray,
                generator: torch.Generator) -> torch.Tensor:
    """Re-decode segments of one tour greedily with the policy.

    Parameters
    ----------
    model
        The local-view policy.
    env
        One instance (a batch of one).
    order, heads
        The tour: ``(K,)`` cluster order and ``(K,)`` head index of each cluster (by cluster).
    starts
        ``(R,)`` first position of each segment (``0 <= start <= K - length``).
    length
        Clusters per segment.
    backwards
        ``(R,)`` which segments are decoded from their end to their start.
    generator
        Draws each segment's rotated frame.

    Returns
    -------
    torch.Tensor
        ``(R, K)`` the tours with their segment re-decoded.
    """
    _, k, _ = env.shape
    r = len(starts)
    xy = env.coords[0, order, heads[order]]  # (K, 2) the tour's points in visiting order
    depot = env.depot[0]
    st = torch.from_numpy(starts)
    before = torch.where((st > 0)[:, None], xy[(st - 1).clamp_min(0)], depot)
    after_i = st + length
    after = torch.where((after_i < k)[:, None], xy[after_i.clamp_max(k - 1)], depot)
    back = torch.from_numpy(backwards)[:, None]
    walk = Walk(env, r, model.k, _flight_per_m(env), shrink=True)
    walk.pos = torch.where(back, after, before)
    walk.depot = torch.where(back, before, after)
    walk.size = length
    pos = st[:, None] + torch.arange(length)  # (R, L) positions of each segment
    seg = order[pos]
    visited = torch.ones((r, k), dtype=torch.bool)
    visited.scatter_(1, seg, False)
    walk.visited = visited
    maps = random_maps(r, generator)
    steps = []
    for step in range(length):
        v = walk.view()
        if step == length - 1:  # one cluster left: no choice to score
            choice = v.mask.int().argmax(-1)
        else:
            choice = model.scores(*turn(v, maps), v.mask).argmax(-1)
        steps.append(walk.move(v, choice))
    new = torch.stack(steps, 1)
    new = torch.where(back, new.flip(1), new)
    out = order.repeat(r, 1)
    out.scatter_(1, pos, new)
    return out


def partition(k: int, length: int, rng: np.random.Generator) -> np.ndarray:
    """First positions of ``k // length`` consecutive segments of ``length`` clusters that tile
    a tour of ``k`` clusters from a random offset (the rest, fewer than ``length``, is left
    as it is; the depot is never inside a segment)."""
    n = k // length
    offset = int(rng.integers(0, k - n * length + 1))
    return offset + length * np.arange(n)


class LocalSearchSolver(LearnedSolver):
    """The local-view policy as a search: multi-start, local search, re-construction of segments.

    Default policy: ``solvers/learned/checkpoints/local-l3.pt``. Options: ``checkpoint``,
    ``starts`` (rotated greedy decodes first, default 8), ``seconds_per_cluster`` (the budget
    per instance is this times K, default 0.01), ``width`` (decodes per round, default 16),
    ``min_segment``, ``max_segment`` (segment lengths drawn, default 2 to 60 clusters),
    ``patience`` (rounds in a row without a better tour before it stops, default 100), ``ls``
    (the shared local search after each better tour, default true), ``kick_share`` (the share of
    the budget, at its end, for kicks: :func:`~gtsp_bench.solvers.heuristics.ils.kick`; default
    KICK_SHARE, 0: none), ``threads``. Heads are always optimal for the order.
    """

    model_name = "local"
    checkpoint_name = "local-l3"
    default_heads = "optimal"

    def __init__(self, checkpoint: str | None = None, starts: int = 8,
                 seconds_per_cluster: float = 0.01, width: int = 16, min_segment: int = 2,
                 max_segment: int = 60, patience: int = 100, ls: bool = True,
                 kick_share: float = KICK_SHARE, threads: int = 1) -> None:
        super().__init__(checkpoint, "optimal", samples=0, threads=threads)
        self.starts = check_int("starts", starts, 1)
        self.seconds_per_cluster = check_float("seconds_per_cluster", seconds_per_cluster, 0.0,
                                               math.inf)
        self.width = check_int("width", width, 1)
        self.min_segment = check_int("min_segment", min_segment, 2)
        self.max_segment = check_int("max_segment", max_segment, self.min_segment)
        self.patience = check_int("patience", patience, 1)
        self.ls = check_bool("ls", ls)
        self.kick_share = check_float("kick_share", kick_share, 0.0, 1.0, open_low=False)
        if self.kick_share > 0:
            kernels.warm_up()  # compiled or loaded here, not in a solve's clock

    def solve_batch(self, instances: list[Instance], omegas: list[float], *, seed: int = 0,
                    progress: Progress = no_progress) -> list[Solution]:
        """Each instance in turn, each in its own budget."""
        return [self.solve(inst, w, seed=seed) for inst, w in zip(instances, omegas, strict=True)]

    def solve(self, instance: Instance, omega: float | None, *, time_limit: float | None = None,
              seed: int = 0, progress: Progress = no_progress) -> Solution:
        """Search for ``seconds_per_cluster * K`` seconds (or ``time_limit`` if smaller), each
        better tour reported to ``progress``."""
        start = time.perf_counter()
        if omega is None:
            raise InputError(f"{instance.name}: learned policies need a UAV instance and omega")
        budget = self.seconds_per_cluster * instance.n_clusters
        if time_limit is not None:
            budget = min(budget, float(time_limit))
        deadline = start + budget * (1.0 - MARGIN)
        rounds_end = start + budget * (1.0 - MARGIN) * (1.0 - self.kick_share)
        torch.set_num_threads(self.threads)
        env = env_from_instances([instance], [omega])
        problem = price(instance, omega)
        search = LocalSearch(problem) if self.ls else None
        gen = torch.Generator().manual_seed(int(seed))
        rng = np.random.default_rng([int(seed), 7])
        k = instance.n_clusters
        rounds = better = kicks = 0
        with torch.inference_mode():
            t_decode = time.perf_counter()
            orders, _ = self.model.decode(env, "greedy", starts=self.starts)
            # seconds per decoding step of a round's batch, first judged by the starts' decode
            per_step = (time.perf_counter() - t_decode) / k * max(1.0, self.width / self.starts)
            hs, costs = optimal_heads_batch(env.repeat(self.starts), orders)
            j = int(costs.argmin())
            order, heads, cost = orders[j], hs[j], float(costs[j])
            progress(cost)
            if self.ls:
                order, heads, cost = self._local_search(search, env, order, heads, cost, rounds_end)
                progress(cost)
            stall = 0
            shortest = min(self.min_segment, k)
            while stall < self.patience and k >= 2:
                t_round = time.perf_counter()
                length = int(rng.integers(shortest, min(self.max_segment, k) + 1))
                # the last round is cut to what fits in the time left (none starts that would
                # end past the deadline)
                length = min(length, int((rounds_end - t_round) / per_step))
                if length < shortest:
                    break
                found = self._round(env, order, heads, cost, length, rng, gen)
                rounds += 1
                if found is not None:
                    order, heads, cost = found
                    if self.ls:
                        order, heads, cost = self._local_search(search, env, order, heads, cost,
                                                                rounds_end)
                    progress(cost)
                    better += 1
                    stall = 0
                else:
                    stall += 1
                per_step = (time.perf_counter() - t_round) / length
        o = tuple(int(c) for c in order)
        h = unpad_heads(heads.tolist(), instance.sizes)
        if self.kick_share > 0 and time.perf_counter() < deadline:
            tour, kicked, kicks = kick(problem, problem.to_tour(o, h), deadline, seed)
            if kicked < cost - REL_TOL * abs(cost):
                o, h = problem.to_solution(tour)
                progress(kicked)
        value = evaluate(instance, omega, o, h).objective
        return Solution(o, h, objective=value, status="feasible",
                        stats={"heads": "optimal", "rounds": rounds, "better": better,
                               "kicks": kicks, "budget_s": budget,
                               "wall_s": time.perf_counter() - start})

    def _round(self, env: EnvBatch, order: torch.Tensor, heads: torch.Tensor, cost: float,
               length: int, rng: np.random.Generator, gen: torch.Generator,
               ) -> tuple[torch.Tensor, torch.Tensor, float] | None:
        """One round of re-construction: the tour cut into segments of ``length`` clusters
        (:func:`partition`), each re-decoded ``copies`` times (own frames and directions) in one
        batch; every segment whose best copy is better replaces its old run. Returns the better
        tour, or ``None``."""
        k = env.shape[1]
        seg = partition(k, length, rng)
        copies = max(1, self.width // len(seg))
        starts = np.repeat(seg, copies)
        backwards = rng.random(len(starts)) < 0.5
        cand = reconstruct(self.model, env, order, heads, starts, length, backwards, gen)
        ch, cc = optimal_heads_batch(env.repeat(len(starts)), cand)
        tol = REL_TOL * abs(cost)
        j = int(cc.argmin())
        if not float(cc[j]) < cost - tol:
            return None
        best = (cand[j], ch[j], float(cc[j]))
        pick = cc.view(len(seg), copies).argmin(1) + torch.arange(len(seg)) * copies
        gain = cost - cc[pick]
        rows = pick[gain > tol]
        if len(rows) > 1:  # every better segment at once (they do not overlap)
            merged = order.clone()
            for r in rows.tolist():
                a = int(starts[r])
                merged[a:a + length] = cand[r, a:a + length]
            mh, mc = optimal_heads_batch(env, merged[None])
            if float(mc[0]) < best[2]:
                best = (merged, mh[0], float(mc[0]))
        return best

    @staticmethod
    def _local_search(search: LocalSearch | None, env: EnvBatch, order: torch.Tensor,
                      heads: torch.Tensor, cost: float, deadline: float,
                      ) -> tuple[torch.Tensor, torch.Tensor, float]:
        """The shared local search from the tour; the tour back as policy tensors (heads of
        padded clusters mapped to node 0 first)."""
        if search is None:
            return order, heads, cost
        problem = search.problem
        h = unpad_heads(heads.tolist(), [len(c) for c in problem.clusters[:-1]])
        tour, new_cost, _ = search.run(problem.to_tour(order.tolist(), list(h)), deadline)
        if new_cost >= cost:
            return order, heads, cost
        o, _ = problem.to_solution(tour)
        order = torch.tensor(o, dtype=torch.long)
        hb, cb = optimal_heads_batch(env, order[None])
        return order, hb[0], min(float(cb[0]), new_cost)

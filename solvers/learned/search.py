"""The ``local-search`` solver: the local-view policy (:mod:`~.local`) as a search, in a time budget.

One greedy decode is the policy's best guess; a search spends more time for a better tour:

1. **Multi-start**: ``starts`` greedy decodes, each in its own rotated (odd: mirrored) frame
   (POMO-style instance augmentation); the best tour, optimal heads.
2. **Local search** (``ls``, default on): the shared 2-opt / or-opt / heads search
   (:mod:`gtsp_bench.solvers.heuristics.local_search`) to its local optimum.
3. **Re-construction by the policy** (LEHD's random re-construct): each round picks ``width``
   random segments of the current tour (one random length per round, random positions, half of
   them flown backwards) and re-decodes each greedily with the policy as a small problem of its
   own: the UAV starts where the tour enters the segment, the segment's clusters are the
   unvisited ones, and the point where the tour leaves it stands in for the depot (the policy's
   "return home"), each segment seen in its own random rotated frame. The candidate tours are
   priced with optimal heads; the best is kept if it is better (then ``ls`` again). Rounds go on
   until the next would end past the budget (judged by the last round's time) or ``patience``
   rounds in a row found nothing better.

The budget is ``seconds_per_cluster`` * K (default 0.01 s: 1 s at K = 100, 2 s at K = 200), or
the runner's time limit where smaller. The search is seeded (the segments and frames); on a
loaded machine fewer rounds fit in the budget, so results depend on the machine's speed.
"""

from __future__ import annotations

import math
import time

import numpy as np
import torch
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
from gtsp_bench.problem import Problem, price
from gtsp_bench.solver import Progress, Solution, no_progress

#: Improvements smaller than this share of the tour cost are ignored (rounding noise).
REL_TOL = 1e-9


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
    walk = Walk(env, r, model.k, _flight_per_m(env))
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
    for _ in range(length):
        v = walk.view()
        steps.append(walk.move(v, model.scores(*turn(v, maps), v.mask).argmax(-1)))
    new = torch.stack(steps, 1)
    new = torch.where(back, new.flip(1), new)
    out = order.repeat(r, 1)
    out.scatter_(1, pos, new)
    return out


class LocalSearchSolver(LearnedSolver):
    """The local-view policy as a search: multi-start, local search, re-construction of segments.

    Default policy: ``solvers/learned/checkpoints/local-l3.pt``. Options: ``checkpoint``,
    ``starts`` (rotated greedy decodes first, default 8), ``seconds_per_cluster`` (the budget
    per instance is this times K, default 0.01), ``width`` (segments re-decoded per round, default
    16), ``max_segment`` (longest segment, default 40 clusters), ``patience`` (rounds in a row
    without a better tour before it stops, default 100), ``ls`` (the shared local search after
    each better tour, default true), ``threads``. Heads are always optimal for the order.
    """

    model_name = "local"
    checkpoint_name = "local-l3"
    default_heads = "optimal"

    def __init__(self, checkpoint: str | None = None, starts: int = 8,
                 seconds_per_cluster: float = 0.01, width: int = 16, max_segment: int = 40,
                 patience: int = 100, ls: bool = True, threads: int = 1) -> None:
        super().__init__(checkpoint, "optimal", samples=0, threads=threads)
        self.starts = check_int("starts", starts, 1)
        self.seconds_per_cluster = check_float("seconds_per_cluster", seconds_per_cluster, 0.0,
                                               math.inf)
        self.width = check_int("width", width, 1)
        self.max_segment = check_int("max_segment", max_segment, 2)
        self.patience = check_int("patience", patience, 1)
        self.ls = check_bool("ls", ls)

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
        deadline = start + budget
        torch.set_num_threads(self.threads)
        env = env_from_instances([instance], [omega])
        problem = price(instance, omega)
        gen = torch.Generator().manual_seed(int(seed))
        rng = np.random.default_rng([int(seed), 7])
        k = instance.n_clusters
        rounds = better = 0
        with torch.inference_mode():
            orders, _ = self.model.decode(env, "greedy", starts=self.starts)
            hs, costs = optimal_heads_batch(env.repeat(self.starts), orders)
            j = int(costs.argmin())
            order, heads, cost = orders[j], hs[j], float(costs[j])
            progress(cost)
            if self.ls:
                order, heads, cost = self._local_search(problem, env, order, heads, cost, deadline)
                progress(cost)
            stall, last = 0, 0.0  # last: seconds of the latest round (none is started that
            # would end past the deadline)
            while time.perf_counter() + last < deadline and stall < self.patience and k >= 2:
                t_round = time.perf_counter()
                length = int(rng.integers(min(2, k), min(self.max_segment, k) + 1))
                seg_starts = rng.integers(0, k - length + 1, self.width)
                backwards = rng.random(self.width) < 0.5
                cand = reconstruct(self.model, env, order, heads, seg_starts, length, backwards,
                                   gen)
                ch, cc = optimal_heads_batch(env.repeat(self.width), cand)
                j = int(cc.argmin())
                rounds += 1
                if float(cc[j]) < cost - REL_TOL * abs(cost):
                    order, heads, cost = cand[j], ch[j], float(cc[j])
                    if self.ls:
                        order, heads, cost = self._local_search(problem, env, order, heads, cost,
                                                                deadline)
                    progress(cost)
                    better += 1
                    stall = 0
                else:
                    stall += 1
                last = time.perf_counter() - t_round
        o = tuple(int(c) for c in order)
        h = unpad_heads(heads.tolist(), instance.sizes)
        value = evaluate(instance, omega, o, h).objective
        return Solution(o, h, objective=value, status="feasible",
                        stats={"heads": "optimal", "rounds": rounds, "better": better,
                               "budget_s": budget, "wall_s": time.perf_counter() - start})

    @staticmethod
    def _local_search(problem: Problem, env: EnvBatch, order: torch.Tensor, heads: torch.Tensor,
                      cost: float, deadline: float) -> tuple[torch.Tensor, torch.Tensor, float]:
        """The shared local search from the tour; the tour back as policy tensors (heads of
        padded clusters mapped to node 0 first)."""
        h = unpad_heads(heads.tolist(), [len(c) for c in problem.clusters[:-1]])
        tour, new_cost, _ = LocalSearch(problem).run(problem.to_tour(order.tolist(), list(h)),
                                                     deadline)
        if new_cost >= cost:
            return order, heads, cost
        o, _ = problem.to_solution(tour)
        order = torch.tensor(o, dtype=torch.long)
        hb, cb = optimal_heads_batch(env, order[None])
        return order, hb[0], min(float(cb[0]), new_cost)

"""The ``local`` solver: the local-view policy (:mod:`~.local`), greedy, from its checkpoint.

Each instance is decoded ``starts`` times, each start seeing its view in its own rotated (odd
starts: mirrored) frame, and the best tour is kept (POMO-style instance augmentation; no
sampling, no search). Heads: optimal for the decoded order (default) or the paper's rule.
Every tour is re-priced by the one evaluator by the runner, like every solver's.

Distance-only instances (GTSPLIB's planar files) are solved one by one through
:mod:`~.distance`: a node of the smallest cluster stands in for the depot, each of its nodes is
tried.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence

import torch
from gtsp_bench.solvers.learned.distance import solve_distance
from gtsp_bench.solvers.learned.env import EnvBatch
from gtsp_bench.solvers.learned.solver import LearnedSolver

from gtsp_bench.checks import check_int
from gtsp_bench.instance import Instance
from gtsp_bench.solver import Progress, Solution, no_progress


class Local(LearnedSolver):
    """Local-view policy, greedy, the best of ``starts`` rotated views; optimal heads by default.

    Default checkpoint: ``solvers/learned/checkpoints/local.pt``. Options: ``checkpoint``,
    ``heads`` (``optimal`` | ``paper``), ``starts`` (rotated frames decoded per instance,
    default 1: one greedy decode; 4 or 8 are closer to the optimum at 2.5-4x the time),
    ``threads``. Distance-only planar instances: see :mod:`~.distance`.
    """

    model_name = "local"
    default_heads = "optimal"

    def __init__(self, checkpoint: str | None = None, heads: str | None = None, starts: int = 1,
                 threads: int = 1) -> None:
        super().__init__(checkpoint, heads, samples=0, threads=threads)
        self.starts = check_int("starts", starts, 1)

    def candidates(self, env: EnvBatch, generator: torch.Generator) -> torch.Tensor:
        """``(B, starts, K)``: the greedy tour of each rotated frame."""
        b, k, _ = env.shape
        order, _ = self.model.decode(env, "greedy", starts=self.starts)
        return order.view(b, self.starts, k)

    def solve_batch(self, instances: Sequence[Instance], omegas: Sequence[float | None], *,
                    seed: int = 0, progress: Progress = no_progress) -> list[Solution]:
        """UAV instances as one batch; distance-only ones (no energy parameters) one by one."""
        if all(inst.params is not None for inst in instances):
            return super().solve_batch(instances, omegas, seed=seed, progress=progress)  # type: ignore[arg-type]
        torch.set_num_threads(self.threads)
        start = time.perf_counter()
        out = [solve_distance(self.model, inst, self.starts) for inst in instances]
        stats = {"batch": len(instances), "batch_wall_s": time.perf_counter() - start}
        return [dataclasses.replace(s, stats={**s.stats, **stats}) for s in out]

    def solve(self, instance: Instance, omega: float | None, *, time_limit: float | None = None,
              seed: int = 0, progress: Progress = no_progress) -> Solution:
        """One instance (a batch of one); a distance-only one needs no omega."""
        if instance.params is None:
            return self.solve_batch([instance], [omega], seed=seed)[0]
        return super().solve(instance, omega, time_limit=time_limit, seed=seed, progress=progress)

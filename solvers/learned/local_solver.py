"""The ``local`` solver: the local-view policy (:mod:`~.local`), greedy, from its checkpoint.

Each instance is decoded ``starts`` times, each start seeing its view in its own rotated (odd
starts: mirrored) frame, and the best tour is kept (POMO-style instance augmentation; no
sampling, no search). Heads: optimal for the decoded order (default) or the paper's rule.
Every tour is re-priced by the one evaluator by the runner, like every solver's.
"""

from __future__ import annotations

import torch
from gtsp_bench.solvers.learned.env import EnvBatch
from gtsp_bench.solvers.learned.solver import LearnedSolver

from gtsp_bench.checks import check_int


class Local(LearnedSolver):
    """Local-view policy, greedy, the best of ``starts`` rotated views; optimal heads by default.

    Default checkpoint: ``solvers/learned/checkpoints/local.pt``. Options: ``checkpoint``,
    ``heads`` (``optimal`` | ``paper``), ``starts`` (rotated frames decoded per instance,
    default 1: one greedy decode; 4 or 8 are closer to the optimum at 2.5-4x the time),
    ``threads``.
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

"""The learned solvers: load a policy, decode batches of instances, return solutions.

``drl`` (:class:`DRL`) and ``drl-sample`` (:class:`DRLSample`) run the pointer policy
(:mod:`~gtsp_bench.solvers.learned.drl`), ``am`` (:class:`AM`) the attention policy
(:mod:`~gtsp_bench.solvers.learned.am`), each from its shipped checkpoint by default.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import torch
from gtsp_bench.solvers.learned.checkpoint import checkpoint_revision, load_policy, shipped_checkpoint
from gtsp_bench.solvers.learned.env import (
    HEAD_RULES,
    EnvBatch,
    choose_heads,
    env_from_instances,
    mirror,
    tour_cost,
    unpad_heads,
)
from torch import nn

from gtsp_bench.checks import check_bool, check_choice, check_int
from gtsp_bench.errors import InputError
from gtsp_bench.instance import Instance
from gtsp_bench.solver import Progress, Solution, no_progress


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
    #: Name of the default policy file (``checkpoints/<name>.pt``); empty: ``model_name``.
    checkpoint_name = ""
    default_heads = "paper"

    def __init__(self, checkpoint: str | None = None, heads: str | None = None, samples: int = 0,
                 threads: int = 1, augment: bool = False, reverse: bool = False) -> None:
        self.heads = check_choice("heads", heads or self.default_heads, tuple(HEAD_RULES))
        self.samples = check_int("samples", samples, 0)
        self.threads = check_int("threads", threads, 1)
        self.checkpoint = Path(checkpoint) if checkpoint else shipped_checkpoint(
            self.checkpoint_name or self.model_name)
        self.augment = check_bool("augment", augment)
        self.reverse = check_bool("reverse", reverse)
        self._model: nn.Module | None = None

    @classmethod
    def revision(cls) -> str:
        """A hash of the default checkpoint's bytes (the runner re-solves when it changes)."""
        return checkpoint_revision(shipped_checkpoint(cls.checkpoint_name or cls.model_name))

    @property
    def model(self) -> nn.Module:
        """The policy, loaded on first use."""
        if self._model is None:
            self._model = load_policy(self.checkpoint, self.model_name)
        return self._model

    def candidates(self, env: EnvBatch, generator: torch.Generator,
                   on_greedy: Callable[[torch.Tensor], None] | None = None) -> torch.Tensor:
        """``(B, R, K)`` candidate orders per instance (greedy first, then samples, then each of
        them reversed if ``reverse``); ``on_greedy`` sees the greedy ones (reversed too if
        ``reverse``) before any is sampled."""
        b, _, _ = env.shape
        views = [env, mirror(env)] if self.augment else [env]
        orders = [self.model.decode(v, "greedy")[0].view(b, -1, env.shape[1]) for v in views]
        if on_greedy is not None:
            greedy = torch.cat(orders, dim=1)
            on_greedy(torch.cat([greedy, greedy.flip(-1)], dim=1) if self.reverse else greedy)
        if self.samples:
            rep = env.repeat(self.samples)
            sampled, _ = self.model.decode(rep, "sample", generator=generator)
            orders.append(sampled.view(b, -1, env.shape[1]))
        cand = torch.cat(orders, dim=1)
        return torch.cat([cand, cand.flip(-1)], dim=1) if self.reverse else cand

    def price(self, env: EnvBatch, cand: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """Heads ``(B * R, K)`` by the head rule and costs ``(B, R)`` of candidates ``(B, R, K)``."""
        b, r, k = cand.shape
        rep = env.repeat(r)
        flat = cand.reshape(b * r, k)
        heads = choose_heads(rep, flat, self.heads)
        return heads, tour_cost(rep, flat, heads).view(b, r)

    def solve_env(self, env: EnvBatch, seed: int = 0, progress: Progress = no_progress
                  ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Best candidate per instance: ``order (B, K)``, ``heads (B, K)``, ``cost (B,)``. With
        samples and a batch of one, the best greedy tour's cost goes to ``progress`` before any
        tour is sampled (the same answer: greedy decoding draws no random numbers)."""
        torch.set_num_threads(self.threads)
        generator = torch.Generator().manual_seed(int(seed))

        def on_greedy(cand: torch.Tensor) -> None:
            progress(float(self.price(env, cand)[1].min()))

        tell = on_greedy if self.samples and env.shape[0] == 1 and progress is not no_progress else None
        with torch.inference_mode():
            # (B, R, K); a subclass's own candidates() (local) takes no on_greedy: it has no samples
            cand = self.candidates(env, generator) if tell is None else self.candidates(env, generator, tell)
            b, r, k = cand.shape
            heads, cost = self.price(env, cand)
            best = cost.argmin(1)
            rows = torch.arange(b)
            return cand[rows, best], heads.view(b, r, k)[rows, best], cost[rows, best]

    def solve_batch(self, instances: Sequence[Instance], omegas: Sequence[float], *,
                    seed: int = 0, progress: Progress = no_progress) -> list[Solution]:
        """Solve many instances of one K at once (what the benchmark times); ``progress``: see
        :meth:`solve_env`."""
        start = time.perf_counter()
        env = env_from_instances(instances, omegas)
        order, heads, cost = self.solve_env(env, seed, progress)
        out = []
        for i, inst in enumerate(instances):
            o = tuple(int(c) for c in order[i])
            h = unpad_heads(heads[i].tolist(), inst.sizes)
            # tour_cost is the evaluator's objective (tested to 1e-12); run_solver re-checks it
            out.append(Solution(o, h, objective=float(cost[i]), status="feasible",
                                stats={"heads": self.heads, "batch": len(instances)}))
        stats = {"batch_wall_s": time.perf_counter() - start}
        return [dataclasses.replace(sol, stats={**sol.stats, **stats}) for sol in out]

    def solve(self, instance: Instance, omega: float | None, *, time_limit: float | None = None,
              seed: int = 0, progress: Progress = no_progress) -> Solution:
        """Decode one instance (a batch of one); ``time_limit`` is not needed (milliseconds).
        With samples, the best greedy tour is reported to ``progress`` before the sampling."""
        if omega is None:
            raise InputError(f"{instance.name}: learned policies need a UAV instance and omega")
        return self.solve_batch([instance], [omega], seed=seed, progress=progress)[0]


class DRL(LearnedSolver):
    """The paper's policy, greedy decoding; heads by the paper's rule (default) or optimal.

    Default checkpoint: ``solvers/learned/checkpoints/drl.pt``. Options: ``checkpoint``, ``heads``
    (``paper`` | ``optimal``), ``threads``, ``reverse`` (also fly the decoded tour backwards and
    keep the better direction under the head rule; default false, as the paper).
    """

    model_name = "drl"

    def __init__(self, checkpoint: str | None = None, heads: str | None = None, threads: int = 1,
                 reverse: bool = False) -> None:
        super().__init__(checkpoint, heads, samples=0, threads=threads, reverse=reverse)


class DRLSample(LearnedSolver):
    """The paper's policy: the best of the greedy tour and ``samples`` sampled tours (default 64)."""

    model_name = "drl"

    def __init__(self, checkpoint: str | None = None, heads: str | None = None, samples: int = 64,
                 threads: int = 1, reverse: bool = False) -> None:
        super().__init__(checkpoint, heads, samples=samples, threads=threads, reverse=reverse)


class AM(LearnedSolver):
    """Attention model: the best of its K greedy tours (POMO starts), optimal heads by default.

    Default checkpoint: ``solvers/learned/checkpoints/am.pt``. Options: ``checkpoint``, ``heads``
    (``optimal`` | ``paper``), ``samples`` (extra sampled tours per start, default 0),
    ``augment`` (also decode the mirrored instance, default false), ``reverse`` (also price each
    tour backwards; matters with the paper's heads only), ``threads``.
    """

    model_name = "am"
    default_heads = "optimal"

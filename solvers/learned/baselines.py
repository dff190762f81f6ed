"""REINFORCE baselines: what a sampled tour's cost is compared with.

A baseline takes the batch and the costs of the sampled tours and returns the advantage of each
tour (cost minus baseline; the actor's loss is ``mean(advantage * log-probability)``) and its own
loss, if it learns. Its own parameters get their own optimiser (the paper's Algorithm 1: one Adam
for the actor, one for the critic).

* ``critic`` (the paper's): the policy's critic network V(C) predicts each instance's cost; it
  learns by the mean squared error to the sampled cost. The critic is part of the pointer policy
  (its weights travel in the policy file), so the baseline wraps ``policy.critic``.
* ``pomo`` (Kwon et al. 2020): the mean cost of an instance's tours, one per first cluster
  (the attention policy decodes K tours per instance); nothing to learn.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

import torch
from gtsp_bench.solvers.learned.env import EnvBatch
from torch import nn

from gtsp_bench.checks import check_choice
from gtsp_bench.errors import InputError


class Baseline(Protocol):
    """A REINFORCE baseline."""

    def parameters(self) -> list[nn.Parameter]:
        """Its own trainable parameters (optimised apart from the actor's); ``[]`` if none."""
        ...

    def __call__(self, env: EnvBatch, cost: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor | None]:
        """Advantages ``(R,)`` of the sampled tours' costs ``(R,)`` (kJ, an instance's rows
        together), and the baseline's loss (``None`` when it learns nothing)."""
        ...


class CriticBaseline:
    """The paper's critic: ``advantage = cost - V(C)``, loss ``MSE(V(C), cost)``.

    Parameters
    ----------
    policy
        A policy with a ``critic`` sub-module mapping a batch to ``(B,)`` predicted costs (kJ).
    """

    def __init__(self, policy: nn.Module) -> None:
        critic = getattr(policy, "critic", None)
        if not isinstance(critic, nn.Module):
            raise InputError(f"the critic baseline needs a policy with a critic, not "
                             f"{type(policy).__name__}")
        self.critic = critic

    def parameters(self) -> list[nn.Parameter]:
        """The critic's parameters."""
        return list(self.critic.parameters())

    def __call__(self, env: EnvBatch, cost: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor | None]:
        value = self.critic(env)
        return cost - value.detach(), nn.functional.mse_loss(value, cost)


class PomoBaseline:
    """POMO's shared baseline: ``advantage = cost - mean cost of the instance's tours``.

    Parameters
    ----------
    policy
        Unused (the baseline has no parameters); taken so every baseline is built alike.
    """

    def __init__(self, policy: nn.Module) -> None:
        del policy

    def parameters(self) -> list[nn.Parameter]:
        """None: the shared baseline learns nothing."""
        return []

    def __call__(self, env: EnvBatch, cost: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor | None]:
        c = cost.view(env.shape[0], -1)
        return (c - c.mean(1, keepdim=True)).flatten(), None


#: Baselines by name (the ``baseline`` of a recipe).
BASELINES: dict[str, Callable[[nn.Module], Baseline]] = {"critic": CriticBaseline, "pomo": PomoBaseline}


def get_baseline(name: str, policy: nn.Module) -> Baseline:
    """The baseline ``name`` for ``policy``.

    Raises
    ------
    InputError
        For an unknown name (listing the valid ones) or a policy the baseline cannot serve.
    """
    return BASELINES[check_choice("baseline", name, tuple(BASELINES))](policy)

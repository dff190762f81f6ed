"""The policies by name: the registry that model configs, policy files and recipes resolve.

A policy is a plain ``nn.Module`` that decodes visiting orders from a batch environment
(:class:`Policy`); which one a config or a policy file means is its ``"model"`` key, looked up
in :data:`POLICIES`. The policy modules import only the environment and the decoding step, so
nothing imports back into here.
"""

from __future__ import annotations

from typing import Any, ClassVar, Protocol

import torch
from gtsp_bench.solvers.learned.am import AttentionPolicy
from gtsp_bench.solvers.learned.drl import PointerPolicy
from gtsp_bench.solvers.learned.env import EnvBatch
from gtsp_bench.solvers.learned.local import LocalPolicy
from torch import nn

from gtsp_bench.checks import check_choice
from gtsp_bench.errors import InputError


class Policy(Protocol):
    """What the solvers and the trainer ask of a policy."""

    #: Names of the training baselines it supports (keys of ``baselines.BASELINES``).
    baselines: ClassVar[tuple[str, ...]]
    #: Its constructor's arguments plus ``"model"`` (its name here): what a policy file stores.
    config: dict[str, Any]

    def decode(self, env: EnvBatch, mode: str = "greedy", *,
               generator: torch.Generator | None = None) -> tuple[torch.Tensor, torch.Tensor]:
        """Orders ``(R, K)`` (``R`` a multiple of the batch size, an instance's rows together)
        and their log-probabilities ``(R,)``; ``mode`` is ``"greedy"`` or ``"sample"``."""
        ...


#: Policy classes by name (the ``"model"`` key of a config, the ``model`` of a recipe).
POLICIES: dict[str, type[nn.Module]] = {"drl": PointerPolicy, "am": AttentionPolicy,
                                         "local": LocalPolicy}


def get_policy(name: str) -> type[nn.Module]:
    """The policy class registered as ``name``.

    Raises
    ------
    InputError
        For an unknown name, listing the valid ones.
    """
    return POLICIES[check_choice("model", name, tuple(POLICIES))]


def build_policy(config: dict[str, Any]) -> nn.Module:
    """The policy described by ``config``: its ``"model"`` key names the class, the other keys
    are the constructor's arguments.

    Raises
    ------
    InputError
        An unknown model, or arguments the class does not take.
    """
    cls = get_policy(config.get("model"))  # type: ignore[arg-type]
    kwargs = {k: v for k, v in config.items() if k != "model"}
    try:
        return cls(**kwargs)
    except TypeError as e:
        raise InputError(f"bad model config {config!r}: {e}") from None

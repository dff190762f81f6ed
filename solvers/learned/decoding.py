"""One decoding step shared by the policies: logits clipped to C_L tanh(.), visited elements
masked, then the greedy, sampled or forced action and its log-probability."""

from __future__ import annotations

import math

import torch

#: Logit clipping C_L (paper, after Bello et al.).
CLIP = 10.0


def clipped(logits: torch.Tensor, visited: torch.Tensor) -> torch.Tensor:
    """Raw logits ``(R, M)`` clipped to C_L tanh(.), visited elements set to -inf."""
    return (CLIP * torch.tanh(logits)).masked_fill(visited, -math.inf)


def step_logprobs(logits: torch.Tensor, visited: torch.Tensor) -> torch.Tensor:
    """Log-probabilities ``(R, M)`` of one step: raw logits clipped to C_L tanh(.), visited
    elements masked (-inf)."""
    return torch.log_softmax(clipped(logits, visited), -1)


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
    logits = clipped(logits, visited)
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



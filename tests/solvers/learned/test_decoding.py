"""One decoding step: clipped logits, masking, greedy / sampled / forced actions."""

from __future__ import annotations

import math

import pytest

torch = pytest.importorskip("torch")

from gtsp_bench.solvers.learned.decoding import CLIP, choose, clipped, step_logprobs  # noqa: E402


def _step():
    torch.manual_seed(0)
    logits = torch.randn(64, 6) * 20
    visited = torch.zeros((64, 6), dtype=torch.bool)
    visited[:, 0] = True
    visited[torch.arange(64), torch.randint(1, 6, (64,))] = True
    return logits, visited


def test_clipping_and_masking():
    """Logits become C_L tanh(.), visited elements -inf; log-probabilities are their softmax."""
    logits, visited = _step()
    out = clipped(logits, visited)
    assert torch.equal(out[visited], torch.full((int(visited.sum()),), -math.inf))
    torch.testing.assert_close(out[~visited], CLIP * torch.tanh(logits[~visited]))
    assert out[~visited].abs().max() <= CLIP
    logp = step_logprobs(logits, visited)
    torch.testing.assert_close(logp.exp().sum(1), torch.ones(64))
    torch.testing.assert_close(logp, torch.log_softmax(out, -1))


def test_greedy_sampled_and_forced_actions():
    """Greedy takes the best unvisited element, sampling never a visited one, forcing the given
    one; each returns the action's log-probability and a new mask (the old one untouched)."""
    logits, visited = _step()
    before = visited.clone()
    logp = step_logprobs(logits, visited)
    rows = torch.arange(64)
    act, lp, new = choose(logits, visited, "greedy", None)
    assert torch.equal(act, clipped(logits, visited).argmax(-1)) and not visited[rows, act].any()
    torch.testing.assert_close(lp, logp[rows, act])
    assert torch.equal(visited, before) and new[rows, act].all()
    assert int(new.sum()) == int(before.sum()) + 64
    for seed in range(5):
        act, lp, _ = choose(logits, visited, "sample", torch.Generator().manual_seed(seed))
        assert not visited[rows, act].any()
        torch.testing.assert_close(lp, logp[rows, act])
    forced = torch.full((64,), 0)
    act, lp, _ = choose(logits, visited, "greedy", None, forced=forced)
    assert torch.equal(act, forced) and torch.isinf(lp).all()  # the depot is masked: log 0

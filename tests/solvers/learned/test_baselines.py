"""REINFORCE baselines: the paper's critic and POMO's shared mean, behind one interface."""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from gtsp_bench.solvers.learned.am import AttentionPolicy  # noqa: E402
from gtsp_bench.solvers.learned.baselines import (  # noqa: E402
    BASELINES,
    CriticBaseline,
    PomoBaseline,
    get_baseline,
)
from gtsp_bench.solvers.learned.drl import PointerPolicy  # noqa: E402
from gtsp_bench.solvers.learned.env import make_env  # noqa: E402

from gtsp_bench.errors import InputError  # noqa: E402
from gtsp_bench.generator import generate_batch  # noqa: E402


def _env(b: int = 8, k: int = 4, n: int = 5):
    return make_env(generate_batch(np.random.default_rng(1), b, k, n), np.linspace(0, 1, b))


def test_critic_advantage_is_cost_minus_value_and_its_loss_the_mse():
    """advantage = cost - V(C) with no gradient into the critic; the loss is MSE(V(C), cost) and
    reaches only the critic's parameters, which are the baseline's own."""
    torch.manual_seed(0)
    policy = PointerPolicy(n_nodes=5, dim=16)
    baseline = get_baseline("critic", policy)
    assert isinstance(baseline, CriticBaseline)
    assert [id(p) for p in baseline.parameters()] == [id(p) for p in policy.critic.parameters()]
    env = _env()
    cost = torch.rand(8) * 3
    advantage, loss = baseline(env, cost)
    value = policy.critic(env).detach()
    torch.testing.assert_close(advantage, cost - value)
    assert not advantage.requires_grad
    torch.testing.assert_close(loss, ((value - cost) ** 2).mean())
    loss.backward()
    assert all(p.grad is not None for p in policy.critic.parameters())
    assert all(p.grad is None for n, p in policy.named_parameters() if not n.startswith("critic."))


def test_pomo_advantage_is_cost_minus_the_instance_mean():
    """Each instance's K tours are compared with their own mean: advantages sum to 0 per
    instance; nothing to learn."""
    baseline = get_baseline("pomo", AttentionPolicy(dim=16, n_heads=2, n_layers=1, ff=32))
    assert isinstance(baseline, PomoBaseline) and baseline.parameters() == []
    env = _env(b=3, k=4)
    cost = torch.arange(12, dtype=torch.float32) ** 1.5
    advantage, loss = baseline(env, cost)
    assert loss is None and advantage.shape == (12,)
    rows = cost.view(3, 4)
    torch.testing.assert_close(advantage.view(3, 4), rows - rows.mean(1, keepdim=True))
    torch.testing.assert_close(advantage.view(3, 4).sum(1), torch.zeros(3), atol=1e-5, rtol=0)


def test_unknown_baseline_or_a_policy_without_a_critic_is_an_input_error():
    """The getter lists the valid names; the critic baseline needs a policy with a critic."""
    assert set(BASELINES) == {"critic", "pomo"}
    with pytest.raises(InputError, match="baseline must be one of 'critic', 'pomo'"):
        get_baseline("rollout", PointerPolicy(n_nodes=3, dim=8))
    with pytest.raises(InputError, match="needs a policy with a critic"):
        get_baseline("critic", AttentionPolicy(dim=16, n_heads=2, n_layers=1, ff=32))

"""The attention-model policy: POMO starts, feasible tours on any K and N."""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from gtsp_bench.solvers.learned.am import AttentionPolicy  # noqa: E402
from gtsp_bench.solvers.learned.env import make_env  # noqa: E402

from gtsp_bench.generator import generate_batch  # noqa: E402


def _tiny() -> AttentionPolicy:
    torch.manual_seed(2)
    return AttentionPolicy(dim=16, n_heads=2, n_layers=1, ff=32)


@pytest.mark.parametrize(("k", "n"), [(1, 3), (4, 5), (8, 2)])
def test_pomo_tours_start_everywhere_and_are_permutations(k, n):
    """Instance i's K tours start at clusters 0..K-1 and each visits every cluster once."""
    env = make_env(generate_batch(np.random.default_rng(k), 6, k, n), np.linspace(0, 1, 6))
    for mode in ("greedy", "sample"):
        order, logp = _tiny().decode(env, mode, generator=torch.Generator().manual_seed(0))
        assert order.shape == (6 * k, k)
        assert torch.equal(order[:, 0], torch.arange(k).repeat(6))
        assert torch.equal(order.sort(1).values, torch.arange(k).expand(6 * k, k))
        assert torch.isfinite(logp).all()

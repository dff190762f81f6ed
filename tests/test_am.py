"""The attention-model policy: POMO starts, feasible tours on any K and N, the am solver."""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from gtsp_bench.solvers.learned.am import AttentionPolicy  # noqa: E402
from gtsp_bench.solvers.learned.rl_common import CHECKPOINT_DIR, make_env, save_policy  # noqa: E402

from gtsp_bench.generator import generate_batch, generate_instance  # noqa: E402
from gtsp_bench.instance import Instance  # noqa: E402
from gtsp_bench.registry import get_solver, run_solver  # noqa: E402


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


def test_am_solver_takes_any_cluster_size(tmp_path):
    """The am solver solves clusters of unequal size (padded) and the harness accepts the tour."""
    path = tmp_path / "am.pt"
    save_policy(_tiny(), path)
    clusters = tuple(np.random.default_rng(i).uniform(100 * i, 100 * i + 90, (3 + i, 2))
                     for i in range(5))
    inst = Instance("uneven", clusters, depot=np.array([500.0, 0.0]))
    for heads in ("optimal", "paper"):
        result = run_solver(get_solver("am", checkpoint=str(path), heads=heads), inst, 0.6)
        assert sorted(result.order) == list(range(5))
        assert all(h < 3 + c for c, h in enumerate(result.heads))
        both = run_solver(get_solver("am", checkpoint=str(path), heads=heads, augment=True), inst, 0.6)
        assert both.objective <= result.objective + 1e-9  # the plain tours are among the candidates


def test_shipped_am_checkpoint_solves():
    """The committed am model loads and solves K = 7, N = 20."""
    if not (CHECKPOINT_DIR / "am.pt").exists():
        pytest.skip("no shipped am checkpoint")
    result = run_solver("am", generate_instance(7, seed=5), 0.6)
    assert sorted(result.order) == list(range(7))

"""Exact oracles: enumeration equals brute force; the paper rule's optimum equals the best
enumerated order under that rule."""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from gtsp_bench.solvers.learned.env import env_from_instances, make_env, paper_heads, tour_cost  # noqa: E402
from gtsp_bench.solvers.learned.oracles import exact_by_enumeration, paper_rule_optimum  # noqa: E402

from gtsp_bench.generator import generate_batch, generate_instance  # noqa: E402
from gtsp_bench.registry import run_solver  # noqa: E402


def test_exact_enumeration_matches_brute_force():
    """The enumerated optimum equals the brute-force solver on tiny instances."""
    instances = [generate_instance(3, 3, seed=i) for i in range(4)]
    env = env_from_instances(instances, [0.2, 0.5, 0.7, 1.0])
    opt = exact_by_enumeration(env, chunk=7)
    for i, inst in enumerate(instances):
        brute = run_solver("brute", inst, [0.2, 0.5, 0.7, 1.0][i]).objective
        assert opt[i].item() == pytest.approx(brute, rel=1e-12)


def test_paper_rule_optimum_equals_best_enumerated_order():
    """The recursion over (visited, last cluster, head) equals trying every order with the
    paper's heads, and is never below the exact optimum."""
    import itertools

    rng = np.random.default_rng(11)
    b, k, n = 6, 5, 7
    env = make_env(generate_batch(rng, b, k, n), rng.uniform(0, 1, b))
    perms = torch.tensor(list(itertools.permutations(range(k))))
    rep, orders = env.repeat(len(perms)), perms.repeat(b, 1)
    enumerated = tour_cost(rep, orders, paper_heads(rep, orders)).view(b, -1).min(1).values
    got = paper_rule_optimum(env)
    assert torch.allclose(got, enumerated, rtol=1e-12, atol=0)
    assert torch.all(got >= exact_by_enumeration(env) * (1 - 1e-12))

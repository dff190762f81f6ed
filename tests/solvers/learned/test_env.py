"""The batch environment: the torch reward equals the evaluator, the head rules, padding."""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from gtsp_bench.solvers.heads import optimal_heads  # noqa: E402
from gtsp_bench.solvers.learned.env import (  # noqa: E402
    env_from_instances,
    make_env,
    mirror,
    optimal_heads_batch,
    paper_heads,
    tour_cost,
)
from gtsp_bench.solvers.learned.oracles import exact_by_enumeration  # noqa: E402

from gtsp_bench.energy import evaluate, evaluate_batch  # noqa: E402
from gtsp_bench.errors import InputError  # noqa: E402
from gtsp_bench.generator import generate_batch, generate_instance  # noqa: E402
from gtsp_bench.instance import Instance  # noqa: E402
from gtsp_bench.problem import price  # noqa: E402
from gtsp_bench.registry import run_solver  # noqa: E402


def _random_orders(rng: np.random.Generator, b: int, k: int) -> torch.Tensor:
    return torch.from_numpy(np.argsort(rng.random((b, k)), axis=1))


def test_torch_reward_equals_numpy_evaluator():
    """tour_cost on random tours equals evaluate_batch and evaluate (relative 1e-12)."""
    rng = np.random.default_rng(3)
    b, k, n = 40, 5, 6
    coords = generate_batch(rng, b, k, n)
    omega = rng.uniform(0, 1, b)
    env = make_env(coords, omega)
    order = _random_orders(rng, b, k)
    heads = torch.from_numpy(rng.integers(0, n, (b, k)))
    got = tour_cost(env, order, heads).numpy()
    ref = evaluate_batch(coords, np.array([500.0, 0.0]), order.numpy(), heads.numpy(), omega)["total"]
    np.testing.assert_allclose(got, ref, rtol=1e-12)
    for i in range(5):
        inst = Instance(f"i{i}", tuple(coords[i]), depot=np.array([500.0, 0.0]))
        ev = evaluate(inst, omega[i], order[i].tolist(), heads[i].tolist())
        assert got[i] == pytest.approx(ev.objective, rel=1e-12)


def test_mirror_keeps_every_cost():
    """The mirrored batch prices every tour exactly as the original (augmentation is safe)."""
    rng = np.random.default_rng(8)
    env = make_env(generate_batch(rng, 16, 4, 5), rng.uniform(0, 1, 16))
    order = _random_orders(rng, 16, 4)
    heads = torch.from_numpy(rng.integers(0, 5, (16, 4)))
    flipped = mirror(env)
    assert not torch.equal(flipped.coords, env.coords)
    torch.testing.assert_close(tour_cost(flipped, order, heads), tour_cost(env, order, heads))


def test_heads_match_the_numpy_rules():
    """Batched optimal heads equal gtsp_bench.solvers.heads.optimal_heads; paper heads follow
    eq. chselection."""
    rng = np.random.default_rng(4)
    k, n = 4, 5
    instances = [generate_instance(k, n, seed=i) for i in range(8)]
    omegas = rng.uniform(0, 1, 8)
    env = env_from_instances(instances, omegas)
    problems = [price(inst, w) for inst, w in zip(instances, omegas, strict=True)]
    for i, problem in enumerate(problems):  # node costs are price()'s
        np.testing.assert_allclose(env.node_cost[i].numpy().ravel(), problem.node_cost[:-1], rtol=1e-12)
    order = _random_orders(rng, 8, k)
    heads, cost = optimal_heads_batch(env, order)
    paper = paper_heads(env, order)
    for i, problem in enumerate(problems):
        _, best = optimal_heads(problem, order[i].tolist())
        assert cost[i].item() == pytest.approx(best, rel=1e-12)
        assert tour_cost(env, order, heads)[i].item() == pytest.approx(best, rel=1e-12)
        prev, expect = problem.depot, [0] * k
        for c in order[i].tolist():
            nodes = problem.clusters[c]
            j = int(np.argmin(problem.edge_cost[prev, nodes] + problem.node_cost[nodes]))
            expect[c], prev = j, nodes[j]
        assert paper[i].tolist() == expect


def test_unequal_clusters_are_padded_without_changing_the_optimum():
    """Padding a small cluster with copies of its node 0 keeps the brute-force optimum."""
    clusters = (np.array([[100.0, 100.0], [120.0, 90.0], [90.0, 130.0]]),
                np.array([[700.0, 500.0]]), np.array([[300.0, 800.0], [320.0, 780.0]]))
    inst = Instance("uneven", clusters, depot=np.array([500.0, 0.0]))
    env = env_from_instances([inst], [0.4])
    assert env.shape == (1, 3, 3)
    assert exact_by_enumeration(env)[0].item() == pytest.approx(run_solver("brute", inst, 0.4).objective)


def test_non_uav_instance_is_refused():
    """A distance-only instance gives a clear InputError."""
    inst = Instance("plain", (np.array([[0.0, 1.0]]),), depot=None, params=None)
    with pytest.raises(InputError, match="need a UAV instance with a depot"):
        env_from_instances([inst], [0.5])

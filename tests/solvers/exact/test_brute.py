"""Brute force, the test oracle: checked against an independent enumeration by hand."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from gtsp_bench.solvers.exact.brute import Brute, count_tours

from gtsp_bench.energy import evaluate
from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance
from gtsp_bench.instance import Instance
from gtsp_bench.registry import run_solver


def _enumerate(instance: Instance, omega: float) -> float:
    """Minimum of evaluate() over every order and every head choice (slow, obviously right)."""
    k = instance.n_clusters
    return min(
        evaluate(instance, omega, list(o), list(h)).objective
        for o in itertools.permutations(range(k))
        for h in itertools.product(*(range(s) for s in instance.sizes))
    )


def test_tiny_hand_checked_optimum(tiny):
    """At omega = 0 the optimum is the 1024.26 m tour through (300, 0)."""
    r = run_solver("brute", tiny, 0.0)
    assert r.status == "optimal"
    assert r.heads == (0, 1)
    assert r.distance == pytest.approx(600 + 300 * 2**0.5)
    assert r.lower_bound == pytest.approx(r.objective)


@pytest.mark.parametrize("seed", range(6))
def test_brute_equals_plain_enumeration(seed):
    """On random instances (K = 1..4, mixed cluster sizes) brute matches the plain enumeration."""
    rng = np.random.default_rng(seed)
    k = int(rng.integers(1, 5))
    base = generate_instance(k, 4, seed=seed)
    sizes = rng.integers(1, 5, size=k)
    inst = Instance(name="mixed", clusters=tuple(c[:s] for c, s in zip(base.clusters, sizes,
                                                                        strict=True)),
                    depot=base.depot)
    omega = float(rng.uniform())
    r = run_solver("brute", inst, omega)
    assert r.objective == pytest.approx(_enumerate(inst, omega), rel=1e-12)


def test_refuses_large_instances_clearly():
    """Above its limit it raises InputError with the count."""
    inst = generate_instance(8, 20, seed=0)
    assert count_tours(inst) > 1e10
    with pytest.raises(InputError, match=r"brute force would enumerate .* use 'dp' or 'milp'"):
        run_solver(Brute(), inst, 0.5)


def test_gtsp_without_depot():
    """Without a depot, brute force fixes cluster 0 first and still finds the optimum."""
    inst = Instance(name="nodepot", params=None, edge_weight_type="EUC_2D", clusters=(
        np.array([[0.0, 0.0], [10.0, 0.0]]), np.array([[10.0, 10.0]]),
        np.array([[0.0, 10.0], [5.0, 5.0]]), np.array([[20.0, 5.0]])))
    r = run_solver("brute", inst, None)
    assert r.objective == pytest.approx(_enumerate(inst, None))

"""Held-Karp DP: agrees with brute force, handles K = 1, 2, single-node clusters, no depot."""

from __future__ import annotations

import numpy as np
import pytest
from gtsp_bench.solvers.exact.dp import DynamicProgramming

from gtsp_bench.data.io import read_instance
from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance
from gtsp_bench.instance import Instance
from gtsp_bench.registry import run_solver
from tests.conftest import GTSPLIB
from tests.tiny_cases import not_below


def _mixed(seed: int, depot: bool) -> tuple[Instance, float]:
    rng = np.random.default_rng(seed)
    k = int(rng.integers(1, 6))
    base = generate_instance(k, 4, seed=seed)
    sizes = rng.integers(1, 5, size=k)
    inst = Instance(name=f"mixed{seed}", depot=base.depot if depot else None,
                    clusters=tuple(c[:s] for c, s in zip(base.clusters, sizes, strict=True)))
    return inst, float(rng.choice([0.0, 1.0, rng.uniform()]))


@pytest.mark.parametrize("seed", range(12))
@pytest.mark.parametrize("depot", [True, False])
def test_dp_equals_brute_force(seed, depot):
    """Random K = 1..5, cluster sizes 1..4, omega in {0, 1, random}: same optimum as brute."""
    inst, omega = _mixed(seed, depot)
    dp = run_solver("dp", inst, omega)
    brute = run_solver("brute", inst, omega)
    assert dp.status == "optimal"
    assert dp.objective == pytest.approx(brute.objective, rel=1e-9, abs=1e-9)
    assert dp.lower_bound == pytest.approx(dp.objective)


def test_dp_solves_berlin_to_the_proven_optimum():
    """11berlin52 (no depot, integer weights): 4040, the optimum in the literature."""
    r = run_solver("dp", read_instance(GTSPLIB / "11berlin52.gtsp.gz"), None)
    assert r.status == "optimal"
    assert r.objective == 4040


def test_dp_refuses_tables_that_do_not_fit():
    """A K = 30 table is refused with the memory it would need."""
    with pytest.raises(InputError, match=r"dp needs .* GiB .* use 'milp'"):
        run_solver(DynamicProgramming(max_memory_gb=1), generate_instance(30, seed=0), 0.5)


def test_dp_time_limit_returns_a_feasible_tour():
    """With a tiny time limit it returns a feasible tour with status time_limit, never below
    the optimum it proves given the time."""
    inst = generate_instance(12, seed=1)
    r = run_solver(DynamicProgramming(), inst, 0.5, time_limit=1e-4)
    assert r.status == "time_limit"
    assert sorted(r.order) == list(range(12))
    optimum = run_solver(DynamicProgramming(), inst, 0.5)
    assert optimum.status == "optimal" and not_below(r.objective, optimum.objective)


def test_bad_option():
    """max_memory_gb must be positive."""
    with pytest.raises(InputError, match="max_memory_gb must be a number > 0"):
        DynamicProgramming(max_memory_gb=0)

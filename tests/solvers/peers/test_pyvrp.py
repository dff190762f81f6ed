"""The PyVRP peer: feasible tours at the optimum, no depot, missing package (its integer
costs: test_scaling.py)."""

from __future__ import annotations

import sys

import pytest

from gtsp_bench.data.io import read_instance
from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance
from gtsp_bench.instance import Instance
from gtsp_bench.registry import get_solver, run_solver
from tests.conftest import GTSPLIB
from tests.tiny_cases import not_below, tiny_case

pytest.importorskip("pyvrp")

FAST = {"no_improvement": 300}


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("depot", [True, False])
def test_feasible_and_at_the_optimum(seed, depot):
    """On tiny instances PyVRP's tour is feasible, never below brute force, and matches it."""
    inst, omega, optimum = tiny_case(seed, depot)
    r = run_solver(get_solver("pyvrp", **FAST), inst, omega, seed=seed)
    assert r.status == "feasible"
    assert not_below(r.objective, optimum)
    assert r.objective == pytest.approx(optimum, rel=1e-6)


def test_no_depot_runs_once_per_node_of_the_smallest_cluster():
    """Without a depot and no one-node cluster, each node of the smallest cluster is tried."""
    base = generate_instance(4, 3, seed=4)
    inst = Instance(name="nd", clusters=base.clusters)
    r = run_solver(get_solver("pyvrp", **FAST), inst, 0.5)
    assert r.stats["runs"] == 3
    assert r.objective == pytest.approx(run_solver("brute", inst, 0.5).objective, rel=1e-6)


def test_single_cluster_without_depot():
    """One cluster and no depot: the cheapest node alone."""
    base = generate_instance(1, 5, seed=0)
    inst = Instance(name="one", clusters=base.clusters)
    r = run_solver(get_solver("pyvrp", **FAST), inst, 0.5)
    assert r.objective == pytest.approx(run_solver("brute", inst, 0.5).objective, rel=1e-12)


def test_gtsplib_file():
    """On 11berlin52 PyVRP reaches the proven optimum 4040."""
    r = run_solver(get_solver("pyvrp", **FAST), read_instance(GTSPLIB / "11berlin52.gtsp.gz"), None)
    assert r.objective == 4040


def test_time_limit_status():
    """A short limit stops PyVRP with a feasible tour and status time_limit, never below the
    DP's optimum."""
    inst = generate_instance(10, 5, seed=0)
    r = run_solver(get_solver("pyvrp", no_improvement=10**9), inst, 0.5, time_limit=0.05)
    assert r.status == "time_limit"
    assert sorted(r.order) == list(range(10))
    assert not_below(r.objective, run_solver("dp", inst, 0.5).objective)


def test_seed_reproduces_the_run():
    """With the stall criterion stopping it, the same seed gives the same tour."""
    inst = generate_instance(12, 5, seed=1)
    a = run_solver(get_solver("pyvrp", **FAST), inst, 0.5, seed=2, time_limit=60)
    b = run_solver(get_solver("pyvrp", **FAST), inst, 0.5, seed=2, time_limit=60)
    assert (a.order, a.heads, a.stats["iterations"]) == (b.order, b.heads, b.stats["iterations"])


def test_missing_package_is_a_clear_error(monkeypatch):
    """Without pyvrp installed the solver raises InputError saying how to install it."""
    monkeypatch.setitem(sys.modules, "pyvrp", None)
    with pytest.raises(InputError, match="needs the optional package pyvrp"):
        run_solver("pyvrp", generate_instance(3, 3, seed=0), 0.5)


@pytest.mark.parametrize("options", [{"no_improvement": 0}, {"resolution": -1.0}])
def test_bad_options_rejected(options):
    """Invalid options raise InputError."""
    with pytest.raises(InputError):
        get_solver("pyvrp", **options)


def test_pyvrp_reports_each_better_tour():
    """PyVRP's on_best callback reports each better tour, priced exactly: the objectives never
    rise and end at the answer."""
    inst = generate_instance(15, 8, seed=4)
    r = run_solver(get_solver("pyvrp", **FAST), inst, 0.5, time_limit=30.0, seed=0)
    objectives = [p.objective for p in r.trajectory]
    assert len(objectives) >= 2 and objectives == sorted(objectives, reverse=True)
    assert objectives[-1] == r.objective

"""The search: input check, the LP-free bound, the no-model path, the solvers' shared options."""

from __future__ import annotations

import dataclasses
import inspect

import numpy as np
import pytest
from gtsp_bench.solvers.exact.gurobi import Gurobi
from gtsp_bench.solvers.exact.milp import Milp
from gtsp_bench.solvers.exact.mip.branch_cut import check_symmetric, degree_bound
from gtsp_bench.solvers.exact.mip.options import MipOptions
from gtsp_bench.solvers.exact.mip.solve import MipSolver, solve_exact

from gtsp_bench.data.io import read_instance
from gtsp_bench.errors import InputError
from gtsp_bench.instance import Instance
from gtsp_bench.problem import price
from gtsp_bench.registry import run_solver
from tests.conftest import GTSPLIB
from tests.solvers.exact.test_milp import _instance


def test_asymmetric_costs_are_refused():
    """An EXPLICIT instance with asymmetric weights is refused with a clear message."""
    w = np.array([[0, 1, 2, 3], [5, 0, 1, 2], [2, 1, 0, 1], [3, 2, 1, 0]], dtype=float)
    inst = Instance(name="asym", clusters=tuple(np.zeros((1, 2)) for _ in range(4)), params=None,
                    edge_weight_type="EXPLICIT", weights=w, symmetric=False)
    with pytest.raises(InputError, match="not symmetric"):
        check_symmetric(price(inst, None))


@pytest.mark.parametrize("seed", range(12))
@pytest.mark.parametrize("depot", [True, False])
def test_degree_bound_is_below_the_optimum(seed, depot):
    """The LP-free bound reported when time runs out first never exceeds the brute-force optimum."""
    rng = np.random.default_rng(seed)
    k = int(rng.integers(3 if depot else 4, 6))
    inst = _instance(seed, k, rng.integers(1, 5, size=k).tolist(), depot)
    omega = float(rng.choice([0.0, 1.0, rng.uniform()]))
    bound = degree_bound(price(inst, omega))
    assert 0 < bound <= run_solver("brute", inst, omega).objective * (1 + 1e-12)


def test_degree_bound_on_gtsplib():
    """On 11berlin52 the bound is below the proven optimum 4040 (and not trivially zero)."""
    bound = degree_bound(price(read_instance(GTSPLIB / "11berlin52.gtsp.gz"), None))
    assert 0.5 * 4040 < bound <= 4040


@pytest.mark.parametrize("sizes, depot", [([3], True), ([2, 4], True), ([4, 1, 3], False)])
def test_three_clusters_or_fewer_need_no_backend(sizes, depot):
    """Up to three GTSP clusters (the depot's included) the optimum is proven without a model."""
    inst = _instance(7, len(sizes), sizes, depot)

    def no_backend(options: MipOptions):
        raise AssertionError("no backend should be built")

    r = solve_exact(price(inst, 0.5), no_backend, MipOptions())
    assert r.status == "optimal"
    assert r.objective == pytest.approx(run_solver("brute", inst, 0.5).objective, rel=1e-12)
    assert r.lower_bound == r.objective


@pytest.mark.parametrize("solver", [MipSolver, Milp, Gurobi])
def test_solver_defaults_are_the_option_defaults(solver):
    """Each solver's keyword defaults are MipOptions' defaults (the options are written twice)."""
    defaults = {f.name: f.default for f in dataclasses.fields(MipOptions)}
    params = inspect.signature(solver.__init__).parameters
    assert {name: params[name].default for name in defaults} == defaults
    assert not set(params) - {"self", *defaults}


@pytest.mark.parametrize("seed", range(4))
def test_a_root_paused_for_the_restarts_goes_on_to_the_proof(seed, monkeypatch):
    """With the root's share of the limit at zero the first root loop pauses before its first
    round; after the restarts it goes on, and the solve still proves the brute-force optimum."""
    from gtsp_bench.solvers.exact.mip import branch_cut, solve
    from gtsp_bench.solvers.exact.mip.backends import HighsBackend

    paused: list[bool] = []
    root = branch_cut._Search.root

    def spy(self, until=None):
        paused.append(root(self, until))
        return paused[-1]

    monkeypatch.setattr(solve, "ROOT_SHARE", 0.0)
    monkeypatch.setattr(branch_cut._Search, "root", spy)
    inst = _instance(seed, 6, [3, 2, 3, 1, 2, 3], True)
    r = solve_exact(price(inst, 0.5), HighsBackend, MipOptions(), time_limit=60.0)
    assert paused == [True, False]  # paused before its first round, then went on to the end
    assert r.status == "optimal"
    assert r.objective == pytest.approx(run_solver("brute", inst, 0.5).objective, rel=1e-9)
    assert r.stats["root_rounds"] >= 1


def test_the_root_trace_has_a_record_per_root_round():
    """``stats["root_trace"]``: one record per root round, its times, seconds and simplex
    iterations never falling, each below the solve's totals, and its best bound the root's."""
    r = run_solver("milp", read_instance(GTSPLIB / "11berlin52.gtsp.gz"), None, time_limit=60.0)
    trace = r.stats["root_trace"]
    assert len(trace) == r.stats["root_rounds"] >= 2
    for key in ("time_s", "lp_s", "separation_s", "iterations"):
        column = [t[key] for t in trace]
        assert column == sorted(column), key
    last = trace[-1]
    assert last["lp_s"] + last["separation_s"] <= last["time_s"] <= r.stats["total_s"]
    assert 0 < last["iterations"] <= r.stats["lp_iterations"]
    assert max(t["bound"] for t in trace) == pytest.approx(r.stats["root_bound"])
    assert all(t["bound"] <= t["lp"] + 1e-9 for t in trace) and last["cuts"] > 0


@pytest.mark.parametrize("rule", ["ROOT_TAIL", "ROOT_FLAT_SHARE"])
@pytest.mark.parametrize("seed", range(4))
def test_a_root_that_tails_off_at_once_leaves_the_search_exact(seed, rule, monkeypatch):
    """With a tail-off rule at its loosest (the second round without pricing, or the second round,
    ends the root) the root ends in fewer rounds than by default, and the branch and cut still
    proves dp's optimum."""
    from gtsp_bench.solvers.exact.mip import branch_cut
    from gtsp_bench.solvers.exact.mip.backends import HighsBackend

    from gtsp_bench.generator import generate_instance

    inst = generate_instance(9, 5, seed=seed)
    default = solve_exact(price(inst, 0.5), HighsBackend, MipOptions(lns_trials=0))
    monkeypatch.setattr(branch_cut, rule, 1e9)
    monkeypatch.setattr(branch_cut, "ROOT_FLAT_AFTER", 0)
    monkeypatch.setattr(branch_cut, rule.replace("TAIL", "TAIL_ROUNDS").replace("SHARE", "ROUNDS"), 1)
    r = solve_exact(price(inst, 0.5), HighsBackend, MipOptions(lns_trials=0))
    assert r.status == "optimal"
    assert r.objective == pytest.approx(run_solver("dp", inst, 0.5).objective, rel=1e-9)
    assert r.lower_bound == pytest.approx(r.objective, rel=1e-9)
    assert r.stats["root_rounds"] < default.stats["root_rounds"] and r.stats["bc_nodes"] >= 1


def test_the_flat_root_rule_waits_for_its_round(monkeypatch):
    """The bound rule acts only from round ``ROOT_FLAT_AFTER`` on: at its loosest (every second
    round ends the root) a K = 9 root of a few rounds runs as with the rule off while the rule waits,
    and ends sooner, at the same optimum, when it does not wait."""
    from gtsp_bench.solvers.exact.mip import branch_cut
    from gtsp_bench.solvers.exact.mip.backends import HighsBackend

    from gtsp_bench.generator import generate_instance

    problem, wait = price(generate_instance(9, 5, seed=1), 0.5), branch_cut.ROOT_FLAT_AFTER
    monkeypatch.setattr(branch_cut, "ROOT_FLAT_ROUNDS", 0)
    off = solve_exact(problem, HighsBackend, MipOptions(lns_trials=0))
    monkeypatch.setattr(branch_cut, "ROOT_FLAT_ROUNDS", 1)
    monkeypatch.setattr(branch_cut, "ROOT_FLAT_SHARE", 1e9)
    waiting = solve_exact(problem, HighsBackend, MipOptions(lns_trials=0))
    monkeypatch.setattr(branch_cut, "ROOT_FLAT_AFTER", 0)
    early = solve_exact(problem, HighsBackend, MipOptions(lns_trials=0))
    assert 2 < off.stats["root_rounds"] == waiting.stats["root_rounds"] < wait
    assert early.stats["root_rounds"] < off.stats["root_rounds"]
    assert early.status == waiting.status == "optimal"
    assert off.objective == waiting.objective == pytest.approx(early.objective, rel=1e-9)

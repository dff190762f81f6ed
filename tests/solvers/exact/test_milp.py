"""milp (HiGHS): agrees with brute force and dp, proves GTSPLIB optima, honours time limits."""

from __future__ import annotations

import importlib.util
import subprocess
import sys

import numpy as np
import pytest
from gtsp_bench.solvers.exact.milp import Milp
from gtsp_bench.solvers.exact.mip import backends, branch_cut, columns, tree_search
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from gtsp_bench.data.io import read_instance
from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance
from gtsp_bench.instance import Instance
from gtsp_bench.registry import get_solver, run_solver
from tests.conftest import GTSPLIB, REPO


def _instance(seed: int, k: int, sizes: list[int], depot: bool) -> Instance:
    base = generate_instance(k, max(sizes), seed=seed)
    return Instance(name=f"p{seed}", depot=base.depot if depot else None,
                    clusters=tuple(c[:s] for c, s in zip(base.clusters, sizes, strict=True)))


#: gurobipy with its size-limited licence is an optional extra (``make install`` installs it).
HAVE_GUROBI = importlib.util.find_spec("gurobipy") is not None


@st.composite
def _sizes(draw):
    """Cluster sizes: K = 1..5 clusters of 1..4 nodes."""
    k = draw(st.integers(1, 5))
    return draw(st.lists(st.integers(1, 4), min_size=k, max_size=k))


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 10**6), sizes=_sizes(), depot=st.booleans(),
       omega=st.sampled_from([0.0, 0.5, 0.9, 1.0]))
# K = 1 and 2 and one-node clusters every run, whatever hypothesis draws
@example(seed=1, sizes=[1], depot=True, omega=0.0)
@example(seed=2, sizes=[3], depot=False, omega=0.5)
@example(seed=3, sizes=[1, 4], depot=True, omega=0.9)
@example(seed=4, sizes=[2, 1], depot=False, omega=1.0)
@example(seed=5, sizes=[1, 1, 1, 1], depot=False, omega=0.5)
@example(seed=6, sizes=[4, 1, 3, 1, 2], depot=True, omega=0.9)
def test_exact_solvers_agree_with_brute(seed, sizes, depot, omega):
    """Random K = 1..5 (with and without a depot), clusters of 1..4 nodes, four omegas: milp,
    dp and (when installed) gurobi, with its root proof and with its own MILP search, all
    find the brute-force optimum."""
    inst = _instance(seed, len(sizes), sizes, depot)
    brute = run_solver("brute", inst, omega)
    exact = {"milp": run_solver("milp", inst, omega), "dp": run_solver("dp", inst, omega)}
    if HAVE_GUROBI:
        exact["gurobi"] = run_solver("gurobi", inst, omega)
        exact["gurobi-mip"] = run_solver(get_solver("gurobi", root_rounds=0, lns_trials=0), inst, omega)
    for name, r in exact.items():
        assert r.status == "optimal", name
        assert r.objective == pytest.approx(brute.objective, rel=1e-9, abs=1e-9), name
        assert r.lower_bound <= r.objective + 1e-9, name
        assert r.lower_bound >= r.objective - 1.01e-6, name  # the default abs_gap


@pytest.mark.parametrize("options", [
    {"prune": False, "core_edges": 0},
    {"root_rounds": 1, "lns_trials": 0, "core_edges": 1},  # the branch and cut does the work
    {"root_rounds": 0, "prune": False, "lns_trials": 0},
])
@pytest.mark.parametrize("seed", range(4))
def test_every_path_is_exact(options, seed):
    """With pruning, pricing, root cuts or the upper bound switched off, still the optimum."""
    inst = generate_instance(6, 3, seed=seed)
    brute = run_solver("brute", inst, 0.3)
    r = run_solver(Milp(**options), inst, 0.3)
    assert r.status == "optimal"
    assert r.objective == pytest.approx(brute.objective, rel=1e-9)


@pytest.mark.parametrize("big_from, root_age", [(0, branch_cut.BIG_ROOT_PURGE_AGE),
                                                 (branch_cut.BIG_ROOT_NODES, branch_cut.ROOT_PURGE_AGE)])
@pytest.mark.parametrize("seed", range(3))
def test_root_purge_age_by_model_size(monkeypatch, big_from, root_age, seed):
    """The root purges slack cuts after BIG_ROOT_PURGE_AGE optima on a model of at least
    BIG_ROOT_NODES nodes (here forced on a K = 8 one), else after ROOT_PURGE_AGE; the node loop
    after NODE_PURGE_AGE. Either way the dp optimum is proven."""
    monkeypatch.setattr(branch_cut, "BIG_ROOT_NODES", big_from)
    ages: list[int] = []
    purge = backends.LpModel.purge
    monkeypatch.setattr(backends.LpModel, "purge",
                        lambda lp, values, age: (ages.append(age), purge(lp, values, age))[1])
    inst = generate_instance(8, 4, seed=seed)
    r = run_solver(Milp(root_rounds=3, lns_trials=0), inst, 0.5)
    assert r.status == "optimal"
    assert r.objective == pytest.approx(run_solver("dp", inst, 0.5).objective, rel=1e-9)
    assert ages and ages[0] == root_age
    assert set(ages) <= {root_age, tree_search.NODE_PURGE_AGE}


@pytest.mark.parametrize("seed", range(4))
def test_a_big_root_drops_priced_out_columns_and_still_proves(monkeypatch, tmp_path, seed):
    """The root's column rule forced on a K = 8 model (any positive reduced cost, one round):
    edge columns leave the root LP, come back when priced in, the dp optimum is proven and the
    proof's certificate checks."""
    from gtsp_bench.proof import check_certificate
    from gtsp_bench.proof.format import read_certificate

    monkeypatch.setattr(columns, "ROOT_DROP_NODES", 0)
    monkeypatch.setattr(columns, "ROOT_DROP_SHARE", 0.0)
    monkeypatch.setattr(columns, "ROOT_DROP_AGE", 1)
    inst = generate_instance(8, 5, seed=seed)
    cert = tmp_path / "c.cert.json.gz"
    r = run_solver(Milp(root_rounds=4, lns_trials=0, certificate=str(cert)), inst, 0.5)
    assert r.stats["root_dropped"] > 0
    assert r.status == "optimal"
    assert r.objective == pytest.approx(run_solver("dp", inst, 0.5).objective, rel=1e-9)
    checked = check_certificate(inst, read_certificate(cert))
    assert checked.proven and checked.value == pytest.approx(r.objective, rel=1e-12)


@pytest.mark.parametrize("seed", range(3))
def test_a_big_models_lps_on_two_threads_prove_the_optimum(monkeypatch, tmp_path, seed):
    """LP threads forced on a K = 8 model (``BIG_ROOT_NODES`` 0, threads 2: HiGHS's parallel dual
    simplex): the dp optimum is proven and the certificate checks; a small model then solves on
    one thread in the same process (HiGHS's scheduler started again) to the same optimum."""
    from gtsp_bench.proof import check_certificate
    from gtsp_bench.proof.format import read_certificate

    inst = generate_instance(8, 5, seed=seed)
    best = run_solver("dp", inst, 0.5).objective
    monkeypatch.setattr(branch_cut, "BIG_ROOT_NODES", 0)
    cert = tmp_path / "c.cert.json.gz"
    r = run_solver(Milp(root_rounds=4, lns_trials=0, threads=2, certificate=str(cert)), inst, 0.5)
    assert r.stats["lp_threads"] == 2
    assert r.status == "optimal" and r.objective == pytest.approx(best, rel=1e-9)
    checked = check_certificate(inst, read_certificate(cert))
    assert checked.proven and checked.value == pytest.approx(r.objective, rel=1e-12)
    monkeypatch.setattr(branch_cut, "BIG_ROOT_NODES", 10**9)
    r = run_solver(Milp(root_rounds=4, lns_trials=0, threads=2), inst, 0.5)
    assert r.stats["lp_threads"] == 1
    assert r.status == "optimal" and r.objective == pytest.approx(best, rel=1e-9)


def test_a_small_root_keeps_its_columns():
    """Below ROOT_DROP_NODES the root drops no column (GTSPLIB to 1,084 nodes, UAV K <= 100)."""
    r = run_solver(Milp(root_rounds=4, lns_trials=0), generate_instance(8, 5, seed=0), 0.5)
    assert "root_dropped" not in r.stats


def test_branch_and_cut_runs_and_agrees_with_dp():
    """A K = 8 instance whose root LP is not integral: branching proves the dp optimum."""
    inst = generate_instance(8, 6, seed=5)
    r = run_solver(Milp(root_rounds=2, lns_trials=0), inst, 0.5)
    assert r.stats["bc_nodes"] >= 1
    assert r.status == "optimal"
    assert r.objective == pytest.approx(run_solver("dp", inst, 0.5).objective, rel=1e-9)


def test_strong_branching_and_restarts_prove_the_optimum(monkeypatch):
    """14st70 with one root round and the greedy tour as first incumbent: the root does not
    prove it, so LNS restarts improve the incumbent and the branch and cut (strong branching)
    proves the literature optimum (no columns dropped: with them its first node proves it)."""
    monkeypatch.setattr(columns, "DROP_AGE", 0)
    r = run_solver(Milp(root_rounds=1, lns_trials=0), read_instance(GTSPLIB / "14st70.gtsp.gz"), None)
    assert r.status == "optimal"
    assert r.objective == 316 and r.lower_bound == 316
    assert r.stats["restart_gain"] > 0
    assert r.stats["bc_nodes"] >= 2 and r.stats["strong_lps"] >= 4


@pytest.mark.parametrize("name, best", [("11berlin52", 4040), ("20kroA100", 9711)])
def test_proves_gtsplib_optima(name, best):
    """The literature optima of the two smallest GTSPLIB samples, proven (integer bound)."""
    r = run_solver("milp", read_instance(GTSPLIB / f"{name}.gtsp.gz"), None)
    assert r.status == "optimal"
    assert r.objective == best
    assert r.lower_bound == best


@pytest.mark.parametrize("time_limit", [0.01, 1.0])
def test_time_limit_gives_tour_and_bound(time_limit):
    """A K = 40 instance stopped early (after 0.01 s and after 1 s, both before the first root
    round ends): the best tour, a lower bound below it, status time_limit. (It is not solved in 60 s here;
    a K = 20 one was solved in about 1 s, so the 1 s case depended on the machine's speed.)"""
    inst = generate_instance(40, 20, seed=1)
    r = run_solver("milp", inst, 0.5, time_limit=time_limit)
    assert r.status == "time_limit"
    assert sorted(r.order) == list(range(40))
    assert r.lower_bound is not None
    assert 0 < r.lower_bound <= r.objective
    assert r.runtime_s < time_limit + 4.0


@pytest.mark.parametrize("omega", [0.0, 0.9])
def test_tiny_time_limit_bound_is_below_the_dp_optimum(omega):
    """Stopped after 0.02 s (before the root LP loop ends) on a K = 10 instance: status
    time_limit, a tour no better than the dp optimum and a bound not above it."""
    inst = generate_instance(10, 20, seed=3)
    opt = run_solver("dp", inst, omega).objective
    r = run_solver("milp", inst, omega, time_limit=0.02)
    assert r.status == "time_limit"
    assert 0 < r.lower_bound <= opt + 1e-9
    assert r.objective >= opt - 1e-9


@pytest.mark.parametrize("time_limit", [0.2, 0.6])
def test_a_solve_stopped_anywhere_stays_honest(time_limit):
    """Stopped wherever the limit falls (root loop, separation, restarts or branch and cut,
    depending on the machine): a proof is the dp optimum; otherwise the status is time_limit,
    the tour is no better than the optimum and the bound not above it. With one root round and
    the greedy tour, the branch and cut does most of the work."""
    inst = generate_instance(10, 20, seed=4)
    opt = run_solver("dp", inst, 0.5).objective
    for solver in (Milp(), Milp(root_rounds=1, lns_trials=0)):
        r = run_solver(solver, inst, 0.5, time_limit=time_limit)
        assert r.status in ("optimal", "time_limit")
        assert r.lower_bound <= opt + 1e-6 and r.objective >= opt - 1e-9
        if r.status == "optimal":
            assert r.objective == pytest.approx(opt, rel=1e-9)


def test_bad_options_and_input_are_refused():
    """Options are checked when the solver is built; an asymmetric matrix is refused."""
    with pytest.raises(InputError, match="lns_trials must be an integer >= 0"):
        get_solver("milp", lns_trials=-2)
    with pytest.raises(InputError, match="no option 'ants'"):
        get_solver("milp", ants=2)
    with pytest.raises(InputError, match="threads must be an integer >= 1"):
        get_solver("milp", threads=0)
    with pytest.raises(InputError, match="workers must be an integer >= 1"):
        get_solver("milp", workers=0)
    w = np.array([[0, 1, 2, 3], [5, 0, 1, 2], [2, 1, 0, 1], [3, 2, 1, 0]], dtype=float)
    inst = Instance(name="asym", clusters=tuple(np.zeros((1, 2)) for _ in range(4)), params=None,
                    edge_weight_type="EXPLICIT", weights=w, symmetric=False)
    with pytest.raises(InputError, match=r"^milp handles symmetric costs only"):
        run_solver("milp", inst, None)


def test_importing_milp_does_not_import_highspy():
    """highspy is imported when solving only (it cannot share a process with ortools)."""
    code = ("import sys, gtsp_bench.solvers.exact.milp, gtsp_bench.solvers.exact.gurobi; "
            "from gtsp_bench.solvers.exact.mip import backends, branch_cut, model, options, separation; "
            "print('highspy' in sys.modules, 'gurobipy' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO,
                         check=True).stdout
    assert out.split() == ["False", "False"]


def test_milp_reports_incumbents_and_bounds():
    """milp reports its incumbents and bounds: objectives never rise, bounds never fall and end
    at the proof (the last point's bound is the answer's)."""
    r = run_solver("milp", generate_instance(14, 8, seed=6), 0.5, time_limit=120.0, seed=1)
    assert r.status == "optimal"
    objectives = [p.objective for p in r.trajectory]
    bounds = [p.lower_bound for p in r.trajectory if p.lower_bound is not None]
    assert objectives == sorted(objectives, reverse=True) and objectives[-1] == r.objective
    assert len(bounds) >= 3 and bounds == sorted(bounds)
    assert bounds[-1] == pytest.approx(r.objective, rel=1e-9)


def test_milp_warm_start_is_its_first_incumbent():
    """A warm start is milp's first incumbent (no LNS tour first): its first report is the warm
    start's objective, and an optimal one is proven with the same tour cost."""
    inst = generate_instance(12, 6, seed=2)
    solved = run_solver("milp", inst, 0.3, time_limit=120.0, seed=0)
    greedy = run_solver("greedy", inst, 0.3)
    r = run_solver("milp", inst, 0.3, time_limit=120.0, initial=greedy)
    assert r.trajectory[0].objective == pytest.approx(greedy.objective, rel=1e-12)
    assert r.stats["warm_start"] is True
    assert r.status == "optimal" and r.objective == pytest.approx(solved.objective, rel=1e-9)
    again = run_solver("milp", inst, 0.3, time_limit=120.0, initial=solved)
    assert again.status == "optimal" and again.objective == pytest.approx(solved.objective, rel=1e-12)
    assert again.trajectory[0].objective == pytest.approx(solved.objective, rel=1e-12)

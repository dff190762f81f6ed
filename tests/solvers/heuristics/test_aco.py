"""The paper's ACO: feasible, never below the optimum, seeded, validated options, time limit."""

from __future__ import annotations

import pytest
from gtsp_bench.solvers.heuristics.aco import Aco

from gtsp_bench.cli import main
from gtsp_bench.data.io import read_instance
from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance
from gtsp_bench.registry import get_solver, run_solver
from tests.conftest import GTSPLIB
from tests.tiny_cases import not_below, tiny_case


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("depot", [True, False])
def test_feasible_and_never_below_the_optimum(seed, depot):
    """On tiny instances, with and without a depot, aco >= optimum and aco+ls <= aco."""
    inst, omega, optimum = tiny_case(seed, depot)
    options = {"ants": 10, "iterations": 20}
    a = run_solver(get_solver("aco", **options), inst, omega, seed=seed)
    al = run_solver(get_solver("aco+ls", **options), inst, omega, seed=seed)
    assert a.status == al.status == "feasible"
    assert a.stats["iterations"] == 20
    assert optimum - 1e-9 <= al.objective <= a.objective + 1e-9


def test_paper_defaults():
    """The defaults are the paper's: 30 ants, 200 iterations, rho 0.1, alpha 1, beta 5."""
    a = Aco()
    assert (a.ants, a.iterations, a.rho, a.alpha, a.beta) == (30, 200, 0.1, 1.0, 5.0)


def test_finds_the_optimum_of_small_instances():
    """With the paper's settings the colony solves most K = 4 instances exactly, never below
    brute's optimum."""
    hits = 0
    for seed in range(4):
        inst = generate_instance(4, 5, seed=seed)
        optimum = run_solver("brute", inst, 0.5).objective
        found = run_solver("aco", inst, 0.5).objective
        assert not_below(found, optimum)
        hits += found <= optimum * (1 + 1e-9)
    assert hits >= 3


def test_seed_reproduces_the_run():
    """The same seed gives the same tour; the run does not depend on earlier runs."""
    inst = generate_instance(8, 6, seed=2)
    solver = get_solver("aco", iterations=15)
    first = run_solver(solver, inst, 0.4, seed=7)
    run_solver(solver, inst, 0.4, seed=8)
    again = run_solver(solver, inst, 0.4, seed=7)
    assert (first.order, first.heads, first.objective) == (again.order, again.heads, again.objective)


def test_time_limit_returns_best_tour():
    """A limit too short for one iteration still gives a feasible tour, status time_limit."""
    inst = generate_instance(10, 20, seed=0)
    r = run_solver("aco", inst, 0.5, time_limit=1e-9)
    assert r.status == "time_limit"
    assert sorted(r.order) == list(range(10))
    assert r.stats["iterations"] == 0


def test_gtsplib_file():
    """Without a depot the ants start anywhere; the tour is valid and not below the optimum."""
    r = run_solver(get_solver("aco", iterations=10), read_instance(GTSPLIB / "11berlin52.gtsp.gz"), None)
    assert sorted(r.order) == list(range(11))
    assert r.objective >= 4040


@pytest.mark.parametrize("options, message", [
    ({"ants": 0}, "ants must be an integer >= 1"),
    ({"ants": 2.5}, "ants must be an integer"),
    ({"iterations": 0}, "iterations must be an integer >= 1"),
    ({"rho": 0}, r"rho must be a number in \(0, 1\]"),
    ({"rho": 1.5}, r"rho must be a number in \(0, 1\]"),
    ({"rho": float("nan")}, "rho"),
    ({"alpha": -1}, "alpha"),
    ({"beta": True}, "beta"),
    ({"q": 0}, "q must be"),
])
def test_bad_options_rejected(options, message):
    """Invalid parameters raise InputError naming the parameter."""
    with pytest.raises(InputError, match=message):
        get_solver("aco", **options)


def test_cli_bad_option_exits_2(tmp_path, capsys):
    """`solve -p ants=0` and a negative time limit print one error line and exit 2."""
    path = tmp_path / "k3.json"
    assert main(["generate", "--clusters", "3", "--nodes", "3", "-o", str(path)]) == 0
    capsys.readouterr()
    assert main(["solve", str(path), "--solver", "aco", "-p", "ants=0"]) == 2
    assert "ants must be an integer >= 1" in capsys.readouterr().err
    assert main(["solve", str(path), "--solver", "aco", "--time-limit", "-1"]) == 2
    assert "time limit" in capsys.readouterr().err


def test_aco_ls_keeps_a_share_of_its_time_limit_for_the_local_search(monkeypatch):
    """At its time limit the colony of aco+ls stops at (1 - LS_SHARE) of it, so the local search
    still has time; plain aco uses the whole limit."""
    import time

    from gtsp_bench.solvers.heuristics import aco

    seen = {}

    def record(self, problem, *, deadline, seed, **rest):
        seen[type(self).__name__] = deadline - time.perf_counter()
        return real(self, problem, deadline=deadline, seed=seed, **rest)

    real = aco.Aco.search
    monkeypatch.setattr(aco.Aco, "search", record)
    inst = generate_instance(4, 5, seed=0)
    run_solver(get_solver("aco", iterations=1), inst, 0.5, time_limit=100.0)
    run_solver(get_solver("aco+ls", iterations=1), inst, 0.5, time_limit=100.0)
    assert 99.0 < seen["Aco"] <= 100.0
    assert 100.0 * (1 - aco.LS_SHARE) - 1.0 < seen["AcoLS"] <= 100.0 * (1 - aco.LS_SHARE)


@pytest.mark.parametrize("name", ["aco", "aco+ls"])
def test_aco_reports_each_better_tour(name):
    """aco reports its ants' best tour as it improves (aco+ls then the local search's): the
    objectives never rise and end at the answer."""
    inst = generate_instance(15, 8, seed=3)
    r = run_solver(get_solver(name, iterations=30), inst, 0.5, seed=2)
    objectives = [p.objective for p in r.trajectory]
    assert len(objectives) >= 2 and objectives == sorted(objectives, reverse=True)
    assert objectives[-1] == r.objective and all(p.lower_bound is None for p in r.trajectory)

"""The LNS: feasible, never below and usually at the optimum, seeded, time limit, budget, options,
effort presets, the mirror trial.

Most runs use ``stop_at_convergence`` (effort ``fast``: stop after three trials) to stay fast;
those that test the use of a whole time limit say effort ``budget``.
"""

from __future__ import annotations

import numpy as np
import pytest
from gtsp_bench.solvers.heuristics import lns as lns_module
from gtsp_bench.solvers.heuristics import lns_kernels as kernels
from gtsp_bench.solvers.heuristics.lns import EFFORTS, LARGE, LnsSettings, _Search, restart_kind
from gtsp_bench.solvers.heuristics.lns_settings import FAIL_FROM, KICKS

from gtsp_bench.data.io import read_instance
from gtsp_bench.energy import evaluate
from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance
from gtsp_bench.instance import Instance
from gtsp_bench.problem import price
from gtsp_bench.registry import get_solver, run_solver
from tests.conftest import GTSPLIB
from tests.tiny_cases import not_below, tiny_asymmetric_case, tiny_case

#: lns that stops when its trials are done instead of using the whole time limit.
CONVERGE = {"stop_at_convergence": True}
#: lns that uses the whole time limit (the fixed-budget benchmarks' runs).
BUDGET = {"effort": "budget", "workers": 1}  # one thread: one search (test_lns_islands: two)


@pytest.mark.parametrize("depot", [True, False])
def test_finds_most_brute_force_optima(depot):
    """With its defaults, lns matches brute force on most tiny instances, never goes below."""
    hits = 0
    for seed in range(10):
        inst, omega, optimum = tiny_case(seed, depot)
        r = run_solver(get_solver("lns", **CONVERGE), inst, omega, seed=seed)
        assert r.status == "feasible"
        assert not_below(r.objective, optimum)
        hits += r.objective <= optimum + 1e-9 * optimum
    assert hits >= 9


def test_matches_brute_force_on_k7():
    """A K = 7 instance with 3 nodes per cluster (11 million tours): lns finds the optimum."""
    inst = generate_instance(7, 3, seed=5)
    optimum = run_solver("brute", inst, 0.3).objective
    assert run_solver(get_solver("lns", **CONVERGE), inst, 0.3).objective == pytest.approx(optimum, rel=1e-9)


@pytest.mark.parametrize("seed", range(4))
def test_never_below_dp_optimum(seed):
    """K = 9 UAV instances, several seeds: never below the DP's proven optimum, at it for most."""
    inst = generate_instance(9, 4, seed=10 + seed)
    optimum = run_solver("dp", inst, 0.4).objective
    r = run_solver(get_solver("lns", **CONVERGE), inst, 0.4, seed=seed)
    assert not_below(r.objective, optimum)
    assert r.objective == pytest.approx(optimum, rel=1e-9)


def _asymmetric(k: int, seed: int) -> Instance:
    """A distance-only asymmetric GTSP: K clusters of 2 or 3 nodes, arc costs drawn
    independently in each direction."""
    rng = np.random.default_rng([seed, 11])
    sizes = rng.integers(2, 4, size=k)
    n = int(sizes.sum())
    w = np.round(rng.uniform(1.0, 100.0, size=(n, n)), 2)
    np.fill_diagonal(w, 0.0)
    return Instance(name=f"asym-{k}-{seed}", clusters=tuple(np.full((s, 2), np.nan) for s in sizes),
                    params=None, edge_weight_type="EXPLICIT", weights=w, symmetric=False)


def test_asymmetric_tiny_instances_match_brute():
    """Directed costs: never below brute force's optimum, at it on most tiny instances (the
    evaluator re-prices every answer in its direction)."""
    hits = 0
    for seed in range(10):
        inst, optimum = tiny_asymmetric_case(seed)
        r = run_solver(get_solver("lns", **CONVERGE), inst, None, seed=seed)
        assert not_below(r.objective, optimum)
        hits += r.objective <= optimum + 1e-9 * optimum
    assert hits >= 8


@pytest.mark.parametrize("seed", range(3))
def test_asymmetric_reaches_dp_optimum(seed):
    """K = 9 asymmetric instances: lns reaches dp's proven optimum, whose reverse tour
    costs more (the direction matters)."""
    inst = _asymmetric(9, seed)
    best = run_solver("dp", inst, None)
    r = run_solver(get_solver("lns", **CONVERGE), inst, None, seed=seed)
    assert r.objective == pytest.approx(best.objective, rel=1e-9)
    back = evaluate(inst, None, r.order[::-1], r.heads).objective
    assert back > r.objective + 1e-9


def test_stop_at_convergence_stops_after_its_trials():
    """With stop_at_convergence the run ends after exactly ``trials`` trials, converged."""
    inst = generate_instance(12, 4, seed=3)
    r = run_solver(get_solver("lns", iterations=10, patience=5, trials=2, **CONVERGE), inst, 0.5,
                   time_limit=600)
    assert r.status == "feasible"
    assert r.stats["trials"] == 2 and r.stats["converged"] is True
    assert r.stats["iterations"] <= 20


def test_uses_the_time_limit_when_converged():
    """With effort budget, the same settings go on with more trials until the limit, and
    the run still counts as converged (status feasible)."""
    inst = generate_instance(12, 4, seed=3)
    r = run_solver(get_solver("lns", iterations=10, patience=5, trials=2, **BUDGET), inst, 0.5,
                   time_limit=1.0)
    assert r.status == "feasible"
    assert r.stats["converged"] is True
    assert r.stats["trials"] > 2


def test_seed_reproduces_the_run():
    """Without a binding time limit the same seed gives the same result and iteration count."""
    inst = generate_instance(9, 5, seed=1)
    solver = get_solver("lns", iterations=60, trials=2, **CONVERGE)
    a = run_solver(solver, inst, 0.7, seed=3, time_limit=60)
    b = run_solver(solver, inst, 0.7, seed=3, time_limit=60)
    assert (a.order, a.heads, a.objective, a.stats["iterations"]) == \
        (b.order, b.heads, b.objective, b.stats["iterations"])


def test_time_limit_returns_best_tour():
    """A tiny limit still gives a feasible tour, with status time_limit, never below milp's
    proven optimum."""
    inst = generate_instance(15, 10, seed=0)
    r = run_solver("lns", inst, 0.5, time_limit=1e-6)
    assert r.status == "time_limit"
    assert sorted(r.order) == list(range(15))
    optimum = run_solver("milp", inst, 0.5)
    assert optimum.status == "optimal" and not_below(r.objective, optimum.objective)


def test_gtsplib_file():
    """On 11berlin52 (no depot) a short run reaches the proven optimum 4040."""
    r = run_solver(get_solver("lns", iterations=100, trials=1, **CONVERGE),
                   read_instance(GTSPLIB / "11berlin52.gtsp.gz"), None)
    assert sorted(r.order) == list(range(11))
    assert r.objective == 4040


@pytest.mark.parametrize("k, depot", [(1, True), (1, False), (2, True), (2, False), (3, False)])
def test_very_small_instances(k, depot):
    """One to three clusters, with or without a depot, are solved exactly (and at once: no trials)."""
    base = generate_instance(k, 4, seed=k)
    inst = base if depot else Instance(name="nd", clusters=base.clusters)
    r = run_solver("lns", inst, 0.5)
    assert r.stats["trials"] == 0 and r.status == "feasible"
    assert r.objective == pytest.approx(run_solver("brute", inst, 0.5).objective, rel=1e-12)


def test_operators_are_all_used():
    """Every removal and insertion operator keeps a positive weight (none is switched off)."""
    solver = get_solver("lns", iterations=80, trials=1, **CONVERGE)
    r = run_solver(solver, generate_instance(8, 4, seed=0), 0.5)
    assert set(r.stats["weights"]) == {"random", "worst", "segment", "distance", "cheapest", "farthest",
                                       "randomised"}
    assert all(w > 0 for w in r.stats["weights"].values())


@pytest.mark.parametrize("options, message", [
    ({"iterations": 0}, "iterations must be an integer >= 1"),
    ({"trials": 0}, "trials must be an integer >= 1"),
    ({"patience": -3}, "patience"),
    ({"remove_fraction": 0}, "remove_fraction"),
    ({"remove_fraction": 1.2}, "remove_fraction"),
    ({"start_temperature": -1}, "start_temperature"),
    ({"start_temperature": 0.01, "end_temperature": 0.1}, "must not exceed"),
    ({"reaction": 0}, "reaction"),
    ({"noise": float("inf")}, "noise"),
    ({"neighbours": 0}, "neighbours"),
    ({"max_removals": 0}, "max_removals must be an integer >= 1"),
    ({"stop_at_convergence": "yes"}, "stop_at_convergence must be true or false"),
    ({"restart_after": -1}, "restart_after must be an integer >= 0"),
    ({"reopt_window": -1}, "reopt_window must be an integer >= 0"),
    ({"fit_to_time": 1}, "fit_to_time must be true or false"),
    ({"fit_trials": 0}, "fit_trials must be an integer >= 1"),
    ({"macro": 1}, "macro must be true or false"),
    ({"macro_iterations": -1}, "macro_iterations must be an integer >= 0"),
    ({"macro_groups": -1}, "macro_groups must be a number >= 0"),
    ({"macro_groups": float("nan")}, "macro_groups must be a number >= 0"),
    ({"starts": 0}, "starts must be an integer >= 1"),
    ({"start_iterations": 0}, "start_iterations must be an integer >= 1"),
    ({"mirror": 1}, "mirror must be true or false"),
    ({"plateau": "yes"}, "plateau must be true or false"),
    ({"points": 1}, "points must be true or false"),
    ({"quadrants": "no"}, "quadrants must be true or false"),
    ({"workers": 0}, "workers must be an integer >= 1"),
    ({"regional": -0.1}, "regional must be a number in \\[0, 1\\]"),
    ({"regional": 1.5}, "regional must be a number in \\[0, 1\\]"),
    ({"regional": "half"}, "regional must be a number"),
])
def test_bad_options_rejected(options, message):
    """Invalid settings raise InputError naming the setting."""
    with pytest.raises(InputError, match=message):
        get_solver("lns", **options)


def test_time_limited_defaults_cool_each_trial_fully():
    """With effort budget a trial runs all its iterations (no patience) from a hotter
    start; given values win in both modes."""
    s = LnsSettings(**BUDGET)
    assert s.patience_for(41) == s.iterations_for(41) == 1025 and s.hottest == 1.0
    given = LnsSettings(patience=7, start_temperature=0.5, **BUDGET)
    assert given.patience_for(41) == 7 and given.hottest == 0.5
    with pytest.raises(InputError, match="must not exceed"):
        LnsSettings(end_temperature=0.5, stop_at_convergence=True)


def test_cold_restarts_leave_converging_runs_alone():
    """restart_after acts only on a search that uses its time limit: with stop_at_convergence the
    run is the same whatever its value (the paper's runs keep their answers)."""
    inst = generate_instance(14, 4, seed=2)
    runs = [run_solver(get_solver("lns", restart_after=r, **CONVERGE), inst, 0.4, seed=1)
            for r in (0, 1, 2)]
    assert len({(r.order, r.heads, r.objective, r.stats["iterations"]) for r in runs}) == 1


def test_cold_restarts_under_a_time_limit():
    """With tiny trials and restart_after=1 a time-limited run makes many trials, cold ones among
    them, and still returns a tour no better than the DP optimum, at it here."""
    inst = generate_instance(9, 3, seed=4)
    optimum = run_solver("dp", inst, 0.5).objective
    r = run_solver(get_solver("lns", iterations=20, restart_after=1), inst, 0.5, seed=2, time_limit=0.5)
    assert r.stats["trials"] > 3
    assert r.objective == pytest.approx(optimum, rel=1e-9)


def test_default_budget_scales_with_size():
    """Default iterations per trial and patience grow with the number of clusters."""
    s = LnsSettings(stop_at_convergence=True)
    assert s.iterations_for(4) == 100 and s.iterations_for(41) == 1025
    assert s.patience_for(4) == 50 and s.patience_for(41) == 205
    assert s.hottest == 0.3
    assert s.max_removals_for(400) == 100 and s.max_removals_for(401) == 25
    assert LnsSettings(max_removals=7).max_removals_for(5000) == 7
    assert np.all(np.diff([s.iterations_for(n) for n in range(1, 200)]) >= 0)


def test_large_cycles_default_to_the_windowed_reopt():
    """The windowed re-opt is the default only above LARGE clusters; a given width wins."""
    assert LnsSettings().reopt_window_for(LARGE) == 0 and LnsSettings().reopt_window_for(LARGE + 1) == 4
    assert LnsSettings(reopt_window=2).reopt_window_for(10) == 2
    assert LnsSettings(reopt_window=0).reopt_window_for(5000) == 0


@pytest.mark.parametrize("seed", range(3))
def test_windowed_search_never_below_dp_optimum(seed):
    """The large-cycle path forced on K = 12 (windowed re-opt, the removals that sample): a
    valid tour, never below the DP's proven optimum, and its objective is the tour's energy."""
    inst = generate_instance(12, 3, seed=20 + seed)
    optimum = run_solver("dp", inst, 0.5).objective
    r = run_solver(get_solver("lns", reopt_window=1), inst, 0.5, seed=seed, time_limit=0.3)
    assert sorted(r.order) == list(range(12))
    assert not_below(r.objective, optimum)


def test_fitted_trials_leave_converging_runs_alone():
    """fit_to_time and fit_trials act only on a search that uses its time limit: with
    stop_at_convergence the run is the same whatever their values."""
    inst = generate_instance(14, 4, seed=2)
    runs = [run_solver(get_solver("lns", fit_to_time=f, fit_trials=t, **CONVERGE), inst, 0.4, seed=1)
            for f, t in ((True, 32), (False, 1), (True, 2))]
    assert len({(r.order, r.heads, r.objective, r.stats["iterations"]) for r in runs}) == 1


def test_fitted_trials_fill_a_short_budget():
    """A time-limited run whose trials would not fit its budget makes at least several shorter
    ones (the fitted length), and more with a larger fit_trials."""
    inst = generate_instance(14, 4, seed=6)
    few = run_solver(get_solver("lns", iterations=10**6, fit_trials=1, **BUDGET), inst, 0.4, seed=1,
                     time_limit=0.4)
    many = run_solver(get_solver("lns", iterations=10**6, fit_trials=64, **BUDGET), inst, 0.4, seed=1,
                      time_limit=0.4)
    assert few.stats["trials"] <= 2 < 10 <= many.stats["trials"]


def test_large_cycles_fit_only_whole_trials():
    """Above LARGE clusters a fitted trial is not cut below its default length (25 iterations per
    cluster) except by the time limit: however many trials fit_trials asks for, every finished
    trial but the last ran them all; the answer is valid and priced as the evaluator prices it
    (run_solver refuses any other claim).
    (One thread: islands each end a trial at the exchange too.)"""
    n = LARGE + 20
    inst = generate_instance(n, 2, seed=3, zeta=10.0, area=4000.0)
    r = run_solver(get_solver("lns", fit_trials=64, **BUDGET), inst, 0.5, seed=1, time_limit=3.0)
    assert r.stats["iterations"] >= 25 * (n + 1) * (r.stats["trials"] - 1)
    assert sorted(r.order) == list(range(n))


def test_macro_tour_is_off_by_default():
    """The macro first tour is opt-in: the default run on a planar instance above LARGE clusters
    is the run with macro=False."""
    assert LnsSettings().macro is False


@pytest.mark.parametrize("seed", range(3))
def test_macro_start_never_below_dp_optimum(seed):
    """The macro first tour forced on K = 12 UAV instances (the depot a cluster of its own): a
    valid tour, never below the DP's proven optimum, priced as the evaluator prices it
    (run_solver refuses any other claim)."""
    inst = generate_instance(12, 3, seed=30 + seed)
    optimum = run_solver("dp", inst, 0.5).objective
    r = run_solver(get_solver("lns", macro=True, macro_iterations=5, **CONVERGE), inst, 0.5, seed=seed)
    assert sorted(r.order) == list(range(12))
    assert not_below(r.objective, optimum)


def test_macro_needs_points():
    """On explicit costs (no coordinates) macro=True is the greedy start: the same run as without."""
    inst = _asymmetric(9, 1)
    runs = [run_solver(get_solver("lns", macro=m, **CONVERGE), inst, None, seed=2) for m in (True, False)]
    assert len({(r.order, r.heads, r.objective, r.stats["iterations"]) for r in runs}) == 1


def test_macro_starts_large_cycles_elsewhere():
    """Above LARGE clusters (the windowed path) macro=True starts from the macro tour, and the
    default and macro=False from the greedy one: all valid, the macro run a different search,
    the other two the same run."""
    n = LARGE + 20
    inst = generate_instance(n, 2, seed=3, zeta=10.0, area=4000.0)
    runs = [run_solver(get_solver("lns", iterations=200, trials=1, **options, **CONVERGE), inst, 0.5, seed=1)
            for options in ({"macro": True}, {}, {"macro": False})]
    for r in runs:
        assert sorted(r.order) == list(range(n))
    assert runs[0].order != runs[1].order
    default, off = ((r.order, r.heads, r.objective) for r in runs[1:])
    assert default == off


def test_no_race_by_default():
    """One start unless asked: starts=1 is the default run, below and above LARGE clusters."""
    assert LnsSettings().starts == 1
    for n, options in ((12, {}), (LARGE + 20, {"iterations": 200, "trials": 1})):
        inst = generate_instance(n, 2, seed=3, zeta=10.0, area=4000.0)
        runs = [run_solver(get_solver("lns", **given, **options, **CONVERGE), inst, 0.5, seed=1)
                for given in ({}, {"starts": 1})]
        assert len({(r.order, r.heads, r.objective, r.stats["iterations"]) for r in runs}) == 1


@pytest.mark.parametrize("k", [1, 2, 3, 4])
def test_race_on_very_small_instances(k):
    """A race asked for on 1-4 clusters still returns a valid tour (up to 3 clusters no race),
    the DP's optimum (the re-opt solves up to 3 clusters; 4 are a handful of orders)."""
    inst = generate_instance(k, 3, seed=k)
    r = run_solver(get_solver("lns", starts=3, **CONVERGE), inst, 0.5, seed=1)
    assert sorted(r.order) == list(range(k))
    assert r.objective == pytest.approx(run_solver("dp", inst, 0.5).objective, rel=1e-9)


def test_race_kinds():
    """The race takes greedy, then macro (planar costs only), then random-insertion tours."""
    planar = _Search(price(generate_instance(12, 2, seed=1), 0.5), LnsSettings(starts=4),
                     np.random.default_rng(0))
    assert planar.start_kinds() == ["greedy", "macro", "random", "random"]
    assert _Search(price(generate_instance(12, 2, seed=1), 0.5), LnsSettings(starts=2),
                   np.random.default_rng(0)).start_kinds() == ["greedy", "macro"]
    explicit = _Search(price(_asymmetric(9, 1), None), LnsSettings(starts=3), np.random.default_rng(0))
    assert explicit.start_kinds() == ["greedy", "random", "random"]


@pytest.mark.parametrize("seed", range(3))
def test_raced_starts_never_below_dp_optimum(seed):
    """Three raced starts on K = 12 (and on directed costs): valid tours, never below the DP's
    proven optimum, priced as the evaluator prices them; the race's iterations are counted."""
    inst = generate_instance(12, 3, seed=40 + seed)
    optimum = run_solver("dp", inst, 0.5).objective
    r = run_solver(get_solver("lns", starts=3, start_iterations=20, **CONVERGE), inst, 0.5, seed=seed)
    assert sorted(r.order) == list(range(12))
    assert not_below(r.objective, optimum)
    assert r.stats["iterations"] > 3 * max(100, 20 * price(inst, 0.5).n_clusters)
    directed = _asymmetric(9, seed)
    d_opt = run_solver("dp", directed, None).objective
    d = run_solver(get_solver("lns", starts=2, **CONVERGE), directed, None, seed=seed)
    assert not_below(d.objective, d_opt)


def test_race_keeps_the_cheapest_start():
    """Above LARGE clusters the race's answer is the cheapest of its starts' short trials: each
    raced start alone (same kernel seed) ends no cheaper than the race of all three."""
    n = LARGE + 20
    problem = price(generate_instance(n, 2, seed=5, zeta=10.0, area=4000.0), 0.5)
    search = _Search(problem, LnsSettings(starts=3, start_iterations=1), np.random.default_rng(0))
    kernels.seed(9)
    tour, cost, _, _, done = search.race(search.start_kinds(), None)
    assert done == 3 * max(100, problem.n_clusters)
    assert sorted(problem.cluster_of[tour].tolist()) == list(range(problem.n_clusters))
    assert cost == pytest.approx(problem.tour_cost(tour), rel=1e-9)
    alone = []
    for kind in ("greedy", "macro", "random"):
        kernels.seed(9)
        for earlier in ("greedy", "macro", "random")[: ("greedy", "macro", "random").index(kind)]:
            search.race([earlier], None)  # the same random numbers as in the race
        alone.append(search.race([kind], None)[1])
    assert cost == min(alone)


def test_lns_reports_each_better_tour():
    """On 40d198 lns reports the first tour and later better ones: objectives never rise, and
    the trajectory ends at the answer."""
    r = run_solver("lns", read_instance(GTSPLIB / "40d198.gtsp.gz"), None, time_limit=1.0, seed=1)
    objectives = [p.objective for p in r.trajectory]
    assert len(objectives) >= 2 and objectives == sorted(objectives, reverse=True)
    assert objectives[-1] == r.objective


def test_lns_warm_start():
    """From a warm start the search starts at that tour (its first report is no worse) and ends
    no worse; a warm start whose claimed bound meets its objective comes back at once,
    unchanged."""
    from gtsp_bench.solver import Solution

    inst = generate_instance(12, 6, seed=5)
    first = run_solver("greedy", inst, 0.4)
    r = run_solver("lns", inst, 0.4, time_limit=0.5, seed=2, initial=first)
    assert r.trajectory[0].objective <= first.objective and r.objective <= first.objective
    assert r.stats["warm_start"] is True
    proven = Solution(r.order, r.heads, r.objective, lower_bound=r.objective)
    again = run_solver("lns", inst, 0.4, time_limit=30.0, seed=3, initial=proven)
    assert (again.order, again.heads, again.objective) == (r.order, r.heads, r.objective)
    assert again.runtime_s < 1.0 and again.stats["warm_start"] == "at its lower bound"


@pytest.mark.parametrize("effort", list(EFFORTS))
def test_effort_presets_set_the_stopping_rule(effort):
    """Each preset: whether the search stops after its trials, how many, when a cold restart
    comes; explicitly given trials and restart_after win over the preset's."""
    s = LnsSettings(effort=effort)
    preset = EFFORTS[effort]
    assert s.preset == preset and s.stops == (effort != "budget")
    assert (s.trial_count, s.cold_after) == (preset.trials, preset.restart_after)
    given = LnsSettings(effort=effort, trials=5, restart_after=0)
    assert (given.trial_count, given.cold_after) == (5, 0)


def test_effort_defaults_and_the_old_switch():
    """The default effort is ``default``; stop_at_convergence true is ``fast`` (the paper's runs),
    false is ``budget``; both at once is refused."""
    assert LnsSettings().preset == EFFORTS["default"] and LnsSettings().stops
    assert LnsSettings(stop_at_convergence=True).preset == EFFORTS["fast"]
    assert LnsSettings(stop_at_convergence=False).preset == EFFORTS["budget"]
    with pytest.raises(InputError, match="give effort or stop_at_convergence, not both"):
        LnsSettings(effort="fast", stop_at_convergence=True)


def test_unknown_effort_lists_the_presets():
    """A misspelt preset is refused with the valid names."""
    valid = "'fast', 'default', 'slow', 'budget'"
    with pytest.raises(InputError, match=f"effort must be one of {valid}, got 'quick'"):
        get_solver("lns", effort="quick")


@pytest.mark.parametrize("effort", ["fast", "default", "slow"])
def test_stopping_efforts_end_on_their_own(effort):
    """On 11berlin52 (proven optimum 4040) the presets that stop end after their trials, long
    before a 600 s cap (status feasible, converged), never below the optimum; the same seed gives
    the same run."""
    inst = read_instance(GTSPLIB / "11berlin52.gtsp.gz")
    solver = get_solver("lns", effort=effort)
    r = run_solver(solver, inst, None, seed=4, time_limit=600)
    assert r.status == "feasible" and r.stats["converged"] is True
    assert r.stats["trials"] == EFFORTS[effort].trials
    assert not_below(r.objective, 4040)
    again = run_solver(solver, inst, None, seed=4, time_limit=600)
    assert (again.order, again.heads, again.stats["iterations"]) == (r.order, r.heads, r.stats["iterations"])


def test_without_a_time_limit_every_effort_stops():
    """Called directly with no time limit, lns stops after its trials whatever its effort (the
    default limit is the harness's, run_solver's, to give)."""
    inst = generate_instance(9, 3, seed=4)
    for effort in EFFORTS:
        sol = get_solver("lns", effort=effort, iterations=50).solve(inst, 0.5, seed=1)
        assert sol.status == "feasible" and sol.stats["converged"] is True, effort


#: Two trials of 350 iterations, cooled from 1.0, no cold restart: the first two trials of a
#: 0.07 s budget run on 35ftv170, without the clock.
TWO_TRIALS = {"effort": "default", "iterations": 350, "patience": 350, "start_temperature": 1.0,
              "trials": 2, "restart_after": 0}


def test_mirror_defaults_to_asymmetric_budget_runs():
    """The mirror trial is on by default only with effort budget on asymmetric costs (so the
    presets that stop, the paper's runs among them, and symmetric files are unchanged); a given
    value wins."""
    assert LnsSettings(**BUDGET).mirror_for(False)
    assert not LnsSettings(**BUDGET).mirror_for(True)
    for effort in ("fast", "default", "slow"):
        assert not LnsSettings(effort=effort).mirror_for(False)
    assert LnsSettings(effort="fast", mirror=True).mirror_for(True)
    assert not LnsSettings(mirror=False, **BUDGET).mirror_for(False)


def test_plateau_defaults_to_budget_runs():
    """Equal-cost tours replace the current one by default only with effort budget (the presets
    that stop, the paper's runs among them, keep rejecting them); a given value wins, and the
    trial settings carry it."""
    assert LnsSettings(**BUDGET).plateau_for()
    for effort in ("fast", "default", "slow"):
        assert not LnsSettings(effort=effort).plateau_for()
    assert LnsSettings(effort="fast", plateau=True).plateau_for()
    assert not LnsSettings(plateau=False, **BUDGET).plateau_for()
    p = price(generate_instance(6, 3, seed=1), 0.5)
    for settings, flag in ((LnsSettings(**BUDGET), 1.0), (LnsSettings(effort="fast"), 0.0)):
        search = _Search(p, settings, np.random.default_rng(0))
        tour = search.first(None).best
        assert search.trial_settings(tour, 1.0, 100, 100)[8] == flag


def test_mirror_trial_starts_from_the_reversed_best(monkeypatch):
    """With mirror, the second trial starts from the best tour of the first, reversed (then
    improved by the local search); without it no trial starts from a reversed best."""
    inst = read_instance(GTSPLIB / "35ftv170.gtsp.gz")
    for mirror in (True, False):
        solver = get_solver("lns", mirror=mirror, **TWO_TRIALS)  # warms its kernels up before the spies
        searched: list[np.ndarray] = []
        bests: list[np.ndarray] = []
        local_search, run_trial = _Search.local_search, kernels.run_trial

        def spy_search(self, t, searched=searched, local_search=local_search):
            searched.append(np.array(t))
            return local_search(self, t)

        def spy_trial(*args, bests=bests, run_trial=run_trial):
            ended = run_trial(*args)
            if ended:
                bests.append(args[1].copy())
            return ended

        monkeypatch.setattr(_Search, "local_search", spy_search)
        monkeypatch.setattr(kernels, "run_trial", spy_trial)
        run_solver(solver, inst, None, seed=5)
        monkeypatch.undo()
        assert len(bests) == 2
        reversed_best = [np.array_equal(t, bests[0][::-1]) for t in searched]
        assert reversed_best == ([False, True] if mirror else [False])


def test_mirror_trial_leaves_the_reversed_trap_on_35ftv170():
    """On 35ftv170 (AGTSP, optimum 1205) the trials keep a tour's direction, and the reversal of
    the optimum's basin is a trap at 1247: over seeds 0-39, two trials end there 7 times without
    the mirror trial and twice with it (every other seed at the optimum; before the segment swap
    joined the directed local search, 3 and 0 times)."""
    inst = read_instance(GTSPLIB / "35ftv170.gtsp.gz")
    off = get_solver("lns", mirror=False, **TWO_TRIALS)
    on = get_solver("lns", mirror=True, **TWO_TRIALS)
    without = [run_solver(off, inst, None, seed=s).objective for s in range(40)]
    with_mirror = [run_solver(on, inst, None, seed=s).objective for s in range(40)]
    assert set(without) == set(with_mirror) == {1205.0, 1247.0}
    assert without.count(1247.0) >= 5 and with_mirror.count(1247.0) <= 2


def test_regional_restarts_default_and_size():
    """A regional restart takes out the given share of the clusters (at least 1, at most all but
    one); no effort makes one unless asked (the committed runs keep their answers)."""
    for effort in EFFORTS:
        assert LnsSettings(effort=effort).regional_for(100) == 0
    assert LnsSettings(effort="default", regional=0.25).regional_for(100) == 25
    assert LnsSettings(regional=0.0, **BUDGET).regional_for(100) == 0
    assert LnsSettings(regional=0.001, **BUDGET).regional_for(100) == 1
    assert LnsSettings(regional=1.0, **BUDGET).regional_for(100) == 99


def test_restart_kind_is_regional_only_after_a_chain_that_won():
    """A restart is regional only with ``regional`` on, after the run's first restart, and when
    the chain that ends improved the run's best; every other restart is cold."""
    assert restart_kind(30, 1, True) == restart_kind(30, 5, True) == "regional"
    assert restart_kind(30, 0, True) == "random"  # the first restart is cold
    assert restart_kind(30, 3, False) == "random"  # a chain that did not improve the best
    assert restart_kind(0, 3, True) == "random"  # regional off


def test_regional_restarts_come_only_after_a_chain_that_won(monkeypatch):
    """A budget run whose first chain is at the DP optimum makes many restarts, none regional
    (no later chain improves its best); when restart_kind says regional, the restart re-plans the
    given share of the best tour, and the answer is still the optimum; without ``regional`` none."""
    inst = generate_instance(9, 3, seed=4)
    optimum = run_solver("dp", inst, 0.5).objective
    kind_of = lns_module.restart_kind
    for share, forced, some in ((0.4, False, False), (0.4, True, True), (0.0, True, False)):
        solver = get_solver("lns", iterations=20, restart_after=1, regional=share, **BUDGET)
        calls: list[int] = []
        kinds: list[tuple[int, bool]] = []
        regional_tour = kernels.regional_tour

        def spy(t, k, *args, calls=calls, regional_tour=regional_tour):
            calls.append(k)
            return regional_tour(t, k, *args)

        def spy_kind(regional, restarts, won, kinds=kinds, forced=forced):
            kinds.append((restarts, won))
            return kind_of(regional, restarts, won or (forced and restarts % 2 == 1))

        monkeypatch.setattr(kernels, "regional_tour", spy)
        monkeypatch.setattr(lns_module, "restart_kind", spy_kind)
        r = run_solver(solver, inst, 0.5, seed=3, time_limit=0.3)
        monkeypatch.undo()
        assert [restarts for restarts, _ in kinds] == list(range(len(kinds))) and len(kinds) > 10
        assert not any(won for _, won in kinds[1:])  # the first chain found the best
        assert bool(calls) == some
        assert set(calls) <= {4}  # 0.4 of the 10 clusters (the depot's included)
        assert r.objective == pytest.approx(optimum, rel=1e-9)


def test_regional_restarts_leave_stopping_efforts_alone():
    """With effort ``default`` (which makes cold restarts) the run is the same whether
    ``regional`` is left to its default or set to 0."""
    inst = generate_instance(14, 4, seed=2)
    runs = [run_solver(get_solver("lns", effort="default", **extra), inst, 0.4, seed=1)
            for extra in ({}, {"regional": 0.0})]
    assert len({(r.order, r.heads, r.objective, r.stats["iterations"]) for r in runs}) == 1


def test_kicks_run_after_failed_trials_only_when_asked(monkeypatch):
    """With ``kicks`` a budget run kicks the start of each failed trial (that many kicks in all
    per failed trial) and still ends at the DP optimum, never below; with 0 (the default at 10
    clusters) no kick is made; a negative count is refused."""
    inst = generate_instance(9, 3, seed=4)
    optimum = run_solver("dp", inst, 0.5).objective
    kick_search = kernels.kick_search
    for count in (0, 100):
        solver = get_solver("lns", iterations=20, kicks=count, **BUDGET)
        calls: list[int] = []

        def spy(t, cost, n, *args, calls=calls, kick_search=kick_search):
            calls.append(n)
            return kick_search(t, cost, n, *args)

        monkeypatch.setattr(kernels, "kick_search", spy)
        r = run_solver(solver, inst, 0.5, seed=3, time_limit=0.2)
        monkeypatch.undo()
        assert not_below(r.objective, optimum)
        assert r.objective == pytest.approx(optimum, rel=1e-9)
        assert bool(calls) == bool(count)
        assert all(n <= lns_module.KICK_CHUNK for n in calls)
    with pytest.raises(InputError, match="kicks"):
        get_solver("lns", kicks=-1)


@pytest.mark.parametrize("n, symmetric, options, kicks", [
    (FAIL_FROM, True, {"effort": "budget"}, KICKS),
    (LARGE, True, {"effort": "budget"}, KICKS),
    (FAIL_FROM - 1, True, {"effort": "budget"}, 0),  # below FAIL_FROM: off by default
    (LARGE + 1, True, {"effort": "budget"}, 0),  # above LARGE: off by default
    (FAIL_FROM, True, {}, 0),  # the default effort stops after its trials: off
    (FAIL_FROM, True, {"effort": "fast"}, 0),
    (FAIL_FROM, True, {"stop_at_convergence": False}, KICKS),  # effort budget by its old name
    (FAIL_FROM, False, {"effort": "budget"}, KICKS),  # directed costs: at every size
    (12, False, {"effort": "budget"}, KICKS),
    (LARGE + 1, False, {"effort": "budget"}, KICKS),
    (12, False, {"effort": "default"}, 0),  # an effort that stops: off on directed costs too
    (12, False, {"kicks": 7}, 7),  # given: at any size, either kind of costs
    (FAIL_FROM, True, {"effort": "budget", "kicks": 0}, 0),
])
def test_kicks_by_size(n, symmetric, options, kicks):
    """Kicks after a failed trial: ``kicks``, by default KICKS with effort ``budget`` from
    FAIL_FROM to LARGE clusters on symmetric costs and at every size on directed ones, else 0."""
    assert LnsSettings(**options).kicks_for(n, symmetric) == kicks


@pytest.mark.parametrize("k, kicks", [(FAIL_FROM - 1, KICKS), (FAIL_FROM - 2, 0)])
def test_budget_search_kicks_from_fail_from(k, kicks):
    """A budget search on a UAV instance of FAIL_FROM clusters (K = FAIL_FROM - 1 and the base
    station) kicks its failed trials' starts by default; one of a cluster fewer does not."""
    problem = price(generate_instance(k, 2, seed=3, zeta=10.0, area=4000.0), 0.5)
    search = _Search(problem, LnsSettings(effort="budget"), np.random.default_rng(0))
    assert search.kicks == kicks

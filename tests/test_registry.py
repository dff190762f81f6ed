"""Registry and harness: unknown names, plug-in solvers (registered, or by entry point), and the
checks on what solvers claim."""

from __future__ import annotations

import dataclasses
import itertools
import re
from pathlib import Path

import numpy as np
import pytest

from gtsp_bench.energy import evaluate
from gtsp_bench.errors import InputError, SolverError
from gtsp_bench.registry import (
    Solution,
    get_solver,
    handles_asymmetric,
    register_solver,
    run_solver,
    solver_names,
)

from .conftest import OPTIONAL_PACKAGE
from .tiny_cases import not_below, tiny_asymmetric_case


class Fixed:
    """A test solver that returns whatever it was built with."""

    def __init__(self, order=(0, 1), heads=(0, 1), objective=None, status="feasible",
                 lower_bound=None):
        self.args = (order, heads, objective, status, lower_bound)

    def solve(self, instance, omega, *, time_limit=None, seed=0):
        order, heads, objective, status, lower_bound = self.args
        if objective is None:
            from gtsp_bench.energy import evaluate

            objective = evaluate(instance, omega, order, heads).objective
        return Solution(order, heads, objective, status, lower_bound)


def test_builtin_solvers_are_registered():
    """greedy and brute are there."""
    assert {"greedy", "brute"} <= set(solver_names())


def test_unknown_solver_lists_valid_names():
    """The error names the valid solvers."""
    with pytest.raises(InputError, match=r"unknown solver 'nope' \(valid: .*brute.*greedy"):
        get_solver("nope")


def test_unknown_option_lists_valid_options():
    """An option the solver does not take is rejected with the ones it does take."""
    with pytest.raises(InputError, match=r"solver 'brute' has no option 'ants' \(options: max_tours\)"):
        get_solver("brute", ants=3)


def test_a_user_solver_plugs_in_with_one_registration(tiny):
    """register_solver makes a class usable by name; its result is re-priced."""
    register_solver("test-fixed", Fixed, "fixed tour for tests", replace=True)
    assert "test-fixed" in solver_names()
    result = run_solver("test-fixed", tiny, 0.5)
    assert result.solver == "test-fixed"
    assert result.order == (0, 1) and result.heads == (0, 1)
    assert result.energy is not None and result.energy.total == result.objective
    assert result.runtime_s >= 0


def test_registering_a_taken_name_is_an_error():
    """A second, different class under a taken name needs replace=True."""
    with pytest.raises(ValueError, match="already registered"):
        register_solver("greedy", Fixed, "clash")


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"objective": 1.0}, "claims objective 1.0 but the evaluator finds"),
        ({"order": (0, 0), "objective": 1.0}, "infeasible solution: cluster 0 is visited 2 times"),
        ({"heads": (0, 5), "objective": 1.0}, r"infeasible solution: heads\[1\] = 5"),
        ({"status": "great"}, "unknown status 'great'"),
        ({"status": "failed"}, "failed on tiny"),
        ({"lower_bound": 1e9}, "lower bound 1000000000.0 above its objective"),
        ({"objective": float("nan")}, "claims objective nan"),
    ],
)
def test_harness_rejects_what_the_evaluator_does_not_confirm(tiny, kwargs, message):
    """A wrong claim, an infeasible tour, an unknown status or a bad bound is a SolverError."""
    with pytest.raises(SolverError, match=message):
        run_solver(Fixed(**kwargs), tiny, 0.5)


def test_harness_checks_omega_and_time_limit(tiny):
    """Bad omega, time limit or seed are input errors raised before solving."""
    with pytest.raises(InputError, match="omega"):
        run_solver(Fixed(), tiny, 2.0)
    with pytest.raises(InputError, match="time limit must be > 0"):
        run_solver(Fixed(), tiny, 0.5, time_limit=-1)
    for seed in (-1, 1.5, True):
        with pytest.raises(InputError, match="seed must be an integer >= 0"):
            run_solver(Fixed(), tiny, 0.5, seed=seed)


class Capped(Fixed):
    """A test solver that declares ``capped`` and records the time limit it was given."""

    capped = True

    def solve(self, instance, omega, *, time_limit=None, seed=0):
        self.given = time_limit
        return super().solve(instance, omega, time_limit=time_limit, seed=seed)


def test_the_default_time_limit_is_given_in_one_place(tiny):
    """run_solver gives a solver that declares ``capped`` the default time limit when none is
    given, a given one unchanged; a solver without the declaration gets ``None``; lns and the
    peers that search until a limit declare it."""
    from gtsp_bench.checks import default_time_limit
    from gtsp_bench.solver import is_capped

    capped = Capped()
    run_solver(capped, tiny, 0.5)
    assert capped.given == default_time_limit(tiny.n_clusters)
    run_solver(capped, tiny, 0.5, time_limit=3)
    assert capped.given == 3
    assert is_capped(Capped) and not is_capped(Fixed)
    assert is_capped(get_solver("lns")) and not is_capped(get_solver("dp"))


def test_allowed_threads_follow_the_limit_the_cores_and_the_environment():
    """At most the limit and the cores; a benchmark worker's variable, else OMP_NUM_THREADS,
    caps it; a setting that is not a number is ignored; never below 1."""
    from gtsp_bench.solver import SOLVE_THREADS_VAR, allowed_threads

    assert allowed_threads(2, {}, cores=16) == 2
    assert allowed_threads(4, {}, cores=3) == 3
    assert allowed_threads(0, {}, cores=3) == 1
    assert allowed_threads(8, {SOLVE_THREADS_VAR: "2", "OMP_NUM_THREADS": "1"}, cores=8) == 2
    assert allowed_threads(8, {"OMP_NUM_THREADS": "3"}, cores=8) == 3
    assert allowed_threads(8, {SOLVE_THREADS_VAR: "all", "OMP_NUM_THREADS": "0"}, cores=8) == 8


def test_result_json_shape(tiny):
    """to_dict has exactly the CLI's keys."""
    d = run_solver(Fixed(), tiny, 0.5).to_dict()
    assert list(d) == ["instance", "solver", "omega", "order", "heads", "objective", "energy",
                       "distance", "status", "lower_bound", "runtime_s", "trajectory", "stats"]
    assert list(d["energy"]) == ["total", "ground", "flight", "hover"]


def test_result_json_carries_the_solvers_stats_in_json_types(tiny):
    """A solver's stats reach ``to_dict`` as plain JSON: numpy numbers as numbers, arrays and
    tuples as lists, a float that is not finite as null, anything else as its text."""
    import json

    class WithStats(Fixed):
        def solve(self, instance, omega, *, time_limit=None, seed=0):
            sol = super().solve(instance, omega, time_limit=time_limit, seed=seed)
            stats = {"n": np.int64(3), "x": np.float32(0.5), "gap": float("inf"), "path": Path("a"),
                     "trace": [{"t": np.float64(1.5), "v": (1, 2)}], 7: np.arange(2)}
            return dataclasses.replace(sol, stats=stats)

    d = run_solver(WithStats(), tiny, 0.5).to_dict()
    assert json.loads(json.dumps(d, allow_nan=False))["stats"] == {
        "n": 3, "x": 0.5, "gap": None, "path": "a", "trace": [{"t": 1.5, "v": [1, 2]}], "7": [0, 1]}


def test_bench_flag():
    """Test oracles are registered with bench=False so the runner skips them by default."""
    from gtsp_bench.registry import solver_specs

    flags = {s.name: s.bench for s in solver_specs()}
    assert flags["brute"] is False and flags["greedy"] is True


def test_import_path_for_worker_processes():
    """A string target is its own path; a module-level class gets module:Class; a class that only
    exists in this process (defined in a function, or in __main__) has none."""
    from gtsp_bench.registry import SolverSpec

    target = "gtsp_bench.solvers.heuristics.greedy:Greedy"
    assert SolverSpec("g", target, "").import_path() == target
    assert SolverSpec("f", Fixed, "").import_path() == "tests.test_registry:Fixed"

    class Local(Fixed):
        pass

    assert SolverSpec("l", Local, "").import_path() is None
    Local.__module__, Local.__qualname__ = "__main__", "Local"
    assert SolverSpec("m", Local, "").import_path() is None
    Local.__module__ = "builtins"  # what exec() gives a class; builtins has no Local
    assert SolverSpec("e", Local, "").import_path() is None


def test_solver_revision_is_the_learned_checkpoints_hash():
    """drl's revision is a hash of its shipped weights; a solver without one has ""."""
    import hashlib

    from gtsp_bench.solvers.learned.checkpoint import CHECKPOINT_DIR

    from gtsp_bench.registry import solver_revision

    digest = hashlib.sha256((CHECKPOINT_DIR / "drl.pt").read_bytes()).hexdigest()[:12]
    assert solver_revision("drl") == solver_revision("drl-sample") == digest
    assert solver_revision("am") != digest and solver_revision("greedy") == ""
    with pytest.raises(InputError, match="unknown solver"):
        solver_revision("nope")


# ---------------------------------------------------------------------- entry-point plug-ins
def _plugins(monkeypatch, *eps: tuple[str, str]) -> None:
    """Reload the registry as if the installed packages declared these entry points."""
    from importlib.metadata import EntryPoint

    from gtsp_bench import registry

    def entry_points(group: str) -> list[EntryPoint]:
        assert group == registry.ENTRY_POINT_GROUP == "gtsp_bench.solvers"
        return [EntryPoint(name, value, group) for name, value in eps]

    monkeypatch.setattr(registry, "entry_points", entry_points)
    monkeypatch.setattr(registry, "_builtins_loaded", False)
    registry._REGISTRY.clear()  # conftest restores it after the test


def test_plugin_is_described_by_its_docstring_and_solves(monkeypatch, tiny):
    """A plug-in is listed with its class docstring's first line and solves by name."""
    from gtsp_bench.registry import solver_specs

    _plugins(monkeypatch, ("t-plugin", "tests.test_registry:Fixed"))
    spec = next(s for s in solver_specs() if s.name == "t-plugin")
    assert spec.description == (
        "A test solver that returns whatever it was built with. (plug-in from tests.test_registry:Fixed)")
    assert spec.plugin == "tests.test_registry:Fixed"
    assert run_solver("t-plugin", tiny, 0.5).solver == "t-plugin"


def test_plugin_clash_and_broken_plugins_leave_the_others(monkeypatch, capsys, tmp_path):
    """A plug-in under a built-in's name is skipped with a warning; one whose module is missing,
    raises on import, or is not a solver class is left out of the listing with a warning, and
    asking for it by name is a clear InputError."""
    from gtsp_bench.registry import solver_specs

    (tmp_path / "t_raising_plugin.py").write_text("raise RuntimeError('boom')\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    _plugins(monkeypatch, ("greedy", "tests.test_registry:Fixed"), ("t-missing", "t_no_such_module:X"),
             ("t-raising", "t_raising_plugin:X"), ("t-function", "os.path:join"),
             ("t-noattr", "tests.test_registry:Nope"), ("t-good", "tests.test_registry:Fixed"))
    assert {"t-missing", "t-raising", "t-function", "t-good"} <= set(solver_names())  # nothing imported
    err = capsys.readouterr().err
    assert "solver 'greedy' from entry point 'tests.test_registry:Fixed' is already registered" in err
    specs = {s.name: s for s in solver_specs()}
    err = capsys.readouterr().err
    assert "t-good" in specs and "greedy" in specs and specs["greedy"].plugin is None
    assert not {"t-missing", "t-raising", "t-function", "t-noattr"} & set(specs)
    assert "warning: solver 't-missing' is not available: No module named 't_no_such_module'; skipped" in err
    assert ("warning: solver 't-raising' (plug-in t_raising_plugin:X) cannot be loaded: "
            "RuntimeError: boom; skipped") in err
    assert "warning: solver 't-function': os.path:join is not a solver class" in err
    assert "warning: solver 't-noattr': module 'tests.test_registry' has no 'Nope'" in err


def test_broken_plugin_by_name_is_an_input_error(monkeypatch):
    """Used by name (without listing first), a broken plug-in is one clean InputError."""
    _plugins(monkeypatch, ("t-raising", "t_raising_plugin_absent:X"))
    with pytest.raises(InputError, match="solver 't-raising' is not available"):
        get_solver("t-raising")
    assert "greedy" in solver_names()


# ---------------------------------------------------------------------- asymmetric costs
#: The built-in solvers that declare ``asymmetric = True``.
ASYMMETRIC_SOLVERS = {"brute", "dp", "greedy", "greedy+ils", "aco", "lns", "pyvrp", "ortools", "lkh"}
REFUSAL = "handles symmetric costs only (this instance is asymmetric)"


def test_which_builtins_handle_asymmetric_costs():
    """Exactly the solvers that price tours in their direction declare it; the claim is read from
    the class itself, so greedy+ls and aco+ls (subclasses adding a 2-opt local search) do not
    inherit it from greedy and aco."""
    from gtsp_bench.solvers import BUILTIN

    declared = {b.name for b in BUILTIN if handles_asymmetric(get_spec_class(b.name))}
    assert declared == ASYMMETRIC_SOLVERS

    class Child(Fixed):
        pass

    Fixed.asymmetric = True
    try:
        assert handles_asymmetric(Fixed) and handles_asymmetric(Fixed())
        assert not handles_asymmetric(Child)
    finally:
        del Fixed.asymmetric


def get_spec_class(name):
    """The class of a registered solver (imported, not instantiated)."""
    from gtsp_bench.registry import _registry

    return _registry()[name].load()


@pytest.mark.parametrize("name", ["milp", "gurobi", "greedy+ls", "aco+ls", "drl", "am"])
def test_symmetric_only_solvers_refuse_asymmetric_instances(name):
    """One InputError line naming the solver, before it runs (the CLI adds the file)."""
    inst, _ = tiny_asymmetric_case(0)
    with pytest.raises(InputError) as err:
        run_solver(name, inst, None)
    assert str(err.value) == f"{name} {REFUSAL}"


def test_a_plugin_without_the_declaration_is_refused():
    """A solver object without ``asymmetric = True`` is refused; with it, it runs."""
    inst, _ = tiny_asymmetric_case(1)
    k = inst.n_clusters
    with pytest.raises(InputError, match=f"^Fixed {re.escape(REFUSAL)}$"):
        run_solver(Fixed(tuple(range(k)), (0,) * k), inst, None)

    class Directed(Fixed):
        asymmetric = True

    r = run_solver(Directed(tuple(range(k)), (0,) * k), inst, None)
    w = inst.weights
    assert r.objective == pytest.approx(sum(w[inst.offsets[i], inst.offsets[(i + 1) % k]] for i in range(k)))


@pytest.mark.parametrize("seed", range(10))
def test_exact_solvers_agree_with_brute_on_asymmetric_instances(seed):
    """dp proves brute's optimum; the reverse of the optimal tour costs something else."""
    inst, best = tiny_asymmetric_case(seed)
    r = run_solver("dp", inst, None)
    assert r.status == "optimal" and r.objective == pytest.approx(best, rel=1e-12)
    if inst.n_clusters >= 3:
        back = evaluate(inst, None, r.order[::-1], r.heads).objective
        assert back != pytest.approx(best, rel=1e-9)


@pytest.mark.parametrize("seed", range(6))
def test_greedy_follows_outgoing_arcs(seed):
    """Each greedy step takes the cheapest arc *leaving* the current node for an unvisited
    cluster (row = from), starting from a node of the smallest cluster."""
    inst, best = tiny_asymmetric_case(seed)
    r = run_solver("greedy", inst, None)
    assert not_below(r.objective, best)
    tour = [int(inst.offsets[c] + r.heads[c]) for c in r.order]
    smallest = int(np.argmin(inst.sizes))
    start = next(i for i, v in enumerate(tour) if inst.cluster_of[v] == smallest)
    tour = tour[start:] + tour[:start]
    w = inst.weights
    for a, b in itertools.pairwise(tour):
        seen = {int(inst.cluster_of[v]) for v in tour[:tour.index(b)]}
        allowed = [v for v in range(inst.n_nodes) if int(inst.cluster_of[v]) not in seen]
        assert w[a, b] == min(w[a, v] for v in allowed)


def test_aco_on_asymmetric_instances():
    """aco's claims are confirmed by the evaluator (run_solver re-prices them) and never below the
    optimum; on these tiny instances its directed colony finds the optimum of at least half, and
    of more than greedy does."""
    found = {"aco": 0, "greedy": 0}
    for seed in range(8):
        inst, best = tiny_asymmetric_case(seed)
        for name in found:
            r = run_solver(name, inst, None, seed=seed)
            assert not_below(r.objective, best)
            found[name] += r.objective == pytest.approx(best, rel=1e-12)
    assert found["aco"] >= 4 and found["aco"] > found["greedy"]


@pytest.mark.parametrize(("name", "options"), [
    ("pyvrp", {"no_improvement": 500}),
    ("ortools", {"solution_limit": 200}),
    ("lkh", {"runs": 5}),
])
@pytest.mark.parametrize("seed", range(4))
def test_peers_find_brutes_optimum_on_asymmetric_instances(name, options, seed):
    """The peers take the directed matrix as it is (PyVRP's and OR-Tools' arc matrices are row =
    from; LKH gets the Noon-Bean ATSP): on tiny instances they find brute's optimum."""
    if name in OPTIONAL_PACKAGE:  # ortools is a core dependency: never skipped
        pytest.importorskip(OPTIONAL_PACKAGE[name])
    inst, best = tiny_asymmetric_case(seed)
    r = run_solver(get_solver(name, **options), inst, None, time_limit=10.0, seed=seed)
    assert r.objective == pytest.approx(best, rel=1e-12)


# ---------------------------------------------------------------------- trajectories
class Reporting(Fixed):
    """A test solver that reports a scripted list of (objective, lower bound) calls."""

    def __init__(self, calls, **kwargs):
        super().__init__(**kwargs)
        self.calls = calls

    def solve(self, instance, omega, *, time_limit=None, seed=0, progress=None):
        for objective, bound in self.calls:
            progress(objective, bound)
        return super().solve(instance, omega, time_limit=time_limit, seed=seed)


class WarmStarted(Fixed):
    """A test solver that returns its warm start as it got it."""

    def solve(self, instance, omega, *, time_limit=None, seed=0, initial=None):
        self.got = initial
        return initial


def test_a_solver_that_reports_nothing_gets_its_answer_as_one_point(tiny):
    """A solver without ``progress`` in its signature is not given one; its trajectory is its
    answer, at the solve's runtime."""
    r = run_solver(Fixed(lower_bound=1.0), tiny, 0.5)
    assert len(r.trajectory) == 1
    point = r.trajectory[0]
    assert (point.time_s, point.objective, point.lower_bound) == (r.runtime_s, r.objective, 1.0)
    assert r.to_dict()["trajectory"] == [{"time_s": r.runtime_s, "objective": r.objective,
                                          "lower_bound": 1.0}]


def test_trajectory_keeps_improvements_only_and_ends_at_the_answer(tiny):
    """Reports that improve neither the objective nor the bound are dropped; objectives never
    rise, bounds never fall, times never fall; the answer is appended when the solver did not
    report it, and the listener sees every point as it is recorded."""
    answer = evaluate(tiny, 0.5, (0, 1), (0, 1)).objective
    calls = [(answer + 50, None), (answer + 60, 1.0), (None, 5.0), (None, 2.0), (answer + 10, None),
             (answer + 10, None), (answer + 20, 7.0)]
    seen = []
    r = run_solver(Reporting(calls, lower_bound=3.0), tiny, 0.5, on_progress=seen.append)
    got = [(p.objective, p.lower_bound) for p in r.trajectory]
    assert got == [(answer + 50, None), (answer + 50, 1.0), (answer + 50, 5.0),
                   (answer + 10, 5.0), (answer + 10, 7.0), (answer, 7.0)]
    times = [p.time_s for p in r.trajectory]
    assert times == sorted(times) and times[-1] == r.runtime_s
    assert seen == list(r.trajectory)


def test_the_answer_is_not_repeated_when_the_solver_reported_it(tiny):
    """A solver that reported its answer (within rounding) gets no extra point, and the last
    point is the evaluator's number exactly."""
    answer = evaluate(tiny, 0.5, (0, 1), (0, 1)).objective
    r = run_solver(Reporting([(answer + 1, None), (answer * (1 - 1e-12), None)]), tiny, 0.5)
    assert [p.objective for p in r.trajectory] == [answer + 1, answer]
    assert r.trajectory[-1].objective == r.objective


@pytest.mark.parametrize(("calls", "message"), [
    ([(1.0, None)], "reported objective 1.0 below its answer's"),
    ([(None, 1e9)], "reported lower bound 1000000000.0 above its answer's"),
    ([(float("nan"), None)], "reported objective nan, not a finite number"),
    ([(None, "x")], "reported lower bound 'x', not a finite number"),
])
def test_a_trajectory_the_answer_contradicts_is_a_solver_error(tiny, calls, message):
    """An objective reported below the answer, a bound above it or a non-number is a
    SolverError after the solve (the callback itself never raises into the solver)."""
    with pytest.raises(SolverError, match=message):
        run_solver(Reporting(calls), tiny, 0.5)


def test_trajectory_point_gap_and_keywords():
    """A point's gap is relative to its objective (None without a bound); takes_keyword reads
    the declared keywords of solve, not a bare **kwargs."""
    from gtsp_bench.solver import TrajectoryPoint, takes_keyword

    assert TrajectoryPoint(1.0, 200.0, 150.0).gap == pytest.approx(0.25)
    assert TrajectoryPoint(1.0, 200.0).gap is None

    class Kwargs:
        def solve(self, instance, omega, **rest):
            pass

    assert takes_keyword(Reporting([]), "progress") and not takes_keyword(Fixed(), "progress")
    assert takes_keyword(WarmStarted, "initial") and not takes_keyword(Kwargs(), "initial")


# ---------------------------------------------------------------------- warm starts
def test_warm_start_is_checked_and_priced_before_the_solve(tiny):
    """The solver gets a Solution priced by the evaluator, with the caller's bound; (order,
    heads), a Solution and a Result are all accepted."""
    solver = WarmStarted()
    objective = evaluate(tiny, 0.5, (1, 0), (0, 0)).objective
    r = run_solver(solver, tiny, 0.5, initial=((1, 0), (0, 0)))
    assert solver.got == Solution((1, 0), (0, 0), objective, "feasible", None)
    assert (r.order, r.heads, r.objective) == ((1, 0), (0, 0), objective)
    run_solver(solver, tiny, 0.5, initial=Solution((1, 0), (0, 0), 0.0, lower_bound=1.0))
    assert solver.got.objective == objective and solver.got.lower_bound == 1.0
    run_solver(solver, tiny, 0.5, initial=r)
    assert solver.got.order == (1, 0)


@pytest.mark.parametrize(("initial", "message"), [
    (((0, 0), (0, 0)), "infeasible initial solution: cluster 0 is visited 2 times"),
    (((0, 1), (0, 7)), r"infeasible initial solution: heads\[1\] = 7"),
    (Solution((0, 1), (0, 0), 0.0, lower_bound=1e9), "lower bound 1000000000.0 is above its objective"),
    ("tour", "an initial solution is a Solution, a Result or"),
])
def test_a_bad_warm_start_is_one_input_error(tiny, initial, message):
    """An infeasible warm start, a bound above its objective or another type: one InputError
    line, before the solver runs."""
    solver = WarmStarted()
    with pytest.raises(InputError, match=message):
        run_solver(solver, tiny, 0.5, initial=initial)
    assert not hasattr(solver, "got")


def test_a_solver_without_initial_refuses_a_warm_start(tiny):
    """A solver whose solve does not declare ``initial`` refuses a warm start in one line."""
    with pytest.raises(InputError, match=r"^solver 'greedy' cannot start from an initial solution$"):
        run_solver("greedy", tiny, 0.5, initial=((0, 1), (0, 0)))


# ---------------------------------------------------------------------- seeds
#: Options that let each solver end by its own criterion on a small instance, not by the clock.
_OWN_END = {"aco": {"iterations": 20}, "aco+ls": {"iterations": 20}, "lns": {"stop_at_convergence": True},
            "ortools": {"solution_limit": 100}, "pyvrp": {"no_improvement": 300}}


def _builtin_names() -> list[str]:
    """The built-in solvers (test solvers that other test modules register are not among them)."""
    from gtsp_bench.solvers import BUILTIN

    return sorted(b.name for b in BUILTIN)


@pytest.mark.parametrize("name", _builtin_names())
def test_every_solver_repeats_its_tour_for_a_seed(name):
    """Run twice with the same seed, ended by its own criterion (not the time limit), every
    registered solver returns the same tour; an optional one whose package is not installed is
    skipped (any other error at construction fails the test)."""
    from gtsp_bench.generator import generate_instance

    if name in OPTIONAL_PACKAGE:
        pytest.importorskip(OPTIONAL_PACKAGE[name])
    # K = 5 clusters of 20 nodes (the drl policy's size); brute gets 4 nodes a cluster
    inst = generate_instance(5, 4 if name == "brute" else 20, seed=11)
    solver = get_solver(name, **_OWN_END.get(name, {}))
    runs = [run_solver(solver, inst, 0.4, time_limit=120.0, seed=3) for _ in range(2)]
    assert all(r.status != "time_limit" for r in runs)
    assert (runs[0].order, runs[0].heads) == (runs[1].order, runs[1].heads)

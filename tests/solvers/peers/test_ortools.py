"""The OR-Tools peer: optima on tiny instances, GTSPLIB, time limit, options, refusals, CLI."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from gtsp_bench.solvers.peers import ortools as peer

from gtsp_bench.checks import MAX_COORD
from gtsp_bench.cli import main
from gtsp_bench.data import gtsplib
from gtsp_bench.data.io import read_instance, write_instance
from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance
from gtsp_bench.instance import Instance
from gtsp_bench.registry import get_solver, run_solver
from tests.tiny_cases import not_below, tiny_case

#: Stops guided local search after a fixed number of solutions: fast and reproducible.
FAST = {"solution_limit": 150}


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("depot", [True, False])
def test_reaches_the_brute_force_optimum(seed, depot):
    """On tiny instances (with and without a depot) the tour is the optimum, never below it."""
    inst, omega, optimum = tiny_case(seed, depot)
    r = run_solver(get_solver("ortools", **FAST), inst, omega, seed=seed, time_limit=30)
    assert r.status == "feasible"
    assert not_below(r.objective, optimum)
    assert r.objective == pytest.approx(optimum, rel=1e-6)


@pytest.mark.parametrize("omega", [0.0, 0.3, 0.7, 1.0])
def test_optimum_for_several_omegas(omega):
    """Node and edge costs are both folded in: the optimum for every weighting."""
    inst = generate_instance(5, 3, seed=11)
    optimum = run_solver("brute", inst, omega).objective
    r = run_solver(get_solver("ortools", **FAST), inst, omega, time_limit=30)
    assert not_below(r.objective, optimum)
    assert r.objective == pytest.approx(optimum, rel=1e-6)


def test_uav_instance_k7():
    """A generated K = 7 instance: a valid tour whose objective is exactly re-priced, and at least
    as good as what the shared local search makes of the greedy tour."""
    inst = generate_instance(7, 6, seed=2)
    r = run_solver(get_solver("ortools", **FAST), inst, 0.5, time_limit=30)
    assert sorted(r.order) == list(range(7))
    assert all(0 <= h < 6 for h in r.heads)
    assert r.objective >= run_solver("dp", inst, 0.5).objective - 1e-6
    assert r.objective <= run_solver("greedy+ls", inst, 0.5).objective + 1e-6


def test_gtsplib_file():
    """11berlin52 (proven optimum 4040): a valid tour, never below the optimum; within 2 s guided
    local search reaches it (the first local optimum already does on this file)."""
    inst = gtsplib.read("11berlin52")
    r = run_solver("ortools", inst, None, time_limit=2.0)
    assert sorted(r.order) == list(range(11))
    assert r.status == "time_limit"  # guided local search runs until the limit
    assert r.stats["runs"] == 1 and r.stats["scale"] == 1.0
    assert r.objective == 4040


def test_no_depot_runs_once_per_node_of_the_smallest_cluster():
    """Without a depot and no one-node cluster, each node of the smallest cluster is tried."""
    base = generate_instance(4, 3, seed=4)
    inst = Instance(name="nd", clusters=base.clusters)
    r = run_solver(get_solver("ortools", **FAST), inst, 0.5, time_limit=30)
    assert r.stats["runs"] == 3
    assert r.objective == pytest.approx(run_solver("brute", inst, 0.5).objective, rel=1e-6)


def test_single_cluster_without_depot():
    """One cluster and no depot: the cheapest node alone."""
    inst = Instance(name="one", clusters=generate_instance(1, 5, seed=0).clusters)
    r = run_solver("ortools", inst, 0.5, time_limit=0.1)
    assert r.objective == pytest.approx(run_solver("brute", inst, 0.5).objective, rel=1e-12)


def test_short_time_limit_is_respected():
    """Guided local search stops at the limit with a tour and status time_limit (a generous
    bound on the wall time: the machine may be loaded)."""
    r = run_solver("ortools", generate_instance(20, 5, seed=0), 0.5, time_limit=0.2)
    assert r.status == "time_limit"
    assert sorted(r.order) == list(range(20))
    assert r.runtime_s < 10


def test_solution_limit_reproduces_the_run():
    """A run stopped by solution_limit is the same run twice."""
    inst = generate_instance(12, 5, seed=1)
    a = run_solver(get_solver("ortools", **FAST), inst, 0.5, seed=2, time_limit=60)
    b = run_solver(get_solver("ortools", **FAST), inst, 0.5, seed=2, time_limit=60)
    assert a.status == b.status == "feasible"
    assert (a.order, a.heads, a.stats["solutions"]) == (b.order, b.heads, b.stats["solutions"])


@pytest.mark.parametrize("first_solution", peer.FIRST_SOLUTIONS)
def test_every_offered_first_solution_strategy_builds_a_tour(first_solution):
    """Each offered strategy exists in the installed OR-Tools and builds a tour of this model
    (greedy descent to its local optimum: a tenth of a second)."""
    solver = get_solver("ortools", first_solution=first_solution, metaheuristic="GREEDY_DESCENT")
    inst = generate_instance(6, 4, seed=3)
    r = run_solver(solver, inst, 0.5, time_limit=30)
    assert sorted(r.order) == list(range(6)) and r.status == "feasible"
    assert not_below(r.objective, run_solver("brute", inst, 0.5).objective)


@pytest.mark.parametrize("metaheuristic", peer.METAHEURISTICS)
def test_every_offered_metaheuristic_runs(metaheuristic):
    """Each offered metaheuristic exists in the installed OR-Tools and returns a tour."""
    solver = get_solver("ortools", metaheuristic=metaheuristic, solution_limit=20)
    inst = generate_instance(5, 3, seed=3)
    r = run_solver(solver, inst, 0.5, time_limit=0.3)
    assert sorted(r.order) == list(range(5))
    assert not_below(r.objective, run_solver("brute", inst, 0.5).objective)


@pytest.mark.parametrize(("options", "message"), [
    ({"first_solution": "CHEAPEST"}, "first_solution must be one of 'AUTOMATIC', 'PATH_CHEAPEST_ARC'"),
    ({"first_solution": "SWEEP"}, "first_solution must be one of"),
    ({"metaheuristic": "ANNEALING"}, "metaheuristic must be one of 'GUIDED_LOCAL_SEARCH'"),
    ({"resolution": 0.0}, "resolution must be a number in"),
    ({"solution_limit": 0}, "solution_limit must be an integer >= 1"),
    ({"solution_limit": True}, "solution_limit must be an integer >= 1"),
])
def test_bad_options_are_one_line_input_errors(options, message):
    """Invalid options raise one InputError line naming the option and the valid values."""
    with pytest.raises(InputError, match=message) as e:
        get_solver("ortools", **options)
    assert "\n" not in str(e.value)


def test_far_apart_instance_within_the_loader_limits_is_solved(tmp_path):
    """Coordinates at the loader's limit: whole-number distances up to ~2.8e9, used unscaled, far
    inside the int64 bound of a tour; the tour is exact."""
    far = Instance(name="far", clusters=(
        np.array([[-MAX_COORD, -MAX_COORD], [-MAX_COORD, MAX_COORD]]),
        np.array([[MAX_COORD, MAX_COORD]]), np.array([[MAX_COORD, -MAX_COORD], [0.0, 0.0]]),
    ), params=None, edge_weight_type="EUC_2D")
    inst = read_instance(write_instance(far, tmp_path / "far.gtsp"))
    r = run_solver(get_solver("ortools", **FAST), inst, None, time_limit=30)
    assert r.stats["scale"] == 1.0
    assert r.objective == run_solver("brute", inst, None).objective


def test_costs_that_cannot_be_scaled_are_refused_with_one_line(tmp_path, capsys, monkeypatch):
    """Costs whose scaling would overflow the int64 sums, or lose the order of tours (a subnormal
    largest cost, accepted by the loader), or that are not finite: one line, never a wrong tour."""
    from gtsp_bench.solvers.peers import scaling

    inst = generate_instance(3, 2, seed=0)
    monkeypatch.setattr(scaling, "MAX_TOUR_UNITS", 10)  # out of reach otherwise (scaling.py)
    with pytest.raises(InputError, match="would overflow OR-Tools' 64-bit sums") as e:
        run_solver("ortools", inst, 0.5)
    assert "\n" not in str(e.value)
    monkeypatch.undo()
    tiny = Instance(name="tiny", clusters=tuple(np.array([[float(i), 0.0]]) for i in range(3)),
                    params=None, edge_weight_type="EXPLICIT",
                    weights=np.where(np.eye(3) > 0, 0.0, 1e-320))
    path = write_instance(tiny, tmp_path / "tiny.gtsp")
    assert main(["solve", str(path), "--solver", "ortools", "--json"]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err.count("\n") == 1 and "too small to scale to integers" in err
    far = Instance(name="far", clusters=(np.array([[0.0, 0.0]]), np.array([[1e308, -1e308]])),
                   params=None, edge_weight_type="EUC_2D")  # built directly: a file is refused
    with np.errstate(over="ignore"), pytest.raises(InputError, match="not finite numbers"):
        get_solver("ortools").solve(far, None, time_limit=1.0)


def test_cli_solve_json(tmp_path, capsys):
    """gtsp-bench solve FILE --solver ortools --json prints one JSON object of a valid tour."""
    path = tmp_path / "k5.json"
    assert main(["generate", "--clusters", "5", "--nodes", "3", "--seed", "1", "-o", str(path)]) == 0
    capsys.readouterr()
    code = main(["solve", str(path), "--solver", "ortools", "--omega", "0.4", "--time-limit", "0.3",
                 "-p", "first_solution=CHRISTOFIDES", "--json"])
    out, _ = capsys.readouterr()
    assert code == 0
    data = json.loads(out)
    assert data["solver"] == "ortools" and data["status"] == "time_limit"
    assert sorted(data["order"]) == list(range(5))
    best = run_solver("brute", read_instance(path), 0.4).objective
    assert not_below(data["objective"], best)


def test_ortools_is_not_imported_by_the_registry_or_a_listing():
    """Listing the solvers and making the solver (options checked) leave OR-Tools unimported
    (a solve imports it in its worker process only: see the highspy test)."""
    code = ("import sys\n"
            "from gtsp_bench.registry import get_solver, solver_specs\n"
            "from gtsp_bench.cli import main\n"
            "solver_specs(); get_solver('ortools', first_solution='SAVINGS')\n"
            "main(['solvers'])\n"
            "assert not [m for m in sys.modules if m.startswith('ortools')], 'ortools imported'\n"
            "assert 'highspy' not in sys.modules\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr


def test_shares_a_process_with_highspy_either_way():
    """OR-Tools and highspy bundle clashing libhighs.so.1 builds, so OR-Tools runs in a worker
    process: ortools, then milp (highspy), then ortools again solve in one process, and OR-Tools
    is never loaded into it."""
    pytest.importorskip("highspy")
    code = ("import sys\n"
            "from gtsp_bench.generator import generate_instance\n"
            "from gtsp_bench.registry import run_solver\n"
            "inst = generate_instance(4, 3, seed=0)\n"
            "print([run_solver(s, inst, 0.5, time_limit=0.2).objective\n"
            "       for s in ('ortools', 'milp', 'ortools')])\n"
            "assert 'highspy' in sys.modules\n"
            "assert not [m for m in sys.modules if m.startswith('ortools')]\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    a, b, c = json.loads(proc.stdout)
    assert a == pytest.approx(b, rel=1e-6) and c == a


def test_a_lost_worker_is_an_error_then_replaced():
    """A worker killed between solves: the next solve starts a fresh one."""
    inst = generate_instance(4, 3, seed=5)
    first = run_solver(get_solver("ortools", **FAST), inst, 0.5, time_limit=30)
    worker = peer._WORKER
    worker.proc.kill()
    worker.proc.wait()
    again = run_solver(get_solver("ortools", **FAST), inst, 0.5, time_limit=30)
    assert peer._WORKER is not worker and peer._WORKER.proc.poll() is None
    assert (again.order, again.heads) == (first.order, first.heads)


def test_ortools_reports_solutions_and_takes_a_warm_start():
    """OR-Tools' solution callback reports each better tour (priced exactly, in order), and a
    warm start read from its route is its first solution: the first report is no worse."""
    inst = generate_instance(15, 8, seed=4)
    r = run_solver(get_solver("ortools", **FAST), inst, 0.5, time_limit=30.0, seed=0)
    objectives = [p.objective for p in r.trajectory]
    assert len(objectives) >= 2 and objectives == sorted(objectives, reverse=True)
    assert objectives[-1] == r.objective
    first = run_solver("greedy", inst, 0.5)
    warm = run_solver(get_solver("ortools", **FAST), inst, 0.5, time_limit=30.0, initial=first)
    assert warm.trajectory[0].objective <= first.objective + 1e-9
    assert warm.objective <= first.objective + 1e-9 and warm.stats["warm_start"] is True


def test_ortools_warm_start_without_a_depot():
    """On a GTSPLIB file (no depot) the warm start goes to the run from its node of the
    smallest cluster: the answer is no worse than the warm start."""
    inst = gtsplib.read("11berlin52")
    first = run_solver("greedy", inst, None)
    warm = run_solver(get_solver("ortools", solution_limit=5), inst, None, time_limit=30.0,
                      initial=first)
    assert warm.objective <= first.objective

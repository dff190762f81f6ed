"""Backends: the model held in HiGHS (reduced costs, purged cuts), Gurobi's stop at no time left."""

from __future__ import annotations

import numpy as np
import pytest
from gtsp_bench.solvers.exact.mip.backends import GurobiBackend, HighsBackend, LpModel
from gtsp_bench.solvers.exact.mip.model import build_model, core_columns
from gtsp_bench.solvers.exact.mip.options import MipOptions, upper_bound_tour
from gtsp_bench.solvers.exact.mip.separation import separate

from gtsp_bench.generator import generate_instance
from gtsp_bench.problem import price


def _lp(backend_class, seed: int = 2) -> tuple[LpModel, float]:
    """A K = 6 model in a new backend, over a core that holds a tour's edges; the tour's cost."""
    problem = price(generate_instance(6, 4, seed=seed), 0.5)
    model = build_model(problem, problem.clusters)
    tour = upper_bound_tour(problem, 0, 0, None)  # its edges keep the core LP feasible
    return LpModel(model, backend_class(MipOptions()), core_columns(model, 3, tour)), problem.tour_cost(tour)


def test_reduced_costs_match_highs():
    """The reduced costs computed from row duals (used for pricing) equal HiGHS's own."""
    lp, _ = _lp(HighsBackend)
    model = lp.model
    for _ in range(4):  # a few rounds with cuts
        res = lp.backend.solve_lp(60.0)
        assert res.status == "optimal"
        ours = lp.reduced_costs(res.duals, lp.cols)
        np.testing.assert_allclose(ours, res.reduced_costs, atol=1e-7)
        cuts = separate(model, lp.full(res.values))
        if cuts is None:
            break
        lp.add_cuts(cuts)


def test_purge_keeps_the_backend_rows_in_step_with_the_cuts():
    """After purging slack cuts, HiGHS holds the base rows and exactly the cuts kept: its LP
    equals that of a new backend given those cuts."""
    lp, _ = _lp(HighsBackend, seed=3)
    model = lp.model
    purged = 0
    for _ in range(6):
        res = lp.backend.solve_lp(60.0)
        cuts = separate(model, lp.full(res.values))
        if cuts is None:
            break
        before = len(lp.cuts)
        lp.purge(lp.full(res.values), 1)
        purged += before - len(lp.cuts)
        lp.add_cuts(cuts)
    assert purged > 0
    assert lp.backend.h.getNumRow() == model.n_base_rows + len(lp.cuts)
    fresh = LpModel(model, HighsBackend(MipOptions()), lp.cols)
    fresh.add_cuts(lp.cuts)
    np.testing.assert_allclose(lp.backend.solve_lp(60.0).objective, fresh.backend.solve_lp(60.0).objective,
                               rtol=1e-9)


def test_a_copy_holds_the_same_lp_and_goes_its_own_way():
    """A tree worker's copy of the LP solves to the same optimum from the copied basis; cuts added
    to it take ids from its own range and leave the original's rows and ids as they were; copies
    solve at once on two threads to the optimum each has alone."""
    import threading

    lp, _ = _lp(HighsBackend, seed=3)
    model = lp.model
    res = lp.backend.solve_lp(60.0)
    lp.add_cuts(separate(model, lp.full(res.values)))
    first = lp.backend.solve_lp(60.0)
    twin = lp.copy(1000)
    again = twin.backend.solve_lp(60.0)
    assert again.objective == pytest.approx(first.objective, rel=1e-9)
    assert again.status == "optimal" and twin.backend.iterations == 0  # the basis was optimal
    rows, ids = lp.backend.h.getNumRow(), lp.cut_ids.copy()
    twin.add_cuts(separate(model, twin.full(again.values)))
    assert twin.cut_ids[len(ids):].tolist() == list(range(1000, 1000 + len(twin.cuts) - len(ids)))
    assert lp.backend.h.getNumRow() == rows and lp.cut_ids.tolist() == ids.tolist()
    alone = [lp.backend.solve_lp(60.0).objective, twin.backend.solve_lp(60.0).objective]
    both = [0.0, 0.0]
    for x in (lp, twin):  # both from no basis
        x.backend.h.clearSolver()
    runs = [threading.Thread(target=lambda j, x: both.__setitem__(j, x.backend.solve_lp(60.0).objective),
                             args=(j, x)) for j, x in enumerate((lp, twin))]
    for t in runs:
        t.start()
    for t in runs:
        t.join()
    assert both == pytest.approx(alone, rel=1e-9)
    lp.backend.absorb(twin.backend)
    assert lp.backend.iterations >= twin.backend.iterations > 0


def test_highs_backends_on_other_threads_share_a_process():
    """HiGHS keeps one task scheduler per process and fails a run whose thread count differs from
    it: backends on 2 threads (parallel dual simplex), then 1, then 2 again, each solve the same
    LP to the same optimum."""
    objectives = []
    for threads in (2, 1, 2):
        lp, _ = _lp(HighsBackend)
        lp.backend.use_threads(threads)
        res = lp.backend.solve_lp(60.0)
        assert res.status == "optimal"
        objectives.append(res.objective)
    assert objectives == pytest.approx([objectives[0]] * 3, rel=1e-9)


def test_highs_and_gurobi_agree_on_the_lp():
    """The same model and cuts in both backends: the same LP optimum."""
    pytest.importorskip("gurobipy")
    highs, _ = _lp(HighsBackend)
    gurobi, _ = _lp(GurobiBackend)
    for _ in range(3):
        res = highs.backend.solve_lp(60.0)
        other = gurobi.backend.solve_lp(60.0)
        assert res.status == other.status == "optimal"
        assert other.objective == pytest.approx(res.objective, rel=1e-7)
        cuts = separate(highs.model, highs.full(res.values))
        if cuts is None:
            break
        highs.add_cuts(cuts)
        gurobi.add_cuts(cuts)


def test_time_already_up_stops_instead_of_raising():
    """The solve passes the seconds left, which can be just below 0 by the time Gurobi is called:
    that is a stop (no answer), not a GurobiError about a negative TimeLimit."""
    pytest.importorskip("gurobipy")
    lp, tour_cost = _lp(GurobiBackend)
    assert lp.backend.solve_lp(-0.01).status == "stopped"
    res = lp.backend.solve_mip(-0.01, tour_cost, 1e-6, lambda v: None)
    assert res.values is None and not res.complete


def test_dropped_columns_leave_the_backend_and_the_lp_equals_them_fixed_to_zero():
    """Dropping columns (fixed or priced out) removes them from HiGHS and from ``cols``; the LP
    then equals the LP with those columns fixed to 0, and the reduced costs stay HiGHS's own."""
    lp, _ = _lp(HighsBackend, seed=4)
    model = lp.model
    for _ in range(3):
        res = lp.backend.solve_lp(60.0)
        cuts = separate(model, lp.full(res.values))
        if cuts is None:
            break
        lp.add_cuts(cuts)
    res = lp.backend.solve_lp(60.0)
    drop = np.flatnonzero((lp.cols >= model.n_nodes) & (res.values < 1e-9))[::2]
    assert len(drop) > 0
    gone = lp.cols[drop]
    fixed = LpModel(model, HighsBackend(MipOptions()), lp.cols)
    fixed.add_cuts(lp.cuts)
    fixed.fix_zero(drop)
    lp.drop_cols(drop)
    assert lp.backend.h.getNumCol() == len(lp.cols) and not np.isin(gone, lp.cols).any()
    after = lp.backend.solve_lp(60.0)
    np.testing.assert_allclose(after.objective, fixed.backend.solve_lp(60.0).objective, rtol=1e-9)
    np.testing.assert_allclose(lp.reduced_costs(after.duals, lp.cols), after.reduced_costs, atol=1e-7)


def test_a_stalled_run_restarts_and_reaches_the_same_optimum(monkeypatch):
    """With a stall limit of one iteration, each LP run stops and is solved from no basis by the
    interior point method: the same optimum as without the limit, one stall counted per solve,
    and HiGHS back on its own choice of method afterwards."""
    from gtsp_bench.solvers.exact.mip import backends

    plain, _ = _lp(HighsBackend, seed=4)
    stalled, _ = _lp(HighsBackend, seed=4)
    solves = 0
    for _ in range(3):
        solves += 1
        expected = plain.backend.solve_lp(60.0)
        with monkeypatch.context() as m:
            m.setattr(backends, "STALL_ITERATIONS", 1)
            m.setattr(backends, "STALL_PER_LINE", 0)
            res = stalled.backend.solve_lp(60.0)
        assert res.status == expected.status == "optimal"
        np.testing.assert_allclose(res.objective, expected.objective, rtol=1e-9)
        cuts = separate(plain.model, plain.full(expected.values))
        if cuts is None:
            break
        plain.add_cuts(cuts)
        stalled.add_cuts(cuts)
    assert stalled.backend.stalls == solves > 1
    assert plain.backend.stalls == 0
    assert stalled.backend.h.getOptionValue("solver")[1] == "choose"


def test_a_run_ending_otherwise_is_solved_again_from_no_basis():
    """A HiGHS run that ends neither solved, infeasible, cut off nor out of time (seen once in
    a K = 50 branch and cut) is run again from no basis: the optimum, and the retry counted; an
    iteration-limited (strong-branching) run is not retried."""
    plain, _ = _lp(HighsBackend, seed=4)
    odd, _ = _lp(HighsBackend, seed=4)
    expected = plain.backend.solve_lp(60.0)
    backend = odd.backend
    run, calls = backend._run, []

    def first_unknown(limit: int):
        status = run(limit)
        calls.append(limit)
        return backend._hs.HighsModelStatus.kUnknown if len(calls) == 1 else status

    backend._run = first_unknown
    res = backend.solve_lp(60.0)
    assert res.status == expected.status == "optimal"
    np.testing.assert_allclose(res.objective, expected.objective, rtol=1e-9)
    assert backend.retries == 1 and len(calls) == 2
    calls.clear()
    backend.h.clearSolver()
    assert backend.solve_lp(60.0, iterations=10**6).status == "stopped"
    assert backend.retries == 1 and len(calls) == 1


def test_a_cold_start_is_solved_by_the_interior_point_method():
    """Once a run has stalled, after ``start_cold`` the next LP without iteration limit is solved
    by the interior point method (an iteration-limited one before it is not): the same optimum,
    counted once, and HiGHS back on the dual simplex from that basis afterwards. Before any
    stall, ``start_cold`` does nothing."""
    plain, _ = _lp(HighsBackend, seed=4)
    cold, _ = _lp(HighsBackend, seed=4)
    backend = cold.backend
    expected = plain.backend.solve_lp(60.0)
    plain.backend.start_cold()
    plain.backend.solve_lp(60.0)
    assert plain.backend.h.getInfo().ipm_iteration_count == 0 and plain.backend.cold_starts == 0
    backend.stalls = 1  # (as after a stalled run)
    backend.start_cold()
    backend.solve_lp(60.0, iterations=1)
    assert backend.h.getInfo().ipm_iteration_count == 0 and backend.cold_starts == 0
    res = backend.solve_lp(60.0)
    assert backend.h.getInfo().ipm_iteration_count > 0 and backend.cold_starts == 1
    assert res.status == expected.status == "optimal"
    np.testing.assert_allclose(res.objective, expected.objective, rtol=1e-9)
    assert backend.h.getOptionValue("solver")[1] == "choose"
    backend.solve_lp(60.0)
    info = backend.h.getInfo()
    assert info.ipm_iteration_count == 0 and info.simplex_iteration_count == 0
    assert backend.cold_starts == 1 and backend.stalls == 1

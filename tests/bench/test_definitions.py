"""The benchmark definitions: data the engine can run, each naming what it measures."""

from __future__ import annotations

from gtsp_bench.bench.definitions import BENCHMARKS


def test_every_definition_is_runnable_data():
    """Each definition names registered solvers (optional peers may be absent), outputs the
    engine knows, quick fields that exist, and a rough time for --list."""
    from dataclasses import fields

    from gtsp_bench.bench.output_kinds import OUTPUTS
    from gtsp_bench.registry import solver_names

    names = set(solver_names())
    valid = {f.name for f in fields(next(iter(BENCHMARKS.values())))}
    for b in BENCHMARKS.values():
        assert b.rough_time and b.description and b.sources, b.name
        assert {r.solver for r in b.runs} <= names, b.name
        assert set(b.outputs) - {"paper"} <= set(OUTPUTS), b.name
        assert set(b.quick) <= valid, b.name
        assert len({r.name for r in b.runs}) == len(b.runs), f"{b.name}: two runs share a label"


def test_lns_runs_say_their_effort_and_fixed_budgets_say_budget():
    """An lns column names its preset; a benchmark with a fixed time per solve runs lns on the
    whole budget (effort=budget), so its rows are not a search that stopped early.
    ``stop_at_convergence`` is the older name of ``effort=fast``."""
    from gtsp_bench.solvers.heuristics.lns_settings import EFFORTS

    for b in BENCHMARKS.values():
        for r in b.runs:
            if r.solver != "lns":
                continue
            options = dict(r.options)
            effort = "fast" if options.get("stop_at_convergence") else options.get("effort")
            assert effort in EFFORTS, f"{b.name}: {r.name} names no effort"
            if b.budget.seconds is not None or b.budget.factor is not None:
                assert effort == "budget" or b.name == "lns-effort", f"{b.name}: {r.name}"

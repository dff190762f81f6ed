"""Distance-only instances for the local policy: an anchor node stands in for the depot, the
tour is feasible and priced by the evaluator, non-planar files are refused in one line."""

from __future__ import annotations

import pytest

torch = pytest.importorskip("torch")

from gtsp_bench.solvers.learned.distance import anchor_env, solve_distance  # noqa: E402
from gtsp_bench.solvers.learned.local import LocalPolicy  # noqa: E402

from gtsp_bench.data.io import read_instance  # noqa: E402
from gtsp_bench.energy import evaluate  # noqa: E402
from gtsp_bench.errors import InputError  # noqa: E402
from gtsp_bench.registry import get_solver, run_solver  # noqa: E402

GTSPLIB = "instances/gtsplib"


def test_anchor_env_is_the_rest_from_each_anchor_node():
    inst = read_instance(f"{GTSPLIB}/11berlin52.gtsp.gz")
    env, anchor, others = anchor_env(inst)
    assert anchor == int(inst.sizes.argmin()) and anchor not in others
    assert env.shape == (int(inst.sizes[anchor]), inst.n_clusters - 1, int(inst.sizes.max()))
    assert torch.equal(env.depot, torch.tensor(inst.clusters[anchor].copy(), dtype=torch.float64))
    assert float(env.node_cost.abs().max()) == 0.0 and float(env.omega.max()) == 0.0


def test_tour_feasible_and_priced_by_the_evaluator():
    torch.manual_seed(0)
    model = LocalPolicy(dim=16, n_heads=2, n_layers=1, ff=32, k=6)
    inst = read_instance(f"{GTSPLIB}/40kroa200.gtsp.gz")
    sol = solve_distance(model, inst, starts=2)
    assert sorted(sol.order) == list(range(inst.n_clusters))
    assert sol.objective == evaluate(inst, None, sol.order, sol.heads).objective


def test_shipped_policy_through_the_registry():
    """The shipped policy on a GTSPLIB file: feasible, and not below the best known."""
    inst = read_instance(f"{GTSPLIB}/11berlin52.gtsp.gz")
    result = run_solver(get_solver("local"), inst, None)
    assert result.status == "feasible" and result.objective >= 4040  # GTSPLIB's optimum


def test_non_planar_refused_in_one_line():
    inst = read_instance(f"{GTSPLIB}/10gr48.gtsp.gz")
    with pytest.raises(InputError, match="needs planar distances") as err:
        anchor_env(inst)
    assert "\n" not in str(err.value)

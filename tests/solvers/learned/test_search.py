"""The local-search solver: feasible tours priced by the evaluator at K = 200, its time cap,
never below a proven optimum, segments re-decoded in place, the budget split with the kicks, bad
options refused."""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from gtsp_bench.solvers.learned.checkpoint import save_policy  # noqa: E402
from gtsp_bench.solvers.learned.env import env_from_instances, optimal_heads_batch  # noqa: E402
from gtsp_bench.solvers.learned.local import LocalPolicy  # noqa: E402
from gtsp_bench.solvers.learned.search import LocalSearchSolver, reconstruct  # noqa: E402

from gtsp_bench.energy import evaluate  # noqa: E402
from gtsp_bench.errors import InputError  # noqa: E402
from gtsp_bench.generator import instance_set  # noqa: E402
from gtsp_bench.registry import get_solver, run_solver  # noqa: E402
from tests.tiny_cases import not_below  # noqa: E402


def _tiny(tmp_path):
    torch.manual_seed(0)
    model = LocalPolicy(dim=16, n_heads=2, n_layers=1, ff=32, k=6)
    path = tmp_path / "local.pt"
    save_policy(model, path)
    return model, path


def test_feasible_at_k200_and_priced_by_the_evaluator(tmp_path):
    """Through the registry at K = 200: a feasible tour whose objective is the evaluator's."""
    _, path = _tiny(tmp_path)
    inst = instance_set(1, 200, 4_343, 6, area=3_000.0)[0]
    solver = get_solver("local-search", checkpoint=str(path), starts=2, seconds_per_cluster=0.002)
    result = run_solver(solver, inst, 0.6)
    assert result.status == "feasible"
    assert sorted(result.order) == list(range(200))
    assert result.objective == pytest.approx(
        evaluate(inst, 0.6, result.order, result.heads).objective, rel=1e-12)


def test_no_round_starts_past_the_budget(tmp_path):
    """The budget is seconds_per_cluster * K, or the time limit where smaller; a spent budget
    starts no re-construction round (the multi-start tour is the answer)."""
    _, path = _tiny(tmp_path)
    inst = instance_set(1, 30, 4_343, 6)[0]
    spent = LocalSearchSolver(checkpoint=str(path), seconds_per_cluster=1e-9).solve(inst, 0.3)
    assert spent.stats["rounds"] == 0 and spent.stats["budget_s"] == pytest.approx(30e-9)
    capped = LocalSearchSolver(checkpoint=str(path)).solve(inst, 0.3, time_limit=1e-9)
    assert capped.stats["rounds"] == 0 and capped.stats["budget_s"] == 1e-9


def test_never_below_a_proven_optimum():
    """The shipped policy's search on tiny instances: never below dp's proven optimum."""
    exact = get_solver("dp")
    search = get_solver("local-search", seconds_per_cluster=0.02)
    for inst in instance_set(4, 5, 4_343, 8):
        for omega in (0.0, 0.6):
            opt = run_solver(exact, inst, omega).objective
            got = run_solver(search, inst, omega).objective
            assert not_below(got, opt)


def test_reconstruct_keeps_the_rest_of_the_tour(tmp_path):
    """Each re-decoded tour is a permutation that keeps every cluster outside its segment in
    place, forwards and backwards."""
    model, _ = _tiny(tmp_path)
    inst = instance_set(1, 20, 4_343, 6)[0]
    env = env_from_instances([inst], [0.3])
    order = torch.randperm(20, generator=torch.Generator().manual_seed(1))
    heads = optimal_heads_batch(env, order[None])[0][0]
    starts = np.array([0, 3, 12, 15])
    with torch.inference_mode():
        out = reconstruct(model, env, order, heads, starts, 5, np.array([False, True, False, True]),
                          torch.Generator().manual_seed(0))
    assert out.shape == (4, 20)
    for row, a in zip(out, starts, strict=True):
        assert sorted(row.tolist()) == list(range(20))
        keep = np.r_[0:a, a + 5:20]
        assert torch.equal(row[keep], order[keep])
        assert sorted(row[a:a + 5].tolist()) == sorted(order[a:a + 5].tolist())


def test_bad_options_are_refused_with_the_valid_names():
    with pytest.raises(InputError, match="options: checkpoint, starts"):
        get_solver("local-search", bogus=1)
    for bad in ({"width": 0}, {"seconds_per_cluster": -1.0}, {"max_segment": 1}, {"ls": "maybe"},
                {"min_segment": 10, "max_segment": 5}, {"kick_share": -0.1}, {"kick_share": 1.5}):
        with pytest.raises(InputError):
            LocalSearchSolver(**bad)


def test_shipped_policy_loads_on_the_cpu_and_a_wrong_file_is_one_line(tmp_path):
    """The default policy file (local-l3.pt) loads on the CPU; an am file is refused in one line."""
    from gtsp_bench.solvers.learned.am import AttentionPolicy

    model = LocalSearchSolver().model
    assert model.config["dim"] == 96 and next(model.parameters()).device.type == "cpu"
    am = tmp_path / "am.pt"
    save_policy(AttentionPolicy(dim=16, n_heads=2, n_layers=1, ff=16), am)
    inst = instance_set(1, 5, 4_343, 6)[0]
    with pytest.raises(InputError, match="holds a 'am' model, not 'local'") as err:
        LocalSearchSolver(checkpoint=str(am)).solve(inst, 0.3)
    assert "\n" not in str(err.value)


def test_partition_tiles_the_tour_with_disjoint_segments():
    """Consecutive segments of one length, inside the tour, k // length of them."""
    from gtsp_bench.solvers.learned.search import partition

    rng = np.random.default_rng(0)
    for k, length in ((10, 2), (10, 3), (100, 7), (100, 60), (37, 37), (200, 41)):
        for _ in range(20):
            st = partition(k, length, rng)
            assert len(st) == k // length
            assert st[0] >= 0 and st[-1] + length <= k
            assert np.all(np.diff(st) == length)


def test_a_round_gives_a_better_tour_priced_exactly_or_none(tmp_path):
    """From a random tour, rounds of re-construction (several segments replaced at once) give
    permutations whose cost is below the old one and equals their optimal-heads price."""
    _, path = _tiny(tmp_path)
    solver = LocalSearchSolver(checkpoint=str(path))
    inst = instance_set(1, 40, 4_343, 6)[0]
    env = env_from_instances([inst], [0.3])
    order = torch.randperm(40, generator=torch.Generator().manual_seed(2))
    heads, cost = optimal_heads_batch(env, order[None])
    heads, cost = heads[0], float(cost[0])
    rng, gen = np.random.default_rng(0), torch.Generator().manual_seed(0)
    improved = 0
    with torch.inference_mode():
        for length in (4, 5, 8, 10, 4, 5):
            found = solver._round(env, order, heads, cost, length, rng, gen)
            if found is None:
                continue
            new_order, new_heads, new_cost = found
            assert sorted(new_order.tolist()) == list(range(40))
            assert new_cost < cost
            assert new_cost == pytest.approx(
                float(optimal_heads_batch(env, new_order[None])[1][0]), rel=1e-12)
            order, heads, cost = new_order, new_heads, new_cost
            improved += 1
    assert improved >= 1


def test_kick_share_splits_the_budget_between_rounds_and_kicks(tmp_path):
    """kick_share=0: rounds only, no kicks (the search without them); kick_share=1: kicks only,
    no round; the answer is priced by the evaluator either way."""
    _, path = _tiny(tmp_path)
    inst = instance_set(1, 30, 4_343, 6)[0]
    rounds_only = LocalSearchSolver(checkpoint=str(path), kick_share=0.0, seconds_per_cluster=0.005)
    kicks_only = LocalSearchSolver(checkpoint=str(path), kick_share=1.0, seconds_per_cluster=0.005)
    a = run_solver(rounds_only, inst, 0.3)
    b = run_solver(kicks_only, inst, 0.3)
    assert a.stats["kicks"] == 0 and a.stats["rounds"] > 0
    assert b.stats["rounds"] == 0 and b.stats["kicks"] > 0
    for r in (a, b):
        assert r.objective == pytest.approx(evaluate(inst, 0.3, r.order, r.heads).objective, rel=1e-12)

"""The tree search: cold starts after jumps, strong branching, and its workers."""

from __future__ import annotations

from pathlib import Path

import pytest
from gtsp_bench.solvers.exact.mip.backends import HighsBackend
from gtsp_bench.solvers.exact.mip.options import MipOptions
from gtsp_bench.solvers.exact.mip.solve import solve_exact

from gtsp_bench.generator import generate_instance
from gtsp_bench.problem import price


@pytest.mark.parametrize("dive", [True, False])
def test_a_node_after_a_jump_starts_cold(dive, monkeypatch):
    """A K = 16 instance left to the branch and cut (two root rounds, greedy tour), every jump
    counted as one, HiGHS told that a run stalled: each node taken from the open ones (every node
    but the first when nothing dives) has its first LP solved from no basis, a dived-into child
    not; with no jump large enough, none is; the proof is the same."""
    from gtsp_bench.solvers.exact.mip import tree_search

    class Stalled(HighsBackend):
        def __init__(self, options: MipOptions) -> None:
            super().__init__(options)
            self.stalls = 1

    if not dive:
        monkeypatch.setattr(tree_search, "DIVE_SHARE", -1.0)
    monkeypatch.setattr(tree_search, "JUMP_BOUNDS", 0)
    problem = price(generate_instance(16, 6, seed=8), 0.5)
    options = MipOptions(root_rounds=2, lns_trials=0, workers=1)
    r = solve_exact(problem, Stalled, options)
    assert r.status == "optimal" and r.stats["bc_nodes"] >= 3
    cold = r.stats["lp_cold_starts"]
    assert cold == r.stats["jumps"]
    assert cold == r.stats["bc_nodes"] - 1 if not dive else 1 <= cold < r.stats["bc_nodes"] - 1
    if dive:
        return
    monkeypatch.setattr(tree_search, "JUMP_BOUNDS", 10**9)
    warm = solve_exact(problem, Stalled, options)
    assert warm.stats["lp_cold_starts"] == 0 and "jumps" not in warm.stats
    assert warm.status == "optimal"
    assert r.objective == pytest.approx(warm.objective, rel=1e-12)


def test_full_strong_branching_takes_every_candidate(monkeypatch):
    """While strong-branching LPs finish (a small instance), every one of the closest candidates
    is strong-branched: the reliability-branching budget (:data:`branching.MAX_STRONG`,
    :data:`branching.LOOKAHEAD`) leaves the search unchanged."""
    from gtsp_bench.solvers.exact.mip import branching

    problem = price(generate_instance(16, 6, seed=8), 0.5)
    options = MipOptions(root_rounds=2, lns_trials=0, workers=1)
    full = solve_exact(problem, HighsBackend, options)
    assert full.status == "optimal" and "strong_partial" not in full.stats
    assert full.stats["strong_lps"] > 2 * 2  # some node strong-branched more than 2 candidates
    monkeypatch.setattr(branching, "MAX_STRONG", 1)
    monkeypatch.setattr(branching, "LOOKAHEAD", 1)
    capped = solve_exact(problem, HighsBackend, options)
    for key in ("strong_lps", "bc_nodes", "node_lps"):
        assert capped.stats[key] == full.stats[key]
    assert capped.objective == pytest.approx(full.objective, rel=1e-12)


#: Instances that the root leaves to the branch and cut (two root rounds, greedy tour): a few
#: nodes, and about 90.
TREES = [(16, 6, 8), (20, 5, 0)]


@pytest.mark.parametrize("k, n, seed", TREES)
def test_two_workers_prove_the_same_optimum(k, n, seed):
    """Two workers search one tree: the optimum of one worker proven, with both workers' nodes
    counted (the one-worker search is checked against brute force in ``test_milp``)."""
    problem = price(generate_instance(k, n, seed=seed), 0.5)
    one = solve_exact(problem, HighsBackend, MipOptions(root_rounds=2, lns_trials=0, workers=1))
    two = solve_exact(problem, HighsBackend, MipOptions(root_rounds=2, lns_trials=0, workers=2))
    assert one.status == two.status == "optimal"
    assert two.objective == pytest.approx(one.objective, rel=1e-9)
    assert two.stats["tree_workers"] == 2 and one.stats["tree_workers"] == 1
    assert two.stats["bc_nodes"] >= 3


def test_a_proof_by_two_workers_is_certified(tmp_path: Path):
    """A certificate of a tree searched by two workers (their cuts numbered apart, one log)
    passes the checker."""
    from gtsp_bench.proof import check_certificate
    from gtsp_bench.proof.format import read_certificate

    inst = generate_instance(20, 5, seed=0)
    problem = price(inst, 0.5)
    path = tmp_path / "two.cert.json.gz"
    sol = solve_exact(problem, HighsBackend, MipOptions(root_rounds=2, lns_trials=0, workers=2),
                      certificate=path)
    assert sol.status == "optimal" and sol.stats["bc_nodes"] >= 20
    assert sol.stats["tree_workers"] == 2
    result = check_certificate(inst, read_certificate(path))
    assert result.proven and result.value == pytest.approx(sol.objective, rel=1e-9)


def test_a_failing_worker_ends_the_search_at_once(monkeypatch):
    """An error in one worker's node ends the other worker at its next node (at most one more
    node begins; the tree has about 90), and the solve raises the error."""
    import threading
    import time

    from gtsp_bench.solvers.exact.mip import tree_search

    node_loop = tree_search.TreeSearch._node_loop
    calls = {"n": 0}
    lock = threading.Lock()

    def failing(self, branched=None):
        with lock:
            calls["n"] += 1
            fail = calls["n"] == 6
        if fail:
            raise RuntimeError("a worker broke")
        return node_loop(self, branched)

    monkeypatch.setattr(tree_search.TreeSearch, "_node_loop", failing)
    problem = price(generate_instance(20, 5, seed=0), 0.5)
    start = time.perf_counter()
    with pytest.raises(RuntimeError, match="a worker broke"):
        solve_exact(problem, HighsBackend, MipOptions(root_rounds=2, lns_trials=0, workers=2),
                    time_limit=300.0)
    assert time.perf_counter() - start < 60.0
    assert calls["n"] <= 6 + 1


@pytest.mark.parametrize("workers", [1, 2])
def test_two_workers_take_their_own_nodes_first_and_one_takes_the_best(workers, monkeypatch):
    """With two workers each open node is marked by the worker that made it, and each ``take``
    asks for the worker's own nodes near the best (``near`` within the incumbent); one worker
    always takes the best node (no ``near``), as before there were workers."""
    from gtsp_bench.solvers.exact.mip.workers import OpenNodes

    take, put = OpenNodes.take, OpenNodes.put
    nears: list[object] = []
    makers: set[int] = set()

    def spy_take(self, worker, stop, near=None):
        nears.append(near)
        return take(self, worker, stop, near)

    def spy_put(self, node):
        makers.add(node.worker)
        return put(self, node)

    monkeypatch.setattr(OpenNodes, "take", spy_take)
    monkeypatch.setattr(OpenNodes, "put", spy_put)
    problem = price(generate_instance(20, 5, seed=0), 0.5)
    r = solve_exact(problem, HighsBackend, MipOptions(root_rounds=2, lns_trials=0, workers=workers))
    assert r.status == "optimal" and r.stats["bc_nodes"] >= 20
    if workers == 1:
        assert nears and all(near is None for near in nears) and makers == {0}
        return
    assert nears and all(callable(near) for near in nears) and makers == {0, 1}
    assert nears[0](10.0) >= 10.0  # the window starts at the best bound

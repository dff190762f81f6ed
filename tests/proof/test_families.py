"""Cut families: every member that passes the checks holds for every tour; bad sets are refused."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from gtsp_bench.generator import generate_instance
from gtsp_bench.problem import Problem, price
from gtsp_bench.proof.families import Blossom, Gsec, parse_cut


def tiny(seed: int = 0, k: int = 4, n: int = 2) -> Problem:
    """A UAV instance of ``k`` clusters of ``n`` nodes (and the depot's cluster), priced."""
    return price(generate_instance(k, n, seed=seed), 0.5)


def all_tours(problem: Problem) -> list[tuple[np.ndarray, np.ndarray, float]]:
    """Every tour as ``(y, x, cost)``: ``y`` per node, ``x`` a symmetric 0/1 node matrix."""
    out = []
    first, *rest = range(problem.n_clusters)
    for order in itertools.permutations(rest):
        if order[0] > order[-1]:  # each cycle once (symmetric costs)
            continue
        cyc = (first, *order)
        for heads in itertools.product(*(problem.clusters[c] for c in cyc)):
            y = np.zeros(problem.n_nodes, dtype=np.int64)
            y[list(heads)] = 1
            x = np.zeros((problem.n_nodes, problem.n_nodes), dtype=np.int64)
            for a, b in zip(heads, heads[1:] + heads[:1], strict=True):
                x[a, b] = x[b, a] = 1
            out.append((y, x, problem.tour_cost(np.array(heads))))
    return out


def lhs_rhs(cut: Gsec | Blossom, cluster_of: np.ndarray, y: np.ndarray, x: np.ndarray) -> tuple[int, int]:
    """Left- and right-hand side of a row at a tour, straight from the family's definition."""
    if isinstance(cut, Gsec):
        q = cut.members
        inside = int(x[np.ix_(q, q)].sum()) // 2
        return inside, int(y[q & (cluster_of != cut.c1)].sum() + y[q & (cluster_of == cut.c2)].sum())
    m = len(cut.handle)
    z = np.zeros((m, m), dtype=np.int64)
    np.add.at(z, (cluster_of[:, None].repeat(len(y), 1), cluster_of[None, :].repeat(len(y), 0)), x)
    h = cut.handle
    lhs = int(z[np.ix_(h, h)].sum()) // 2 + int(sum(z[a, b] for a, b in cut.teeth))
    return lhs, cut.rhs


def random_cuts(problem: Problem, rng: np.random.Generator, count: int) -> list[dict]:
    """Random members of both families (JSON form), every one passing :func:`parse_cut`."""
    n, m = problem.n_nodes, problem.n_clusters
    cuts: list[dict] = []
    while len(cuts) < count:
        if rng.random() < 0.6:
            q = sorted(int(v) for v in rng.choice(n, size=int(rng.integers(1, n)), replace=False))
            c1, c2 = (int(v) for v in rng.choice(m, size=2, replace=False))
            cuts.append({"family": "gsec", "Q": q, "C1": c1, "C2": c2})
        else:
            h = sorted(int(v) for v in rng.choice(m, size=int(rng.integers(1, m)), replace=False))
            pairs = [[a, b] for a in h for b in range(m) if b not in h]
            k = int(rng.integers(0, (len(pairs) + 1) // 2)) * 2 + 1
            if k > len(pairs):
                continue
            teeth = [pairs[i] for i in rng.choice(len(pairs), size=k, replace=False)]
            cuts.append({"family": "blossom", "handle": h, "teeth": teeth})
    return cuts


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_every_member_holds_for_every_tour(seed: int) -> None:
    problem = tiny(seed)
    rng = np.random.default_rng(seed)
    tours = all_tours(problem)
    assert len(tours) == 12 * 2**4
    tight = 0
    for raw in random_cuts(problem, rng, 60):
        cut = parse_cut(raw, problem.cluster_of)
        for y, x, _ in tours:
            lhs, rhs = lhs_rhs(cut, problem.cluster_of, y, x)
            assert lhs <= rhs, raw
            tight += lhs == rhs
    assert tight > 0  # (the rows are not all slack: the test can fail)


def test_blossom_rhs_and_a_violated_even_blossom() -> None:
    """``|H| + (|F| - 1) / 2``; with an even number of teeth the row would cut tours off."""
    problem = tiny(0)
    cut = parse_cut({"family": "blossom", "handle": [0, 1], "teeth": [[0, 2], [1, 3], [1, 4]]},
                    problem.cluster_of)
    assert isinstance(cut, Blossom) and cut.rhs == 3
    even = Blossom(np.array([True, True, False, False, False]), np.array([[0, 2], [1, 3]]))
    worst = max(lhs_rhs(even, problem.cluster_of, y, x)[0] - (2 + (2 - 1) // 2)
                for y, x, _ in all_tours(problem))
    assert worst > 0  # why parse_cut refuses even tooth counts


@pytest.mark.parametrize(("cut", "reason"), [
    ({"family": "comb"}, "unknown family 'comb'"),
    ({"family": "gsec", "Q": [0, 1], "C1": 2, "C2": 2}, "C1 and C2 are the same cluster"),
    ({"family": "gsec", "Q": [], "C1": 0, "C2": 1}, "Q must be a non-empty list"),
    ({"family": "gsec", "Q": list(range(9)), "C1": 0, "C2": 1}, "Q holds every node"),
    ({"family": "gsec", "Q": [0, 0], "C1": 0, "C2": 1}, "Q repeats an id"),
    ({"family": "gsec", "Q": [0, 99], "C1": 0, "C2": 1}, "Q names an id outside"),
    ({"family": "gsec", "Q": [0], "C1": 0, "C2": 7}, "C2 must be a cluster"),
    ({"family": "blossom", "handle": [0, 1], "teeth": [[0, 2], [1, 3]]}, "2 teeth"),
    ({"family": "blossom", "handle": [0, 1], "teeth": [[2, 0]]}, "does not go from the handle"),
    ({"family": "blossom", "handle": [0, 1], "teeth": [[0, 2], [0, 2], [1, 3]]}, "repeated"),
    ({"family": "blossom", "handle": [0, 1, 2, 3, 4], "teeth": [[0, 1]]}, "holds every cluster"),
])
def test_bad_sets_are_refused_with_the_reason(cut: dict, reason: str) -> None:
    with pytest.raises(ValueError, match=reason):
        parse_cut(cut, tiny(0).cluster_of)


def test_gsec_nodes_are_its_members_ascending() -> None:
    """``Gsec.nodes`` lists the member nodes in order."""
    members = np.zeros(5, dtype=bool)
    members[[3, 1]] = True
    assert Gsec(members, 0, 1).nodes.tolist() == [1, 3]

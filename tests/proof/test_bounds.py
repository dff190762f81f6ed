"""Exact bounds: any duals of the right signs bound every tour of the domain from below; the
arithmetic is exact; Farkas proofs show empty domains; bad duals are refused."""

from __future__ import annotations

import itertools
from fractions import Fraction

import numpy as np
import pytest

from gtsp_bench.data.io import read_instance
from gtsp_bench.problem import price
from gtsp_bench.proof.bounds import Domain, Space, price_duals
from gtsp_bench.proof.families import Gsec, parse_cut
from tests.conftest import GTSPLIB

from .test_families import all_tours, random_cuts, tiny

BITS = 20


def _y_row(c: Gsec, cluster_of: np.ndarray) -> np.ndarray:
    """A gsec row's y coefficients from its definition, apart from the code under test: -1 on
    ``Q - C1``, -1 more on ``Q & C2``."""
    return np.array([-(int(q and k != c.c1) + int(q and k == c.c2))
                     for q, k in zip(c.members, cluster_of, strict=True)])


def _random_proof(rng: np.random.Generator, n: int, m: int, n_cuts: int, kind: str = "dual") -> dict:
    scale = 2**BITS
    return {"kind": kind,
            "cluster": [[c, int(rng.integers(-50, 400) * scale // 7)] for c in range(m)],
            "degree": [[i, int(rng.integers(-100, 100) * scale // 3)] for i in range(n)],
            "cuts": [[k, -int(rng.integers(0, 80) * scale // 5)] for k in range(n_cuts)]}


@pytest.mark.parametrize("seed", range(6))
def test_random_duals_bound_every_tour_of_the_domain(seed: int) -> None:
    problem = tiny(seed)
    rng = np.random.default_rng(seed)
    space = Space.of(problem)
    cuts = [parse_cut(c, space.cluster_of) for c in random_cuts(problem, rng, 8)]
    tours = all_tours(problem)
    domain = Domain.free(space)
    i = int(rng.integers(0, 8))  # a branching: y_i = 1, and one edge at i fixed to 0
    j = int(np.flatnonzero(space.edge[i] | space.edge[:, i])[0])
    a, b = min(i, j), max(i, j)
    domain.set(i, -1, 1)
    domain.set(a, b, 0)
    inside = [cost for y, x, cost in tours if y[i] == 1 and x[a, b] == 0]
    for _ in range(5):
        proof = _random_proof(rng, space.n_nodes, space.n_clusters, len(cuts))
        priced = price_duals(space, cuts, proof, BITS)
        assert priced.bound(Domain.free(space)) <= min(c for _, _, c in tours)
        assert priced.bound(domain) <= min(inside)


def test_the_bound_is_exact() -> None:
    """Against a plain fraction sum over every column (an integer-cost GTSPLIB file), in the
    free domain and in one with columns fixed to 1 and to 0."""
    problem = price(read_instance(GTSPLIB / "11berlin52.gtsp.gz"), None)
    space = Space.of(problem)
    assert space.integral
    rng = np.random.default_rng(3)
    cuts = [parse_cut({"family": "gsec", "Q": list(range(5 * k, 5 * k + 9)), "C1": 0, "C2": 9},
                      space.cluster_of) for k in range(4)]
    proof = _random_proof(rng, space.n_nodes, space.n_clusters, len(cuts))
    proof["degree"] = [[i, 20 * v] for i, v in proof["degree"]]  # some edges priced below 0
    priced = price_duals(space, cuts, proof, BITS)
    scale = Fraction(1, 2**BITS)
    u = {c: v * scale for c, v in proof["cluster"]}
    pi = {i: v * scale for i, v in proof["degree"]}
    lam = [v * scale for _, v in proof["cuts"]]
    reduced = {}  # column (i, -1) or (i, j): its exact reduced cost
    for i in range(space.n_nodes):
        aw = u[int(space.cluster_of[i])] - 2 * pi[i]
        for c, w in zip(cuts, lam, strict=True):
            assert isinstance(c, Gsec)
            aw += w * int(_y_row(c, space.cluster_of)[i])
        reduced[i, -1] = Fraction(space.node_cost[i]) - aw
    for i, j in zip(*np.nonzero(space.edge), strict=True):
        aw = pi[i] + pi[j] + sum((w for c, w in zip(cuts, lam, strict=True)
                                  if c.members[i] and c.members[j]), Fraction(0))
        reduced[int(i), int(j)] = Fraction(space.edge_cost[i, j]) - aw
    fixed = Domain.free(space)
    kinds = set()
    for is_y in (True, False):  # of each sign, node and edge columns fixed to 1 and to 0
        for sign in (1, -1):
            cols = [c for c, r in reduced.items() if (c[1] == -1) == is_y and r * sign > 0]
            for col, value in zip(cols, (1, 0), strict=False):
                fixed.set(*col, value)
                kinds.add((is_y, sign, value))
    assert {(False, 1, 1), (False, -1, 1), (True, -1, 1), (False, -1, 0)} <= kinds
    for domain in (Domain.free(space), fixed):
        want = sum(u.values(), Fraction(0))
        for (i, j), r in reduced.items():
            state = domain.get(i, j)
            want += r if state == 1 else min(r, 0) if state == -1 else 0
        assert priced.bound(domain) == want


def test_farkas_shows_an_empty_domain() -> None:
    """Two heads in one cluster: the cluster row with dual -1 proves no tour has them."""
    problem = tiny(0)
    space = Space.of(problem)
    a, b = problem.clusters[0][:2]
    domain = Domain.free(space)
    domain.set(int(a), -1, 1)
    domain.set(int(b), -1, 1)
    ray = {"kind": "farkas", "cluster": [[0, -(2**BITS)]], "degree": [], "cuts": []}
    priced = price_duals(space, [], ray, BITS)
    assert priced.bound(domain) == 1  # -1 * 1 + (1 + 1): positive, so the domain is empty
    assert priced.bound(Domain.free(space)) <= 0  # (a ray shows nothing about a feasible domain)


def test_bad_duals_are_refused() -> None:
    problem = tiny(0)
    space = Space.of(problem)
    cut = [parse_cut({"family": "gsec", "Q": [0, 2], "C1": 0, "C2": 1}, space.cluster_of)]
    with pytest.raises(ValueError, match="dual of cut 0 is positive"):
        price_duals(space, cut, {"kind": "dual", "cuts": [[0, 5]]}, BITS)
    with pytest.raises(ValueError, match="kind 'primal'"):
        price_duals(space, cut, {"kind": "primal"}, BITS)
    with pytest.raises(ValueError, match="not \\[index in"):
        price_duals(space, cut, {"kind": "dual", "degree": [[99, 1]]}, BITS)
    for value in (2**61, -(2**63), 2**70):  # the last does not fit int64
        with pytest.raises(ValueError, match="too large"):
            price_duals(space, cut, {"kind": "dual", "degree": [[0, value]]}, BITS)
    for entry in ([0, True], [0, 1.0], [0], [-1, 1], "0 1"):
        with pytest.raises(ValueError, match="not \\[index in"):
            price_duals(space, cut, {"kind": "dual", "degree": [entry]}, BITS)
    many = {"kind": "dual", "cuts": [[0, -(2**58)]] + [[k, -(2**58)] for k in range(1, 64)]}
    with pytest.raises(ValueError, match="too large to sum"):  # their sum would wrap in int64
        price_duals(space, cut * 64, many, BITS)
    with pytest.raises(ValueError, match="repeated"):
        price_duals(space, cut, {"kind": "dual", "degree": [[0, 1], [0, 2]]}, BITS)
    numpy_ints = {"kind": "dual", "degree": [[np.int64(0), np.int32(3)]]}  # accepted as ints
    assert price_duals(space, cut, numpy_ints, BITS).aw_y[0] == -6


def test_the_sums_of_subtour_rows_are_exact() -> None:
    """The gsec rows' duals summed over the y columns equal each row's coefficients times its
    dual, and over the edge columns (with degree duals) the exact product M'diag(w)M plus
    ``pi_i + pi_j``, also for duals near the largest allowed (no float rounding anywhere)."""
    from gtsp_bench.proof.bounds import _gsec_sums

    rng = np.random.default_rng(3)
    n, cluster_of = 40, np.arange(40) // 4
    rows = [Gsec(rng.random(n) < p, *rng.choice(10, 2, replace=False)) for p in rng.random(60)]
    rows = [r for r in rows if r.members.any()]
    w = -rng.integers(2**57 // len(rows), 2**58 // len(rows), len(rows))
    mask = np.array([r.members for r in rows]).astype(object)
    exact_x = (mask.T * w.astype(object)) @ mask
    exact_y = sum(int(wk) * _y_row(r, cluster_of).astype(object) for r, wk in zip(rows, w, strict=True))
    got_y, indices, indptr = _gsec_sums(rows, w, cluster_of)
    assert got_y.dtype == np.int64 and (got_y.astype(object) == exact_y).all()
    assert [indices[a:b].tolist() for a, b in itertools.pairwise(indptr)] == [r.nodes.tolist() for r in rows]

    space = Space(cluster_of, np.zeros(n), np.zeros((n, n)), np.triu(cluster_of[:, None] != cluster_of, 1),
                  True)
    cuts = [{"family": "gsec", "Q": r.nodes.tolist(), "C1": r.c1, "C2": r.c2} for r in rows]
    pi = rng.integers(-(2**50), 2**50, n)
    proof = {"kind": "dual", "degree": [[i, int(v)] for i, v in enumerate(pi)],
             "cuts": [[k, int(v)] for k, v in enumerate(w)]}
    priced = price_duals(space, [parse_cut(c, cluster_of) for c in cuts], proof, BITS)
    want = exact_x + np.add.outer(pi, pi).astype(object)
    got = priced.aw_x[space.edge].astype(object)
    assert priced.aw_x.dtype == np.int64 and (got == want[space.edge]).all()


def test_nonzero_through_the_flat_array_is_numpys() -> None:
    """The bounds' ``_nonzero`` gives numpy's index arrays, in numpy's order, in one and two
    dimensions, for empty and full masks too."""
    from gtsp_bench.proof.bounds import _nonzero

    rng = np.random.default_rng(5)
    for mask in (rng.random((37, 41)) < 0.1, rng.random(50) < 0.3, np.zeros((4, 4), bool),
                 np.ones((3, 5), bool), np.zeros(0, bool)):
        got, want = _nonzero(mask), np.nonzero(mask)
        assert len(got) == len(want) and all(np.array_equal(g, w) for g, w in zip(got, want, strict=True))


def test_plain_and_numpy_dual_entries_price_alike() -> None:
    """A proof's ``[index, value]`` pairs read the same as plain ints (a JSON file's) and as numpy
    ints; an index outside the range among many good pairs is named."""
    problem = tiny(0)
    space = Space.of(problem)
    n = space.n_nodes
    plain = {"kind": "dual", "degree": [[i, 3 * i - 7] for i in range(n)]}
    numpy = {"kind": "dual", "degree": [[np.int64(i), np.int16(3 * i - 7)] for i in range(n)]}
    a, b = price_duals(space, [], plain, BITS), price_duals(space, [], numpy, BITS)
    assert np.array_equal(a.aw_y, b.aw_y) and np.array_equal(a.aw_x, b.aw_x) and a.rhs == b.rhs
    with pytest.raises(ValueError, match=rf"\[{n}, 1\] is not \[index in \[0, {n}\)"):
        price_duals(space, [], {"kind": "dual", "degree": [*plain["degree"][1:], [n, 1]]}, BITS)


@pytest.mark.parametrize("kind", ["dual", "farkas"])
def test_the_float_reduced_costs_are_within_their_error_bound(kind: str) -> None:
    """The float reduced costs (they choose the columns summed exactly and those fixed by
    reduced cost) are within the stated error of the exact ones on every column, with fractional
    costs and duals near the largest allowed, whose sums floats cannot hold exactly."""
    rng = np.random.default_rng(5)
    n, cluster_of = 30, np.arange(30) // 3
    cost = rng.random((n, n)) * 1e6
    edge = np.triu(cluster_of[:, None] != cluster_of[None, :], 1)
    space = Space(cluster_of, rng.random(n) * 1e3, (cost + cost.T) / 3, edge, False)
    bits = 40
    proof = {"kind": kind,
             "cluster": [[c, int(rng.integers(-2**56, 2**56))] for c in range(10)],
             "degree": [[i, int(rng.integers(-2**56, 2**56))] for i in range(n)], "cuts": []}
    priced = price_duals(space, [], proof, bits)
    scale = 2**bits
    for is_x in (False, True):
        r, err = priced.approx(is_x)
        cols = list(zip(*np.nonzero(edge), strict=True)) if is_x else [(i,) for i in range(n)]
        worst = Fraction(0)
        for col in cols:
            aw = Fraction(int((priced.aw_x if is_x else priced.aw_y)[col]), scale)
            c = 0 if kind == "farkas" else Fraction((space.edge_cost if is_x else space.node_cost)[col])
            worst = max(worst, abs(Fraction(r[col]) - (c - aw)))
        assert 0 < worst <= Fraction(err)  # (floats did round: the bound is tested)

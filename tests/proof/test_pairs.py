"""The checker's compiled loop: the edge columns' ``A'w``, exactly."""

from __future__ import annotations

import numpy as np

from gtsp_bench.proof.pairs import edge_sums


def test_edge_sums_are_exact_on_the_edge_columns() -> None:
    """Above the diagonal, ``pi_i + pi_j + pair[c(i), c(j)]`` plus each row's weight over its
    member pairs, against Python-int arithmetic, for weights near the largest the checker allows
    (unsorted members, rows without members); below it, the same without the rows."""
    rng = np.random.default_rng(11)
    n, r, m = 30, 50, 7
    cluster_of = rng.integers(0, m, n)
    mask = rng.random((r, n)) < rng.random((r, 1))
    mask[[4, 9]] = False
    w = -rng.integers(2**57 // r, 2**58 // r, r)
    members = [rng.permutation(np.flatnonzero(row)) for row in mask]
    indices = np.concatenate(members).astype(np.int64)
    indptr = np.concatenate([[0], np.cumsum([len(q) for q in members])]).astype(np.int64)
    pi = rng.integers(-(2**50), 2**50, n)
    pair = rng.integers(-(2**50), 2**50, (m, m))
    pair += pair.T
    out = edge_sums(pi, pair, cluster_of, indices, indptr, w)
    mk = mask.astype(object)
    base = np.add.outer(pi, pi).astype(object) + pair[cluster_of][:, cluster_of].astype(object)
    full = base + (mk.T * w.astype(object)) @ mk
    upper = np.triu(np.ones((n, n), bool), 1)
    assert out.dtype == np.int64
    assert (out[upper].astype(object) == full[upper]).all()
    assert (out[~upper].astype(object) == base[~upper]).all()

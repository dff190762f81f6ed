"""The checker's compiled loop: a dual summed over subtour rows' member pairs, exactly."""

from __future__ import annotations

import numpy as np

from gtsp_bench.proof.pairs import add_member_pairs


def test_member_pairs_add_the_exact_product_into_out() -> None:
    """``out += M' diag(w) M`` (every ordered member pair, ``i == j`` too) against Python-int
    arithmetic, for weights near the largest the checker allows, added onto what ``out`` held;
    rows without members add nothing."""
    rng = np.random.default_rng(11)
    n, r = 30, 50
    mask = rng.random((r, n)) < rng.random((r, 1))
    mask[[4, 9]] = False
    w = -rng.integers(2**57 // r, 2**58 // r, r)
    counts = mask.sum(1)
    indices = np.flatnonzero(mask) % n
    indptr = np.concatenate([[0], np.cumsum(counts)])
    start = rng.integers(-(2**40), 2**40, (n, n))
    out = start.copy()
    add_member_pairs(indices.astype(np.int64), indptr.astype(np.int64), w, out)
    m = mask.astype(object)
    exact = start.astype(object) + (m.T * w.astype(object)) @ m
    assert out.dtype == np.int64 and (out.astype(object) == exact).all()

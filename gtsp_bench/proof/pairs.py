"""The checker's one compiled loop (numba, ``cache=True``): ``A'w`` over the edge columns.

A proof of a large instance puts duals on about a thousand subtour rows of about a hundred
members each, so its reduced costs take about a million additions over member pairs; as a
sparse product (scipy), with the degree and blossom parts added as dense arrays, they took about
half of a certificate's check. The loop is plain integer addition in int64:
:func:`gtsp_bench.proof.bounds.price_duals` bounds every sum below ``2**62`` before it runs, so
no sum wraps.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def edge_sums(pi: np.ndarray, pair: np.ndarray, cluster_of: np.ndarray, indices: np.ndarray,
              indptr: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """``A'w`` of the edge columns, scaled: ``out[i, j] = pi[i] + pi[j] + pair[c(i), c(j)]`` (the
    degree rows' and the cluster-pair rows' duals), plus, for ``i < j`` only, ``weights[r]`` of
    every row ``r`` holding both ``i`` and ``j`` among its members
    ``indices[indptr[r]:indptr[r + 1]]`` (distinct, in any order: the subtour rows' duals).

    Returns
    -------
    numpy.ndarray
        ``(n, n)`` int64. The entries ``i < j`` are the edge columns' sums; the others lack the
        subtour rows' part (no column reads them).
    """
    n = len(pi)
    out = np.empty((n, n), dtype=np.int64)
    for i in range(n):
        ci = cluster_of[i]
        for j in range(n):
            out[i, j] = pi[i] + pi[j] + pair[ci, cluster_of[j]]
    for r in range(len(indptr) - 1):
        w = weights[r]
        a, b = indptr[r], indptr[r + 1]
        for p in range(a, b):
            i = indices[p]
            for q in range(p + 1, b):  # each unordered pair once, added above the diagonal
                j = indices[q]
                if i < j:
                    out[i, j] += w
                else:
                    out[j, i] += w
    return out


def warm_up() -> None:
    """Compile (first use on a machine) or load (from numba's cache) the loop on a tiny input."""
    one = np.zeros(2, dtype=np.int64)
    edge_sums(one, np.zeros((2, 2), dtype=np.int64), one, np.array([0, 1], dtype=np.int64),
              np.array([0, 2], dtype=np.int64), np.array([1], dtype=np.int64))

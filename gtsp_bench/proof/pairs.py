"""The checker's one compiled loop (numba, ``cache=True``): a dual summed over the member pairs
of subtour rows.

A proof of a large instance puts duals on about a thousand subtour rows of about a hundred
members each, so its reduced costs take about a million such additions; as a sparse product
(scipy) they took about a third of a certificate's check. The loop is plain integer addition in
int64: :func:`gtsp_bench.proof.bounds.price_duals` bounds every sum below ``2**62`` before it
runs, so no sum wraps.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def add_member_pairs(indices: np.ndarray, indptr: np.ndarray, weights: np.ndarray,
                     out: np.ndarray) -> None:
    """Add ``weights[r]`` to ``out[i, j]`` for every row ``r`` and every ordered pair ``(i, j)``
    of its members ``indices[indptr[r]:indptr[r + 1]]`` (``i == j`` too): ``out += M' diag(w) M``
    for ``M`` the rows' 0/1 member masks."""
    for r in range(len(indptr) - 1):
        w = weights[r]
        a, b = indptr[r], indptr[r + 1]
        for p in range(a, b):
            i = indices[p]
            for q in range(a, b):
                out[i, indices[q]] += w


def warm_up() -> None:
    """Compile (first use on a machine) or load (from numba's cache) the loop on a tiny input."""
    out = np.zeros((2, 2), dtype=np.int64)
    add_member_pairs(np.array([0, 1], dtype=np.int64), np.array([0, 2], dtype=np.int64),
                     np.array([1], dtype=np.int64), out)

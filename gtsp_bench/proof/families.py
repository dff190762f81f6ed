"""The cut families a certificate may use: each row is rebuilt from its defining sets, and its
validity follows from the family's theorem once the sets pass :func:`parse_cut`'s checks.

Every row holds for every GTSP tour through at least three clusters (``y`` the heads, ``x`` the
tour's edges, ``z_CD = x(C : D)`` the tour over the clusters, a Hamiltonian cycle):

``gsec`` (generalized subtour elimination; sets ``Q`` (nodes), clusters ``C1 != C2``)
    ``x(E(Q)) <= y(Q - C1) + y(Q & C2)``. If the head of ``C1`` is in ``Q`` and that of ``C2`` is
    not, the tour leaves ``Q``, so its edges inside ``Q`` form paths: at most ``y(Q) - 1`` of
    them, which is the right-hand side. Otherwise the right-hand side is at least ``y(Q)``, the
    most edges a cycle has among ``y(Q)`` nodes.

``blossom`` (the 2-matching inequality of the tour over the clusters; handle ``H`` (clusters),
teeth ``F`` (cluster pairs, one end in ``H``, ``|F|`` odd))
    ``z(E(H)) + z(F) <= |H| + (|F| - 1) / 2``. With ``z(E(H)) = |H| - z(delta(H)) / 2``, it says
    ``a - b <= |F| - 1`` for ``a = z(F)``, ``b = z(delta(H) - F)``; ``a + b`` is even (a cycle
    crosses ``H`` an even number of times), so ``a = |F|`` (odd) forces ``b >= 1``.

Both are ``<=`` rows: their duals in a proof must be at most 0.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any

import numpy as np

from gtsp_bench.checks import all_ints, is_int

#: The families, by the name a certificate uses.
FAMILIES = ("gsec", "blossom")


@dataclass(frozen=True)
class Gsec:
    """``x(E(Q)) <= y(Q - C1) + y(Q & C2)``.

    Attributes
    ----------
    members
        ``(n_nodes,)`` bool mask of ``Q``.
    c1, c2
        The clusters.
    """

    members: np.ndarray
    c1: int
    c2: int

    @functools.cached_property
    def nodes(self) -> np.ndarray:
        """The members' node ids, ascending."""
        return np.flatnonzero(self.members)


def member_y_coef(cluster: np.ndarray, c1: Any, c2: Any) -> np.ndarray:
    """The ``y`` coefficient of a member node of cluster ``cluster`` in a gsec row of clusters
    ``c1``, ``c2`` (arrays broadcast, so that many rows' members are done at once): ``-1`` outside
    ``C1``, ``-1`` more inside ``C2``."""
    return -((cluster != c1).astype(np.int64) + (cluster == c2))


@dataclass(frozen=True)
class Blossom:
    """``z(E(H)) + z(F) <= |H| + (|F| - 1) / 2`` over the tour's cluster pairs.

    Attributes
    ----------
    handle
        ``(n_clusters,)`` bool mask of ``H``.
    teeth
        ``(|F|, 2)`` cluster pairs (inside ``H``, outside).
    """

    handle: np.ndarray
    teeth: np.ndarray

    @property
    def rhs(self) -> int:
        """``|H| + (|F| - 1) / 2`` (an integer: ``|F|`` is odd)."""
        return int(self.handle.sum()) + (len(self.teeth) - 1) // 2


Cut = Gsec | Blossom


def _ints(value: Any, what: str, low: int, high: int) -> np.ndarray:
    """A non-empty list of distinct integers in ``[low, high)``."""
    if not isinstance(value, list) or not value or not all_ints(value):
        raise ValueError(f"{what} must be a non-empty list of integers")
    arr = np.array(value, dtype=np.int64)
    if arr.min() < low or arr.max() >= high:
        raise ValueError(f"{what} names an id outside [{low}, {high})")
    if len(np.unique(arr)) != len(arr):
        raise ValueError(f"{what} repeats an id")
    return arr


def parse_cut(cut: Any, cluster_of: np.ndarray) -> Cut:
    """A cut of a certificate, its sets checked against its family.

    Parameters
    ----------
    cut
        The JSON object: ``{"family": "gsec", "Q": [nodes], "C1": c, "C2": d}`` or
        ``{"family": "blossom", "handle": [clusters], "teeth": [[c, d], ...]}``.
    cluster_of
        The cluster of each node of the priced problem.

    Returns
    -------
    Gsec or Blossom

    Raises
    ------
    ValueError
        Naming what makes the row not a member of its family (then it may be invalid).
    """
    if not isinstance(cut, dict) or cut.get("family") not in FAMILIES:
        family = cut.get("family") if isinstance(cut, dict) else None
        raise ValueError(f"unknown family {family!r} (valid: {', '.join(FAMILIES)})")
    n, m = len(cluster_of), int(cluster_of.max()) + 1
    if cut["family"] == "gsec":
        q = _ints(cut.get("Q"), "Q", 0, n)
        if len(q) == n:
            raise ValueError("Q holds every node (it must be a proper subset)")
        c1, c2 = cut.get("C1"), cut.get("C2")
        for name, c in (("C1", c1), ("C2", c2)):
            if not is_int(c) or not 0 <= c < m:
                raise ValueError(f"{name} must be a cluster in [0, {m})")
        if c1 == c2:
            raise ValueError("C1 and C2 are the same cluster")
        members = np.zeros(n, dtype=bool)
        members[q] = True
        return Gsec(members, int(c1), int(c2))
    h = _ints(cut.get("handle"), "handle", 0, m)
    if len(h) == m:
        raise ValueError("the handle holds every cluster (it must be a proper subset)")
    handle = np.zeros(m, dtype=bool)
    handle[h] = True
    teeth = cut.get("teeth")
    if not isinstance(teeth, list) or not teeth:
        raise ValueError("teeth must be a non-empty list of cluster pairs")
    pairs = []
    for t in teeth:
        if (not isinstance(t, list) or len(t) != 2
                or not all(is_int(v) and 0 <= v < m for v in t)):
            raise ValueError(f"tooth {t!r} is not a pair of clusters")
        if not (handle[t[0]] and not handle[t[1]]):
            raise ValueError(f"tooth {t!r} does not go from the handle to outside it")
        pairs.append((int(t[0]), int(t[1])))
    if len(set(pairs)) != len(pairs):
        raise ValueError("a tooth is repeated")
    if len(pairs) % 2 == 0:
        raise ValueError(f"{len(pairs)} teeth (a blossom needs an odd number)")
    return Blossom(handle, np.array(pairs, dtype=np.int64))

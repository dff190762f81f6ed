"""Random tiny instances with their brute-force optima, shared by the heuristics' tests."""

from __future__ import annotations

from functools import cache

import numpy as np

from gtsp_bench.checks import strictly_better
from gtsp_bench.generator import generate_instance
from gtsp_bench.instance import Instance
from gtsp_bench.registry import run_solver


@cache
def tiny_case(seed: int, depot: bool = True) -> tuple[Instance, float, float]:
    """``(instance, omega, optimum)``: K in 3..6 clusters of 1 to 4 nodes, a random omega.

    Without a depot the instance is a closed tour (as a ``.gtsp`` file).
    """
    rng = np.random.default_rng([seed, int(depot)])
    k = int(rng.integers(3, 7))
    base = generate_instance(k, 4, seed=[seed, 99])
    sizes = rng.integers(1, 5, size=k)
    inst = Instance(name=f"tiny-{seed}-{int(depot)}", depot=base.depot if depot else None,
                    clusters=tuple(c[:s] for c, s in zip(base.clusters, sizes, strict=True)))
    omega = float(rng.uniform())
    return inst, omega, run_solver("brute", inst, omega).objective


@cache
def tiny_asymmetric_case(seed: int) -> tuple[Instance, float]:
    """``(instance, optimum)``: an asymmetric GTSP (as an AGTSP file), K in 3..6 clusters of 1 to
    3 nodes, arc costs drawn independently in each direction (real numbers: no ties)."""
    rng = np.random.default_rng([seed, 7])
    k = int(rng.integers(3, 7))
    sizes = rng.integers(1, 4, size=k)
    n = int(sizes.sum())
    w = np.round(rng.uniform(1.0, 1000.0, size=(n, n)), 3)
    np.fill_diagonal(w, 0.0)
    inst = Instance(name=f"tiny-asym-{seed}", clusters=tuple(np.full((s, 2), np.nan) for s in sizes),
                    params=None, edge_weight_type="EXPLICIT", weights=w, symmetric=False)
    return inst, run_solver("brute", inst, None).objective


def not_below(cost: float, optimum: float) -> bool:
    """Whether ``cost`` is not below a proven ``optimum`` by the package's own rule
    (:func:`gtsp_bench.checks.strictly_better`: a relative 1e-9, for the rounding of sums taken in
    another order): what every heuristic's answer must satisfy."""
    return not strictly_better(cost, optimum)

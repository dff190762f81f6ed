"""Random tiny instances with their brute-force optima, shared by the heuristics' tests."""

from __future__ import annotations

from functools import cache

import numpy as np

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

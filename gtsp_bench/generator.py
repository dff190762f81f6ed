"""Seeded generator of UAV instances after the paper's section VI.

The depot (base station) is at (500, 0) in a 1000 m x 1000 m area. Each of the K cluster centres
is uniform in the area such that the cluster's square [x - zeta, x + zeta] x [y - zeta, y + zeta]
lies inside the area and overlaps no other cluster's square; each cluster's N nodes are uniform in
its square. The paper does not give zeta; the default is ``DEFAULT_ZETA`` = 50 m (squares of
100 m x 100 m, so members are at most ~141 m from any head and the d^4 regime of eq. (11) is used
for far members).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from gtsp_bench import checks
from gtsp_bench.checks import check_int, check_memory
from gtsp_bench.errors import InputError
from gtsp_bench.instance import Instance
from gtsp_bench.params import EnergyParams

DEFAULT_ZETA = 50.0
DEFAULT_AREA = 1000.0
DEFAULT_DEPOT = (500.0, 0.0)
DEFAULT_NODES = 20
#: Above this share of the area covered by cluster squares, random placement usually jams
#: (random sequential adsorption of squares jams near 56 %): refuse at once.
MAX_COVER = 0.5
_MAX_DRAWS = 10_000
#: Peak bytes a node costs while an instance is generated and written as JSON (numpy arrays,
#: Python lists of floats, the JSON text): an estimate checked before anything is allocated.
BYTES_PER_NODE = 320


def check_generator_memory(n_clusters: int, n_nodes: int) -> None:
    """Raise :class:`InputError` at once when K x N nodes would not fit in the memory this
    process can use (:func:`gtsp_bench.checks.memory_limit_bytes`), naming a size that would."""

    limit = checks.memory_limit_bytes()  # looked up here so that tests can patch it
    fit = max(int((limit or 0) // (BYTES_PER_NODE * n_clusters)), 1)
    check_memory(f"an instance of {n_clusters} clusters x {n_nodes} nodes", n_clusters * n_nodes
                 * BYTES_PER_NODE, f"use at most about {fit} nodes per cluster (--nodes)")


def check_generator_args(n_clusters: int, n_nodes: int, zeta: float, area: float) -> None:
    """Raise :class:`InputError` at once when the settings cannot give instances."""
    check_int("number of clusters", n_clusters, 1)
    check_int("number of nodes per cluster", n_nodes, 1)
    if not np.isfinite(zeta) or zeta <= 0:
        raise InputError(f"zeta must be > 0, got {zeta!r}")
    if not np.isfinite(area):
        raise InputError(f"area must be a finite length in m, got {area!r}")
    if area <= 2 * zeta:
        raise InputError(f"area {area!r} m must exceed 2 * zeta = {2 * zeta!r} m")
    cover = n_clusters * (2 * zeta) ** 2 / area**2
    if n_clusters > 1 and cover > MAX_COVER:  # one cluster always fits once area > 2 zeta
        raise InputError(
            f"{n_clusters} clusters of half-width zeta = {zeta:g} m would cover {cover:.0%} of a "
            f"{area:g} m square area; at most {MAX_COVER:.0%} can be placed without overlap "
            f"(use fewer clusters, a smaller zeta or a larger area)"
        )


def generate_centres(
    rng: np.random.Generator, batch: int, n_clusters: int, zeta: float, area: float
) -> np.ndarray:
    """Cluster centres ``(batch, K, 2)``: squares inside the area, pairwise non-overlapping."""
    lo, hi = zeta, area - zeta
    centres = np.empty((batch, n_clusters, 2))
    for k in range(n_clusters):
        pending = np.arange(batch)
        for _ in range(_MAX_DRAWS):
            cand = rng.uniform(lo, hi, size=(len(pending), 2))
            if k:
                gap = np.abs(cand[:, None, :] - centres[pending, :k]).max(axis=-1)
                ok = (gap >= 2 * zeta).all(axis=1)
            else:
                ok = np.ones(len(pending), dtype=bool)
            centres[pending[ok], k] = cand[ok]
            pending = pending[~ok]
            if pending.size == 0:
                break
        else:
            raise InputError(
                f"could not place cluster {k + 1} of {n_clusters} without overlap in "
                f"{_MAX_DRAWS} draws (zeta = {zeta:g} m, area = {area:g} m); "
                f"use fewer clusters or a smaller zeta"
            )
    return centres


def generate_batch(
    rng: np.random.Generator,
    batch: int,
    n_clusters: int,
    n_nodes: int = DEFAULT_NODES,
    zeta: float = DEFAULT_ZETA,
    area: float = DEFAULT_AREA,
) -> np.ndarray:
    """Node coordinates of ``batch`` instances, ``(batch, K, N, 2)`` (vectorised; for training).

    Parameters
    ----------
    rng
        NumPy random generator (the only source of randomness).
    batch, n_clusters, n_nodes
        B, K and N.
    zeta, area
        Cluster half-width and side of the square area (m).
    """
    check_generator_args(n_clusters, n_nodes, zeta, area)
    centres = generate_centres(rng, batch, n_clusters, zeta, area)
    offsets = rng.uniform(-zeta, zeta, size=(batch, n_clusters, n_nodes, 2))
    return centres[:, :, None, :] + offsets


def generate_instance(
    n_clusters: int,
    n_nodes: int = DEFAULT_NODES,
    seed: int | Sequence[int] = 0,
    *,
    zeta: float = DEFAULT_ZETA,
    area: float = DEFAULT_AREA,
    depot: tuple[float, float] = DEFAULT_DEPOT,
    params: EnergyParams | None = None,
    name: str | None = None,
) -> Instance:
    """One seeded UAV instance; the same arguments always give the same instance.

    Coordinates are rounded to the millimetre so that instance files stay small and round-trip
    exactly.

    Parameters
    ----------
    n_clusters, n_nodes
        K clusters of N nodes each.
    seed
        Seed (an int, or a sequence of ints such as ``[set_seed, index]``).
    zeta, area, depot
        Generator settings (m).
    params
        Energy parameters stored in the instance (defaults if ``None``).
    name
        Instance name; by default ``uav-K{K}-N{N}-s{seed}``.

    Raises
    ------
    InputError
        Settings that cannot give an instance, a size that would not fit in memory, or a negative
        or non-integer seed.
    """
    try:
        rng = np.random.default_rng(seed)
    except (TypeError, ValueError):
        raise InputError(f"seed must be an integer >= 0 or a sequence of them, got {seed!r}") from None
    check_generator_args(n_clusters, n_nodes, zeta, area)
    check_generator_memory(n_clusters, n_nodes)
    coords = np.round(generate_batch(rng, 1, n_clusters, n_nodes, zeta, area)[0], 3)
    seed_text = "-".join(str(s) for s in np.atleast_1d(seed))
    return Instance(
        name=name or f"uav-K{n_clusters}-N{n_nodes}-s{seed_text}",
        clusters=tuple(coords),
        depot=np.asarray(depot, dtype=np.float64),
        params=params or EnergyParams(),
        meta={"generator": {"n_clusters": n_clusters, "n_nodes": n_nodes, "zeta": zeta,
                            "area": area, "seed": np.atleast_1d(seed).tolist()}},
    )


def instance_set(
    n_instances: int,
    n_clusters: int,
    seed: int,
    n_nodes: int = DEFAULT_NODES,
    *,
    zeta: float = DEFAULT_ZETA,
    area: float = DEFAULT_AREA,
    params: EnergyParams | None = None,
) -> list[Instance]:
    """A seeded benchmark set: instance i is ``generate_instance(K, N, seed=[seed, K, i])``.

    Instance i is the same whatever ``n_instances`` is, so a larger set extends a smaller one.
    Names are ``uav-K{K}-N{N}-s{seed}-{i:03d}``. The base station is at ``(area / 2, 0)`` as in
    ``gtsp-bench generate``; the default area gives the paper's (500, 0).
    """
    return [
        generate_instance(n_clusters, n_nodes, [seed, n_clusters, i], zeta=zeta, area=area,
                          depot=(area / 2, 0.0), params=params,
                          name=f"uav-K{n_clusters}-N{n_nodes}-s{seed}-{i:03d}")
        for i in range(n_instances)
    ]

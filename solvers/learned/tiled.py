"""Label instances whose clusters tile the plane, as GTSPLIB's do.

The UAV generator's clusters are small squares far apart; GTSPLIB's are Fischetti, Salazar and
Toth's (1997) clustering of a TSPLIB point set: ``ceil(n / 5)`` centres, each the point farthest
from those already chosen, every point in its nearest centre's cluster. Neighbouring clusters
touch and interleave, the point sets are uniform, clumped or drilled on a grid, and there is no
depot and no node cost. A policy trained only on the squares is 10 % above the best known there
(the ``learned-transfer`` benchmark), so these instances give it labels of that kind.

A tiled instance is built as the local policy solves a distance-only file
(:mod:`~gtsp_bench.solvers.learned.distance`): ``5 (K + 1)`` points in a 1000 m square in one of
:data:`LAYOUTS`, clustered into ``K + 1``; one node of the smallest cluster (the anchor) is the
depot and the other ``K`` clusters are the instance. Labelled at omega 0, where a UAV instance's
cost is its flight distance times a constant plus a hover energy per cluster that no choice
changes: the distance-only problem.
"""

from __future__ import annotations

import numpy as np

from gtsp_bench.instance import Instance
from gtsp_bench.params import EnergyParams

#: Point layouts, drawn per instance: TSPLIB's sets are uniform (rd, kroA), clumped (d, u, fl)
#: or drilled / surveyed on a jittered grid (pr, pcb, rat, ts, lin).
LAYOUTS = ("uniform", "blobs", "grid")
#: Points per cluster, as GTSPLIB's ``ceil(n / 5)`` clusters.
POINTS_PER_CLUSTER = 5
SIDE = 1000.0


def layout_points(rng: np.random.Generator, n: int, layout: str) -> np.ndarray:
    """``(n, 2)`` points in the ``SIDE`` square: uniform; Gaussian clumps of random widths and
    weights; or a jittered grid with a random share of its sites used."""
    if layout == "uniform":
        return rng.uniform(0.0, SIDE, (n, 2))
    if layout == "blobs":
        m = int(rng.integers(3, 13))
        centres = rng.uniform(0.1 * SIDE, 0.9 * SIDE, (m, 2))
        widths = SIDE * rng.uniform(0.02, 0.12, m)
        pick = rng.choice(m, n, p=rng.dirichlet(np.ones(m)))
        xy = centres[pick] + rng.normal(size=(n, 2)) * widths[pick, None]
        return np.clip(xy, 0.0, SIDE)
    if layout == "grid":
        side = int(np.ceil(np.sqrt(n / rng.uniform(0.3, 0.9))))
        sites = rng.choice(side * side, n, replace=False)
        step = SIDE / side
        xy = np.stack([sites % side, sites // side], 1) * step + step / 2
        return xy + rng.normal(size=(n, 2)) * step * rng.uniform(0.0, 0.25)
    raise ValueError(f"unknown layout {layout!r} (valid: {', '.join(LAYOUTS)})")


def farthest_clusters(xy: np.ndarray, n_clusters: int, first: int) -> list[np.ndarray]:
    """Fischetti, Salazar and Toth's clustering: centres by farthest-point insertion from point
    ``first``, each point to its nearest centre. Returns each cluster's point indices, clusters
    in the order their centres were chosen (none is empty: a centre is in its own cluster)."""
    near = np.linalg.norm(xy - xy[first], axis=1)  # each point's distance to its centre
    owner = np.zeros(len(xy), dtype=np.int64)
    for c in range(1, n_clusters):
        d = np.linalg.norm(xy - xy[int(np.argmax(near))], axis=1)
        closer = d < near
        owner[closer] = c
        near = np.minimum(near, d)
    return [np.flatnonzero(owner == c) for c in range(n_clusters)]


def tiled_instance(n_clusters: int, seed: list[int], name: str) -> Instance:
    """One tiled UAV instance of ``n_clusters`` clusters (see the module's docstring); the
    layout is drawn from ``seed`` too."""
    rng = np.random.default_rng(seed)
    layout = LAYOUTS[int(rng.integers(len(LAYOUTS)))]
    xy = np.round(layout_points(rng, POINTS_PER_CLUSTER * (n_clusters + 1), layout), 3)
    groups = farthest_clusters(xy, n_clusters + 1, int(rng.integers(len(xy))))
    anchor = int(np.argmin([len(g) for g in groups]))
    depot = xy[groups[anchor][int(rng.integers(len(groups[anchor])))]]
    clusters = tuple(xy[g] for i, g in enumerate(groups) if i != anchor)
    return Instance(name=name, clusters=clusters, depot=depot.copy(), params=EnergyParams(),
                    meta={"generator": {"tiled": layout, "n_clusters": n_clusters,
                                        "seed": list(seed)}})


def tiled_set(count: int, n_clusters: int, seed: int) -> list[Instance]:
    """``count`` tiled instances; instance i from ``[seed, K, i]`` (a larger set extends a
    smaller one)."""
    return [tiled_instance(n_clusters, [seed, n_clusters, i],
                           f"tiled-K{n_clusters}-s{seed}-{i:03d}") for i in range(count)]

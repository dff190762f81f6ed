"""Tiled label instances: Fischetti's clustering, every layout, the anchor as depot, seeded."""

from __future__ import annotations

import numpy as np
import pytest
from gtsp_bench.solvers.learned.tiled import (
    LAYOUTS,
    POINTS_PER_CLUSTER,
    SIDE,
    farthest_clusters,
    layout_points,
    tiled_instance,
    tiled_set,
)


def test_farthest_clusters_by_hand():
    """Centres by farthest-point insertion from the first point; each point to its nearest."""
    xy = np.array([[0.0, 0.0], [1.0, 0.0], [10.0, 0.0], [9.0, 0.0], [5.2, 0.0], [4.0, 3.0]])
    groups = farthest_clusters(xy, 3, 0)
    # centres 0, then 2 (10 away), then 5 (5.0 from 0 beats point 4's 4.8 from 2); point 4 is
    # 3.2 from centre 5
    assert [g.tolist() for g in groups] == [[0, 1], [2, 3], [4, 5]]


@pytest.mark.parametrize("layout", LAYOUTS)
def test_layouts_fill_the_square(layout):
    xy = layout_points(np.random.default_rng(3), 400, layout)
    assert xy.shape == (400, 2) and np.isfinite(xy).all()
    assert len(np.unique(xy, axis=0)) == 400
    if layout != "grid":  # the jitter may step just outside
        assert (xy >= 0).all() and (xy <= SIDE).all()
    with pytest.raises(ValueError, match="uniform, blobs, grid"):
        layout_points(np.random.default_rng(3), 4, "ring")


def test_tiled_instance_is_a_clustering_with_the_anchor_as_depot():
    """K clusters of the 5 (K + 1) points, every point once, the depot one of the other points,
    and each point nearer its own cluster's centre than any other cluster's (a tiling)."""
    inst = tiled_instance(30, [9, 30, 0], "t")
    assert inst.n_clusters == 30 and inst.params is not None
    pts = np.concatenate(inst.clusters)
    assert len(pts) < POINTS_PER_CLUSTER * 31 and len(np.unique(pts, axis=0)) == len(pts)
    assert not (np.abs(pts - inst.depot).sum(1) == 0).any()  # the depot is not a cluster's node
    assert inst.meta["generator"]["tiled"] in LAYOUTS
    again = tiled_set(2, 30, 9)
    assert np.array_equal(np.concatenate(again[0].clusters), pts)
    assert again[1].name == "tiled-K30-s9-001"
    assert not np.array_equal(np.concatenate(again[1].clusters)[:5], pts[:5])

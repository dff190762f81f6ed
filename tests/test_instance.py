"""The instance model: validation, immutability, global numbering, TSPLIB distance rules."""

from __future__ import annotations

import numpy as np
import pytest

from gtsp_bench.errors import InputError
from gtsp_bench.instance import Instance, node_distance_matrix, pair_distances, tour_length


def test_global_numbering(tiny):
    """Nodes are numbered in cluster order; offsets, sizes and cluster_of agree."""
    assert tiny.n_clusters == 2
    assert tiny.n_nodes == 3
    assert tiny.sizes.tolist() == [1, 2]
    assert tiny.offsets.tolist() == [0, 1]
    assert tiny.cluster_of.tolist() == [0, 1, 1]
    assert tiny.coords.tolist() == [[0, 300], [400, 300], [300, 0]]
    assert tiny.is_uav


def test_arrays_are_read_only(tiny):
    """The instance cannot be changed in place."""
    with pytest.raises(ValueError, match="read-only"):
        tiny.clusters[0][0, 0] = 1.0
    with pytest.raises(ValueError, match="read-only"):
        tiny.depot[0] = 1.0
    with pytest.raises(AttributeError):
        tiny.name = "other"


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"clusters": ()}, "at least one cluster"),
        ({"clusters": (np.zeros((0, 2)),)}, "cluster 0 is empty"),
        ({"clusters": (np.array([[0.0, np.nan]]),)}, "cluster 0 has a NaN"),
        ({"clusters": (np.array([[0.0, np.inf]]),)}, "cluster 0 has a NaN or infinite"),
        ({"clusters": (np.zeros((2, 3)),)}, r"cluster 0 must be a list of \[x, y\] pairs"),
        ({"clusters": (np.zeros((1, 2)),), "depot": np.array([np.nan, 0.0])}, "depot has a NaN"),
        ({"clusters": (np.zeros((1, 2)),), "edge_weight_type": "EUC_2D"}, "must use EUCLIDEAN"),
        ({"clusters": (np.zeros((1, 2)),), "edge_weight_type": "XRAY", "params": None},
         "unknown edge weight type"),
        ({"clusters": (np.zeros((2, 2)),), "edge_weight_type": "EXPLICIT", "params": None},
         "need a weight matrix"),
    ],
)
def test_invalid_instances_are_rejected(kwargs, message):
    """Each malformed instance raises InputError naming the problem."""
    with pytest.raises(InputError, match=message):
        Instance(name="bad", **kwargs)


def test_tsplib_distance_rules():
    """EUC_2D rounds to nearest, CEIL_2D rounds up, ATT is pseudo-Euclidean (TSPLIB95)."""
    a, b = np.array([0.0, 0.0]), np.array([1.0, 1.0])  # 1.414...
    assert pair_distances(a, b, "EUCLIDEAN") == pytest.approx(2**0.5)
    assert pair_distances(a, b, "EUC_2D") == 1.0
    assert pair_distances(a, np.array([1.5, 1.0]), "EUC_2D") == 2.0  # 1.803 -> 2
    assert pair_distances(a, b, "CEIL_2D") == 2.0
    # ATT: r = sqrt(200 / 10) = 4.47, nint = 4 < r, so 5.
    assert pair_distances(a, np.array([10.0, 10.0]), "ATT") == 5.0
    # ATT: r = sqrt(250 / 10) = 5 exactly, so 5.
    assert pair_distances(a, np.array([15.0, 5.0]), "ATT") == 5.0


def test_geo_distance_follows_tsplib():
    """GEO: coordinates are DDD.MM; the TSPLIB formula with RRR = 6378.388 and the +1 rounding."""
    # Two points one degree of latitude apart on the same meridian: 6378.388 * pi/180 = 111.3 km.
    d = pair_distances(np.array([10.0, 20.0]), np.array([11.0, 20.0]), "GEO")
    assert d == 112.0  # int(111.32 + 1.0)
    # 30 minutes (x.30) is half a degree.
    d_half = pair_distances(np.array([10.0, 20.0]), np.array([10.30, 20.0]), "GEO")
    assert d_half == 56.0  # int(55.66 + 1.0)


def test_geom_distance_is_great_circle_metres():
    """GEOM: exact degrees, a sphere of radius 6378388 m, int(d + 1) (LKH, Concorde); checked
    against the haversine formula on long and short legs."""
    import math

    def haversine(a, b):
        (la, lo), (lb, lob) = (tuple(math.radians(v) for v in p) for p in (a, b))
        h = math.sin((lb - la) / 2) ** 2 + math.cos(la) * math.cos(lb) * math.sin((lob - lo) / 2) ** 2
        return 6378388.0 * 2 * math.asin(math.sqrt(h))

    for a, b in [((40.0, 75.0), (34.05, 118.25)), ((33.58, 85.85), (32.67, 85.44)), ((-10, 5), (10, -5))]:
        d = pair_distances(np.array(a), np.array(b), "GEOM")
        assert d == math.floor(haversine(a, b) + 1.0)
        assert pair_distances(np.array(b), np.array(a), "GEOM") == d


def test_distance_matrix_puts_the_depot_last(tiny):
    """The matrix has the depot as its last row and column, zero diagonal, symmetric; its points
    (``node_points``, read-only) are the nodes' then the depot's."""
    assert tiny.node_points.tolist() == [[0, 300], [400, 300], [300, 0], tiny.depot.tolist()]
    assert not tiny.node_points.flags.writeable
    w = node_distance_matrix(tiny)
    assert w.shape == (4, 4)
    assert w[3, 0] == 300.0 and w[3, 2] == 300.0
    np.testing.assert_array_equal(w, w.T)
    assert np.all(np.diag(w) == 0)


def test_tour_length_without_depot_is_a_cycle():
    """Without a depot the tour closes on its first node."""
    inst = Instance(name="c", clusters=(np.array([[0.0, 0.0]]), np.array([[3.0, 4.0]]),
                                         np.array([[3.0, 0.0]])), params=None)
    assert tour_length(inst, np.array([0, 1, 2]), np.array([0, 0, 0])) == pytest.approx(12.0)


@pytest.mark.parametrize("rule", ["EUCLIDEAN", "EUC_2D", "CEIL_2D", "ATT", "GEO"])
def test_distance_matrix_in_row_chunks_is_the_broadcast_one(monkeypatch, rule):
    """Filled a few rows at a time (in place for the planar rules), the matrix is exactly the
    all-pairs broadcast of :func:`pair_distances`, ties at .5 included."""
    import gtsp_bench.instance as instance_module

    rng = np.random.default_rng(3)
    clusters = tuple(rng.integers(0, 2000, (5, 2)) / 2.0 for _ in range(7))
    if rule == "EUCLIDEAN":
        inst = Instance(name="chunks", clusters=clusters, depot=np.array([500.0, 0.0]))
        pts = np.vstack([inst.coords, inst.depot])
    else:
        inst = Instance(name="chunks", clusters=clusters, params=None, edge_weight_type=rule)
        pts = inst.coords
    monkeypatch.setattr(instance_module, "_CHUNK_BYTES", 16 * len(pts) * 3)  # three rows at a time
    monkeypatch.setattr(instance_module, "_PLANAR_CHUNK_BYTES", 8 * len(pts) * 3)
    want = pair_distances(pts[:, None, :], pts[None, :, :], rule)
    np.fill_diagonal(want, 0.0)
    assert np.array_equal(node_distance_matrix(inst), want)


def test_a_matrix_too_large_is_refused_before_allocating():
    """An instance above MAX_MATRIX_NODES nodes: one InputError line naming the size, no matrix."""
    from gtsp_bench.instance import MAX_MATRIX_NODES
    from gtsp_bench.problem import price

    n = MAX_MATRIX_NODES + 1
    inst = Instance(name="huge", clusters=(np.zeros((n, 2)),), params=None, edge_weight_type="EUC_2D")
    with pytest.raises(InputError, match=rf"^huge has {n:,} nodes: its full cost matrix would need 7.63 GiB"):
        price(inst, None)


def test_asymmetric_weights_need_the_flag():
    """Only symmetric=False admits a matrix that differs from its transpose, and only EXPLICIT
    weights can be asymmetric; the tour is priced in its direction."""
    w = np.array([[0.0, 1.0, 5.0], [7.0, 0.0, 2.0], [3.0, 11.0, 0.0]])
    clusters = tuple(np.full((1, 2), np.nan) for _ in range(3))
    with pytest.raises(InputError, match=r"^weight matrix is not symmetric"):
        Instance(name="a", clusters=clusters, params=None, edge_weight_type="EXPLICIT", weights=w)
    with pytest.raises(InputError, match="only EXPLICIT edge weights can be asymmetric"):
        Instance(name="a", clusters=(np.zeros((2, 2)),), params=None, edge_weight_type="EUC_2D",
                 symmetric=False)
    inst = Instance(name="a", clusters=clusters, params=None, edge_weight_type="EXPLICIT", weights=w,
                    symmetric=False)
    there = tour_length(inst, np.array([0, 1, 2]), np.zeros(3, dtype=np.int64))
    back = tour_length(inst, np.array([0, 2, 1]), np.zeros(3, dtype=np.int64))
    assert (there, back) == (1.0 + 2.0 + 3.0, 5.0 + 11.0 + 7.0)

"""The generator: seeded, inside the area, non-overlapping, fails fast when impossible."""

from __future__ import annotations

import time

import numpy as np
import pytest

from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_batch, generate_instance


def test_same_seed_same_instance_other_seed_other_instance():
    """Generation is reproducible from the seed alone."""
    a, b = generate_instance(7, seed=3), generate_instance(7, seed=3)
    c = generate_instance(7, seed=4)
    for x, y in zip(a.clusters, b.clusters, strict=True):
        np.testing.assert_array_equal(x, y)
    assert not np.array_equal(a.coords, c.coords)
    assert a.name == "uav-K7-N20-s3"
    assert a.depot.tolist() == [500.0, 0.0]


@pytest.mark.parametrize(("k", "zeta"), [(4, 50.0), (10, 50.0), (30, 50.0), (10, 100.0)])
def test_clusters_inside_area_and_not_overlapping(k, zeta):
    """Every node lies in its cluster's square; squares are inside the area and disjoint."""
    coords = generate_batch(np.random.default_rng(k), 50, k, 20, zeta=zeta)
    assert coords.shape == (50, k, 20, 2)
    lo, hi = coords.min(axis=2), coords.max(axis=2)  # (B, K, 2) bounding boxes
    assert np.all(hi - lo <= 2 * zeta)
    centres = (lo + hi) / 2
    assert np.all(lo > 0) and np.all(hi < 1000)
    # Squares of half-width zeta around the true centres are disjoint, so any two clusters are
    # separated along some axis by at least the width of their bounding boxes' gap.
    for b in range(50):
        for i in range(k):
            for j in range(i):
                sep = np.maximum(lo[b, i] - hi[b, j], lo[b, j] - hi[b, i])
                assert np.max(sep) > -1e-9, (b, i, j, centres[b, i], centres[b, j])


def test_impossible_settings_fail_fast_with_a_clear_message():
    """Too many clusters for the area is refused at once, not after an endless loop."""
    start = time.perf_counter()
    with pytest.raises(InputError, match=r"would cover .* at most 50%"):
        generate_instance(60, seed=0, zeta=50.0)
    with pytest.raises(InputError, match="must exceed 2 \\* zeta"):
        generate_instance(1, seed=0, zeta=600.0)
    assert time.perf_counter() - start < 1.0


def test_one_cluster_fits_whenever_the_area_exceeds_its_square():
    """The coverage rule is about placing several squares; a single one is never refused."""
    inst = generate_instance(1, 3, seed=0, zeta=50.0, area=120.0)
    assert np.all((inst.coords >= 0) & (inst.coords <= 120.0))
    with pytest.raises(InputError, match="would cover"):
        generate_instance(2, 3, seed=0, zeta=50.0, area=120.0)


def test_infinite_area_is_refused_as_such():
    """An infinite area is refused for what it is, not as too small."""
    with pytest.raises(InputError, match="area must be a finite length in m, got inf"):
        generate_instance(3, 3, seed=0, area=float("inf"))


@pytest.mark.parametrize("bad", [{"n_clusters": 0}, {"n_nodes": 0}, {"zeta": -1.0}])
def test_bad_arguments(bad):
    """Non-positive K, N or zeta are rejected."""
    args = {"n_clusters": 3, "n_nodes": 5, "zeta": 50.0} | bad
    with pytest.raises(InputError):
        generate_instance(args["n_clusters"], args["n_nodes"], seed=0, zeta=args["zeta"])


@pytest.mark.parametrize("seed", [-1, [3, -1], 1.5, "7"])
def test_bad_seed_is_an_input_error(seed):
    """numpy's own error (a ValueError or TypeError) becomes an InputError naming the seed."""
    with pytest.raises(InputError, match="seed must be an integer >= 0"):
        generate_instance(3, 4, seed=seed)


def test_centres_are_two_zeta_apart_along_some_axis():
    """The centres themselves satisfy the non-overlap rule max(|dx|, |dy|) >= 2 zeta."""
    from gtsp_bench.generator import generate_centres

    c = generate_centres(np.random.default_rng(1), 20, 25, 50.0, 1000.0)
    gap = np.abs(c[:, :, None, :] - c[:, None, :, :]).max(axis=-1)
    gap[:, np.arange(25), np.arange(25)] = np.inf
    assert gap.min() >= 100.0
    assert c.min() >= 50.0 and c.max() <= 950.0


def test_instance_set_is_prefix_stable():
    """Instance i of a set does not depend on the set's size; names carry K, seed and index."""
    from gtsp_bench.generator import instance_set

    small, big = instance_set(2, 4, seed=9), instance_set(5, 4, seed=9)
    np.testing.assert_array_equal(small[1].coords, big[1].coords)
    assert big[4].name == "uav-K4-N20-s9-004"
    assert not np.array_equal(big[0].coords, big[1].coords)


def test_a_size_beyond_the_available_memory_is_refused_before_allocating(monkeypatch):
    """K x N nodes whose estimate exceeds the memory available: InputError at once, naming a
    size that fits; a size within it is generated."""
    from gtsp_bench import checks, generator

    monkeypatch.setattr(checks, "memory_limit_bytes", lambda: 2**30)
    start = time.perf_counter()
    with pytest.raises(InputError, match=r"4 clusters x 100000000 nodes needs about 119 GiB of "
                                         r"memory, more than the 1 GiB available; use at most about "
                                         r"838860 nodes per cluster"):
        generate_instance(4, 100_000_000)
    assert time.perf_counter() - start < 1.0
    fits = 2**30 // (generator.BYTES_PER_NODE * 4)
    with pytest.raises(InputError, match="needs about"):
        generator.check_generator_memory(4, fits + 1)
    generator.check_generator_memory(4, fits)
    assert generate_instance(2, 3).n_nodes == 6

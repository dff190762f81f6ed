"""A benchmark's sources read into entries: GTSPLIB by name, size group, symmetry and GLNS's
list; generated sets written beside the run unless committed; -K and --names."""

from __future__ import annotations

import pytest

from gtsp_bench.bench.definitions import BENCHMARKS, Committed, Generated, Gtsplib
from gtsp_bench.bench.sources import glns_times, load_sources
from gtsp_bench.errors import InputError
from tests.conftest import REPO

INSTANCES = REPO / "instances"


def test_gtsplib_by_size_group_takes_the_smallest_symmetric_files_of_each():
    """Each group gets its first files in best_known.csv order, within its node range."""
    groups = (("small", 1, 200), ("middle", 201, 500))
    entries = load_sources([Gtsplib(size_groups=groups, per_group=2)], INSTANCES)
    assert [e.set for e in entries] == ["small", "small", "middle", "middle"]
    assert all(e.stored.instance.symmetric for e in entries)
    assert all(e.stored.instance.n_nodes <= 200 for e in entries[:2])
    assert all(201 <= e.stored.instance.n_nodes <= 500 for e in entries[2:])
    assert all(e.references[None].status in ("optimal", "best_known") for e in entries)


def test_agtsp_and_glns_lists():
    """The asymmetric group holds only AGTSP files; GLNS's 45 carry GLNS's time."""
    agtsp = load_sources([Gtsplib(symmetric_only=False, asymmetric_only=True, max_nodes=200)], INSTANCES)
    assert agtsp and not any(e.stored.instance.symmetric for e in agtsp)
    times = glns_times()
    assert len(times) == 45
    glns = load_sources([Gtsplib(group="glns-45", symmetric_only=False, max_nodes=160)], INSTANCES)
    assert glns and all(e.glns_s == times[e.stem] for e in glns)


def test_generated_sets_go_beside_the_run_unless_committed(tmp_path):
    """A set committed under instances/ is read there; another is written into the scratch
    folder, never into instances/; -K sets the generated K and filters the other sources."""
    committed = load_sources([Generated((4,), 2, seed=1)], INSTANCES, scratch=tmp_path)
    assert all(INSTANCES in e.stored.path.parents for e in committed)
    assert committed[0].references, "the committed set's reference.csv is read"
    fresh = load_sources([Generated((4,), 2, seed=0), Gtsplib(("11berlin52",))], tmp_path / "none",
                         ks=(3,), scratch=tmp_path / "scratch")
    assert [e.k for e in fresh] == [3, 3]
    assert all((tmp_path / "scratch") in e.stored.path.parents for e in fresh)
    assert not (INSTANCES / "uav-K3-N20-s0").exists()


def test_names_keep_those_instances_and_a_missing_name_is_an_error():
    """--names filters by file stem; a name no source holds is one clear error."""
    picked = load_sources([Committed(("uav-K20-N20-s1",))], INSTANCES, names=("uav-K20-N20-s1-003",))
    assert [e.stem for e in picked] == ["uav-K20-N20-s1-003"]
    with pytest.raises(InputError, match="--names: no instance 'nope'"):
        load_sources([Committed(("uav-K20-N20-s1",))], INSTANCES, names=("nope",))
    with pytest.raises(InputError, match="no GTSPLIB instance 'nope'"):
        load_sources([Gtsplib(("nope",))], INSTANCES)


def test_every_definitions_sources_load(tmp_path):
    """Each benchmark's quick sources resolve (no solve): a renamed set or file would fail here."""
    for b in BENCHMARKS.values():
        q = b.quick_variant()
        entries = load_sources(q.sources, INSTANCES, scratch=tmp_path)
        assert entries, b.name

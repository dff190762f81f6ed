"""File I/O: round trips through tmp_path (gzip-compressed too), file names in errors, atomic
writes, tour files."""

from __future__ import annotations

import gzip
import os
import stat

import numpy as np
import pytest

from gtsp_bench.data import gtsplib
from gtsp_bench.data.io import (
    atomic_write_csv,
    atomic_write_json,
    atomic_write_text,
    format_suffix,
    read_instance,
    read_solution,
    read_solution_file,
    read_tour,
    write_instance,
    write_tour,
)
from gtsp_bench.data.parse import parse_tour
from gtsp_bench.energy import evaluate
from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance
from tests.conftest import GTSPLIB


def test_json_file_round_trip(tmp_path):
    """write_instance -> read_instance keeps a generated instance exactly."""
    inst = generate_instance(5, 4, seed=2)
    path = write_instance(inst, tmp_path / "k5.json")
    again = read_instance(path)
    assert again.name == inst.name
    for a, b in zip(inst.clusters, again.clusters, strict=True):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(again.depot, inst.depot)
    assert dict(again.meta) == dict(inst.meta)


def test_gtsp_file_round_trip(tmp_path):
    """A GTSPLIB sample written back and read again has identical clusters."""
    inst = read_instance(GTSPLIB / "20kroA100.gtsp.gz")
    again = read_instance(write_instance(inst, tmp_path / "copy.gtsp"))
    assert again.n_clusters == 20
    for a, b in zip(inst.clusters, again.clusters, strict=True):
        np.testing.assert_array_equal(a, b)


def test_errors_name_the_file(tmp_path):
    """Missing, malformed, binary, directory and unknown-format files name their path."""
    missing = tmp_path / "nope.json"
    with pytest.raises(InputError, match=f"^{missing}: no such file$"):
        read_instance(missing)
    bad = tmp_path / "bad.json"
    bad.write_text('{"clusters": [[]]}')
    with pytest.raises(InputError, match=rf"^{bad}: clusters\[0\] is empty$"):
        read_instance(bad)
    other = tmp_path / "x.txt"
    other.write_text("")
    with pytest.raises(InputError, match=f"^{other}: unknown instance format"):
        read_instance(other)
    folder = tmp_path / "dir.json"
    folder.mkdir()
    with pytest.raises(InputError, match=f"^{folder}: is a directory"):
        read_instance(folder)
    binary = tmp_path / "bin.gtsp"
    binary.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(InputError, match=f"^{binary}: not a UTF-8 text file$"):
        read_instance(binary)


def test_solution_file_errors_name_the_file(tmp_path):
    """A malformed solution file is reported with its path."""
    sol = tmp_path / "sol.json"
    sol.write_text('{"order": [0]}')
    with pytest.raises(InputError, match=f"^{sol}: missing key 'heads'$"):
        read_solution(sol)
    with pytest.raises(InputError, match="no such file"):
        read_solution(tmp_path / "none.json")


def test_atomic_write_leaves_no_temporary_files(tmp_path):
    """After an atomic write only the target exists, with the new content."""
    target = tmp_path / "sub" / "out.txt"
    atomic_write_text(target, "one")
    atomic_write_text(target, "two")
    assert target.read_text() == "two"
    assert [p.name for p in target.parent.iterdir()] == ["out.txt"]


def test_tables_and_manifests_round_trip_in_the_suites_format(tmp_path):
    """A table is written without its index, floats to 10 significant digits, and reads back; a
    manifest is indented JSON ending in a newline; neither leaves a temporary file."""
    import json

    import pandas as pd

    table = pd.DataFrame({"instance": ["a", "b"], "objective": [1 / 3, 2.0], "K": [5, 7]})
    atomic_write_csv(tmp_path / "rows.csv", table)
    assert (tmp_path / "rows.csv").read_text() == "instance,objective,K\na,0.3333333333,5\nb,2,7\n"
    back = pd.read_csv(tmp_path / "rows.csv")
    assert back["objective"].tolist() == pytest.approx([1 / 3, 2.0], rel=1e-9)
    atomic_write_json(tmp_path / "manifest.json", {"merges": [{"added": 1}]})
    text = (tmp_path / "manifest.json").read_text()
    assert text.endswith("}\n") and json.loads(text) == {"merges": [{"added": 1}]}
    assert "\n " in text  # indented
    assert sorted(p.name for p in tmp_path.iterdir()) == ["manifest.json", "rows.csv"]


def test_atomic_write_gives_ordinary_permissions(tmp_path):
    """A new file is readable as after a plain write (0o666 less the umask), not owner-only;
    an existing file keeps its mode."""
    umask = os.umask(0o022)
    try:
        target = tmp_path / "new.csv"
        atomic_write_text(target, "a")
        assert stat.S_IMODE(target.stat().st_mode) == 0o644
        target.chmod(0o600)
        atomic_write_text(target, "b")
        assert stat.S_IMODE(target.stat().st_mode) == 0o600 and target.read_text() == "b"
    finally:
        os.umask(umask)


def test_atomic_write_leaves_the_process_umask_alone(tmp_path, monkeypatch):
    """The kernel applies the umask to the new file; the process umask is never set (setting it,
    even for a moment, races with other threads creating files)."""
    def no_umask(mask):
        raise AssertionError("os.umask called")

    monkeypatch.setattr(os, "umask", no_umask)
    atomic_write_text(tmp_path / "a.txt", "x")
    assert (tmp_path / "a.txt").read_text() == "x"


def test_atomic_write_onto_a_directory_is_an_input_error(tmp_path):
    """Writing to a path that is a directory names the path; no temporary file is left."""
    folder = tmp_path / "out.json"
    folder.mkdir()
    with pytest.raises(InputError, match=f"^{folder}: cannot write"):
        atomic_write_text(folder, "x")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.json"]


def test_gzip_instances_read_as_the_plain_file(tmp_path):
    """A .gtsp.gz reads exactly like its decompressed .gtsp."""
    packed = GTSPLIB / "11berlin52.gtsp.gz"
    plain = tmp_path / "11berlin52.gtsp"
    plain.write_bytes(gzip.decompress(packed.read_bytes()))
    a, b = read_instance(packed), read_instance(plain)
    assert a.name == b.name == "11berlin52" and a.n_clusters == 11
    np.testing.assert_array_equal(a.coords, b.coords)
    assert dict(a.meta) == dict(b.meta)


@pytest.mark.parametrize("suffix", [".gtsp.gz", ".json.gz", ".GTSP.GZ"])
def test_gzip_write_round_trip(tmp_path, suffix):
    """A .gz suffix writes gzip (reproducibly, the same bytes twice) that reads back intact."""
    inst = read_instance(GTSPLIB / "20kroA100.gtsp.gz") if "gtsp" in suffix.lower() else (
        generate_instance(4, 3, seed=1))
    path = write_instance(inst, tmp_path / f"x{suffix}")
    first = path.read_bytes()
    assert first[:2] == b"\x1f\x8b"  # the gzip magic number
    plain = write_instance(inst, tmp_path / f"x{suffix[:-3]}")
    assert gzip.decompress(first) == plain.read_bytes()
    write_instance(inst, path)
    assert path.read_bytes() == first
    again = read_instance(path)
    for a, b in zip(inst.clusters, again.clusters, strict=True):
        np.testing.assert_array_equal(a, b)
    if inst.is_uav:
        assert again.name == inst.name


def test_json_gz_name_defaults_to_the_file_stem(tmp_path):
    """A JSON instance without a name takes the file name less .json.gz."""
    path = tmp_path / "field.json.gz"
    path.write_bytes(gzip.compress(b'{"depot": [0, 0], "clusters": [[[1, 2]]]}'))
    assert read_instance(path).name == "field"


def test_format_suffix():
    """The suffix before .gz names the format."""
    assert format_suffix("a/b.gtsp.gz") == ".gtsp"
    assert format_suffix("b.JSON") == ".json"
    assert format_suffix("b.gz") == ""


def test_bad_gzip_files_are_one_input_error(tmp_path):
    """Not gzip, truncated, corrupt, or gzip of bytes that are not UTF-8: one InputError each."""
    good = gzip.compress(b"NAME: x\n" * 100, mtime=0)
    corrupt = bytearray(good)
    corrupt[-8] ^= 0xFF  # the CRC
    cases = {
        "plain.gtsp.gz": (b"NAME: x\n", "not a valid gzip file"),
        "cut.gtsp.gz": (good[: len(good) // 2], "not a valid gzip file"),
        "crc.gtsp.gz": (bytes(corrupt), "not a valid gzip file"),
        "bin.gtsp.gz": (gzip.compress(b"\xff\xfe\x00"), "not a UTF-8 text file"),
    }
    for name, (data, message) in cases.items():
        path = tmp_path / name
        path.write_bytes(data)
        with pytest.raises(InputError, match=f"^{path}: {message}"):
            read_instance(path)
    with pytest.raises(InputError, match="unknown instance format"):
        read_instance(tmp_path / "x.txt.gz")
    with pytest.raises(InputError, match="unknown instance format"):
        write_instance(generate_instance(3, 2, seed=0), tmp_path / "x.gz")


def test_read_tour(tmp_path):
    """A TSPLIB tour file (.tour or .tour.gz) of a GTSPLIB instance reads as (order, heads)."""
    inst = read_instance(GTSPLIB / "11berlin52.gtsp.gz")
    packed = GTSPLIB / "tours" / "11berlin52.4040.tour.gz"
    order, heads = read_tour(packed, inst)
    assert sorted(order) == list(range(11)) and len(heads) == 11
    plain = tmp_path / "t.tour"
    plain.write_bytes(gzip.decompress(packed.read_bytes()))
    assert read_tour(plain, inst) == (order, heads)
    plain.write_text("TOUR_SECTION\n999\n-1\n")
    with pytest.raises(InputError, match=f"^{plain}: tour names node 999"):
        read_tour(plain, inst)


@pytest.mark.parametrize("suffix", [".tour", ".tour.gz"])
def test_uav_tour_file_round_trip(tmp_path, suffix):
    """A UAV solution written as a tour file (plain or gzip) reads back as the same solution, at
    the same energy; its ids are the heads' 1-based node numbers in cluster order."""
    inst = generate_instance(5, 4, seed=3)
    order, heads = [3, 0, 4, 1, 2], [1, 3, 0, 2, 1]
    path = write_tour(inst, tmp_path / f"t{suffix}", order, heads, comments=["five clusters"])
    assert read_solution_file(path, inst) == (order, heads)
    text = gzip.decompress(path.read_bytes()).decode() if suffix.endswith(".gz") else path.read_text()
    assert parse_tour(text) == [4 * c + heads[c] + 1 for c in order]
    assert "COMMENT : five clusters" in text
    again = read_solution_file(path, inst)
    assert evaluate(inst, 0.4, *again).objective == evaluate(inst, 0.4, order, heads).objective


@pytest.mark.parametrize("name", ["11berlin52", "20gr96", "10gr48", "10ftv47"])
def test_gtsplib_gtsp_and_tour_round_trip(tmp_path, name):
    """EUC_2D, GEO, a LOWER_DIAG_ROW matrix and an asymmetric file: the instance written as .gtsp
    and GLKH's tour written against the copy read back at the best-known length; written against
    the original file, the tour lists GLKH's own node ids."""
    original = gtsplib.read(name)
    order, heads = gtsplib.best_tour(name, original)
    best = gtsplib.best_known()[name].value
    copy = read_instance(write_instance(original, tmp_path / f"{name}.gtsp"))
    path = write_tour(copy, tmp_path / f"{name}.tour", order, heads)
    assert read_solution_file(path, copy) == (order, heads)
    assert evaluate(copy, None, order, heads).objective == best
    ours = write_tour(original, tmp_path / "original.tour", order, heads)
    glkh = gzip.decompress(gtsplib.tour_path(name).read_bytes()).decode()
    assert parse_tour(ours.read_text()) == parse_tour(glkh)


def test_read_solution_file_chooses_by_suffix(tmp_path):
    """.tour and .tour.gz read as tours; any other name as a solution JSON object."""
    inst = read_instance(GTSPLIB / "11berlin52.gtsp.gz")
    order, heads = read_tour(GTSPLIB / "tours" / "11berlin52.4040.tour.gz", inst)
    sol = tmp_path / "sol.txt"
    sol.write_text(f'{{"order": {order}, "heads": {heads}}}')
    assert read_solution_file(sol, inst) == (order, heads)
    assert read_solution_file(GTSPLIB / "tours" / "11berlin52.4040.tour.gz", inst) == (order, heads)


def test_a_tour_of_another_instance_or_missing_a_node_is_refused(tmp_path):
    """Each bad tour file is one InputError that starts with its path and says what is wrong."""
    berlin = GTSPLIB / "tours" / "11berlin52.4040.tour.gz"
    with pytest.raises(InputError, match=f"^{berlin}: the tour lists 11 nodes, but a tour of 20kroA100 "
                                         "lists one node of each of its 20 clusters$"):
        read_solution_file(berlin, read_instance(GTSPLIB / "20kroA100.gtsp.gz"))
    inst = read_instance(GTSPLIB / "11berlin52.gtsp.gz")
    ids = parse_tour(gzip.decompress(berlin.read_bytes()).decode())
    short = tmp_path / "short.tour"
    short.write_text("TOUR_SECTION\n" + "\n".join(map(str, ids[:-1])) + "\n-1\n")
    with pytest.raises(InputError, match=f"^{short}: the tour lists 10 nodes, but a tour of 11berlin52"):
        read_solution_file(short, inst)
    twice = tmp_path / "twice.tour"  # node 22's cluster visited twice, another cluster never
    twice.write_text("TOUR_SECTION\n" + "\n".join(map(str, [ids[0], *ids[:-1]])) + "\n-1\n")
    with pytest.raises(InputError, match=f"^{twice}: infeasible solution: cluster .* is visited 2 times$"):
        read_solution_file(twice, inst)
    unknown = tmp_path / "unknown.tour"
    unknown.write_text("TOUR_SECTION\n" + "\n".join(map(str, [*ids[:-1], 53])) + "\n-1\n")
    with pytest.raises(InputError, match=rf"^{unknown}: tour names node 53, which is not in 11berlin52 "
                                         r"\(its nodes are 1..52\)$"):
        read_solution_file(unknown, inst)


def test_write_tour_needs_a_tour_name(tmp_path):
    """Only a .tour (or .tour.gz) name is read back as a tour, so no other is written."""
    inst = generate_instance(3, 2, seed=0)
    with pytest.raises(InputError, match=r"sol.json: a tour file's name ends in .tour \(or .tour.gz\)$"):
        write_tour(inst, tmp_path / "sol.json", [0, 1, 2], [0, 0, 0])
    assert list(tmp_path.iterdir()) == []

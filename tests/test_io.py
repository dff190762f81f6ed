"""File I/O: round trips through tmp_path, file names in errors, atomic writes."""

from __future__ import annotations

import os
import stat

import numpy as np
import pytest

from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance
from gtsp_bench.io import atomic_write_text, read_instance, read_solution, write_instance

from .conftest import GTSPLIB


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
    inst = read_instance(GTSPLIB / "20kroA100.gtsp")
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

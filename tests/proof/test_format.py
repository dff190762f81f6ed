"""The certificate file: written and read back, bad files refused in one line, variables."""

from __future__ import annotations

import gzip
import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance
from gtsp_bench.problem import price
from gtsp_bench.proof.format import (
    FORMAT,
    READABLE,
    VERSION,
    fingerprint,
    parse_var,
    read_certificate,
    var_name,
    write_certificate,
)


def test_round_trip(tmp_path: Path) -> None:
    cert = {"format": FORMAT, "version": VERSION, "nodes": [{}]}
    size = write_certificate(tmp_path / "a.cert.json.gz", cert)
    assert size == (tmp_path / "a.cert.json.gz").stat().st_size
    assert read_certificate(tmp_path / "a.cert.json.gz") == cert
    assert VERSION == 2 and READABLE == (1, 2)
    old = dict(cert, version=1)  # the first version is still read
    write_certificate(tmp_path / "v1.cert.json.gz", old)
    assert read_certificate(tmp_path / "v1.cert.json.gz") == old
    (tmp_path / "b.json").write_text(json.dumps(cert))  # plain JSON is read too
    assert read_certificate(tmp_path / "b.json") == cert


@pytest.mark.parametrize(("data", "reason"), [
    (b"\x1f\x8b broken", "not a certificate \\(not gzip-compressed JSON"),
    (b"{nope", "not a certificate \\(not gzip-compressed JSON"),
    (json.dumps({"format": "other"}).encode(), "no 'format'"),
    (gzip.compress(json.dumps({"format": FORMAT, "version": 99}).encode()),
     "version 99; this checker reads versions 1, 2"),
])
def test_bad_files_are_refused(tmp_path: Path, data: bytes, reason: str) -> None:
    path = tmp_path / "x.cert.json.gz"
    path.write_bytes(data)
    with pytest.raises(InputError, match=f"{path}: .*{reason}"):
        read_certificate(path)
    with pytest.raises(InputError, match="cannot read"):
        read_certificate(tmp_path / "missing")


def test_fingerprint_names_the_costs() -> None:
    """The same costs, priced twice (another instance object), give one fingerprint; another
    omega, or one node cost changed, another."""
    inst = generate_instance(4, 3, seed=0)
    again = generate_instance(4, 3, seed=0)
    assert fingerprint(price(inst, 0.5)) == fingerprint(price(again, 0.5))
    assert fingerprint(price(inst, 0.5)) != fingerprint(price(inst, 0.6))
    base = price(inst, 0.5)
    cost = base.node_cost.copy()
    cost[1] += 1e-6
    assert fingerprint(replace(base, node_cost=cost)) != fingerprint(base)


def test_variables() -> None:
    cluster_of = np.array([0, 0, 1, 1, 2])
    assert parse_var(["y", 3], 5, cluster_of) == (3, -1)
    assert parse_var(["x", 1, 4], 5, cluster_of) == (1, 4)
    assert var_name(1, 4) == "x[1,4]" and var_name(3, -1) == "y[3]"
    for bad in (["x", 0, 1], ["x", 4, 1], ["y", 5], ["z", 1], ["y", True], "y1"):
        with pytest.raises(ValueError, match="is not a variable"):
            parse_var(bad, 5, cluster_of)

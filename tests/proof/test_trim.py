"""Trimming: a certificate with fewer root fixings, proofs and cuts that still proves the same."""

from __future__ import annotations

import copy
from pathlib import Path

from gtsp_bench.solvers.exact.milp import Milp
from gtsp_bench.solvers.exact.mip import certify

from gtsp_bench.data.io import read_instance
from gtsp_bench.proof import check_certificate
from gtsp_bench.proof.format import read_certificate
from gtsp_bench.proof.trim import _compact, main, trim_certificate
from tests.conftest import GTSPLIB


def test_trimming_keeps_the_proof_and_drops_fixings(tmp_path: Path, monkeypatch) -> None:
    """An untrimmed certificate (the writer's own trimming off) gets shorter and still proves the
    optimum; one with nothing to drop comes back unchanged."""
    monkeypatch.setattr(certify.ProofLog, "_needed_fixings", lambda self, chained: self.nodes[0].fix)
    inst = read_instance(GTSPLIB / "20kroA100.gtsp.gz")
    path = tmp_path / "k.cert.json.gz"
    assert Milp(certificate=str(path)).solve(inst, None, time_limit=60).status == "optimal"
    cert = read_certificate(path)
    assert len(cert["nodes"][0]["fix"]) >= 2
    out = trim_certificate(inst, cert)
    assert len(out["proofs"]) < len(cert["proofs"]) and len(out["cuts"]) <= len(cert["cuts"])
    assert check_certificate(inst, out).proven
    assert trim_certificate(inst, out)["proofs"] == out["proofs"] or len(out["nodes"][0]["fix"]) < 2
    assert main([str(GTSPLIB / "20kroA100.gtsp.gz"), str(path), str(tmp_path / "t.cert.json.gz")]) == 0
    assert (tmp_path / "t.cert.json.gz").stat().st_size < path.stat().st_size


def test_compact_renumbers_proofs_and_cuts() -> None:
    cert = {"cuts": [{"c": 0}, {"c": 1}, {"c": 2}],
            "proofs": [{"cuts": [[0, -1]]}, {"cuts": [[2, -3]]}, {"cuts": [[1, -2]]}],
            "nodes": [{"fix": [{"proof": 1, "rule": "reduced_cost"}], "proof": 2}]}
    out = _compact(copy.deepcopy(cert))
    assert out["cuts"] == [{"c": 1}, {"c": 2}]
    assert out["proofs"] == [{"cuts": [[1, -3]]}, {"cuts": [[0, -2]]}]
    assert out["nodes"] == [{"fix": [{"proof": 0, "rule": "reduced_cost"}], "proof": 1}]

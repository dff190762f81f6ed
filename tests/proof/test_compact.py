"""Compacting: each proof on the coarsest scale that still does its part, in version 2's layout,
still proving the same; rounding keeps cut duals at most 0."""

from __future__ import annotations

from pathlib import Path

import pytest
from gtsp_bench.solvers.exact.milp import Milp
from gtsp_bench.solvers.exact.mip import certify

from gtsp_bench.data.io import read_instance
from gtsp_bench.instance import Instance
from gtsp_bench.proof import check_certificate
from gtsp_bench.proof.compact import (
    BITS,
    compact_certificate,
    main,
    proof_scales,
    rescale,
    rescale_proof,
)
from gtsp_bench.proof.encode import to_version1
from gtsp_bench.proof.format import read_certificate
from tests.conftest import GTSPLIB, uncompacted

NAME = "20kroA100"


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> tuple[Instance, Path]:
    """A version 1 certificate as the writer made them before version 2 (untrimmed, every dual on
    the scale 2**-32)."""
    inst = read_instance(GTSPLIB / f"{NAME}.gtsp.gz")
    path = tmp_path_factory.mktemp("c") / "k.cert.json.gz"
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(certify, "compact_certificate", uncompacted)
        mp.setattr(certify.ProofLog, "_needed_fixings", lambda self, chained: self.nodes[0].fix)
        assert Milp(certificate=str(path)).solve(inst, None, time_limit=60).status == "optimal"
    cert = read_certificate(path)
    assert cert["version"] == 1 and cert["dual_bits"] == 32
    return inst, path


def test_rounding_keeps_cut_duals_at_most_zero() -> None:
    """Duals round to the nearest multiple of the coarser scale; a negative one never turns
    positive, one that rounds to 0 is dropped."""
    proof = {"kind": "dual", "cluster": [[0, 1024], [1, 1535], [2, -1537]], "degree": [[3, 200]],
             "cuts": [[0, -1], [1, -1536], [2, -512]]}
    out = rescale_proof(proof, 12, 2)  # the step 2**10 = 1024
    assert out == {"kind": "dual", "bits": 2, "cluster": [[0, 1], [1, 1], [2, -2]], "degree": [],
                   "cuts": [[1, -1]]}
    with pytest.raises(ValueError, match="cannot refine"):
        rescale_proof(proof, 2, 12)
    cert = {"dual_bits": 12, "proofs": [proof, dict(proof, bits=4)]}
    assert [p["bits"] for p in rescale(cert, [2, 4])["proofs"]] == [2, 4]


def test_a_certificate_compacts_and_still_proves(written: tuple[Instance, Path]) -> None:
    """The compacted certificate is version 2, smaller, proves the same optimum, and each proof's
    scale is one of BITS; converted back to version 1 it checks too."""
    inst, path = written
    cert = read_certificate(path)
    scales = proof_scales(inst, cert)
    assert len(scales) == len(cert["proofs"]) and set(scales) <= set(BITS) | {32}
    assert min(scales) < 32
    out = compact_certificate(inst, cert)
    assert out["version"] == 2 and len(out["proofs"]) <= len(cert["proofs"])
    before, after = check_certificate(inst, cert), check_certificate(inst, out)
    assert after.proven and (after.value, after.cutoff) == (before.value, before.cutoff)
    assert check_certificate(inst, to_version1(out)).proven
    assert compact_certificate(inst, out)["proofs"] == out["proofs"]  # compacting again: the same


def test_too_coarse_a_scale_fails_the_check(written: tuple[Instance, Path]) -> None:
    """Rounding every dual to integers is not a proof here: the scales do matter."""
    inst, path = written
    cert = read_certificate(path)
    scales = proof_scales(inst, cert)
    assert max(scales) > 0
    from gtsp_bench.proof import ProofError

    with pytest.raises(ProofError, match="not above the cutoff"):
        check_certificate(inst, rescale(cert, 0))


def test_the_command_converts_a_file(written: tuple[Instance, Path], tmp_path: Path,
                                     capsys: pytest.CaptureFixture[str]) -> None:
    """``python -m gtsp_bench.proof.compact INSTANCE CERT OUT`` writes a smaller version 2 file."""
    inst, path = written
    out = tmp_path / "small.cert.json.gz"
    assert main([str(GTSPLIB / f"{NAME}.gtsp.gz"), str(path), str(out)]) == 0
    assert "version 1 -> 2" in capsys.readouterr().out
    assert out.stat().st_size < path.stat().st_size / 2
    assert check_certificate(inst, read_certificate(out)).proven
    assert main([]) == 2


def test_a_refused_certificate_is_kept_or_raised(written: tuple[Instance, Path]) -> None:
    """A certificate the checker refuses is only rewritten in version 2's layout (and still
    refused); with ``strict`` the checker's error is raised instead."""
    from gtsp_bench.proof import ProofError

    inst, path = written
    coarse = rescale(read_certificate(path), 0)
    out = compact_certificate(inst, coarse, trim=False)
    assert out["version"] == 2
    with pytest.raises(ProofError, match="not above the cutoff"):
        check_certificate(inst, out)
    for trim in (False, True):
        with pytest.raises(ProofError, match="not above the cutoff"):
            compact_certificate(inst, coarse, trim=trim, strict=True)

"""``gtsp-bench check-proof`` and ``solve --certificate``: exit 0 on a proof, 1 naming the failing
step, 2 with one line for bad input."""

from __future__ import annotations

import gzip
import json
from pathlib import Path

import pytest

from gtsp_bench.cli import main
from tests.conftest import GTSPLIB

BERLIN = str(GTSPLIB / "11berlin52.gtsp.gz")


@pytest.fixture(scope="module")
def cert(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("c") / "b.cert.json.gz"
    assert main(["solve", BERLIN, "-s", "milp", "--certificate", str(path)]) == 0
    return path


def test_a_proof_checks(cert: Path, capsys: pytest.CaptureFixture[str]) -> None:
    capsys.readouterr()
    assert main(["check-proof", BERLIN, str(cert)]) == 0
    done = capsys.readouterr()  # no bar: stderr is not a terminal here
    assert done.out == "proven optimal: 4040\n" and done.err == ""
    assert main(["check-proof", "--no-progress", BERLIN, str(cert)]) == 0
    assert capsys.readouterr().out == "proven optimal: 4040\n"


def test_a_tampered_proof_fails_naming_the_step(cert: Path, tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    data = json.loads(gzip.decompress(cert.read_bytes()))
    data["value"] = 4000
    bad = tmp_path / "bad.cert.json.gz"
    bad.write_bytes(gzip.compress(json.dumps(data).encode()))
    capsys.readouterr()
    assert main(["check-proof", BERLIN, str(bad)]) == 1
    out = capsys.readouterr().out
    assert out.startswith("not proven: tour: the certificate prices it at 4000")


def test_bad_input_is_one_line(cert: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    capsys.readouterr()
    assert main(["check-proof", str(GTSPLIB / "11eil51.gtsp.gz"), str(cert)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"gtsp-bench: error: {cert}: the certificate is for")
    (tmp_path / "junk").write_text("junk")
    assert main(["check-proof", BERLIN, str(tmp_path / "junk")]) == 2
    assert "not a certificate" in capsys.readouterr().err
    assert main(["solve", BERLIN, "-s", "lns", "--certificate", str(tmp_path / "x")]) == 2
    assert "has no option 'certificate'" in capsys.readouterr().err


def test_both_versions_check(cert: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The solver writes version 2; the same proof in version 1's layout checks too."""
    from gtsp_bench.proof.encode import to_version1
    from gtsp_bench.proof.format import read_certificate, write_certificate

    v2 = read_certificate(cert)
    assert v2["version"] == 2
    write_certificate(tmp_path / "v1.cert.json.gz", to_version1(v2))
    capsys.readouterr()
    assert main(["check-proof", BERLIN, str(tmp_path / "v1.cert.json.gz")]) == 0
    assert capsys.readouterr().out == "proven optimal: 4040\n"

"""The checker: certificates of small proofs verify; tampered ones are refused with the reason."""

from __future__ import annotations

import copy
from typing import Any

import pytest
from gtsp_bench.solvers.exact.milp import Milp

from gtsp_bench.data.io import read_instance
from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance
from gtsp_bench.instance import Instance
from gtsp_bench.proof import ProofError, check_certificate
from gtsp_bench.proof.format import read_certificate
from gtsp_bench.registry import run_solver
from tests.conftest import GTSPLIB


def _certify(instance: Instance, omega: float | None, path: Any, **options: Any) -> dict:
    sol = Milp(certificate=str(path), **options).solve(instance, omega, time_limit=120)
    assert sol.status == "optimal" and sol.stats["certificate_bytes"] > 0
    return read_certificate(path)


@pytest.fixture(scope="module")
def berlin(tmp_path_factory: pytest.TempPathFactory) -> tuple[Instance, dict]:
    """11berlin52: proven at the root (a leaf, reduced-cost fixings)."""
    inst = read_instance(GTSPLIB / "11berlin52.gtsp.gz")
    return inst, _certify(inst, None, tmp_path_factory.mktemp("c") / "b.cert.json.gz")


@pytest.fixture(scope="module")
def branched(tmp_path_factory: pytest.TempPathFactory) -> tuple[Instance, dict]:
    """A UAV instance (float costs) whose proof branches (a short root, the greedy tour)."""
    inst = generate_instance(16, 6, seed=8)
    cert = _certify(inst, 0.5, tmp_path_factory.mktemp("c") / "u.cert.json.gz", root_rounds=1,
                    lns_trials=0)
    assert len(cert["nodes"]) >= 3
    return inst, cert


def test_certificates_verify(berlin: tuple[Instance, dict], branched: tuple[Instance, dict]) -> None:
    inst, cert = berlin
    r = check_certificate(inst, cert)
    assert r.proven and r.integral and r.value == 4040 and r.lower_bound == 4040
    assert r.summary() == "proven optimal: 4040"
    inst, cert = branched
    r = check_certificate(inst, cert)
    assert r.proven and not r.integral and r.leaves >= 2 and 0 <= r.gap < 1e-5
    assert r.summary().startswith("proven optimal: ")


def test_the_certified_value_is_dps_optimum(tmp_path: Any) -> None:
    inst = generate_instance(7, 4, seed=0)
    r = check_certificate(inst, _certify(inst, 0.3, tmp_path / "k7.cert.json.gz"))
    assert r.value == pytest.approx(run_solver("dp", inst, 0.3).objective, rel=1e-12)


def _refused(instance: Instance, cert: dict, reason: str) -> None:
    with pytest.raises(ProofError, match=reason):
        check_certificate(instance, cert)


def test_a_changed_dual_no_longer_closes(berlin: tuple[Instance, dict]) -> None:
    inst, cert = berlin
    bad = copy.deepcopy(cert)
    leaf = bad["nodes"][0]["proof"]
    bad["proofs"][leaf]["cluster"] = bad["proofs"][leaf]["cluster"][1:]  # one cluster dual zeroed
    _refused(inst, bad, f"node 0 \\(leaf\\): proof {leaf} bounds it at .* not above the cutoff 4039")


def test_a_removed_leaf_leaves_the_space_uncovered(branched: tuple[Instance, dict]) -> None:
    inst, cert = branched
    bad = copy.deepcopy(cert)
    gone = next(k for k in range(len(bad["nodes"]) - 1, 0, -1) if "proof" in bad["nodes"][k])
    parent = bad["nodes"][gone]["parent"]
    del bad["nodes"][gone]
    for node in bad["nodes"]:  # (later nodes' parents renumbered)
        if node.get("parent") is not None and node["parent"] > gone:
            node["parent"] -= 1
    _refused(inst, bad, f"node {parent}: branch on .* lacks its child .*do not cover the space")


def test_an_invalid_cut_is_refused(berlin: tuple[Instance, dict]) -> None:
    inst, cert = berlin
    bad = copy.deepcopy(cert)
    k = next(i for i, c in enumerate(bad["cuts"]) if c["family"] == "gsec")
    bad["cuts"][k]["C2"] = bad["cuts"][k]["C1"]  # x(E(Q)) <= y(Q): no longer a subtour cut
    _refused(inst, bad, f"cut {k}: C1 and C2 are the same cluster")
    bad = copy.deepcopy(cert)
    bad["cuts"][k]["Q"] = list(range(inst.n_nodes))
    _refused(inst, bad, f"cut {k}: Q holds every node")


def test_a_positive_cut_dual_is_refused(berlin: tuple[Instance, dict]) -> None:
    inst, cert = berlin
    bad = copy.deepcopy(cert)
    leaf = bad["nodes"][0]["proof"]
    bad["proofs"][leaf]["cuts"][0][1] = abs(bad["proofs"][leaf]["cuts"][0][1]) + 1
    _refused(inst, bad, "is positive")


def test_a_tour_priced_wrong_is_refused(berlin: tuple[Instance, dict]) -> None:
    inst, cert = berlin
    bad = copy.deepcopy(cert)
    bad["value"] = cert["value"] - 1
    _refused(inst, bad, "tour: the certificate prices it at 4039, the evaluator at 4040")
    bad = copy.deepcopy(cert)
    bad["tour"] = cert["tour"][:-1]
    _refused(inst, bad, "tour: not a tour")


def test_a_claim_above_the_proof_is_refused(branched: tuple[Instance, dict]) -> None:
    inst, cert = branched
    bad = copy.deepcopy(cert)
    bad["cutoff"] = cert["value"] + 1.0
    _refused(inst, bad, "not above the cutoff")
    low = copy.deepcopy(cert)
    low["cutoff"] = cert["value"] * 0.9  # true but weak: a gap, not a proof
    r = check_certificate(inst, low)
    assert not r.proven and r.gap == pytest.approx(0.1 * cert["value"])
    assert r.summary().startswith("not optimal as certified")


def test_malformed_trees_are_refused(berlin: tuple[Instance, dict], branched: tuple[Instance, dict]) -> None:
    inst, cert = berlin
    bad = copy.deepcopy(cert)
    bad["nodes"].append({"parent": 0, "branch": [["y", 0], 1], "proof": 0})
    _refused(inst, bad, "node 0: a leaf with children")
    bad = copy.deepcopy(cert)
    bad["nodes"][0]["fix"] = [{"proof": 0, "rule": "guess"}]
    _refused(inst, bad, "a fixing needs")
    inst, cert = branched
    bad = copy.deepcopy(cert)
    bad["nodes"][1]["branch"][0] = ["x", 0, 0]
    _refused(inst, bad, "node 1: .* is not a variable")


def test_another_instance_is_bad_input(berlin: tuple[Instance, dict]) -> None:
    _, cert = berlin
    with pytest.raises(InputError, match="for instance '11berlin52', whose costs differ"):
        check_certificate(read_instance(GTSPLIB / "11eil51.gtsp.gz"), cert)

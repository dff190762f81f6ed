"""The checker: certificates of small proofs verify; tampered ones are refused with the reason."""

from __future__ import annotations

import copy
from typing import Any

import pytest
from gtsp_bench.solvers.exact.milp import Milp
from gtsp_bench.solvers.exact.mip import certify

from gtsp_bench.data.io import read_instance
from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance
from gtsp_bench.instance import Instance
from gtsp_bench.proof import ProofError, check_certificate
from gtsp_bench.proof.encode import encode_proofs, to_version1, to_version2
from gtsp_bench.proof.format import read_certificate
from gtsp_bench.registry import run_solver
from tests.conftest import GTSPLIB, uncompacted


def _certify(instance: Instance, omega: float | None, path: Any, version: int = 2,
             **options: Any) -> dict:
    """A certificate of the milp solve, in the layout ``version`` (1: as the writer made them
    before version 2, every dual on the scale 2**-32)."""
    with pytest.MonkeyPatch.context() as mp:
        if version == 1:
            mp.setattr(certify, "compact_certificate", uncompacted)
        sol = Milp(certificate=str(path), **options).solve(instance, omega, time_limit=120)
    assert sol.status == "optimal" and sol.stats["certificate_bytes"] > 0
    cert = read_certificate(path)
    assert cert["version"] == version
    return cert


@pytest.fixture(scope="module", params=[1, 2])
def berlin(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
           ) -> tuple[Instance, dict]:
    """11berlin52: proven at the root (a leaf, reduced-cost fixings), in each version."""
    inst = read_instance(GTSPLIB / "11berlin52.gtsp.gz")
    return inst, _certify(inst, None, tmp_path_factory.mktemp("c") / "b.cert.json.gz", request.param)


@pytest.fixture(scope="module", params=[1, 2])
def branched(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
             ) -> tuple[Instance, dict]:
    """A UAV instance (float costs) whose proof branches (a short root, the greedy tour)."""
    inst = generate_instance(16, 6, seed=8)
    cert = _certify(inst, 0.5, tmp_path_factory.mktemp("c") / "u.cert.json.gz", request.param,
                    root_rounds=1, lns_trials=0)
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


def test_on_node_counts_every_node_of_the_tree(branched: tuple[Instance, dict]) -> None:
    """The progress feed gets (nodes walked, nodes in all) once per node, up to all of them."""
    inst, cert = branched
    calls: list[tuple[int, int]] = []
    r = check_certificate(inst, cert, on_node=lambda seen, total: calls.append((seen, total)))
    assert r.nodes >= 3 and calls == [(k, r.nodes) for k in range(1, r.nodes + 1)]


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
    if cert["version"] == 1:
        bad["proofs"][leaf]["cluster"] = bad["proofs"][leaf]["cluster"][1:]  # one cluster dual zeroed
    else:  # one cluster dual lowered by 1,000
        bits = bad["proofs"][leaf].get("bits", bad["dual_bits"])
        bad["proofs"][leaf]["cluster"][0] -= 1000 << bits
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
    v1 = cert["version"] == 1
    bad = copy.deepcopy(cert)
    k = next(i for i, c in enumerate(bad["cuts"]) if (c["family"] if v1 else c[0]) == "gsec")
    if v1:  # x(E(Q)) <= y(Q): no longer a subtour cut
        bad["cuts"][k]["C2"] = bad["cuts"][k]["C1"]
    else:
        bad["cuts"][k][2] = bad["cuts"][k][1]
    _refused(inst, bad, f"cut {k}: C1 and C2 are the same cluster")
    bad = copy.deepcopy(cert)
    every = list(range(inst.n_nodes))
    if v1:
        bad["cuts"][k]["Q"] = every
    else:
        bad["cuts"][k][3] = [0] + [1] * (inst.n_nodes - 1)
    _refused(inst, bad, f"cut {k}: Q holds every node")


def test_a_positive_cut_dual_is_refused(berlin: tuple[Instance, dict]) -> None:
    inst, cert = berlin
    bad = copy.deepcopy(cert)
    leaf = bad["nodes"][0]["proof"]
    if cert["version"] == 1:
        bad["proofs"][leaf]["cuts"][0][1] = abs(bad["proofs"][leaf]["cuts"][0][1]) + 1
    else:  # the leaf's proof written whole (no base), with its first cut dual made positive
        proof = to_version1(cert)["proofs"][leaf]
        proof["cuts"][0][1] = abs(proof["cuts"][0][1]) + 1
        bad["proofs"][leaf] = encode_proofs([proof], inst.n_clusters, inst.n_nodes, cert["dual_bits"])[0]
    _refused(inst, bad, "is positive")


def test_a_malformed_version_2_proof_is_named(berlin: tuple[Instance, dict]) -> None:
    """A version 2 proof whose lists do not fit the instance, or whose base is not earlier, is
    refused naming the proof."""
    inst, cert = berlin
    bad = copy.deepcopy(to_version2(cert))  # (version 1 converted, the same duals)
    bad["proofs"][0]["degree"] = bad["proofs"][0]["degree"][1:]
    _refused(inst, bad, f"proof 0: 'degree' must be a list of {inst.n_nodes} integers")
    bad = copy.deepcopy(to_version2(cert))
    bad["proofs"][0]["base"] = 0
    _refused(inst, bad, "proof 0: base 0 is not an earlier proof")


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

"""The proof log: every LP cut row becomes a family member whose canonical row, plus the cluster
and degree rows it names, is the LP's row; a certificate only of a proven solve."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from gtsp_bench.solvers.exact.milp import Milp
from gtsp_bench.solvers.exact.mip.certify import CertificateError, ProofLog, gsec_form
from gtsp_bench.solvers.exact.mip.model import build_model
from gtsp_bench.solvers.exact.mip.separation import Cuts, node_cluster_cuts, subtour_cut

from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance
from gtsp_bench.problem import price


def _canonical(model, family: dict, alpha: dict, crossing: list) -> np.ndarray:
    """Dense row over every column: the family's row, its cluster rows and degree rows."""
    n = model.n_nodes
    row = np.zeros(model.n_cols)
    if family["family"] == "gsec":
        q = np.isin(model.nodes, family["Q"])
        c1, c2 = model.cluster != family["C1"], model.cluster == family["C2"]
        row[:n] = -((q & c1).astype(float) + (q & c2))
        row[n:] = q[model.tail] & q[model.head]
    else:
        h = np.isin(model.cluster, family["handle"])
        row[n:] = h[model.tail] & h[model.head]
        for a, b in family["teeth"]:
            ct, ch = model.cluster[model.tail], model.cluster[model.head]
            row[n:] += ((ct == a) & (ch == b)) | ((ct == b) & (ch == a))
    for c, a in alpha.items():
        row[:n] += a * (model.cluster == c)
    for side in crossing:  # -1/2 of each side node's degree row x(delta(i)) - 2 y_i
        row[:n] += side.astype(float)
        row[n:] -= 0.5 * (side[model.tail].astype(float) + side[model.head].astype(float))
    return row


@pytest.mark.parametrize("seed", range(4))
def test_cut_rows_become_family_members(seed: int) -> None:
    problem = price(generate_instance(6, 3, seed=seed), 0.5)
    model = build_model(problem, problem.clusters)
    rng = np.random.default_rng(seed)
    blocks = []
    for _ in range(12):
        s = rng.random(model.n_nodes) < rng.uniform(0.2, 0.8)
        c, d = (int(v) for v in rng.choice(model.n_clusters, 2, replace=False))
        if rng.random() < 0.3:
            s |= model.cluster == c  # S holds all of C (right-hand side -1)
        blocks.append(subtour_cut(model, s, c, d))
    values = np.zeros(model.n_cols)
    values[model.n_nodes:] = rng.random(len(model.tail))  # node-cluster rows violated somewhere
    blocks.append(node_cluster_cuts(model, values))
    sides = np.array([np.isin(model.cluster, [0, 1]), np.isin(model.cluster, [0, 2]),
                      np.isin(model.cluster, [1, 3]), np.isin(model.cluster, [1, 4])])
    blocks.append(Cuts.one(sides, np.zeros(model.n_nodes), 2 + (3 - 1) / 2))  # a blossom
    cuts = Cuts.stack(blocks)
    log = ProofLog(model)
    for form in (cuts, cuts.sparsest(model, np.arange(model.n_cols))):  # both ways of writing sides
        assert form.cross.any() or form is cuts
        dense = form.matrix(model, np.arange(model.n_cols))
        for r in range(len(form)):
            family, alpha, crossing = log._family(form, r)
            assert np.allclose(_canonical(model, family, alpha, crossing), dense[r])
            assert form.rhs[r] == sum(alpha.values()) + (
                0 if family["family"] == "gsec" else len(family["handle"]) + (len(family["teeth"]) - 1) // 2)


def test_a_proof_keeps_its_cuts_of_nonzero_dual_once() -> None:
    """A logged proof holds the duals of its base rows and of its cuts of nonzero dual only; each
    cut's row is kept once, by id, however many proofs use it, and the reduced costs it gives are
    those of the whole LP's duals."""
    problem = price(generate_instance(6, 3, seed=1), 0.5)
    model = build_model(problem, problem.clusters)
    rng = np.random.default_rng(1)
    cuts = Cuts.stack([subtour_cut(model, rng.random(model.n_nodes) < 0.5, 0, 1 + k % 5)
                       for k in range(6)])
    ids = np.array([10, 11, 12, 13, 14, 15])
    base = model.n_clusters + model.n_nodes
    duals = rng.normal(size=base + len(cuts))
    duals[base + np.array([1, 4])] = 0.0  # two cuts of zero dual
    log = ProofLog(model)
    raw = log.proofs[log.proof("dual", duals, cuts, ids)]
    kept = dict(log.cut_rows)
    log.proof("dual", duals, cuts, ids)  # the same cuts again: nothing new is kept
    assert list(raw.ids) == [10, 12, 13, 15] and sorted(log.cut_rows) == [10, 12, 13, 15]
    assert all(log.cut_rows[i] is kept[i] for i in kept)
    assert np.array_equal(raw.duals, np.delete(duals, base + np.array([1, 4])))
    assert np.array_equal(log._cuts(raw).matrix(model, np.arange(model.n_cols)),
                          cuts.select(np.isin(ids, raw.ids)).matrix(model, np.arange(model.n_cols)))
    cols = np.arange(model.n_cols)
    whole = ProofLog(model)
    whole.cut_rows = {int(i): cuts.select(ids == i) for i in ids}
    everything = type(raw)("dual", duals, ids)
    assert np.allclose(log._reduced_costs(raw, cols), whole._reduced_costs(everything, cols),
                       rtol=0, atol=1e-12)


def test_a_row_of_no_family_is_refused() -> None:
    cluster = np.array([0, 0, 1, 1, 2, 2])
    q = np.array([True, False, True, False, False, False])
    with pytest.raises(CertificateError, match="not a generalized subtour row"):
        gsec_form(cluster, q, np.array([-3, 0, 0, 0, 0, 0]), 0.0)
    with pytest.raises(CertificateError, match="vary inside a cluster"):
        gsec_form(cluster, q, np.array([0, 0, 0, 0, -1, 0]), 0.0)


def test_only_a_proof_writes_a_certificate(tmp_path: Path) -> None:
    inst = generate_instance(12, 5, seed=4)
    path = tmp_path / "c.cert.json.gz"
    sol = Milp(certificate=str(path)).solve(inst, 0.5, time_limit=60)
    assert sol.status == "optimal" and path.stat().st_size == sol.stats["certificate_bytes"]
    stopped = Milp(certificate=str(tmp_path / "no.cert.json.gz")).solve(
        generate_instance(40, 20, seed=1), 0.5, time_limit=0.5)
    assert stopped.status == "time_limit" and "not proven" in stopped.stats["certificate"]
    assert not (tmp_path / "no.cert.json.gz").exists()


def test_three_clusters_are_certified_by_the_model(tmp_path: Path) -> None:
    """Three clusters (solved by enumeration without a certificate) get a certificate from the
    model, proving the enumerated optimum; fewer clusters have none."""
    from gtsp_bench.proof import check_certificate
    from gtsp_bench.proof.format import read_certificate

    inst = generate_instance(2, 4, seed=0)  # two clusters and the depot
    plain = Milp().solve(inst, 0.5)
    sol = Milp(certificate=str(tmp_path / "c")).solve(inst, 0.5)
    assert sol.status == "optimal" and sol.objective == pytest.approx(plain.objective, rel=1e-12)
    result = check_certificate(inst, read_certificate(tmp_path / "c"))
    assert result.proven and result.value == pytest.approx(plain.objective, rel=1e-12)
    with pytest.raises(InputError, match="needs at least 3 clusters"):
        Milp(certificate=str(tmp_path / "d")).solve(generate_instance(1, 3, seed=0), 0.5)


def test_an_infeasible_lp_gives_a_farkas_proof_the_checker_accepts() -> None:
    """Two heads fixed in one cluster: HiGHS's ray, logged and written, is a Farkas proof that the
    checker's exact arithmetic confirms over that box (and not over the free one)."""
    from gtsp_bench.solvers.exact.mip.backends import HighsBackend, LpModel
    from gtsp_bench.solvers.exact.mip.options import MipOptions

    from gtsp_bench.proof.bounds import Domain, Space, price_duals
    from gtsp_bench.proof.encode import to_version1
    from gtsp_bench.proof.families import parse_cut

    problem = price(generate_instance(5, 3, seed=2), 0.5)
    model = build_model(problem, problem.clusters)
    lp = LpModel(model, HighsBackend(MipOptions()), np.arange(model.n_cols))
    s = np.zeros(model.n_nodes, dtype=bool)
    s[[0, 3, 6]] = True
    lp.add_cuts(subtour_cut(model, s, 0, 1))
    lp.backend.set_bounds(np.array([0, 1]), np.ones(2), np.ones(2))
    res = lp.backend.solve_lp(60.0)
    assert res.status == "infeasible"
    log = ProofLog(model)
    log.leaf(0, log.proof("farkas", lp.backend.dual_ray(), lp.cuts, lp.cut_ids))
    tour = problem.to_tour(*_any_solution(problem))
    cert = to_version1(log.certificate(problem, tour, problem.tour_cost(tour), 0.0, []))
    space = Space.of(problem)
    cuts = [parse_cut(c, space.cluster_of) for c in cert["cuts"]]
    proof = cert["proofs"][0]
    priced = price_duals(space, cuts, proof, proof.get("bits", cert["dual_bits"]))
    box = Domain.free(space)
    box.y[[int(model.nodes[0]), int(model.nodes[1])]] = 1
    assert priced.farkas and priced.bound(box) > 0 >= priced.bound(Domain.free(space))


def _any_solution(problem) -> tuple[list[int], list[int]]:
    k = problem.instance.n_clusters
    return list(range(k)), [0] * k


def test_fewer_root_fixings_that_do_not_check_fall_back_to_all(tmp_path: Path,
                                                               monkeypatch: pytest.MonkeyPatch) -> None:
    """The writer tries shorter lists of root fixings and keeps one only if the checker accepts
    the certificate (``compact_certificate(strict=True)`` raises otherwise); here the checker is
    made to refuse both, so the written certificate has every root fixing and still proves the
    optimum."""
    from gtsp_bench.solvers.exact.mip import certify

    from gtsp_bench.proof import ProofError, check_certificate
    from gtsp_bench.proof.compact import compact_certificate
    from gtsp_bench.proof.format import read_certificate

    calls = []

    def refusing(instance: Any, cert: dict, trim: bool = True, strict: bool = False) -> dict:
        calls.append((strict, len(cert["nodes"][0].get("fix", []))))
        if strict:
            raise ProofError("refused for the test")
        return compact_certificate(instance, cert, trim=trim)

    monkeypatch.setattr(certify, "compact_certificate", refusing)
    inst = generate_instance(12, 5, seed=4)
    path = tmp_path / "c.cert.json.gz"
    sol = Milp(certificate=str(path)).solve(inst, 0.5, time_limit=60)
    assert sol.status == "optimal"
    full = calls[-1][1]
    assert [c[0] for c in calls] == [True, True, False] and full > 1
    assert all(n <= full for _, n in calls)
    cert = read_certificate(path)
    assert len(cert["nodes"][0]["fix"]) == full and check_certificate(inst, cert).proven

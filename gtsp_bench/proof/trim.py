"""Shorter certificates: drop the root's reduced-cost fixings that no proof relies on.

A root fixing matters to a later proof only through the columns it fixed whose reduced cost at
that proof is negative (a column of positive reduced cost contributes nothing while free). So
:func:`trim_certificate` replays the root's fixings, keeps those that fixed a column of small
reduced cost at some leaf or later fixing, drops the proofs and cuts nothing refers to any more,
and returns the shorter certificate only if :func:`~gtsp_bench.proof.check.check_certificate`
accepts it (else the certificate unchanged). Trimming never makes a certificate prove more.
"""

from __future__ import annotations

import copy
from fractions import Fraction
from typing import Any

import numpy as np

from gtsp_bench.instance import Instance
from gtsp_bench.problem import price
from gtsp_bench.proof.bounds import Domain, Space
from gtsp_bench.proof.check import ProofChecker, ProofError, check_certificate
from gtsp_bench.proof.encode import to_version1, to_version2
from gtsp_bench.proof.families import parse_cut

#: A free column counts as mattering to a proof when its reduced cost there is below this share
#: of the largest cost (the check afterwards decides).
SMALL = 1e-9


def _compact(cert: dict[str, Any]) -> dict[str, Any]:
    """The certificate with the proofs and cuts no node refers to removed (renumbered)."""
    nodes = cert["nodes"]
    used = sorted({f["proof"] for nd in nodes for f in nd.get("fix", [])}
                  | {nd["proof"] for nd in nodes if "proof" in nd})
    new = {old: i for i, old in enumerate(used)}
    proofs = [cert["proofs"][k] for k in used]
    cut_ids = sorted({c for p in proofs for c, _ in p.get("cuts", [])})
    cut_new = {old: i for i, old in enumerate(cut_ids)}
    out = dict(cert)
    out["cuts"] = [cert["cuts"][c] for c in cut_ids]
    out["proofs"] = [dict(p, cuts=[[cut_new[c], v] for c, v in p.get("cuts", [])]) for p in proofs]
    out["nodes"] = []
    for nd in nodes:
        nd = dict(nd)
        if "fix" in nd:
            nd["fix"] = [dict(f, proof=new[f["proof"]]) for f in nd["fix"]]
        if "proof" in nd:
            nd["proof"] = new[nd["proof"]]
        out["nodes"].append(nd)
    return out


def trim_certificate(instance: Instance, cert: dict[str, Any]) -> dict[str, Any]:
    """A shorter certificate proving the same, or ``cert`` itself.

    Parameters
    ----------
    instance
        The instance.
    cert
        A certificate (version 1 or 2) that :func:`~gtsp_bench.proof.check.check_certificate`
        accepts.

    Returns
    -------
    dict
        The trimmed certificate (checked; in ``cert``'s version), or ``cert`` when nothing could
        be dropped safely.
    """
    if cert.get("version") == 2:
        v1 = to_version1(cert)
        out = trim_certificate(instance, v1)
        return cert if out is v1 else to_version2(out)
    root = cert["nodes"][0]
    fixes = root.get("fix", [])
    rules = [i for i, f in enumerate(fixes) if f.get("rule") == "reduced_cost"]
    if len(rules) < 2:
        return cert
    problem = price(instance, cert["instance"].get("omega"))
    space = Space.of(problem)
    cuts = [parse_cut(c, space.cluster_of) for c in cert["cuts"]]
    checker = ProofChecker(space, cuts, cert["proofs"], cert["dual_bits"], Fraction(cert["cutoff"]))
    domain = Domain.free(space)
    fixed: dict[int, tuple[np.ndarray, np.ndarray]] = {}  # per rule: fixed y mask, fixed x mask
    for i, f in enumerate(fixes):
        before_y, before_x = domain.y.copy(), domain.x.copy()
        checker.fix(f, domain, "node 0")
        fixed[i] = (domain.y != before_y, domain.x != before_x)
    small = SMALL * max(1.0, float(np.abs(space.edge_cost[space.edge]).max(initial=0)),
                        float(np.abs(space.node_cost).max(initial=0)))
    consumers = {nd["proof"] for nd in cert["nodes"] if "proof" in nd}
    consumers |= {f["proof"] for nd in cert["nodes"][1:] for f in nd.get("fix", [])}
    for chained in (False, True):
        keep = {i for i, f in enumerate(fixes) if i not in rules}
        todo, done = set(consumers), set()
        while todo:
            k = todo.pop()
            done.add(k)
            p = checker.priced(k, "trim")
            ry, _ = p.approx(False)
            rx, _ = p.approx(True)
            low_y, low_x = ry < small, rx < small
            for i in rules:
                if i not in keep and (low_y[fixed[i][0]].any() or low_x[fixed[i][1]].any()):
                    keep.add(i)
                    if chained and fixes[i]["proof"] not in done:
                        todo.add(fixes[i]["proof"])
        trimmed = copy.deepcopy(cert)
        trimmed["nodes"][0]["fix"] = [f for i, f in enumerate(fixes) if i in keep]
        trimmed = _compact(trimmed)
        try:
            check_certificate(instance, trimmed)
            return trimmed
        except ProofError:
            continue
    return cert


def main(argv: list[str] | None = None) -> int:
    """``python -m gtsp_bench.proof.trim INSTANCE CERT [OUT]``: write the trimmed certificate to
    OUT (default: over CERT) and print its size."""
    import sys

    from gtsp_bench.data.io import read_instance
    from gtsp_bench.proof.format import read_certificate, write_certificate

    args = sys.argv[1:] if argv is None else argv
    if len(args) not in (2, 3):
        print("usage: python -m gtsp_bench.proof.trim INSTANCE CERT [OUT]", file=sys.stderr)
        return 2
    cert = read_certificate(args[1])
    out = trim_certificate(read_instance(args[0]), cert)
    size = write_certificate(args[2] if len(args) == 3 else args[1], out)
    print(f"{len(cert['proofs'])} proofs -> {len(out['proofs'])}, {size} bytes")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

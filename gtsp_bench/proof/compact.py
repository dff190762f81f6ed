"""Smaller certificates: each proof's duals on the coarsest scale that still proves its part.

A dual vector proves a bound whatever its values (any values give a valid bound; the checker
computes it exactly), so rounding a proof's duals to fewer bits keeps the certificate sound and
only risks a weaker bound. :func:`proof_scales` finds, for each proof, the coarsest scale of
:data:`BITS` at which it still does everything the certificate uses it for (bounding its nodes
above the cutoff, fixing at least the columns its reduced-cost fixings fixed), and
:func:`compact_certificate` writes the certificate with those scales in version 2's layout
(:mod:`gtsp_bench.proof.encode`), after trimming the root's fixings
(:func:`~gtsp_bench.proof.trim.trim_certificate`), and keeps it only if the checker accepts it
(else one scale for all proofs, the coarsest that checks).

``python -m gtsp_bench.proof.compact INSTANCE CERT [OUT]`` converts a file (version 1 or 2).
"""

from __future__ import annotations

import sys
from fractions import Fraction
from typing import Any

import numpy as np

from gtsp_bench.instance import Instance
from gtsp_bench.problem import price
from gtsp_bench.proof.bounds import Space, price_duals
from gtsp_bench.proof.check import ProofError, check_certificate
from gtsp_bench.proof.encode import to_version1, to_version2
from gtsp_bench.proof.families import parse_cut
from gtsp_bench.proof.trim import trim_certificate

#: The scales tried, coarsest first (bits of each dual's fraction).
BITS = (0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 28, 32)


def _round(v: int, shift: int) -> int:
    """``v / 2**shift`` rounded to the nearest integer (a value at most 0 stays at most 0)."""
    return (2 * v + (1 << shift)) >> (shift + 1) if shift else v


def rescale_proof(proof: dict[str, Any], old: int, new: int) -> dict[str, Any]:
    """A proof (version 1's layout) at scale ``old`` rounded to scale ``new <= old``, which it
    names as its ``"bits"``."""
    if new > old:
        raise ValueError(f"cannot refine duals from {old} to {new} bits")
    out: dict[str, Any] = {"kind": proof["kind"], "bits": new}
    for key in ("cluster", "degree", "cuts"):
        out[key] = [[i, r] for i, v in proof.get(key, []) if (r := _round(v, old - new))]
    return out


def rescale(cert: dict[str, Any], bits: int | list[int]) -> dict[str, Any]:
    """A version 1 certificate with each proof's duals rounded to ``bits`` (one scale for all, or
    one per proof), at most the scale each has."""
    proofs = cert["proofs"]
    want = [bits] * len(proofs) if isinstance(bits, int) else bits
    out = [rescale_proof(p, int(p.get("bits", cert["dual_bits"])), b)
           for p, b in zip(proofs, want, strict=True)]
    return dict(cert, proofs=out)


def _does_its_part(priced: Any, uses: list[tuple[Any, ...]], cutoff: Fraction) -> bool:
    """Whether a (rescaled) proof still bounds each of its domains above the cutoff and fixes at
    least the columns each of its reduced-cost fixings fixed."""
    for use in uses:
        if use[0] == "close":
            b = priced.bound(use[1])
            if (b <= 0) if priced.farkas else (b <= cutoff):
                return False
            continue
        _, domain, ys, xs = use
        room = cutoff - priced.bound(domain)
        ys2, xs2 = priced.fixable(domain, room)
        n = len(domain.y)
        if not np.isin(ys, ys2).all() or not np.isin(xs[0] * n + xs[1], xs2[0] * n + xs2[1]).all():
            return False
    return True


def proof_scales(instance: Instance, cert: dict[str, Any]) -> list[int]:
    """For each proof of a certificate (version 1's layout), the coarsest scale of :data:`BITS`
    (up to its own) at which it does what the certificate uses it for; each scale is found by
    bisection. Raises the checker's :class:`~gtsp_bench.proof.check.ProofError` if it refuses the
    certificate."""
    uses: dict[int, list[tuple[Any, ...]]] = {}
    check_certificate(instance, cert, uses)
    problem = price(instance, cert["instance"].get("omega"))
    space = Space.of(problem)
    cuts = [parse_cut(c, space.cluster_of) for c in cert["cuts"]]
    cutoff = Fraction(cert["cutoff"])
    out = []
    for k, proof in enumerate(cert["proofs"]):
        own = int(proof.get("bits", cert["dual_bits"]))
        tries = [b for b in BITS if b < own]
        best, lo, hi = own, 0, len(tries) - 1
        while lo <= hi:
            mid = (lo + hi) // 2
            rounded = rescale_proof(proof, own, tries[mid])
            try:
                ok = _does_its_part(price_duals(space, cuts, rounded, tries[mid]), uses.get(k, []),
                                    cutoff)
            except ValueError:
                ok = False
            if ok:
                best, hi = tries[mid], mid - 1
            else:
                lo = mid + 1
        out.append(best)
    return out


def _accepted(instance: Instance, cert: dict[str, Any]) -> bool:
    try:
        check_certificate(instance, cert)
        return True
    except ProofError:
        return False


def compact_certificate(instance: Instance, cert: dict[str, Any], trim: bool = True,
                        strict: bool = False) -> dict[str, Any]:
    """The densest form of a certificate that still checks, in version 2's layout.

    Parameters
    ----------
    instance
        The instance.
    cert
        A certificate (version 1 or 2); one that the checker refuses is only written in version
        2's layout, its duals unchanged.
    trim
        Whether to trim the root's fixings first.
    strict
        Raise the checker's :class:`~gtsp_bench.proof.check.ProofError` for a certificate it
        refuses instead of writing it as it is (a writer that needs to know pays for no extra
        check: finding the scales checks it anyway).

    Returns
    -------
    dict
        A version 2 certificate that the checker accepts, proving the same cutoff: each proof on
        the coarsest scale found by :func:`proof_scales`, or, should that not check, every proof
        on the coarsest common scale that does (or the duals as they were).
    """
    base = to_version1(cert)
    try:  # finding the scales checks the certificate on the way
        if trim:
            check_certificate(instance, base)
            base = trim_certificate(instance, base)
        scales = proof_scales(instance, base)
    except ProofError:
        if strict:
            raise
        return to_version2(base)  # nothing to keep: only the layout changes
    candidate = rescale(base, scales)
    if not _accepted(instance, candidate):
        top = min(int(p.get("bits", base["dual_bits"])) for p in base["proofs"])
        tries = [b for b in BITS if b < top]
        candidate, lo, hi = base, 0, len(tries) - 1
        while lo <= hi:
            mid = (lo + hi) // 2
            rounded = rescale(base, tries[mid])
            if _accepted(instance, rounded):
                candidate, hi = rounded, mid - 1
            else:
                lo = mid + 1
    scales = [int(p.get("bits", candidate["dual_bits"])) for p in candidate["proofs"]]
    common = max(set(scales), key=scales.count) if scales else candidate["dual_bits"]
    proofs = [{k: v for k, v in p.items() if k != "bits" or v != common} for p in candidate["proofs"]]
    return to_version2(dict(candidate, dual_bits=common, proofs=proofs))


def main(argv: list[str] | None = None) -> int:
    """``python -m gtsp_bench.proof.compact INSTANCE CERT [OUT]``: write the compacted version 2
    certificate to OUT (default: over CERT) and print the sizes."""
    from pathlib import Path

    from gtsp_bench.data.io import read_instance
    from gtsp_bench.proof.format import read_certificate, write_certificate

    args = sys.argv[1:] if argv is None else argv
    if len(args) not in (2, 3):
        print("usage: python -m gtsp_bench.proof.compact INSTANCE CERT [OUT]", file=sys.stderr)
        return 2
    before = Path(args[1]).stat().st_size
    cert = read_certificate(args[1])
    out = compact_certificate(read_instance(args[0]), cert)
    size = write_certificate(args[2] if len(args) == 3 else args[1], out)
    print(f"version {cert['version']} -> 2, {len(cert['proofs'])} proofs -> {len(out['proofs'])}, "
          f"{before} -> {size} bytes")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

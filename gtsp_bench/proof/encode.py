"""The dense certificate layout (version 2), its decoding, and the conversion from version 1.

Version 2 holds what version 1 holds, written more densely (docs/proofs.md documents both):

* a cut is a list: ``["gsec", C1, C2, Q]`` or ``["blossom", H, teeth]``, where ``Q`` and ``H`` are
  sorted ids written as gaps (the first id, then each id minus the one before it, every gap at
  least 1) and ``teeth`` is the flat list ``[c1, d1, c2, d2, ...]``;
* a proof is ``{"kind": ..., "cluster": [m ints], "degree": [n ints], "cuts": [rows, values]}``:
  the cluster and degree duals dense (one integer per cluster and per node), the cut duals sparse
  (``rows`` increasing, written as gaps like ``Q``; ``values`` the duals of those rows); with
  ``"base": j`` (an earlier proof) the lists hold differences: the proof's duals are proof
  ``j``'s plus these (a cut row not listed keeps ``j``'s dual);
* every dual, as in version 1, is an integer ``k`` standing for ``k / 2**dual_bits``; a proof
  may name its own scale, ``"bits": b`` (then ``k / 2**b``; a base's scale is at most its own,
  and its duals count multiplied by ``2**(b - b_base)``).
  :func:`~gtsp_bench.proof.compact.compact_certificate` picks for each proof the coarsest scale
  at which the certificate still checks.

Decoding turns a version 2 certificate back into version 1's objects, which the checker reads;
each step names the entry it cannot decode.
"""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np

from gtsp_bench.checks import all_ints, is_int


def _gaps(ids: list[int]) -> list[int]:
    """Sorted distinct ids as gaps: the first id, then each difference."""
    out = sorted(int(i) for i in ids)
    return out[:1] + [b - a for a, b in itertools.pairwise(out)]


def _ungap(gaps: Any, what: str, allow_empty: bool = False) -> list[int]:
    """Ids from gaps (each after the first at least 1, the first at least 0)."""
    if not isinstance(gaps, list) or (not gaps and not allow_empty) or not all_ints(gaps):
        raise ValueError(f"{what} must be a {'' if allow_empty else 'non-empty '}list of integer gaps")
    if gaps and (gaps[0] < 0 or min(gaps[1:], default=1) < 1):
        raise ValueError(f"{what}: gaps must be positive after a first id of at least 0")
    return list(itertools.accumulate(gaps))


def encode_cut(cut: dict[str, Any]) -> list[Any]:
    """A version 1 cut object as a version 2 list."""
    if cut["family"] == "gsec":
        return ["gsec", cut["C1"], cut["C2"], _gaps(cut["Q"])]
    return ["blossom", _gaps(cut["handle"]), [int(v) for t in cut["teeth"] for v in t]]


def decode_cut(cut: Any) -> dict[str, Any]:
    """A version 2 cut list as the version 1 object (whose sets :func:`~gtsp_bench.proof.families.
    parse_cut` then checks).

    Raises
    ------
    ValueError
        Naming what is malformed.
    """
    if isinstance(cut, list) and len(cut) == 4 and cut[0] == "gsec":
        return {"family": "gsec", "C1": cut[1], "C2": cut[2], "Q": _ungap(cut[3], "Q")}
    if isinstance(cut, list) and len(cut) == 3 and cut[0] == "blossom":
        teeth = cut[2]
        if not isinstance(teeth, list) or len(teeth) % 2:
            raise ValueError("teeth must be a flat list of cluster pairs")
        return {"family": "blossom", "handle": _ungap(cut[1], "handle"),
                "teeth": [teeth[k:k + 2] for k in range(0, len(teeth), 2)]}
    family = cut[0] if isinstance(cut, list) and cut else None
    raise ValueError(f"not a cut list of a known family ({family!r}; valid: "
                     "['gsec', C1, C2, Q], ['blossom', H, teeth])")


def _dense(proofs: list[dict[str, Any]], m: int, n: int) -> np.ndarray:
    """The duals of version 1 proofs as rows of one int64 matrix: clusters, nodes, then cut rows."""
    k = 1 + max((int(r) for p in proofs for r, _ in p.get("cuts", [])), default=-1)
    out = np.zeros((len(proofs), m + n + k), dtype=np.int64)
    for row, p in zip(out, proofs, strict=True):
        for key, at in (("cluster", 0), ("degree", m), ("cuts", m + n)):
            for i, v in p.get(key, []):
                row[at + i] = v
    return out


def _cost(diff: np.ndarray, dense: int) -> float:
    """Rough length of a proof written as ``diff``: the digits of its values, and a gap for each
    nonzero cut dual (the first ``dense`` entries are written whole)."""
    return float(np.log10(np.abs(diff).astype(float) + 1).sum() + 2 * np.count_nonzero(diff[dense:]))


def encode_proofs(proofs: list[dict[str, Any]], m: int, n: int, bits: int) -> list[dict[str, Any]]:
    """Version 1 proofs (each with its ``"bits"`` or ``bits``) as version 2 ones, each written as
    differences from the earlier proof (of a scale at most its own) that makes it shortest, or
    whole when none does."""
    vectors = _dense(proofs, m, n)
    scales = [int(p.get("bits", bits)) for p in proofs]
    out = []
    for k, p in enumerate(proofs):
        best, diff = None, vectors[k]
        best_cost = _cost(diff, m + n)
        for j in range(k):
            if scales[j] > scales[k]:
                continue
            d = vectors[k] - (vectors[j] << (scales[k] - scales[j]))
            cost = _cost(d, m + n) + 2
            if cost < best_cost:
                best, diff, best_cost = j, d, cost
        rows = np.flatnonzero(diff[m + n:])
        entry: dict[str, Any] = {"kind": p["kind"]}
        if scales[k] != bits:
            entry["bits"] = scales[k]
        if best is not None:
            entry["base"] = best
        entry["cluster"] = [int(v) for v in diff[:m]]
        entry["degree"] = [int(v) for v in diff[m:m + n]]
        entry["cuts"] = [_gaps(rows.tolist()), [int(v) for v in diff[m + n + rows]]]
        out.append(entry)
    return out


def decode_proofs(proofs: Any, m: int, n: int, bits: int) -> list[dict[str, Any]]:
    """Version 2 proofs as version 1 ones (sparse, zeros dropped; a proof's own scale kept as
    ``"bits"``), ``bits`` the certificate's scale.

    Raises
    ------
    ValueError
        ``"proof k: <problem>"``.
    """
    if not isinstance(proofs, list):
        raise ValueError("'proofs' must be a list")
    vectors: list[tuple[list[int], dict[int, int], int]] = []
    out = []
    for k, p in enumerate(proofs):
        try:
            if not isinstance(p, dict):
                raise ValueError("not an object")
            own = p.get("bits", bits)
            if not is_int(own) or not 0 <= own <= 60:
                raise ValueError("its scale 'bits' must be an integer in [0, 60]")
            vec, cuts = _decode_one(p, vectors, m, n, own)
        except ValueError as e:
            raise ValueError(f"proof {k}: {e}") from None
        vectors.append((vec, cuts, own))
        entry = {"kind": p.get("kind"),
                 "cluster": [[c, v] for c, v in enumerate(vec[:m]) if v],
                 "degree": [[i, v] for i, v in enumerate(vec[m:]) if v],
                 "cuts": [[r, v] for r, v in sorted(cuts.items()) if v]}
        if "bits" in p:
            entry["bits"] = own
        out.append(entry)
    return out


def _decode_one(p: dict[str, Any], earlier: list[tuple[list[int], dict[int, int], int]], m: int,
                n: int, bits: int) -> tuple[list[int], dict[int, int]]:
    """The dense duals and cut duals of one version 2 proof, its base applied."""
    cl, dg, cu = p.get("cluster"), p.get("degree"), p.get("cuts")
    for name, vals, size in (("cluster", cl, m), ("degree", dg, n)):
        if not isinstance(vals, list) or len(vals) != size or not all_ints(vals):
            raise ValueError(f"'{name}' must be a list of {size} integers")
    if not isinstance(cu, list) or len(cu) != 2:
        raise ValueError("'cuts' must be [rows, values]")
    rows = _ungap(cu[0], "cut rows", allow_empty=True)
    vals = cu[1]
    if not isinstance(vals, list) or len(vals) != len(rows) or not all_ints(vals):
        raise ValueError("cut values must be one integer per row")
    vec = [int(v) for v in cl + dg]
    cuts = dict(zip(rows, (int(v) for v in vals), strict=True))
    if "base" in p:
        j = p["base"]
        if not is_int(j) or not 0 <= j < len(earlier):
            raise ValueError(f"base {j!r} is not an earlier proof")
        bvec, bcuts, bbits = earlier[j]
        if bbits > bits:
            raise ValueError(f"base {j} has a finer scale ({bbits} bits) than the proof ({bits})")
        up = bits - bbits
        vec = [a + (b << up) for a, b in zip(vec, bvec, strict=True)]
        cuts = {r: (bcuts.get(r, 0) << up) + cuts.get(r, 0) for r in set(bcuts) | set(cuts)}
    return vec, cuts


def to_version2(cert: dict[str, Any]) -> dict[str, Any]:
    """A version 1 certificate in version 2's layout, the same duals (a lossless conversion)."""
    if cert.get("version") == 2:
        return cert
    m, n = cert["instance"]["clusters"], cert["instance"]["nodes"]
    out = {k: v for k, v in cert.items() if k not in ("cuts", "proofs", "nodes")}
    out["version"] = 2
    out["cuts"] = [encode_cut(c) for c in cert["cuts"]]
    out["proofs"] = encode_proofs(cert["proofs"], m, n, cert["dual_bits"])
    out["nodes"] = cert["nodes"]
    return out


def to_version1(cert: dict[str, Any]) -> dict[str, Any]:
    """A version 2 certificate in version 1's layout (the same duals; a proof with a scale of its
    own keeps it as ``"bits"``, which the checker reads but a version 1 file does not hold).

    Raises
    ------
    ValueError
        A malformed cut or proof, named.
    """
    if cert.get("version") == 1:
        return cert
    m, n = cert["instance"]["clusters"], cert["instance"]["nodes"]
    out = dict(cert, version=1)
    cuts = []
    for k, c in enumerate(cert.get("cuts", [])):
        try:
            cuts.append(decode_cut(c))
        except ValueError as e:
            raise ValueError(f"cut {k}: {e}") from None
    out["cuts"] = cuts
    out["proofs"] = decode_proofs(cert.get("proofs"), m, n, cert["dual_bits"])
    return out

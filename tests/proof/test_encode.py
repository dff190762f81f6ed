"""Version 2's layout: cuts and proofs survive a round trip; malformed entries are named."""

from __future__ import annotations

import copy

import pytest

from gtsp_bench.proof.encode import (
    decode_cut,
    decode_proofs,
    encode_cut,
    encode_proofs,
    to_version1,
    to_version2,
)

M, N = 3, 5


def _v1(proofs: list[dict]) -> dict:
    return {"format": "f", "version": 1, "instance": {"clusters": M, "nodes": N}, "dual_bits": 8,
            "cuts": [{"family": "gsec", "Q": [4, 0, 2], "C1": 0, "C2": 1},
                     {"family": "blossom", "handle": [2, 0], "teeth": [[0, 1], [2, 1], [0, 1]]}],
            "proofs": proofs, "nodes": [{"proof": len(proofs) - 1}]}


PROOFS = [
    {"kind": "dual", "cluster": [[0, 700], [2, -5]], "degree": [[1, 300], [4, 1]], "cuts": [[1, -9]]},
    {"kind": "dual", "cluster": [[0, 701], [2, -5]], "degree": [[1, 300], [4, 1]],
     "cuts": [[0, -4]]},  # close to the first: written as differences
    {"kind": "farkas", "cluster": [[1, 2]], "degree": [], "cuts": []},
]


def test_cuts_round_trip_with_sets_as_gaps() -> None:
    """Sets come back sorted from their gaps; teeth as pairs from a flat list."""
    gsec = {"family": "gsec", "Q": [4, 0, 2], "C1": 0, "C2": 1}
    assert encode_cut(gsec) == ["gsec", 0, 1, [0, 2, 2]]
    assert decode_cut(encode_cut(gsec)) == dict(gsec, Q=[0, 2, 4])
    blossom = {"family": "blossom", "handle": [2, 0], "teeth": [[0, 1], [2, 1], [0, 3]]}
    assert encode_cut(blossom) == ["blossom", [0, 2], [0, 1, 2, 1, 0, 3]]
    assert decode_cut(encode_cut(blossom)) == dict(blossom, handle=[0, 2])


@pytest.mark.parametrize(("cut", "reason"), [
    (["gsec", 0, 1, [1, 0]], "gaps must be positive"),
    (["gsec", 0, 1, [-1, 2]], "gaps must be positive"),
    (["gsec", 0, 1, []], "Q must be a non-empty list"),
    (["blossom", [0], [0, 1, 2]], "teeth must be a flat list of cluster pairs"),
    (["comb", [0]], "not a cut list of a known family \\('comb'"),
    ({"family": "gsec"}, "not a cut list"),
])
def test_malformed_cuts_are_named(cut: list, reason: str) -> None:
    """Each malformed cut is refused with what is wrong."""
    with pytest.raises(ValueError, match=reason):
        decode_cut(cut)


def test_proofs_round_trip_and_share_a_base() -> None:
    """Dense cluster and degree duals, sparse cut duals; a proof close to an earlier one is its
    differences, and decoding gives back every dual (zeros dropped)."""
    v2 = encode_proofs(PROOFS, M, N, 8)
    assert v2[0] == {"kind": "dual", "cluster": [700, 0, -5], "degree": [0, 300, 0, 0, 1],
                     "cuts": [[1], [-9]]}
    assert v2[1]["base"] == 0 and v2[1]["cluster"] == [1, 0, 0] and v2[1]["degree"] == [0] * N
    assert v2[1]["cuts"] == [[0, 1], [-4, 9]]  # rows 0 and 1: -4, and +9 cancels the base's -9
    assert "base" not in v2[2]
    assert decode_proofs(v2, M, N, 8) == PROOFS


def test_a_base_of_a_coarser_scale_counts_scaled_up() -> None:
    """A proof on a finer scale than its base adds the base's duals times 2**(difference)."""
    proofs = [dict(PROOFS[0], bits=4), dict(PROOFS[0], bits=6)]
    proofs[1]["cluster"] = [[0, 700 * 4 + 1], [2, -20]]
    proofs[1]["degree"] = [[1, 1200], [4, 4]]
    proofs[1]["cuts"] = [[1, -36]]
    v2 = encode_proofs(proofs, M, N, 6)
    assert v2[0]["bits"] == 4 and "bits" not in v2[1]
    assert v2[1]["base"] == 0 and v2[1]["cluster"] == [1, 0, 0] and v2[1]["cuts"] == [[], []]
    assert decode_proofs(v2, M, N, 6) == [proofs[0], {k: v for k, v in proofs[1].items() if k != "bits"}]
    bad = copy.deepcopy(v2)
    bad[0]["bits"], bad[1]["bits"] = 8, 6
    with pytest.raises(ValueError, match="proof 1: base 0 has a finer scale \\(8 bits\\)"):
        decode_proofs(bad, M, N, 6)


@pytest.mark.parametrize(("change", "reason"), [
    (lambda p: p[0].update(cluster=[1, 2]), "proof 0: 'cluster' must be a list of 3 integers"),
    (lambda p: p[0].update(degree=[0.5] * N), "proof 0: 'degree' must be a list of 5 integers"),
    (lambda p: p[0].update(cuts=[[1]]), "proof 0: 'cuts' must be \\[rows, values\\]"),
    (lambda p: p[0].update(cuts=[[1], []]), "proof 0: cut values must be one integer per row"),
    (lambda p: p[0].update(cuts=[[1, 0], [-1, -1]]), "proof 0: cut rows: gaps must be positive"),
    (lambda p: p[1].update(base=1), "proof 1: base 1 is not an earlier proof"),
    (lambda p: p[2].update(bits=99), "proof 2: its scale 'bits' must be an integer in \\[0, 60\\]"),
    (lambda p: p.__setitem__(0, []), "proof 0: not an object"),
])
def test_malformed_proofs_are_named(change, reason: str) -> None:
    """Each malformed proof is refused naming the proof and the field."""
    v2 = encode_proofs(PROOFS, M, N, 8)
    change(v2)
    with pytest.raises(ValueError, match=reason):
        decode_proofs(v2, M, N, 8)


def test_certificates_convert_both_ways() -> None:
    """A version 1 certificate converts to version 2 and back with the same cuts and duals; a
    certificate of the target version comes back as it is."""
    v1 = _v1(PROOFS)
    v2 = to_version2(v1)
    assert v2["version"] == 2 and v2["nodes"] == v1["nodes"] and v2["dual_bits"] == 8
    assert v2["cuts"] == [["gsec", 0, 1, [0, 2, 2]], ["blossom", [0, 2], [0, 1, 2, 1, 0, 1]]]
    back = to_version1(v2)
    assert back["version"] == 1 and back["proofs"] == PROOFS
    assert back["cuts"][0] == {"family": "gsec", "Q": [0, 2, 4], "C1": 0, "C2": 1}
    assert to_version2(v2) is v2 and to_version1(v1) is v1
    bad = copy.deepcopy(v2)
    bad["cuts"][1][0] = "comb"
    with pytest.raises(ValueError, match="cut 1: not a cut list"):
        to_version1(bad)

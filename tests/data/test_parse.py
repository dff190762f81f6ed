"""Parsing and formatting (no files, but the GTSPLIB samples): JSON instances, solutions, GTSPLIB
text in every explicit weight format, TSPLIB tours."""

from __future__ import annotations

import gzip
import json
import os
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gtsp_bench.data.parse import (
    format_gtsp,
    format_json_instance,
    format_tour,
    parse_gtsp,
    parse_json_instance,
    parse_solution,
    parse_tour,
    tour_node_ids,
    tour_to_solution,
)
from gtsp_bench.energy import evaluate
from gtsp_bench.errors import InputError
from tests.conftest import gtsplib_files

GOOD = {"name": "x", "depot": [500, 0], "clusters": [[[1, 2], [3, 4]], [[5, 6]]]}


def _text(**changes) -> str:
    return json.dumps(GOOD | changes)


def test_json_instance_round_trip():
    """format -> parse gives the same clusters, depot, parameters and meta."""
    inst = parse_json_instance(_text(params={"height": 60}, meta={"seed": 1}))
    again = parse_json_instance(format_json_instance(inst))
    assert again.name == "x"
    assert [c.tolist() for c in again.clusters] == [[[1, 2], [3, 4]], [[5, 6]]]
    assert again.depot.tolist() == [500, 0]
    assert again.params == inst.params and again.params.height == 60
    assert dict(again.meta) == {"seed": 1}


def test_json_depot_may_be_null():
    """A null depot gives a closed tour without a depot."""
    assert parse_json_instance(_text(depot=None)).depot is None


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("{", "invalid JSON"),
        ("[]", "must be a JSON object"),
        (json.dumps({"name": "x"}), "missing key 'clusters'"),
        (_text(clusters=[]), "non-empty list"),
        (_text(clusters=[[]]), r"clusters\[0\] is empty"),
        (_text(clusters=[[[1, 2]], []]), r"clusters\[1\] is empty"),
        (_text(clusters=[[[1]]]), r"clusters\[0\]\[0\] must be a pair"),
        (_text(clusters=[[[1, "a"]]]), r"clusters\[0\]\[0\] must be a pair"),
        ('{"clusters": [[[1, NaN]]]}', "NaN is not a number"),
        ('{"clusters": [[[1, Infinity]]]}', "Infinity is not a number"),
        ('{"clusters": [[[1, 1e999]]]}', "NaN or infinite"),
        ('{"clusters": [[[1, 1%s]]]}' % ("0" * 400), "NaN or infinite"),  # int beyond float
        ('{"clusters": [[[1, 1%s]]]}' % ("0" * 5000), "invalid JSON: Exceeds the limit"),
        ("[" * 100_000 + "]" * 100_000, "invalid JSON: maximum recursion depth"),
        (_text(params={"height": 10**400}), "'height' must be finite, got an integer too large"),
        (_text(depot=[1]), "depot must be a pair"),
        (_text(params={"hieght": 1}), "unknown energy parameter 'hieght'"),
        (_text(params={"height": -1}), "'height' must be > 0"),
        (_text(params=[1]), "'params' must be an object"),
        (_text(extra=1), "unknown key 'extra'"),
        (_text(name=""), "'name' must be a non-empty string"),
    ],
)
def test_bad_json_instances(text, message):
    """Each malformed instance gives an InputError naming the problem."""
    with pytest.raises(InputError, match=message):
        parse_json_instance(text)


def test_solution_parsing():
    """Only order and heads are read; other keys are ignored; bad shapes are rejected."""
    assert parse_solution('{"order": [1, 0], "heads": [2, 3], "objective": 5}') == ([1, 0], [2, 3])
    with pytest.raises(InputError, match="missing key 'heads'"):
        parse_solution('{"order": [0]}')
    with pytest.raises(InputError, match="'order' must be a list of integers"):
        parse_solution('{"order": [0.5], "heads": [0]}')
    with pytest.raises(InputError, match="invalid JSON: Exceeds the limit"):
        parse_solution('{"order": [1%s], "heads": [0]}' % ("0" * 5000))


@pytest.mark.parametrize("path", gtsplib_files(), ids=lambda p: p.stem)
def test_every_sample_gtsplib_file_parses_and_round_trips(path):
    """Every sample .gtsp parses with the announced sizes, and write -> read keeps it intact."""
    text = gzip.decompress(path.read_bytes()).decode()
    inst = parse_gtsp(text)
    n_sets = int("".join(ch for ch in path.name[:3] if ch.isdigit()))  # "11berlin52" -> 11
    header = dict(line.split(":", 1) for line in text.splitlines()[:8] if ":" in line)
    header = {k.strip(): v.strip() for k, v in header.items()}
    assert inst.n_clusters == int(header["GTSP_SETS"])
    assert inst.n_nodes == int(header["DIMENSION"])
    assert inst.edge_weight_type == header["EDGE_WEIGHT_TYPE"]
    assert inst.params is None and inst.depot is None
    assert n_sets == inst.n_clusters
    again = parse_gtsp(format_gtsp(inst))
    assert again.name == inst.name
    assert again.edge_weight_type == inst.edge_weight_type
    for a, b in zip(inst.clusters, again.clusters, strict=True):
        np.testing.assert_array_equal(a, b)


SMALL = "\n".join([
    "NAME: small", "TYPE: GTSP", "DIMENSION: 4", "GTSP_SETS: 2", "EDGE_WEIGHT_TYPE: EUC_2D",
    "NODE_COORD_SECTION", "1 0 0", "2 3 4", "3 6 8", "4 0 5",
    "GTSP_SET_SECTION:", "1 1 3", "-1", "2 2 4 -1", "EOF", "",
])


def test_separator_variants_and_wrapped_sets():
    """'KEY: v', 'SECTION:' and a set record spread over two lines are accepted."""
    inst = parse_gtsp(SMALL)
    assert [c.tolist() for c in inst.clusters] == [[[0, 0], [6, 8]], [[3, 4], [0, 5]]]
    assert inst.meta["node_ids"] == [1, 3, 2, 4]


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("2 2 4 -1", "2 2 4 1 -1", "node 1 is in set 1 and in set 2"),
        ("2 2 4 -1", "2 2 -1", "node 4 is in no set"),
        ("2 2 4 -1", "2 2 4", "set 2 is not terminated by -1"),
        ("GTSP_SETS: 2", "GTSP_SETS: 3", "GTSP_SETS says 3 sets"),
        ("EUC_2D", "XRAY", "unsupported EDGE_WEIGHT_TYPE 'XRAY'"),
        ("4 0 5", "4 0 nan", "node 4 has a NaN"),
        ("4 0 5", "4 0", "bad coordinate line"),
        ("4 0 5\n", "", "node 4 has no coordinates"),
        ("DIMENSION: 4", "DIMENSION: four", "DIMENSION must be an integer"),
        ("2 2 4 -1", "2 2 9 -1", "names node 9, outside 1..4"),
        ("GTSP_SETS: 2\n", "", "missing GTSP_SETS"),
        ("2 2 4 -1", "2 2 4 -1\n3 -1", "set 3 is empty"),
        # A DIMENSION far beyond the file is reported, not allocated (this once asked for 1.5 TiB).
        ("DIMENSION: 4", "DIMENSION: 100000000000", "node 5 has no coordinates"),
    ],
)
def test_bad_gtsplib_text(old, new, message):
    """Duplicate membership, missing nodes, bad numbers... each give a clear InputError."""
    with pytest.raises(InputError, match=message):
        parse_gtsp(SMALL.replace(old, new))


EXPLICIT = "\n".join([
    "NAME: e", "TYPE: GTSP", "DIMENSION: 3", "GTSP_SETS: 2", "EDGE_WEIGHT_TYPE: EXPLICIT",
    "EDGE_WEIGHT_FORMAT: FULL_MATRIX", "EDGE_WEIGHT_SECTION", "0 1 2", "1 0 3", "2 3 0",
    "GTSP_SET_SECTION", "1 3 -1", "2 1 2 -1", "EOF", "",
])


def test_explicit_with_a_huge_dimension_is_refused_without_allocating():
    """With no coordinates, the set section alone shows that DIMENSION lies."""
    with pytest.raises(InputError, match="node 4 is in no set"):
        parse_gtsp(EXPLICIT.replace("DIMENSION: 3", "DIMENSION: 100000000000"))


def test_explicit_full_matrix_round_trip():
    """EXPLICIT FULL_MATRIX weights are read in cluster order and written back."""
    inst = parse_gtsp(EXPLICIT)
    # Node order is [3, 1, 2]: weight(3, 1) = 2, weight(3, 2) = 3.
    assert inst.weights[0].tolist() == [0, 2, 3]
    again = parse_gtsp(format_gtsp(inst))
    np.testing.assert_array_equal(again.weights, inst.weights)


def test_formats_refuse_the_wrong_kind(tiny):
    """A UAV instance is not written as .gtsp, nor a GTSPLIB one as JSON."""
    with pytest.raises(InputError, match=r"write it as \.json"):
        format_gtsp(tiny)
    with pytest.raises(InputError, match=r"write it as \.gtsp"):
        format_json_instance(parse_gtsp(SMALL))


# A symmetric 4 x 4 matrix with distinct entries, so that a misplaced value shows.
MATRIX = [[0, 1, 2, 3], [1, 0, 4, 5], [2, 4, 0, 6], [3, 5, 6, 0]]


def _entries(fmt: str) -> list[int]:
    """MATRIX's entries in the order TSPLIB95 defines for ``fmt`` (written out, not computed by
    the parser's rule): ``*_ROW`` row by row, ``*_COL`` column by column."""
    n, m = len(MATRIX), MATRIX
    keep = {
        "UPPER_ROW": lambda i, j: j > i, "LOWER_ROW": lambda i, j: j < i,
        "UPPER_DIAG_ROW": lambda i, j: j >= i, "LOWER_DIAG_ROW": lambda i, j: j <= i,
    }
    if fmt == "FULL_MATRIX":
        return [m[i][j] for i in range(n) for j in range(n)]
    if fmt.endswith("_ROW"):
        return [m[i][j] for i in range(n) for j in range(n) if keep[fmt](i, j)]
    row_rule = keep[fmt.replace("_COL", "_ROW")]  # UPPER_COL: the upper triangle, column by column
    return [m[i][j] for j in range(n) for i in range(n) if row_rule(i, j)]


def _explicit(fmt: str, values: list) -> str:
    return "\n".join([
        "NAME: e4", "TYPE: GTSP", "DIMENSION: 4", "GTSP_SETS: 2", "EDGE_WEIGHT_TYPE: EXPLICIT",
        f"EDGE_WEIGHT_FORMAT: {fmt}", "EDGE_WEIGHT_SECTION",
        *(" ".join(str(v) for v in values[i:i + 3]) for i in range(0, len(values), 3)),
        "GTSP_SET_SECTION", "1 1 2 -1", "2 3 4 -1", "EOF", "",
    ])


@pytest.mark.parametrize("fmt", ["FULL_MATRIX", "UPPER_ROW", "LOWER_ROW", "UPPER_DIAG_ROW",
                                 "LOWER_DIAG_ROW", "UPPER_COL", "LOWER_COL", "UPPER_DIAG_COL",
                                 "LOWER_DIAG_COL"])
def test_every_explicit_weight_format_gives_the_full_matrix(fmt):
    """Each TSPLIB95 EDGE_WEIGHT_FORMAT (values wrapped over lines) is read as the same matrix."""
    inst = parse_gtsp(_explicit(fmt, _entries(fmt)))
    assert inst.weights.tolist() == MATRIX


def test_explicit_diagonal_is_ignored():
    """A large number on the diagonal (as some GTSPLIB files have) is read as 0."""
    values = _entries("LOWER_DIAG_ROW")
    big = [100000000 if v == 0 else v for v in values]
    assert parse_gtsp(_explicit("LOWER_DIAG_ROW", big)).weights.tolist() == MATRIX


@pytest.mark.parametrize(
    ("fmt", "values", "message"),
    [
        ("UPPER_ROW", list(range(5)), "has 5 values, UPPER_ROW needs 6"),
        ("LOWER_DIAG_ROW", list(range(11)), "has 11 values, LOWER_DIAG_ROW needs 10"),
        ("FUNCTION", [], "unsupported EDGE_WEIGHT_FORMAT 'FUNCTION'"),
        ("UPPER_ROW", [1, 2, 3, 4, 5, "x"], "not a number"),
        ("UPPER_ROW", [1, 2, 3, 4, 5, "inf"], "= inf is infinite"),
        ("FULL_MATRIX", [0, 1, 2, 3, 9, 0, 4, 5, 2, 4, 0, 6, 3, 5, 6, 0], "not symmetric"),
    ],
)
def test_bad_explicit_weights(fmt, values, message):
    """A wrong count, an unknown format, a bad number or an asymmetric matrix is an InputError."""
    with pytest.raises(InputError, match=message):
        parse_gtsp(_explicit(fmt, values))


# An asymmetric 4 x 4 matrix (row = from, column = to), with a large diagonal as AGTSP files have.
ASYMMETRIC = [[9999, 1, 2, 3], [9, 9999, 4, 5], [2, 7, 9999, 6], [3, 5, 8, 9999]]


def _agtsp(type_line: str, fmt: str = "FULL_MATRIX") -> str:
    values = [v for row in ASYMMETRIC for v in row]
    return _explicit(fmt, values).replace("TYPE: GTSP", type_line)


@pytest.mark.parametrize(
    ("line", "symmetric"),
    [
        ("TYPE: GTSP", True),
        ("TYPE : GTSP (M.~Hofmeister)", True),   # a comment after the type
        ("TYPE : TSP", True),                    # GTSP_SETS says what it is
        ("TYPE: AGTSP", False),
        ("TYPE  AGTSP", False),                  # no colon
        ("TYPE:  AGTSP", False),
    ],
)
def test_type_line_variants(line, symmetric):
    """GTSPLIB's TYPE lines as they occur; every form of AGTSP gives an asymmetric instance."""
    if symmetric:
        inst = parse_gtsp(SMALL.replace("TYPE: GTSP", line))
        assert inst.n_clusters == 2 and inst.symmetric
    else:
        inst = parse_gtsp(_agtsp(line))
        assert not inst.symmetric
        assert inst.weights.tolist() == [[0, 1, 2, 3], [9, 0, 4, 5], [2, 7, 0, 6], [3, 5, 8, 0]]


def test_asymmetric_matrix_keeps_its_direction():
    """Row = from, column = to, also after the nodes are reordered into cluster order."""
    text = _agtsp("TYPE: AGTSP").replace("1 1 2 -1\n2 3 4 -1", "1 2 1 -1\n2 4 3 -1")
    inst = parse_gtsp(text)
    assert inst.meta["node_ids"] == [2, 1, 4, 3]
    w = inst.weights
    assert (w[0, 1], w[1, 0]) == (ASYMMETRIC[1][0], ASYMMETRIC[0][1])  # node 2 -> 1, node 1 -> 2
    assert (w[2, 3], w[3, 2]) == (ASYMMETRIC[3][2], ASYMMETRIC[2][3])  # node 4 -> 3, node 3 -> 4
    order, heads = tour_to_solution(inst, [2, 3])
    assert evaluate(inst, None, order, heads).objective == ASYMMETRIC[1][2] + ASYMMETRIC[2][1]


def test_asymmetric_round_trip():
    """format_gtsp writes TYPE : AGTSP and the full matrix; reading it back gives the same costs."""
    inst = parse_gtsp(_agtsp("TYPE : AGTSP"))
    again = parse_gtsp(format_gtsp(inst))
    assert not again.symmetric and again.weights.tolist() == inst.weights.tolist()
    assert "TYPE : AGTSP" in format_gtsp(inst)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (_agtsp("TYPE: AGTSP", "UPPER_ROW"), r"\(AGTSP\) file needs EDGE_WEIGHT_FORMAT FULL_MATRIX"),
        (SMALL.replace("TYPE: GTSP", "TYPE: AGTSP"), r"\(AGTSP\) file needs EXPLICIT weights"),
        (_agtsp("TYPE: GTSP"), r"not symmetric \(node 1 to 2 weighs 1, back 9\); an asymmetric file says "
                               "TYPE : AGTSP"),
    ],
)
def test_asymmetric_input_errors(text, message):
    """AGTSP needs a full explicit matrix; a symmetric type with an asymmetric matrix is refused."""
    with pytest.raises(InputError, match=message):
        parse_gtsp(text)


def test_geom_is_a_coordinate_type():
    """GEOM files keep their coordinates and weight type."""
    inst = parse_gtsp(SMALL.replace("EUC_2D", "GEOM"))
    assert inst.edge_weight_type == "GEOM" and inst.weights is None


TOUR = "NAME : small.tour\nCOMMENT : Length = 10\nTYPE : TOUR\nDIMENSION : 2\nTOUR_SECTION\n4\n1\n-1\nEOF\n"


def test_tour_to_solution():
    """A tour's 1-based file node ids become (order, heads) of the instance read from that file."""
    inst = parse_gtsp(SMALL)  # cluster 0 = nodes 1, 3; cluster 1 = nodes 2, 4
    assert parse_tour(TOUR) == [4, 1]
    assert tour_to_solution(inst, [4, 1]) == ([1, 0], [0, 1])
    assert tour_to_solution(inst, [3, 2]) == ([0, 1], [1, 0])


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("TOUR_SECTION\n4\n1\n-1\n", "", "missing TOUR_SECTION"),
        ("4\n1\n-1", "-1", "TOUR_SECTION is empty"),
        ("4\n1", "4\nx", "TOUR_SECTION has 'x', not a node id"),
        ("4\n1", "4\n0", "node ids start at 1"),
        ("DIMENSION : 2", "DIMENSION : 3", "DIMENSION says 3 nodes but TOUR_SECTION has 2"),
    ],
)
def test_bad_tours(old, new, message):
    """A tour file without a usable TOUR_SECTION is an InputError naming the problem."""
    with pytest.raises(InputError, match=message):
        parse_tour(TOUR.replace(old, new))


def test_tour_of_unknown_nodes_or_of_another_size():
    """A node the instance does not have, or a tour of more or fewer nodes than it has clusters,
    is refused with what was expected."""
    with pytest.raises(InputError, match=r"tour names node 7, which is not in small \(its nodes are 1..4\)"):
        tour_to_solution(parse_gtsp(SMALL), [7, 1])
    with pytest.raises(InputError, match="the tour lists 3 nodes, but a tour of small lists one node of "
                                         "each of its 2 clusters"):
        tour_to_solution(parse_gtsp(SMALL), [1, 2, 4])


def test_uav_tour_node_ids_count_the_nodes_in_cluster_order():
    """A UAV instance's node i of cluster k is id offsets[k] + i + 1 (the JSON's order, 1-based);
    the depot has none."""
    uav = parse_json_instance(_text())  # cluster 0: two nodes, cluster 1: one
    assert tour_node_ids(uav).tolist() == [1, 2, 3]
    assert tour_to_solution(uav, [3, 2]) == ([1, 0], [1, 0])


def test_format_tour_writes_what_parse_tour_reads():
    """format_tour lists the heads' file ids in visiting order, DIMENSION = K, and reads back as
    the same solution; GTSPLIB ids are the file's, not the cluster-order numbers."""
    inst = parse_gtsp(SMALL)  # cluster 0 = nodes 1, 3; cluster 1 = nodes 2, 4
    text = format_tour(inst, [1, 0], [0, 1], comments=["Length = 10", "two\nlines"])
    assert parse_tour(text) == [4, 1]
    assert "DIMENSION : 2\n" in text and "COMMENT : two lines\n" in text
    assert tour_to_solution(inst, parse_tour(text)) == ([1, 0], [0, 1])
    uav = parse_json_instance(_text())
    assert parse_tour(format_tour(uav, [0, 1], [1, 0])) == [2, 3]


def test_format_tour_refuses_an_infeasible_solution():
    """A solution that repeats a cluster is not written."""
    with pytest.raises(InputError, match="cluster 0 is visited 2 times"):
        format_tour(parse_gtsp(SMALL), [0, 0], [0, 0])


def test_nan_in_an_explicit_matrix_is_named_as_such():
    """A nan weight is reported as nan with its place, not as an asymmetric matrix."""
    with pytest.raises(InputError, match=r"EDGE_WEIGHT_SECTION\[1\]\[2\] is nan \(not a number\)"):
        parse_gtsp(EXPLICIT.replace("1 0 3", "1 0 nan"))
    with pytest.raises(InputError, match=r"EDGE_WEIGHT_SECTION\[2\]\[0\] = inf is infinite"):
        parse_gtsp(EXPLICIT.replace("2 3 0", "inf 3 0"))


@pytest.mark.parametrize(("text", "message"), [
    (_text(clusters=[[[0, 0], [1e300, 1e300]], [[5, 6]]]), r"clusters\[0\]\[1\]\[0\] = 1e\+300 is beyond"),
    (_text(depot=[-2e9, 0]), r"depot\[0\] = -2e\+09 is beyond"),
    (_text(clusters=[[[0, 0], [9e8, 9e8]], [[5, 6]]]), "a tour's energy could reach"),
    (_text(params={"p_ch_dbm": 1e300}), "p_ch_w = inf"),
    (_text(params={"bandwidth": 1e-300}), r"a tour.s energy could reach 7.77165e\+304"),
])
def test_numbers_too_large_to_order_tours_are_refused(text, message):
    """Finite but huge coordinates, or parameters whose derived energies overflow, are named."""
    with pytest.raises(InputError, match=message):
        parse_json_instance(text)


def test_gtsplib_coordinates_near_the_float_limit_are_refused():
    """Nodes at +-1e308 (finite) would make every distance infinite: refused at load."""
    with pytest.raises(InputError, match=r"clusters\[0\]\[1\]\[0\] = 1e\+308 is beyond"):
        parse_gtsp(SMALL.replace("3 6 8", "3 1e308 -1e308"))


@pytest.mark.parametrize("node", ["inf", "-inf", "nan", "1.5"])
def test_gtsplib_node_ids_that_are_not_integers_are_refused_without_a_warning(node):
    """A node id of inf, nan or 1.5 is refused in one line, and the fast reader does not cast it
    to an integer on the way (numpy's invalid-cast warning)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(InputError):
            parse_gtsp(SMALL.replace("3 6 8", f"{node} 6 8"))


# ---------------------------------------------------------------------- fuzzing
# GTSP_BENCH_FUZZ_EXAMPLES=2000 make test runs many more examples than the default.
FUZZ = settings(max_examples=int(os.environ.get("GTSP_BENCH_FUZZ_EXAMPLES", "40")), deadline=None,
                database=None, suppress_health_check=list(HealthCheck))

_json_values = st.recursive(
    st.none() | st.booleans() | st.integers(-(10**20), 10**20) | st.floats() | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner, max_size=4),
    max_leaves=12,
)
_numbers = st.floats() | st.integers(-(10**30), 10**30) | st.sampled_from([1e300, -1e308, 1e9, 5e-324])


def _loads_or_input_error(parse, text: str) -> None:
    """``parse(text)`` gives an instance whose tours all price to finite numbers, without a
    numpy warning, or raises InputError; anything else fails the test."""
    from gtsp_bench.energy import evaluate

    try:
        inst = parse(text)
    except InputError:
        return
    k = inst.n_clusters
    with np.errstate(over="raise", invalid="raise"):
        ev = evaluate(inst, 0.5, list(range(k)), [len(c) - 1 for c in inst.clusters])
    assert np.isfinite(ev.objective)


@FUZZ
@given(value=_json_values)
def test_fuzz_any_json_value_loads_or_is_an_input_error(value):
    """Any JSON value at all: an instance, or InputError."""
    _loads_or_input_error(parse_json_instance, json.dumps(value))


@FUZZ
@given(data=st.data())
def test_fuzz_mutated_json_instances_load_or_are_input_errors(data):
    """A valid instance with one part replaced (a coordinate, a cluster, the depot, a parameter,
    any key) by a random number or JSON value, or its text cut or spliced."""
    inst = json.loads(_text(params={"height": 60.0}))
    target = data.draw(st.sampled_from(["coordinate", "cluster", "depot", "param", "key", "text"]))
    if target == "coordinate":
        k = data.draw(st.integers(0, 1))
        i = data.draw(st.integers(0, len(inst["clusters"][k]) - 1))
        inst["clusters"][k][i][data.draw(st.integers(0, 1))] = data.draw(_numbers)
    elif target == "cluster":
        inst["clusters"][data.draw(st.integers(0, 1))] = data.draw(_json_values)
    elif target == "depot":
        inst["depot"] = data.draw(st.lists(_numbers, min_size=0, max_size=3) | _json_values)
    elif target == "param":
        name = data.draw(st.sampled_from(["height", "p_ch_dbm", "bandwidth", "eps_mp", "v_uav",
                                          "message_bits", "noise_dbm_per_hz", "speed"]))
        inst["params"][name] = data.draw(_numbers | _json_values)
    elif target == "key":
        inst[data.draw(st.sampled_from(["name", "meta", "clusters", "params", "extra"]))] = \
            data.draw(_json_values)
    text = json.dumps(inst)
    if target == "text":
        cut = data.draw(st.integers(0, len(text)))
        text = text[:cut] + data.draw(st.text(max_size=6)) + text[cut + data.draw(st.integers(0, 4)):]
    _loads_or_input_error(parse_json_instance, text)


@FUZZ
@given(data=st.data())
def test_fuzz_mutated_gtsplib_text_loads_or_is_an_input_error(data):
    """.gtsp text (coordinates and an explicit matrix) with lines dropped, repeated or
    replaced, or tokens replaced by random numbers or text."""
    lines = data.draw(st.sampled_from([SMALL, EXPLICIT])).splitlines()
    for _ in range(data.draw(st.integers(1, 3))):
        i = data.draw(st.integers(0, len(lines) - 1))
        action = data.draw(st.sampled_from(["drop", "repeat", "replace", "token"]))
        if action == "drop":
            del lines[i]
        elif action == "repeat":
            lines.insert(i, lines[i])
        elif action == "replace":
            lines[i] = data.draw(st.text(max_size=12))
        else:
            tokens = lines[i].split() or [""]
            j = data.draw(st.integers(0, len(tokens) - 1))
            tokens[j] = str(data.draw(_numbers | st.text(max_size=5) | st.integers(-3, 10)))
            lines[i] = " ".join(tokens)
        if not lines:
            break
    _loads_or_input_error(parse_gtsp, "\n".join(lines))


@FUZZ
@given(text=st.text(max_size=200))
def test_fuzz_any_text_is_gtsplib_or_an_input_error(text):
    """Arbitrary text: a .gtsp instance, or InputError."""
    _loads_or_input_error(parse_gtsp, text)


def test_parse_instance_text_tells_the_formats_apart(tiny):
    """JSON text (first non-blank character '{') is a UAV instance, anything else GTSPLIB."""
    from gtsp_bench.data.parse import parse_instance_text
    from gtsp_bench.instance import Instance

    uav = parse_instance_text("\n  " + format_json_instance(tiny))
    assert uav.is_uav and uav.name == "tiny"
    flat = Instance("flat", tiny.clusters, params=None, edge_weight_type="EUC_2D")
    back = parse_instance_text(format_gtsp(flat))
    assert not back.is_uav and back.n_clusters == 2 and back.name == "flat"
    with pytest.raises(InputError):
        parse_instance_text("NAME : x\nTYPE : TSP\n")

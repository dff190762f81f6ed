"""The row schema and the reference rule: proven optima of exact tasks, the set's table, a
benchmark's own proofs, the best found; tours below a proven optimum and disagreeing proofs are
errors; a best known value beaten becomes the best found; a partial rerun merged by solve."""

from __future__ import annotations

import math

import pandas as pd
import pytest

from gtsp_bench.bench.definitions import Reference, Run
from gtsp_bench.bench.outputs import errors_of
from gtsp_bench.bench.rows import (
    BELOW_OPTIMUM,
    BETTER_THAN_BEST_KNOWN,
    COLUMNS,
    Cell,
    make_rows,
    merge_rows,
    references,
    summary_table,
)
from gtsp_bench.bench.sources import Entry
from gtsp_bench.bench.tasks import StoredInstance, fingerprint
from gtsp_bench.data.parse import format_json_instance
from gtsp_bench.data.sets import ReferenceRow
from gtsp_bench.generator import generate_instance

INST = generate_instance(3, 4, seed=1, name="t3")
TEXT = format_json_instance(INST)


def _entry(table: dict | None = None) -> Entry:
    stored = StoredInstance(INST, TEXT, fingerprint(TEXT), __import__("pathlib").Path("t3.json"))
    return Entry("set", "t3", stored, table or {})


def _rec(obj: float | None, status: str = "feasible", lb: float | None = None) -> dict:
    if obj is None:
        return {"status": "failed", "objective": None, "note": "boom"}
    return {"status": status, "objective": obj, "lower_bound": lb, "runtime_s": 0.5,
            "order": [0, 1, 2], "heads": [0, 0, 0], "trajectory": [[0.1, obj * 1.1, None], [0.5, obj, lb]]}


def _cells(entry: Entry, *solvers: str) -> list[Cell]:
    return [Cell(entry, Run(s), 0.5, 0, 10.0, f"k-{s}") for s in solvers]


def test_an_exact_tasks_proof_is_the_reference_and_gaps_are_to_it():
    """The exact task's optimum wins over the table; gap_pct to it, bound_gap_pct to the row's
    own bound; the schema's columns in order; the tour and trajectory kept."""
    e = _entry({0.5: ReferenceRow("t3", 0.5, 90.0, None, "best_known", "old", "")})
    cells = _cells(e, "a", "b")
    records = {"k-a": _rec(105.0, lb=100.0), "k-b": _rec(100.0), "k-dp": _rec(100.0, "optimal")}
    refs = references(Reference(exact=(("dp", None),)), cells, records, {("set", "t3", 0.5): ("k-dp", "dp")})
    df = make_rows("b", cells, records, refs)
    assert tuple(df.columns) == COLUMNS
    a = df.set_index("solver").loc["a"]
    assert a["reference_kind"] == "optimal" and a["reference_source"] == "dp (proven)"
    assert math.isclose(a["gap_pct"], 5.0) and math.isclose(a["bound_gap_pct"], 100 * 5 / 105)
    assert a["order"] == "0 1 2" and a["heads"] == "0 0 0" and a["trajectory"].count(":") == 3
    assert 0 < a["primal_integral"] < 1 and a["time_to_1pct_s"] != a["time_to_1pct_s"]  # NaN: never
    assert df.set_index("solver").loc["b", "time_to_0p1pct_s"] == 0.5


def test_the_table_then_own_proofs_then_the_best_found():
    """No exact task: the set's row; without one, a proof of the benchmark's own solves (with
    own_proofs); without either, the best objective found, labelled best_found."""
    table = {0.5: ReferenceRow("t3", 0.5, 99.0, 98.0, "optimal", "milp 60s", "2026-11-27")}
    records = {"k-a": _rec(99.0), "k-b": _rec(101.0, "optimal")}
    by_table = references(Reference(), _cells(_entry(table), "a", "b"), records, {})
    assert by_table[("set", "t3", 0.5)].value == 99.0 and by_table[("set", "t3", 0.5)].kind == "optimal"
    proofs = references(Reference(table=False, own_proofs=True), _cells(_entry(), "a", "b"), records, {})
    assert proofs[("set", "t3", 0.5)].value == 101.0 and proofs[("set", "t3", 0.5)].source == "b (proven)"
    best = references(Reference(table=False), _cells(_entry(), "a", "b"), records, {})
    assert best[("set", "t3", 0.5)].kind == "best_found" and best[("set", "t3", 0.5)].value == 99.0


def test_a_beaten_best_known_becomes_best_found_and_the_row_says_so():
    """A solve below a best_known value: the reference is the best found, and the row notes it."""
    e = _entry({0.5: ReferenceRow("t3", 0.5, 100.0, None, "best_known", "GLKH", "")})
    cells = _cells(e, "a")
    records = {"k-a": _rec(95.0)}
    refs = references(Reference(), cells, records, {})
    table = references(Reference(), cells, {}, {})
    df = make_rows("b", cells, records, refs, table)
    row = df.iloc[0]
    assert row["reference_kind"] == "best_found" and row["gap_pct"] == 0.0
    assert BETTER_THAN_BEST_KNOWN in row["note"]


def test_below_a_proven_optimum_and_disagreeing_proofs_are_errors():
    """A tour below the reference optimum is noted and an error; two proofs that differ are one."""
    e = _entry({0.5: ReferenceRow("t3", 0.5, 100.0, None, "optimal", "dp", "")})
    cells = _cells(e, "a", "b", "c")
    records = {"k-a": _rec(90.0), "k-b": _rec(100.0, "optimal"), "k-c": _rec(101.0, "optimal")}
    df = make_rows("b", cells, records, references(Reference(), cells, records, {}))
    assert BELOW_OPTIMUM in df.set_index("solver").loc["a", "note"]
    errors = errors_of(df)
    assert any("below the proven optimum" in e for e in errors)
    assert any("proven optima disagree" in e for e in errors)


def test_summary_counts_hits_proofs_failures():
    """The summary per set and label: solves, hits, proven and failed counts."""
    cells = _cells(_entry(), "a", "b", "c")
    records = {"k-a": _rec(100.0, "optimal"), "k-b": _rec(110.0), "k-c": _rec(None)}
    df = make_rows("b", cells, records, references(Reference(own_proofs=True), cells, records, {}))
    s = summary_table(df).set_index("label")
    assert s.loc["a", "hits"] == 1 and s.loc["a", "proven"] == 1
    assert math.isclose(s.loc["b", "mean_gap_pct"], 10.0) and s.loc["b", "hits"] == 0
    assert s.loc["c", "failed"] == 1 and pd.isna(s.loc["c", "mean_gap_pct"])


def _rows(*solves: tuple[str, float | None, int, float], benchmark: str = "b",
          kind: str = "best_known") -> pd.DataFrame:
    """Rows of (instance, omega, seed, objective) solves of one label."""
    out = pd.DataFrame([{c: None for c in COLUMNS} for _ in solves])
    out["benchmark"], out["set"], out["label"], out["reference_kind"] = benchmark, "s", "lns", kind
    out["instance"] = [x[0] for x in solves]
    out["omega"] = [x[1] for x in solves]
    out["seed"] = [x[2] for x in solves]
    out["objective"] = [x[3] for x in solves]
    return out


def test_merge_replaces_the_same_solves_and_appends_the_others():
    """A rerun's rows take the place of the rows of the same (set, instance, omega, label, seed),
    in the old order; solves the old rows lack are appended; the rest is left as it was."""
    old = _rows(("a", None, 1, 10.0), ("a", None, 2, 11.0), ("b", 0.5, 1, 20.0), ("b", 0.25, 1, 21.0))
    new = _rows(("b", 0.5, 1, 19.0), ("a", None, 2, 10.5), ("c", None, 1, 30.0))
    merged, replaced, added = merge_rows(old, new)
    assert (replaced, added) == (2, 1)
    assert merged["instance"].tolist() == ["a", "a", "b", "b", "c"]
    assert merged["objective"].tolist() == [10.0, 10.5, 19.0, 21.0, 30.0]
    assert list(merged.columns) == list(COLUMNS)
    assert old["objective"].tolist() == [10.0, 11.0, 20.0, 21.0]  # the inputs are not changed


@pytest.mark.parametrize("old, new, message", [
    (_rows(("a", None, 1, 1.0)), _rows(("a", None, 1, 1.0), benchmark="c"), "different benchmarks"),
    (_rows(("a", None, 1, 1.0), ("a", None, 1, 2.0)), _rows(("a", None, 1, 1.0)), "one solve twice"),
    (_rows(("a", None, 1, 1.0), ("a", None, 2, 1.0)), _rows(("a", None, 1, 1.0), kind="best_found"),
     "rows of s a have gaps to the best found"),
    (_rows(("a", 0.5, 1, 1.0), ("a", 0.5, 2, 1.0), kind="best_found"), _rows(("a", 0.5, 2, 1.0)),
     "rows of s a omega 0.5 have gaps to the best found"),
])
def test_merge_refuses_what_it_cannot_fold(old, new, message):
    """Rows of another benchmark, a solve twice, or a point whose rows have gaps to a run's own
    best found, with only some of them replaced: refused."""
    with pytest.raises(ValueError, match=message):
        merge_rows(old, new)


def test_merge_takes_whole_points_with_their_own_best_found():
    """Gaps to a run's own best found are merged where the point keeps one run's rows: a point
    the new rows replace whole (and one they add), and a point they do not touch."""
    old = _rows(("a", 0.0, 1, 10.0), ("a", 0.0, 2, 11.0), ("b", 0.0, 1, 20.0), kind="best_found")
    new = _rows(("a", 0.0, 1, 9.0), ("a", 0.0, 2, 9.5), ("c", 0.0, 1, 30.0), kind="best_found")
    merged, replaced, added = merge_rows(old, new)
    assert (replaced, added) == (2, 1)
    assert merged["objective"].tolist() == [9.0, 9.5, 20.0, 30.0]

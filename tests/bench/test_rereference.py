"""--re-reference: a run's rows measured against today's reference tables without solving; a
new value rebuilds the rows' gaps, the same value of a new kind only relabels them, a proof of the
run is kept, and a changed instance is refused."""

from __future__ import annotations

import hashlib
import json

import pandas as pd
import pytest

from gtsp_bench.bench.definitions import BENCHMARKS
from gtsp_bench.bench.rereference import Tables, rereference
from gtsp_bench.cli import main
from gtsp_bench.data.io import write_instance
from gtsp_bench.generator import generate_instance
from tests.bench.frames import row_frame

HEADER = "instance,omega,value,lower_bound,status,source,date\n"


def _set(tmp_path, rows: str = ""):
    folder = tmp_path / "mine"
    for i in range(2):
        write_instance(generate_instance(3, 4, seed=i, name=f"mine-{i}"), folder / f"mine-{i}.json")
    (folder / "reference.csv").write_text(HEADER + rows)
    return folder


def _run(tmp_path, capsys, folder, *more):
    argv = ["bench", "sets", "--set", str(folder), "--solvers", "greedy", "--omegas", "0.5",
            "--jobs", "1", "--out", str(tmp_path / "out"), "--no-progress", *more]
    code = main(argv)
    return code, capsys.readouterr()


def test_a_better_reference_rebuilds_the_gaps_and_the_same_value_only_relabels(tmp_path, capsys):
    """Rows measured against the run's own best: after reference.csv gets a better tour for one
    instance and a proof of the run's value for the other, --re-reference gives the first its
    new gap, the second the kind 'optimal' with every number as it was; the manifest says so,
    and a second call changes nothing."""
    folder = _set(tmp_path)
    assert _run(tmp_path, capsys, folder)[0] == 0
    out = tmp_path / "out"
    before = pd.read_csv(out / "rows.csv").set_index("instance")
    assert set(before["reference_kind"]) == {"best_found"}
    obj0, obj1 = float(before.loc["mine-0", "objective"]), float(before.loc["mine-1", "objective"])
    (folder / "reference.csv").write_text(
        HEADER + f"mine-0,0.5,{0.9 * obj0!r},,best_known,a better tour,2026-12-01\n"
        f"mine-1,0.5,{obj1!r},{obj1!r},optimal,a proof,2026-12-01\n")
    code, said = _run(tmp_path, capsys, folder, "--re-reference")
    assert code == 0, said.err
    assert "1 of 2 rows measured against a new reference value, 1 against the same value" in said.err
    after = pd.read_csv(out / "rows.csv").set_index("instance")
    r0, r1 = after.loc["mine-0"], after.loc["mine-1"]
    assert (r0["reference_kind"], r0["reference_source"]) == ("best_known", "a better tour 2026-12-01")
    assert r0["gap_pct"] == pytest.approx(100 * (obj0 - 0.9 * obj0) / (0.9 * obj0), rel=1e-6)
    assert r0["objective"] == pytest.approx(obj0, rel=1e-12)
    assert (r1["reference_kind"], r1["reference_source"]) == ("optimal", "a proof 2026-12-01")
    keep = [c for c in before.columns if not c.startswith("reference_")]
    pd.testing.assert_series_equal(before.loc["mine-1", keep], r1[keep], check_names=False)
    assert "| best_known / optimal | 5.556 | 11.111 | 1/2 |" in (out / "summary.md").read_text()
    merges = json.loads((out / "manifest.json").read_text())["merges"]
    assert [(m["re_referenced"], m["renamed"]) for m in merges] == [(1, 1)]
    text = (out / "rows.csv").read_text()
    code, said = _run(tmp_path, capsys, folder, "--re-reference")
    assert code == 0 and "already measured against today's references" in said.err
    assert (out / "rows.csv").read_text() == text


def test_a_changed_instance_is_refused_and_nothing_is_written(tmp_path, capsys):
    """An instance file that is not the one the run solved: one error line, exit 2, rows kept."""
    folder = _set(tmp_path)
    assert _run(tmp_path, capsys, folder)[0] == 0
    text = (tmp_path / "out" / "rows.csv").read_text()
    write_instance(generate_instance(3, 4, seed=9, name="mine-0"), folder / "mine-0.json")
    code, said = _run(tmp_path, capsys, folder, "--re-reference")
    assert code == 2 and said.err.count("\n") == 1
    assert "mine/mine-0: the instance file changed since the run" in said.err
    assert (tmp_path / "out" / "rows.csv").read_text() == text


def test_a_malformed_row_is_one_line_naming_the_rows_file(tmp_path, capsys):
    """A trajectory that is not numbers: exit 2, the rows file and the point named, no traceback."""
    folder = _set(tmp_path)
    assert _run(tmp_path, capsys, folder)[0] == 0
    rows = tmp_path / "out" / "rows.csv"
    df = pd.read_csv(rows)
    df.loc[0, "trajectory"] = "soon:never"
    df.to_csv(rows, index=False)
    code, said = _run(tmp_path, capsys, folder, "--re-reference")
    assert code == 2 and said.err.count("\n") == 1, said.err
    assert f"{rows}: mine/mine-0: a row is malformed" in said.err


@pytest.mark.parametrize("more", [["--report-only"], ["--update-reference"]])
def test_re_reference_goes_alone(tmp_path, capsys, more):
    """--re-reference with another way of writing the outputs: one line, exit 2."""
    code, said = _run(tmp_path, capsys, tmp_path, "--re-reference", *more)
    assert code == 2 and "--re-reference: give it alone" in said.err


def _row(folder, **over):
    sha = hashlib.sha256((folder / "mine-0.json").read_text().encode()).hexdigest()
    return row_frame(set="mine", instance="mine-0", instance_sha256=sha, solver="greedy",
                     label="greedy", objective=110.0, **over)


def test_a_proof_of_the_run_and_its_best_found_value_are_kept(tmp_path):
    """What the rows alone cannot show stays: an exact task's proven optimum beats today's
    table; a best-found value of the run below today's best known stays the reference."""
    folder = _set(tmp_path, "mine-0,0.5,105,,best_known,a tour,2026-12-01\n")
    tables = Tables([tmp_path])
    bench = BENCHMARKS["sets"]
    proven = _row(folder, reference_value=100.0, reference_kind="optimal",
                  reference_source="dp (proven)", gap_pct=10.0)
    done = rereference(bench, proven, tables)
    assert (done.changed, done.renamed) == (0, 0)
    assert done.rows.iloc[0]["reference_source"] == "dp (proven)"
    found = _row(folder, reference_value=95.0, reference_kind="best_found",
                 reference_source="best of this run", gap_pct=100 * 15 / 95)
    done = rereference(bench, found, tables)
    row = done.rows.iloc[0]
    assert (row["reference_kind"], row["reference_value"]) == ("best_found", 95.0)
    assert row["reference_source"].startswith("best of this run, below a tour")
    assert (done.changed, done.renamed) == (0, 1)


def test_rows_of_an_instance_that_cannot_be_found_are_left_alone(tmp_path):
    """A set found nowhere: its rows as they were, the set named."""
    df = row_frame(set="gone", instance="gone-0", instance_sha256="0" * 64)
    done = rereference(BENCHMARKS["sets"], df, Tables([tmp_path]))
    assert done.missing == ["gone"] and done.rows.equals(df)


def test_a_tour_kept_in_the_table_is_no_longer_better_than_the_best_known(tmp_path):
    """A row that beat the table, whose tour --update-reference kept since: measured against the
    table's row of the same value, without its note."""
    from gtsp_bench.bench.rows import BETTER_THAN_BEST_KNOWN

    folder = _set(tmp_path, "mine-0,0.5,110,,best_known,greedy 10s seed 0,2026-12-01\n")
    row = _row(folder, reference_value=110.0, reference_kind="best_found",
               reference_source="best of this run, below a guess 1e9", gap_pct=0.0,
               note=f"warm; {BETTER_THAN_BEST_KNOWN}")
    done = rereference(BENCHMARKS["sets"], row, Tables([tmp_path]))
    got = done.rows.iloc[0]
    assert (got["reference_kind"], got["reference_source"]) == ("best_known", "greedy 10s seed 0 2026-12-01")
    assert got["note"] == "warm" and (done.changed, done.renamed) == (0, 1)

"""The heuristics-and-peers table (python -m gtsp_bench.bench.heuristics_table): instance groups, the
generated instances of large K, cells, and the generated block it writes into a page."""

from __future__ import annotations

import csv
import math

import pytest

from gtsp_bench.bench import heuristics_table as ht
from gtsp_bench.bench.tables import Row

from .conftest import REPO

PAGE = "# Page\n\ntext before\n\n<!-- BEGIN generated:heuristics-table -->\nold\n" \
       "<!-- END generated:heuristics-table -->\n\ntext after\n"


@pytest.mark.parametrize("k", ht.UAV_KS)
def test_uav_sets_are_the_committed_ones(k):
    """Each K of the table has its committed set of 20 instances of K clusters of 20 nodes."""
    chosen = ht.uav_set(k, REPO / "instances")
    assert chosen.name == f"uav-K{k}-N20-s1" and len(chosen.files) == 20
    first = chosen.files[0].stem
    assert first == f"uav-K{k}-N20-s1-000" and (first, 0.5) in chosen.references


def test_a_k_without_a_committed_set_is_refused_before_any_solve(tmp_path, capsys):
    """-K 3 (no uav-K3-N20-s1): one line listing the committed sets, exit 2, nothing written."""
    argv = ["-K", "3", "--no-gtsplib", "--csv", str(tmp_path / "t.csv"), "--no-docs",
            "--instance-dir", str(REPO / "instances")]
    assert ht.main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("gtsp-bench: error: unknown set 'uav-K3-N20-s1'") and "uav-K20-N20-s1" in err
    assert err.count("\n") == 1 and not (tmp_path / "t.csv").exists()


def _rows(*objectives):
    return [Row("g", "i", 0.5, f"s{j}", "feasible" if math.isfinite(o) else "failed", o)
            for j, o in enumerate(objectives)]


def test_reference_is_the_sets_value_unless_beaten():
    """The set's value (optimum / best known) when no solve beat it; the best found otherwise,
    or when the instance has no reference row."""
    assert ht.reference_for(_rows(101.0, 100.0), 100.0, "optimal") == (100.0, "optimum")
    assert ht.reference_for(_rows(101.0, math.nan), 100.0, "best_known") == (100.0, "best known")
    assert ht.reference_for(_rows(101.0, 99.5), 100.0, "best_known") == (99.5, "best found")
    assert ht.reference_for(_rows(101.0, 102.0), None, None) == (101.0, "best found")


def test_gtsplib_groups_take_the_smallest_of_each_size():
    """per_group instances of each size group in file order, the AGTSP files apart."""
    picked = ht.gtsplib_instances(ht.TableConfig(per_group=2))
    groups = {}
    for group, inst, best in picked:
        groups.setdefault(group, []).append((inst.n_nodes, inst.symmetric, best))
    assert list(groups) == [g for g, _, _ in ht.GTSPLIB_GROUPS] + [ht.AGTSP_GROUP]
    for label, lo, hi in ht.GTSPLIB_GROUPS:
        assert len(groups[label]) == 2 and all(lo <= n <= hi and sym for n, sym, _ in groups[label])
    assert [sym for _, sym, _ in groups[ht.AGTSP_GROUP]] == [False, False]
    assert groups["GTSPLIB <= 200 nodes"][0] == (14, True, 1805.0)  # 3burma14


def _row(solver, status, objective, runtime, group="g", instance="i"):
    row = Row(group, instance, None, solver, status, objective, runtime_s=runtime)
    return row.against(100.0, "best known")


def test_cells():
    """Mean gap and median time of the answers; refused/failed when none answered; n/m when some."""
    assert ht.cell([_row("a", "feasible", 101.0, 1.0), _row("a", "time_limit", 103.0, 3.0)]) == "2.00% 2.00s*"
    assert ht.cell([_row("a", "refused", math.nan, math.nan)]) == "refused"
    none = [_row("a", "failed", math.nan, math.nan), _row("a", "refused", math.nan, math.nan)]
    assert ht.cell(none) == "failed"
    assert ht.cell([_row("a", "feasible", 110.0, 1.0), _row("a", "failed", math.nan, math.nan)]) == \
        "10.00% 1.00s (1/2)"


def test_run_writes_csv_and_the_page_block(tmp_path, capsys):
    """A tiny run: GTSPLIB up to 20 nodes (3burma14 and the AGTSP 4br17) and the first instance of
    the committed K = 4 set (its reference is dp's optimum); greedy+ls refuses the asymmetric file;
    the page's block is replaced, the text around kept."""
    page = tmp_path / "page.md"
    page.write_text(PAGE)
    argv = ["--time-limit", "1", "--per-group", "1", "--max-nodes", "20", "-K", "4",
            "--uav-instances", "1", "--solvers", "greedy,greedy+ls", "--csv", str(tmp_path / "t.csv"),
            "--docs", str(page), "--instance-dir", str(REPO / "instances")]
    assert ht.main(argv) == 0
    with (tmp_path / "t.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert [(r["instance"], r["solver"], r["status"]) for r in rows if r["status"] == "refused"] == [
        ("4br17", "greedy+ls", "refused")]
    assert {r["group"] for r in rows} == {"GTSPLIB <= 200 nodes", "GTSPLIB AGTSP", "UAV K=4"}
    assert {(r["instance"], r["reference_kind"]) for r in rows if r["group"] == "UAV K=4"} == {
        ("uav-K4-N20-s1-000", "optimum")}
    assert all(float(r["gap_percent"]) >= 0 for r in rows if r["status"] != "refused")
    text = page.read_text()
    assert text.startswith("# Page\n\ntext before\n") and text.endswith("text after\n")
    assert "\nold\n" not in text and "| GTSPLIB AGTSP | 1 | best known | 0.00% " in text
    assert "make bench-heuristics-table TABLE_ARGS='--time-limit 1 " in text
    assert "| greedy | greedy+ls |" in capsys.readouterr().out
    assert ht.markdown(ht.read_rows(tmp_path / "t.csv"), ["greedy", "greedy+ls"]) in text


def test_the_committed_block_is_made_from_the_committed_rows():
    """docs/solvers/heuristics.md's table is what markdown() makes of benchmarks/heuristics-table.csv."""
    rows = ht.read_rows(REPO / ht.DEFAULT_CSV)
    solvers = list(dict.fromkeys(r.solver for r in rows))
    assert set(solvers) == set(ht.SOLVERS)
    page = (REPO / ht.DOCS_PAGE).read_text(encoding="utf-8")
    begin = page.index(f"<!-- BEGIN generated:{ht.BLOCK} -->")
    end = page.index(f"<!-- END generated:{ht.BLOCK} -->")
    assert ht.markdown(rows, solvers) in page[begin:end]


def test_bad_options_are_one_line(tmp_path, capsys):
    """An unknown solver, a missing page or a malformed number: one gtsp-bench: error line, exit
    code 2."""
    with pytest.raises(SystemExit) as stop:
        ht.main(["--time-limit", "x"])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err == "gtsp-bench: error: argument --time-limit/-t: invalid float value: 'x'\n"
    assert ht.main(["--solvers", "greedy,nope", "--no-docs"]) == 2
    assert capsys.readouterr().err.startswith("gtsp-bench: error: unknown solver 'nope' (valid: ")
    assert ht.main(["--docs", str(tmp_path / "none.md")]) == 2
    err = capsys.readouterr().err
    assert err == f"gtsp-bench: error: {tmp_path / 'none.md'}: no such page for the table\n"


def _tiny(tmp_path, *extra):
    return ["--time-limit", "1", "--per-group", "1", "--max-nodes", "14", "--no-agtsp", "-K", "4",
            "--uav-instances", "1", "--solvers", "greedy,greedy+ls", "--csv", str(tmp_path / "t.csv"),
            "--no-docs", "--instance-dir", str(REPO / "instances"), *extra]


def _csv(path):
    with path.open(newline="") as f:
        return list(csv.DictReader(f))


def test_a_rerun_keeps_the_rows_of_the_same_settings_and_redo_solves_again(tmp_path, capsys):
    """Rows of the same time limit, seed and omega are kept (a marked objective survives the
    re-run); --redo re-solves the named solver only; another time limit keeps none."""
    path = tmp_path / "t.csv"
    assert ht.main(_tiny(tmp_path)) == 0
    first = _csv(path)
    assert len(first) == 4 and {r["time_limit"] for r in first} == {"1.0"}
    marked = [dict(r, objective=str(float(r["objective"]) + 7.0)) for r in first]
    with path.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=ht.COLUMNS, lineterminator="\n")
        w.writeheader()
        w.writerows(marked)
    capsys.readouterr()
    assert ht.main(_tiny(tmp_path)) == 0
    assert "4 solve(s) kept from" in capsys.readouterr().err
    assert [r["objective"] for r in _csv(path)] == [r["objective"] for r in marked]
    assert ht.main(_tiny(tmp_path, "--redo", "greedy")) == 0
    again = {(r["instance"], r["solver"]): r["objective"] for r in _csv(path)}
    for r, m in zip(first, marked, strict=True):
        expect = r["objective"] if r["solver"] == "greedy" else m["objective"]
        assert again[(r["instance"], r["solver"])] == expect
    capsys.readouterr()
    assert ht.main(_tiny(tmp_path, "--time-limit", "2")) == 0
    assert "kept from" not in capsys.readouterr().err
    assert {r["time_limit"] for r in _csv(path)} == {"2.0"}


def test_an_interrupted_run_leaves_its_finished_instances(tmp_path, monkeypatch):
    """The CSV is rewritten after each instance: a run stopped in the second instance leaves the
    first one's rows, which the next run keeps."""
    calls = []
    real = ht.solve

    def stop_in_the_uav_set(group, *args):
        calls.append(group)
        if group.startswith("UAV"):
            raise KeyboardInterrupt
        return real(group, *args)

    monkeypatch.setattr(ht, "solve", stop_in_the_uav_set)
    with pytest.raises(KeyboardInterrupt):
        ht.main(_tiny(tmp_path))
    assert [(r["instance"], r["solver"]) for r in _csv(tmp_path / "t.csv")] == [
        ("3burma14", "greedy"), ("3burma14", "greedy+ls")]
    monkeypatch.setattr(ht, "solve", real)
    calls.clear()
    assert ht.main(_tiny(tmp_path)) == 0
    assert len(_csv(tmp_path / "t.csv")) == 4


def test_a_csv_of_something_else_is_refused(tmp_path, capsys):
    """--csv naming a file that is not this table's CSV: one line, exit 2, the file untouched."""
    other = tmp_path / "t.csv"
    other.write_text("a,b\n1,2\n")
    assert ht.main(_tiny(tmp_path)) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"gtsp-bench: error: {other}: not a CSV of this table") and err.count("\n") == 1
    assert other.read_text() == "a,b\n1,2\n"

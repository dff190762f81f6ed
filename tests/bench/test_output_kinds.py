"""The output kinds a definition names: GLNS's table, the doc blocks and the sets'
reference.csv, each from the rows (GTSPLIB's best-known tours: test_best_known.py)."""

from __future__ import annotations

import math

import pandas as pd

from gtsp_bench.bench.definitions import BENCHMARKS
from gtsp_bench.bench.output_kinds import (
    DOC_BLOCKS,
    OUTPUTS,
    frontier_block,
    glns_lines,
    glns_targets_block,
    new_references,
    pivot_markdown,
    proof_cell,
)
from tests.bench.frames import row_frame as _rows
from tests.conftest import REPO


def test_glns_table_puts_lns_beside_glns_and_the_targets():
    """One line per instance with GLNS's published columns, then the three target lines."""
    df = pd.concat([_rows(instance="31pr152", seed=s, gap_pct=g) for s, g in ((1, 0.0), (2, 0.5))])
    lines = glns_lines(df)
    line = next(x for x in lines if x.startswith("| 31pr152 |"))
    assert "| 0.2500 | 1/2 | 0.500 |" in line and "/10 |" in line
    assert "- instances at the best known at least once: 1 of 1" in lines


def test_new_references_keep_the_best_tour_its_proof_and_bound():
    """Per point: the best objective, optimal when some solve proved it, the best bound."""
    df = pd.concat([_rows(objective=101.0, lower_bound=99.0, label="lns", seed=2),
                    _rows(objective=100.0, status="optimal", lower_bound=100.0, label="milp", solver="milp")])
    (row,) = new_references(df, "2026-11-27")["s"]
    assert (row.instance, row.omega, row.value) == ("i1", 0.5, 100.0)
    assert (row.status, row.lower_bound) == ("optimal", 100.0)
    assert row.source == "milp 1s seed 0" and row.date == "2026-11-27"


def test_a_better_tour_keeps_the_rows_lower_bound_and_names_its_run(tmp_path):
    """--update-reference on a run without a time limit (a learned policy): the exact cost of its
    tour (rows.csv rounds it), the old row's lower bound (it holds whatever the tour), a source
    without a time; a group of GTSPLIB files (no set folder of that name) is passed over without
    a warning."""
    from types import SimpleNamespace

    from gtsp_bench.data.io import write_instance
    from gtsp_bench.data.sets import read_reference
    from gtsp_bench.generator import generate_instance
    from gtsp_bench.registry import get_solver, run_solver

    folder = tmp_path / "mine"
    inst = generate_instance(3, 4, seed=0, name="i1")
    write_instance(inst, folder / "i1.json")
    r = run_solver(get_solver("greedy"), inst, 0.5)
    (folder / "reference.csv").write_text(
        "instance,omega,value,lower_bound,status,source,date\n"
        f"i1,0.5,{r.objective + 10},1.0,best_known,lns 10s seed 1,2026-01-01\n")
    tour = {"order": " ".join(map(str, r.order)), "heads": " ".join(map(str, r.heads))}
    df = pd.concat([_rows(set="mine", objective=round(r.objective, 1), time_limit=math.nan,
                          label="local-search", seed=3, **tour),
                    _rows(set="GTSPLIB <= 200 nodes", instance="11berlin52", objective=1.0)])
    said: list[str] = []
    settings = SimpleNamespace(update_reference=True, sets=(str(folder),), instance_dir=str(tmp_path))
    written = OUTPUTS["update-references"](BENCHMARKS["sets"], df, tmp_path, settings, said.append)
    assert written == [folder / "reference.csv"]
    row = read_reference(folder / "reference.csv")[("i1", 0.5)]
    assert (row.value, row.lower_bound, row.source) == (r.objective, 1.0, "local-search seed 3")  # re-priced
    assert not [m for m in said if m.startswith("warning")], said


def test_doc_tables_are_pivots_of_the_rows():
    """A line per row value, a column per solver, a cell from the rows of both."""
    df = pd.concat([_rows(status="optimal"), _rows(label="milp", status="time_limit", bound_gap_pct=0.5)])
    text = pivot_markdown(df, "set", "label", proof_cell, "set")
    assert text.splitlines()[0] == "| set | lns | milp |"
    assert "1/1 proven" in text and "0/1 proven, 0.50s, bound gap <= 0.500%" in text
    # a worst gap that is not 0 never prints as 0.000%
    tiny = _rows(label="milp", status="time_limit", bound_gap_pct=0.00012)
    assert proof_cell(tiny).endswith("bound gap <= 0.0001%")


def test_committed_doc_blocks_are_what_their_rows_give():
    """Each generated doc table is exactly its renderer's output on the committed rows.csv."""
    from gtsp_bench.bench.output_kinds import run_command
    from gtsp_bench.bench.rows import read_rows

    for name, (page, block, renderer) in DOC_BLOCKS.items():
        bench = next(b for b in BENCHMARKS.values() if name in b.outputs)
        rows = REPO / "results" / bench.name / "rows.csv"
        if not rows.is_file():
            continue
        text = (REPO / page).read_text()
        want = renderer(bench, read_rows(rows), run_command(rows.parent))
        assert f"<!-- BEGIN generated:{block} -->\n{want}\n<!-- END generated:{block} -->" in text, name


def test_a_narrowed_run_leaves_the_docs_table_alone(tmp_path):
    """A run narrowed by an option (here --solvers) into results/NAME of a checkout does not
    rewrite the page's generated table from its part of the rows; the whole run does."""
    from gtsp_bench.bench.engine import Settings

    bench = BENCHMARKS["exact-scale"]
    page, block, _ = DOC_BLOCKS["doc-exact-scale"]
    (tmp_path / "mkdocs.yml").write_text("site_name: x\n")
    doc = tmp_path / page
    doc.parent.mkdir(parents=True)
    old = f"<!-- BEGIN generated:{block} -->\nold\n<!-- END generated:{block} -->\n"
    doc.write_text(old)
    out = tmp_path / "results" / bench.name
    out.mkdir(parents=True)
    df = _rows(status="optimal", label="milp", solver="milp")
    said: list[str] = []
    write = OUTPUTS["doc-exact-scale"]
    assert write(bench, df, out, Settings(solvers=("milp",)), said.append) == []
    assert doc.read_text() == old and "narrowed by --solvers" in said[0]
    assert write(bench, df, out, Settings(), said.append) == [doc]
    assert "1/1 proven" in doc.read_text()


def test_frontier_block_lists_every_file_and_certifies_against_the_better_tour():
    """exact-frontier's table: a line per file of the benchmark (20, 493-1,084 nodes); a file
    with a solve shows its bound's gap to the better of its tour and the best-known tour, a
    file without one its best_known.csv status; a proof with a certificate its seconds to the
    proof and the certificate's after."""
    from gtsp_bench.data import gtsplib

    bench = BENCHMARKS["exact-frontier"]
    known = gtsplib.best_known()
    u574 = known["115u574"].value
    df = pd.concat([
        _rows(instance="115u574", solver="milp", label="milp", status="time_limit", seed=0,
              objective=u574 + 100, lower_bound=u574 - 0.01 * u574, runtime_s=3600.4),
        _rows(instance="131p654", solver="milp", label="milp", status="optimal", seed=1,
              objective=known["131p654"].value, lower_bound=known["131p654"].value, runtime_s=229.5),
        _rows(instance="132d657", solver="milp", label="milp certificate=true", status="optimal",
              seed=0, objective=known["132d657"].value, lower_bound=known["132d657"].value,
              runtime_s=1160.0, note="certificate checked: proven optimal: 22498 (proofs/x.cert.json.gz)",
              trajectory="0.5:22600:22000;1100:22498:22496.5;1102:22498:22497;1160:22498:22498"),
        _rows(instance="145u724", solver="milp", label="milp", status="failed", objective=math.nan,
              runtime_s=12.0),
        _rows(instance="200dsj1000", solver="milp", label="milp", status="time_limit", seed=0,
              objective=9187884, lower_bound=9187873, runtime_s=3600.1),
    ])
    text = frontier_block(bench, df, "cmd")
    lines = [x for x in text.splitlines() if x.startswith("| ")][1:]
    assert len(lines) == 20 and {x.split(" | ")[0][2:] for x in lines} >= {"99d493", "217vm1084"}
    line = next(x for x in lines if x.startswith("| 115u574 |"))
    assert "| time limit (milp, seed 0) | 3600 |" in line and line.endswith("| 1.000 % |")  # vs best known
    line = next(x for x in lines if x.startswith("| 131p654 |"))
    assert "(optimal) | proven (milp, seed 1) | 230 |" in line and line.endswith("| 0.000 % |")
    line = next(x for x in lines if x.startswith("| 132d657 |"))
    # proven when the bound passed 22,497 (integer costs), the certificate written after
    assert "| proven, certificate checked (milp certificate=true, seed 0) | 1102 (+58 certificate) |" in line
    line = next(x for x in lines if x.startswith("| 99d493 |"))
    assert "not run; proven earlier, certificate shipped" in line
    open_file = next(r.name for r in known.values()
                     if 493 <= r.nodes <= 1084 and not r.proven and r.name not in set(df["instance"]))
    assert "| not run |" in next(x for x in lines if x.startswith(f"| {open_file} |"))
    failed = next(x for x in lines if x.startswith("| 145u724 |"))
    assert failed.endswith("| failed (milp, seed 0) | 12 | - | - | - |")
    proven = sum(r.proven for r in known.values() if 493 <= r.nodes <= 1084 and r.symmetric)
    # a gap that is not 0 never prints as 0.000 % (11 below 9,187,884)
    assert next(x for x in lines if x.startswith("| 200dsj1000 |")).endswith("| 0.0001 % |")
    assert f"{proven} of 20 files proven optimal (2 by the solves below); 5 of 20 run." in text


def test_glns_targets_block_counts_files_runs_and_the_worst():
    """Mean gap = mean over files of each file's mean; a file is hit if one seed is at 0."""
    df = pd.concat([_rows(instance="a", seed=1, gap_pct=0.0), _rows(instance="a", seed=2, gap_pct=0.4),
                    _rows(instance="b", seed=1, gap_pct=0.1), _rows(instance="b", seed=2, gap_pct=0.1)])
    text = glns_targets_block(BENCHMARKS["glns"], df)
    assert "| mean gap | 0.1500 % |" in text
    assert "| files at the best known at least once | 1 of 2 |" in text
    assert "| worst run | 0.400 % (a) |" in text and "| runs at the best known | 1 of 4 |" in text


def test_update_reference_keeps_the_omegas_a_set_holds(tmp_path):
    """--update-reference from a benchmark other than references does not add points at omegas
    the set's reference.csv does not hold (it says so); a better tour at a held omega is kept."""
    from types import SimpleNamespace

    from gtsp_bench.data.io import write_instance
    from gtsp_bench.data.sets import read_reference
    from gtsp_bench.generator import generate_instance
    from gtsp_bench.registry import get_solver, run_solver

    folder = tmp_path / "mine"
    inst = generate_instance(3, 4, seed=0, name="i1")
    write_instance(inst, folder / "i1.json")
    r5, r9 = (run_solver(get_solver("dp"), inst, w) for w in (0.5, 0.9))
    (folder / "reference.csv").write_text(
        "instance,omega,value,lower_bound,status,source,date\n"
        f"i1,0.5,{r5.objective + 10},,best_known,lns 10s seed 1,2026-01-01\n")

    def tour(r):
        return {"order": " ".join(map(str, r.order)), "heads": " ".join(map(str, r.heads))}

    df = pd.concat([_rows(set="mine", omega=0.5, objective=r5.objective, **tour(r5)),
                    _rows(set="mine", omega=0.9, objective=r9.objective, **tour(r9))])
    said: list[str] = []
    settings = SimpleNamespace(update_reference=True, sets=(str(folder),), instance_dir=str(tmp_path))
    OUTPUTS["update-references"](BENCHMARKS["exact-frontier-uav"], df, tmp_path, settings, said.append)
    ref = read_reference(folder / "reference.csv")
    assert set(ref) == {("i1", 0.5)} and math.isclose(ref[("i1", 0.5)].value, r5.objective)
    assert any("not updated at omega 0.9" in m for m in said), said
    # no better tour but a higher proven bound: the bound alone is written, the tour's row kept
    kept = ref[("i1", 0.5)]
    low = _rows(set="mine", omega=0.5, objective=r5.objective + 1, lower_bound=r5.objective - 2,
                status="time_limit", **tour(r5))
    OUTPUTS["update-references"](BENCHMARKS["exact-frontier-uav"], low, tmp_path, settings, said.append)
    again = read_reference(folder / "reference.csv")[("i1", 0.5)]
    assert math.isclose(again.lower_bound, r5.objective - 2)
    assert (again.value, again.source, again.status) == (kept.value, kept.source, kept.status)
    assert any("lower bound None ->" in m for m in said), said
    # a lower one changes nothing
    said.clear()
    lower = low.assign(lower_bound=r5.objective - 3)
    OUTPUTS["update-references"](BENCHMARKS["exact-frontier-uav"], lower, tmp_path, settings, said.append)
    assert read_reference(folder / "reference.csv")[("i1", 0.5)] == again and not said
    # a bound above the row's tour is a wrong solver's: said, not written
    OUTPUTS["update-references"](BENCHMARKS["exact-frontier-uav"], low.assign(lower_bound=r5.objective + 0.5),
                                 tmp_path, settings, said.append)
    assert read_reference(folder / "reference.csv")[("i1", 0.5)] == again
    assert any("above the tour" in m for m in said), said
    # the references benchmark fills a set's grid: it adds the point
    OUTPUTS["update-references"](BENCHMARKS["references"], df, tmp_path, settings, said.append)
    assert set(read_reference(folder / "reference.csv")) == {("i1", 0.5), ("i1", 0.9)}


def test_run_command_names_the_merged_reruns(tmp_path):
    """A page's "Made by" quotes the run's command, then each partial rerun merged into it (past
    two reruns, their count and the last one's command)."""
    import json

    from gtsp_bench.bench.output_kinds import run_command

    assert run_command(tmp_path) == ""  # no manifest
    manifest = {"command": "gtsp-bench bench glns"}
    (tmp_path / "manifest.json").write_text(json.dumps(manifest))
    assert run_command(tmp_path) == "gtsp-bench bench glns"
    manifest["merges"] = [{"command": "A --merge-into X"}, {"command": "B --merge-into X"}]
    (tmp_path / "manifest.json").write_text(json.dumps(manifest))
    assert run_command(tmp_path) == "gtsp-bench bench glns`, then `A --merge-into X`, then `B --merge-into X"
    manifest["merges"].append({"command": "C --merge-into X"})  # past two: their count and the last
    (tmp_path / "manifest.json").write_text(json.dumps(manifest))
    said = run_command(tmp_path)
    assert said == ("gtsp-bench bench glns`, then 3 partial reruns merged in (each command in its "
                    "`manifest.json`), the last `C --merge-into X")
    assert "A --merge-into" not in said and said.count("`") % 2 == 0

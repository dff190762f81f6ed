"""The benchmark suites (gtsp-bench bench --suite exact|heuristics|learned): presets and option
checks, each suite's table and CSV on a small run, the exact suite's agreement check and the
heuristics suite's reference fallback."""

from __future__ import annotations

import csv
import shutil

import pytest

from gtsp_bench.bench import suites
from gtsp_bench.bench.suites import SUITES, make_suite_config, parse_exact
from gtsp_bench.bench.tables import Row, time_to_proof_cell
from gtsp_bench.cli import main
from gtsp_bench.data.gtsplib import SAMPLES
from gtsp_bench.errors import InputError
from gtsp_bench.generator import instance_set
from gtsp_bench.registry import run_solver

from .conftest import REPO

EXACT_SMALL = ["bench", "--suite", "exact", "-K", "4", "--instances", "2", "--omegas", "0.5",
               "--no-gtsplib"]
HEURISTICS_SMALL = ["bench", "--suite", "heuristics", "-K", "4", "--instances", "2",
                    "--solvers", "greedy,greedy+ls", "--no-gtsplib"]


def _rows(path) -> list[dict[str, str]]:
    with path.open(newline="") as f:
        return list(csv.DictReader(f))


# ---------------------------------------------------------------------- presets and options
def test_presets_are_the_documented_defaults():
    """The full runs and --quick presets each suite had as a script (README's figures)."""
    exact = make_suite_config("exact")
    assert exact.ks == (4, 5, 6, 7, 8, 9, 10, 15, 20, 30) and exact.omegas == (0.0, 0.5, 0.9)
    assert (exact.instances, exact.set_seed, exact.time_limit, exact.max_nodes) == (5, 0, 60.0, 318)
    assert exact.solvers == ("milp", "dp") and exact.names == SAMPLES  # of the bundled library
    quick = make_suite_config("exact", quick=True)
    assert quick.ks == (4, 7, 10) and quick.omegas == (0.5,)
    assert quick.names == ("11berlin52", "20kroA100") and quick.instances == 5
    heur = make_suite_config("heuristics")
    assert heur.ks == (4, 7, 10, 20) and (heur.instances, heur.time_limit, heur.omegas) == (10, 10.0, (0.5,))
    assert heur.exact == (("dp", 10), ("milp", None)) and heur.exact_time_limit == 120.0
    assert heur.solvers == ("greedy", "greedy+ls", "aco", "aco+ls", "lns", "pyvrp")
    hq = make_suite_config("heuristics", quick=True)
    assert (hq.instances, hq.time_limit, hq.names) == (3, 5.0, ("11berlin52", "20kroA100", "40d198"))
    learned = make_suite_config("learned")
    assert (learned.ks, learned.instances, learned.set_seed, learned.repeats) == ((4, 7, 10), 100, 5000, 3)
    assert learned.omegas == (0.3, 0.6) and learned.gtsplib is None and learned.time_limit is None
    assert learned.solvers == tuple(label for label, _, _ in suites.LEARNED_SOLVERS)
    assert make_suite_config("learned", quick=True).repeats == 1
    assert exact.csv_path == suites.DEFAULT_OUT / "exact.csv"


def test_options_override_and_k_sets():
    """Explicit values win over the preset; K takes ranges, lists and mixes, text or ints."""
    c = make_suite_config("exact", quick=True, ks="4..6,10", omegas="0,0.9", instances=2,
                          names="11berlin52", out_dir="x")
    assert c.ks == (4, 5, 6, 10) and c.omegas == (0.0, 0.9) and c.instances == 2
    assert c.names == ("11berlin52",) and c.csv_path.as_posix() == "x/exact.csv"
    assert make_suite_config("heuristics", ks=[20, 4]).ks == (4, 20)
    assert make_suite_config("exact", no_gtsplib=True).gtsplib is None
    assert make_suite_config("exact", gtsplib="lib").gtsplib.as_posix() == "lib"


def test_learned_solvers_are_label_prefixes():
    """--solvers drl picks every drl variant (the script's --only); am only the am ones."""
    c = make_suite_config("learned", solvers="greedy,am")
    assert c.solvers == ("greedy", "am", "am heads=paper", "am augment=true")
    assert all(s.startswith("drl") for s in make_suite_config("learned", solvers="drl").solvers)


@pytest.mark.parametrize("suite, options, message", [
    ("exact", {"ks": "4..x"}, "bad K '4..x'"),
    ("exact", {"omegas": "0.5,1.5"}, "bad omegas"),
    ("exact", {"solvers": "milp,magic"}, "unknown solver 'magic' (valid: "),
    ("exact", {"repeats": 2}, "--repeats is not an option of the exact suite"),
    ("heuristics", {"omegas": "0.3,0.6"}, "takes one omega"),
    ("heuristics", {"exact": "dp:ten"}, "bad entry 'dp:ten'"),
    ("heuristics", {"dp_max_k": 5}, "--dp-max-k is not an option of the heuristics suite"),
    ("learned", {"time_limit": 5.0}, "--time-limit is not an option of the learned suite"),
    ("learned", {"seed": 1}, "--seed is not an option of the learned suite"),
    ("learned", {"solvers": "pointer"}, "no learned-suite solver starts with 'pointer'"),
    ("learned", {"instances": 0}, "number of instances must be an integer >= 1"),
    ("nope", {}, "suite must be one of 'exact', 'heuristics', 'learned'"),
])
def test_bad_options_are_refused(suite, options, message):
    """Each bad value or misplaced option is one InputError naming it."""
    with pytest.raises(InputError) as info:
        make_suite_config(suite, **options)
    assert message in str(info.value) and "\n" not in str(info.value)


def test_parse_exact():
    """NAME[:MAX_K] entries in order; a bad K is an InputError."""
    assert parse_exact("dp:10,milp") == (("dp", 10), ("milp", None))
    with pytest.raises(InputError, match="bad entry"):
        parse_exact("dp:ten")


@pytest.mark.parametrize("argv, message", [
    (["bench", "--suite", "exact", "-K", "7..4"], "bad K '7..4': range 7..4 is reversed"),
    (["bench", "--suite", "heuristics", "-K", "4", "--instances", "1", "--solvers", "nope",
      "--no-gtsplib"], "unknown solver 'nope'"),
])
def test_cli_bad_input_exits_2(tmp_path, capsys, argv, message):
    """Bad suite input through the CLI: one error line, exit code 2, nothing written."""
    assert main([*argv, "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("gtsp-bench: error: ") and message in err and err.count("\n") == 1
    assert not (tmp_path / "out").exists()


# ---------------------------------------------------------------------- exact
def test_exact_small_run_table_and_csv(tmp_path, capsys):
    """milp and dp on two K = 4 instances: both prove every optimum, they agree, one CSV row
    each; stdout has the table and nothing else (the CSV's path goes to stderr)."""
    assert main([*EXACT_SMALL, "--out", str(tmp_path)]) == 0
    out, err = capsys.readouterr()
    assert "2/2" in out and "0 disagreement(s)" in out
    assert "rows:" not in out and f"rows: {tmp_path / 'exact.csv'}" in err
    rows = _rows(tmp_path / "exact.csv")
    assert len(rows) == 4 and list(rows[0]) == list(suites.EXACT_COLUMNS)
    assert {r["solver"] for r in rows} == {"milp", "dp"}
    assert all(r["status"] == "optimal" for r in rows)
    by_solver = {r["solver"]: float(r["objective"]) for r in rows if r["instance"].endswith("-000")}
    assert by_solver["milp"] == pytest.approx(by_solver["dp"], rel=1e-6)


def test_disagreement_is_reported():
    """Two proven optima that differ are listed; unproven solves are ignored."""
    runs = [Row("K=4", "a", 0.5, "milp", "optimal", 10.0, 10.0, 0.1),
            Row("K=4", "a", 0.5, "dp", "optimal", 10.5, 10.5, 0.1),
            Row("K=4", "b", 0.5, "milp", "time_limit", 11.0, 9.0, 60.0),
            Row("K=4", "b", 0.5, "dp", "optimal", 10.0, 10.0, 0.1)]
    bad = suites.disagreements(runs)
    assert len(bad) == 1 and bad[0].startswith("a omega=0.5")
    cell = time_to_proof_cell(runs[2:], 60.0)  # one of two proven: the median is past the limit
    assert cell.startswith(">") and cell.split()[-1] == "1/2"


def test_exact_sample_table(tmp_path, capsys):
    """A sample folder with one made-up .gtsp file: dp solves it, the row says whether the
    objective matches best_known.csv, and dp is left out above --dp-max-k."""
    lib = tmp_path / "lib"
    lib.mkdir()
    (lib / "3tiny4.gtsp").write_text(
        "NAME : 3tiny4\nTYPE : GTSP\nDIMENSION : 4\nGTSP_SETS : 3\nEDGE_WEIGHT_TYPE : EUC_2D\n"
        "NODE_COORD_SECTION\n1 0 0\n2 3 0\n3 3 4\n4 10 10\n"
        "GTSP_SET_SECTION\n1 1 -1\n2 2 -1\n3 3 4 -1\nEOF\n")  # best tour 1-2-3: 3 + 4 + 5
    (lib / "best_known.csv").write_text(
        "name,clusters,nodes,best_known,status,type,edge_weight_type,edge_weight_format,tour\n"
        "3tiny4,3,4,12,optimal,GTSP,EUC_2D,,\n")
    argv = ["bench", "--suite", "exact", "--no-generated", "--solvers", "dp", "--gtsplib", str(lib),
            "--out", str(tmp_path)]
    assert main(argv) == 0
    out = capsys.readouterr().out
    line = next(x for x in out.splitlines() if x.startswith("3tiny4"))
    assert line.split()[3:6] == ["dp", "optimal", "12"] and " yes " in line
    assert main([*argv, "--dp-max-k", "2"]) == 0
    assert "3tiny4" not in capsys.readouterr().out and _rows(tmp_path / "exact.csv") == []


def test_sample_folder_without_or_with_a_bad_table(tmp_path, capsys):
    """No best_known.csv: GTSPLIB is skipped with a note; one in an old or damaged format: one
    line naming the file and the problem, exit 2."""
    lib = tmp_path / "lib"
    lib.mkdir()
    argv = ["bench", "--suite", "exact", "--no-generated", "--solvers", "dp", "--gtsplib", str(lib),
            "--out", str(tmp_path / "out")]
    assert main(argv) == 0
    assert f"no {lib / 'best_known.csv'}: GTSPLIB skipped" in capsys.readouterr().err
    (lib / "best_known.csv").write_text("name,clusters,nodes,best_known,status\n3tiny4,3,4,12,optimal\n")
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err == f"gtsp-bench: error: {lib / 'best_known.csv'}: missing column 'type'\n"


# ---------------------------------------------------------------------- heuristics
def test_heuristics_exact_reference_and_csv(tmp_path, capsys):
    """With dp as the reference the gaps are to the optimum; the CSV has one row per solve."""
    assert main([*HEURISTICS_SMALL, "--exact", "dp", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "optimum (dp)" in out and "greedy+ls" in out
    rows = _rows(tmp_path / "heuristics.csv")
    assert len(rows) == 4 and list(rows[0]) == list(suites.HEURISTICS_COLUMNS)
    assert all(float(r["gap_percent"]) >= -1e-9 for r in rows)
    assert {r["reference_kind"] for r in rows} == {"optimum (dp)"}


def test_heuristics_fallback_to_best_found(tmp_path, capsys):
    """An exact solver that is not registered falls back to the best found, labelled so; the
    best solver's gap is then zero."""
    assert main([*HEURISTICS_SMALL, "--exact", "no-such-solver", "--out", str(tmp_path)]) == 0
    assert "best found" in capsys.readouterr().out
    rows = _rows(tmp_path / "heuristics.csv")
    for inst in {r["instance"] for r in rows}:
        assert min(float(r["gap_percent"]) for r in rows if r["instance"] == inst) == 0.0


def test_a_failed_solve_is_a_row_and_exit_code_1(tmp_path, capsys):
    """A solver that raises gives failed rows in the CSV (kept out of the table), a line on
    stderr and exit code 1; the other solver's rows are unaffected."""
    from gtsp_bench.registry import register_solver

    from .runner_solvers import Crash

    register_solver("suite-crash", Crash, "raises")
    assert main([*HEURISTICS_SMALL, "--solvers", "greedy,suite-crash", "--out", str(tmp_path)]) == 1
    out, err = capsys.readouterr()
    assert "2 solve(s) failed" in err and "RuntimeError: boom" not in out
    rows = _rows(tmp_path / "heuristics.csv")
    assert {r["status"] for r in rows if r["solver"] == "suite-crash"} == {"failed"}
    assert all(r["status"] != "failed" for r in rows if r["solver"] == "greedy")


# ---------------------------------------------------------------------- learned
def test_learned_table_and_csv_against_cached_optima(tmp_path, capsys):
    """Three K = 4 instances: a bound row and one row per solver and omega, gaps >= 0, the paper
    rule's bound never above drl (which uses that rule), and the cached optima are dp's."""
    pytest.importorskip("torch")
    cache = tmp_path / "exact.csv"
    shutil.copy(REPO / suites.DEFAULT_CACHE, cache)
    argv = ["bench", "--suite", "learned", "-K", "4", "--instances", "3", "--repeats", "1",
            "--solvers", "greedy,drl,am", "--cache", str(cache), "--out", str(tmp_path)]
    assert main(argv) == 0
    assert "bound: paper heads" in capsys.readouterr().out
    rows = _rows(tmp_path / "learned.csv")
    labels = {r["solver"] for r in rows}
    assert {"bound: paper heads", "greedy", "drl", "am"} <= labels
    assert len(rows) == 2 * len(labels)  # one row per omega
    gap = {(r["solver"], r["omega"]): float(r["mean_gap_pct"]) for r in rows}
    assert all(v >= -1e-7 for v in gap.values())
    for w in ("0.3", "0.6"):
        assert gap[("bound: paper heads", w)] <= gap[("drl", w)] + 1e-9
    with cache.open(newline="") as f:
        cached = {(r["instance"], float(r["omega"])): float(r["optimum"]) for r in csv.DictReader(f)}
    inst = instance_set(1, 4, SUITES["learned"].set_seed)[0]
    dp = run_solver("dp", inst, 0.3)
    assert dp.objective == pytest.approx(cached[(inst.name, 0.3)], rel=1e-9)


def test_exact_optima_fills_a_missing_cache(tmp_path):
    """Without a cache the optima are solved by dp and written; a second call reads them back."""
    cache = tmp_path / "sub" / "opt.csv"
    insts = {4: instance_set(2, 4, 7, n_nodes=4)}
    first = suites.exact_optima(cache, insts, (0.3,))
    assert cache.read_text().splitlines()[0] == "instance,omega,optimum" and len(first) == 2
    assert first[(insts[4][0].name, 0.3)] == run_solver("dp", insts[4][0], 0.3).objective
    assert suites.exact_optima(cache, insts, (0.3,)) == first

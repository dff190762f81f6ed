"""bench --set: planning, one tiny real sweep, re-use without solver calls, references, the CLI."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from gtsp_bench.bench import tasks
from gtsp_bench.bench.sweep import (
    TIDY_COLUMNS,
    load_sets,
    make_sweep_config,
    parse_seeds,
    plan_sweep,
    run_sweep,
)
from gtsp_bench.cli import main
from gtsp_bench.data.io import read_instance, write_instance
from gtsp_bench.data.sets import ReferenceRow, read_reference, write_reference
from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance
from gtsp_bench.instance import Instance
from gtsp_bench.registry import run_solver

UAV = ("tiny-000", "tiny-001")
GTSP = "tiny-gtsp"


def _folder(tmp_path):
    """Two UAV instances (K = 3, 2 nodes each) and a distance-only one (K = 4) as .gtsp.gz."""
    folder = tmp_path / "tiny"
    for i, name in enumerate(UAV):
        write_instance(generate_instance(3, 2, seed=i, name=name), folder / f"{name}.json")
    rng = np.random.default_rng(5)
    clusters = tuple(rng.integers(0, 100, size=(2, 2)).astype(float) for _ in range(4))
    write_instance(Instance(GTSP, clusters, params=None, edge_weight_type="EUC_2D"),
                   folder / f"{GTSP}.gtsp.gz")
    return folder


def _optimum(folder, name, omega):
    suffix = ".json" if name in UAV else ".gtsp.gz"
    return run_solver("brute", read_instance(folder / f"{name}{suffix}"), omega).objective


def test_parse_seeds():
    assert parse_seeds("0..2,7,1") == (0, 1, 2, 7)
    assert parse_seeds([3, 3, 4]) == (3, 4)
    for bad in ("x", "3..1", "", "-1"):
        with pytest.raises(InputError, match="bad seeds"):
            parse_seeds(bad)


def test_plan_counts_omegas_and_seeds_and_ignores_omega_for_gtsplib(tmp_path):
    """instance x solver x omega x seed, with one omega for a distance-only instance; the
    selection by --instances (per K), --names and -K."""
    folder = _folder(tmp_path)
    config = make_sweep_config(sets=[str(folder)], solvers="greedy,dp", omegas="0.2,0.8",
                               seeds="0..2", time_limit=1, out_dir=tmp_path / "out")
    cells, tasks = plan_sweep(config, load_sets(config))
    assert len(cells) == len(tasks) == 2 * 2 * 2 * 3 + 1 * 2 * 1 * 3
    gtsp = [c for c in cells if c.entry.stem == GTSP]
    assert {c.omega for c in gtsp} == {None} and all("|w=0|" in c.key for c in gtsp)
    per_k = make_sweep_config(sets=[str(folder)], solvers="greedy", n_instances=1, time_limit=1)
    assert [e.stem for e in load_sets(per_k)[0][1]] == ["tiny-000", GTSP]
    named = make_sweep_config(sets=[str(folder)], solvers="greedy", names="tiny-001", ks="3")
    assert [e.stem for e in load_sets(named)[0][1]] == ["tiny-001"]
    with pytest.raises(InputError, match="--names: no selected set holds 'nope'"):
        load_sets(make_sweep_config(sets=[str(folder)], solvers="greedy", names="tiny-000,nope"))
    with pytest.raises(InputError, match="has no instance left"):
        load_sets(make_sweep_config(sets=[str(folder)], solvers="greedy", ks="9"))
    lib = make_sweep_config(sets=["gtsplib"], solvers="greedy", n_instances=1, max_nodes=30)
    assert [e.stem for e in load_sets(lib)[0][1]] == ["3burma14", "4ulysses16", "5gr21", "6fri26"]
    twice = make_sweep_config(sets=[str(folder), str(folder) + "/", str(tmp_path / "." / "tiny")],
                              solvers="greedy")
    assert len(load_sets(twice)) == 1
    _folder(tmp_path / "other")
    with pytest.raises(InputError, match="another set is also named 'tiny'"):
        load_sets(make_sweep_config(sets=[str(folder), str(tmp_path / "other" / "tiny")], solvers="greedy"))
    with pytest.raises(InputError, match="unknown solver 'nosuch'"):
        make_sweep_config(sets=[str(folder)], solvers="greedy,nosuch")


def test_sweep_outputs_reuse_and_references(tmp_path, monkeypatch, capsys):
    """One real sweep (greedy and dp, 1 s) writes the tidy CSV, summary and PNGs with gaps
    labelled by the reference's status; every later run re-uses each solve (no solver call);
    --update-reference writes only a strictly better tour; a tour below a proven optimum is an
    error."""
    folder = _folder(tmp_path)
    opt0 = _optimum(folder, "tiny-000", 0.5)
    opt_g = _optimum(folder, GTSP, None)
    ref = folder / "reference.csv"
    write_reference(ref, [ReferenceRow("tiny-000", 0.5, opt0, None, "optimal", "brute", "2026-01-01"),
                          ReferenceRow(GTSP, None, opt_g, None, "best_known", "brute", "2026-01-01")])
    out = tmp_path / "out"
    config = make_sweep_config(sets=[str(folder)], solvers="greedy,dp", time_limit=1, jobs=1,
                               out_dir=out, progress=False)
    first = run_sweep(config, log=lambda m: None)
    assert (first.tasks, first.run, first.cached, first.failed) == (6, 6, 0, 0)
    for name in ("sweep.csv", "summary.md", "profile.csv", "profile.png", "gap-time.csv", "gap-time.png",
                 "gap-k.csv", "gap-k.png"):
        assert (out / name).is_file(), name
    df = pd.read_csv(out / "sweep.csv", keep_default_na=False, na_values=[""])
    assert tuple(df.columns) == TIDY_COLUMNS and len(df) == 6
    by = {(r.instance, r.solver): r for r in df.itertuples()}
    assert by[("tiny-000", "dp")].gap_label == "to optimum"
    assert by[("tiny-000", "dp")].gap_percent == pytest.approx(0, abs=1e-9)
    assert by[("tiny-000", "dp")].objective == pytest.approx(opt0)
    assert by[(GTSP, "dp")].gap_label == "to best known" and math.isnan(by[(GTSP, "dp")].omega)
    assert by[("tiny-001", "dp")].gap_label == "to best found"  # no reference row
    assert by[("tiny-000", "greedy")].gap_percent == pytest.approx(
        100 * (by[("tiny-000", "greedy")].objective - opt0) / opt0)
    assert (by[(GTSP, "dp")].K, by[(GTSP, "dp")].N, by[("tiny-000", "dp")].omega) == (4, 8, 0.5)
    assert "| tiny | dp | 3 | to best found / to best known / to optimum | 0.000 |" in first.table

    def no_solves(*a, **k):
        raise AssertionError("a re-used sweep must not call the solvers")

    monkeypatch.setattr(tasks, "run_solver_tasks", no_solves)
    capsys.readouterr()
    code = main(["bench", "--set", str(folder), "--solvers", "greedy,dp", "--time-limit", "1",
                 "--jobs", "1", "--out", str(out), "--no-progress"])
    stdout = capsys.readouterr().out
    assert code == 0 and stdout == first.table  # the summary table is the whole answer
    assert pd.read_csv(out / "sweep.csv", keep_default_na=False, na_values=[""]).equals(df)

    # a best_known value above dp's tour: reported; written only with update_reference
    high = ReferenceRow(GTSP, None, opt_g + 7, None, "best_known", "old", "2020-01-01")
    write_reference(ref, [read_reference(ref)[("tiny-000", 0.5)], high])
    before = ref.read_text()
    summary = run_sweep(config, log=lambda m: None)
    found = sorted(i.objective for i in summary.improvements)
    assert summary.run == 0 and found[0] == opt_g and found[-1] < opt_g + 7
    assert ref.read_text() == before
    lines = []
    summary = run_sweep(make_sweep_config(sets=[str(folder)], solvers="greedy,dp", time_limit=1, jobs=1,
                                          out_dir=out, update_reference=True), log=lines.append)
    new = read_reference(ref)[(GTSP, None)]
    assert (new.value, new.status) == (opt_g, "best_known") and new.source.endswith(" 1s seed 0")
    assert new.date == pd.Timestamp.now(tz="UTC").date().isoformat()
    assert any(line.startswith(f"updated {ref}: {GTSP}: ") for line in lines)
    summary = run_sweep(make_sweep_config(sets=[str(folder)], solvers="greedy,dp", time_limit=1, jobs=1,
                                          out_dir=out, update_reference=True), log=lines.append)
    assert summary.updated == []  # nothing strictly better any more

    # a proven optimum above dp's tour: the run reports it as an error (exit code 1)
    write_reference(ref, [ReferenceRow("tiny-000", 0.5, opt0 * 1.1, None, "optimal", "x", "2026-01-01")])
    code = main(["bench", "--set", str(folder), "--solvers", "greedy,dp", "--time-limit", "1",
                 "--jobs", "1", "--out", str(out), "--no-progress"])
    err = capsys.readouterr().err
    assert code == 1 and "below the proven optimum" in err and "tiny/tiny-000: dp" in err


def test_an_asymmetric_gtsplib_instance_is_refused_not_failed(tmp_path, capsys):
    """The gtsplib set includes the AGTSP files: a symmetric-only solver's solve of one is
    `refused` (counted apart, exit 0), a solver that handles asymmetric costs answers it at its
    best known value."""
    out = tmp_path / "out"
    argv = ["bench", "--set", "gtsplib", "--names", "4br17", "--solvers", "greedy+ls,dp",
            "--time-limit", "5", "--jobs", "1", "--no-progress", "--out", str(out)]
    assert main(argv) == 0
    df = pd.read_csv(out / "sweep.csv").set_index("solver")
    assert df.loc["greedy+ls", "status"] == "refused" and math.isnan(df.loc["greedy+ls", "objective"])
    assert "symmetric costs only" in df.loc["greedy+ls", "note"]
    assert df.loc["dp", "objective"] == 31 and df.loc["dp", "gap_percent"] == 0
    table = capsys.readouterr().out
    assert "| gtsplib | greedy+ls | 1 | to best known | - | - | 0/1 | - | 1 | 0 |" in table


@pytest.mark.parametrize("args, message", [
    (["--set", "no-such-set", "--solvers", "greedy"], "unknown set 'no-such-set'"),
    (["--set", "gtsplib", "--solvers", "greedy", "--seeds", "x"], "bad seeds 'x'"),
])
def test_bad_set_options_exit_2_with_one_line(tmp_path, capsys, args, message):
    code = main(["bench", *args, "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and message in err and err.count("\n") == 1 and err.startswith("gtsp-bench: error: ")
    assert not (tmp_path / "out").exists()

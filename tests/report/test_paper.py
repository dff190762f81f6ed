"""The report: claims checked against hand-made tables, generated blocks refreshed in place with
the hand-written text kept, training logs validated."""

from __future__ import annotations

import pandas as pd
import pytest

from gtsp_bench.errors import InputError
from gtsp_bench.report.paper import (
    check_claims,
    docs_dir_for,
    ks_text,
    parse_ints,
    read_training_logs,
    refresh_blocks,
    write_report,
)


def _ratios(values: dict[str, list[float]], x: str, xs: list) -> pd.DataFrame:
    rows = []
    for s, rs in values.items():
        for v, r in zip(xs, rs, strict=True):
            rows.append({x: v, "K" if x == "omega" else "omega": 4 if x == "omega" else 0.5,
                         "solver": s, "ratio": r, "status": "feasible", "runtime_s": 0.1})
    return pd.DataFrame(rows)


def _verdicts(frames) -> dict[tuple[str, str], str]:
    return {(fig, claim): verdict for fig, claim, _, verdict in check_claims(frames)}


def test_claims_hold_when_drl_is_near_optimal_and_best():
    """DRL at 1.01 below ACO below greedy at every omega: all three K = 4 claims hold."""
    df = _ratios({"drl": [1.01, 1.02], "aco": [1.05, 1.06], "greedy": [1.2, 1.1], "dp": [1, 1]},
                 "omega", [0.0, 0.5])
    v = _verdicts({"ratio-omega": df})
    assert v[("ratio-omega, K = 4", "DRL within a few % of the optimum for every omega")] == "holds"
    assert v[("ratio-omega, K = 4", "DRL below ACO and greedy for every omega")] == "holds"
    assert v[("ratio-omega, K = 4", "ACO below greedy")] == "holds"


def test_claims_fail_plainly():
    """DRL 8 % off and above ACO at one omega: the claims are reported as not holding."""
    df = _ratios({"drl": [1.08, 1.02], "aco": [1.05, 1.06], "greedy": [1.2, 1.1]}, "omega", [0.0, 0.5])
    v = _verdicts({"ratio-omega": df})
    assert v[("ratio-omega, K = 4", "DRL within a few % of the optimum for every omega")] == "does not hold"
    assert v[("ratio-omega, K = 4", "DRL below ACO and greedy for every omega")] == "does not hold"


def test_claims_gap_grows_with_k_and_runtime_order():
    """Gap growth with K is checked per solver; the runtime order needs all four methods."""
    df = _ratios({"greedy": [1.05, 1.08, 1.12], "aco": [1.01, 1.02, 1.04]}, "K", [4, 5, 6])
    v = _verdicts({"ratio-k": df, "runtime": df})
    grows = v[("ratio-k", "the gap to the optimum grows with K (greedy, ACO, DRL)")]
    assert grows.startswith("holds") and "drl not run" in grows
    assert v[("runtime", "greedy < DRL < ACO < Gurobi (exact; here milp) at every K")] == \
        "not checked (drl, milp not run)"
    timed = df.assign(reference="dp", runtime_s=df["solver"].map({"greedy": 0.1, "aco": 1.0}))
    timed = pd.concat([timed, timed[timed["solver"] == "aco"].assign(solver="drl", runtime_s=0.5),
                       timed[timed["solver"] == "aco"].assign(solver="dp", runtime_s=2.0)])
    assert _verdicts({"runtime": timed})[
        ("runtime", "greedy < DRL < ACO < Gurobi (exact; here dp) at every K")] == "holds"
    shrinking = _ratios({"greedy": [1.12, 1.08, 1.05]}, "K", [4, 5, 6])
    assert _verdicts({"ratio-k": shrinking})[
        ("ratio-k", "the gap to the optimum grows with K (greedy, ACO, DRL)")].startswith("does not hold")


def test_missing_experiments_are_not_checked():
    """With no tables at all every claim says why it was not checked."""
    verdicts = [v for *_, v in check_claims({})]
    assert verdicts and all(v.startswith("not checked") for v in verdicts)


def test_write_report_keeps_prose_and_refreshes_blocks(tmp_path):
    """Text outside the generated markers survives; the block is replaced, not appended."""
    (tmp_path / "ratio-k.csv").write_text(
        "experiment,K,N,instance,omega,solver,status,ratio,reference,runtime_s,time_limit_s,order\n"
        "ratio-k,4,20,a,0.5,greedy,feasible,1.25,dp,0.01,10,0 1 2 3\n"
        "ratio-k,4,20,a,0.5,dp,optimal,1.0,dp,0.02,10,0 1 2 3\n")
    readme = tmp_path / "README.md"
    readme.write_text("# Mine\n\nHand-written claim.\n\n<!-- BEGIN generated:ratio-k -->\nold\n"
                      "<!-- END generated:ratio-k -->\n\nMore prose.\n")
    write_report(tmp_path)
    write_report(tmp_path)
    text = readme.read_text()
    assert text.startswith("# Mine\n\nHand-written claim.") and text.endswith("More prose.\n")
    assert "old" not in text and text.count("| 4 | 1.0000 | 1.2500 |") == 1


_RATIO_K = (
    "experiment,K,N,instance,omega,solver,status,ratio,reference,runtime_s,time_limit_s,order\n"
    "ratio-k,4,20,a,0.5,greedy,feasible,1.25,dp,0.01,10,0 1 2 3\n"
    "ratio-k,4,20,a,0.5,dp,optimal,1.0,dp,0.02,10,0 1 2 3\n"
    "ratio-k,5,20,b,0.5,greedy,feasible,1.5,dp,0.03,10,0 1 2 3 4\n"
    "ratio-k,5,20,b,0.5,dp,optimal,1.0,dp,0.5,10,0 1 2 3 4\n")


def test_refresh_blocks_touches_only_the_named_blocks(tmp_path):
    """Named blocks are rewritten, others and the prose kept; an unchanged file is not rewritten."""
    page = tmp_path / "page.md"
    page.write_text("Intro.\n<!-- BEGIN generated:a -->\nold a\n<!-- END generated:a -->\nMid.\n"
                    "<!-- BEGIN generated:b -->\nold b\n<!-- END generated:b -->\nEnd.\n")
    assert refresh_blocks(page, {"a": "new a", "b": "new b"}, names=["a"])
    text = page.read_text()
    assert "new a" in text and "old b" in text and "old a" not in text
    assert text.startswith("Intro.\n") and "\nMid.\n" in text and text.endswith("End.\n")
    assert not refresh_blocks(page, {"a": "new a"})


def test_a_run_into_the_results_folder_refreshes_the_docs(tmp_path):
    """With mkdocs.yml beside results/, write_report fills the docs pages' blocks (summary: gap %
    per K and the median time at the largest K); a run into results/quick leaves them alone."""
    (tmp_path / "mkdocs.yml").write_text("site_name: t\n")
    page = tmp_path / "docs" / "sub" / "page.md"
    page.parent.mkdir(parents=True)
    page.write_text("# P\n\n<!-- BEGIN generated:summary -->\n(not run)\n<!-- END generated:summary -->\n"
                    "<!-- BEGIN generated:setup -->\nkept\n<!-- END generated:setup -->\n")
    quick = tmp_path / "results" / "quick"
    quick.mkdir(parents=True)
    for out in (quick, tmp_path / "results"):
        (out / "ratio-k.csv").write_text(_RATIO_K)
        (out / "runtime.csv").write_text(_RATIO_K.replace("ratio-k,", "runtime,"))
    assert docs_dir_for(quick) is None and docs_dir_for(tmp_path / "results") == tmp_path / "docs"
    write_report(quick)
    assert "(not run)" in page.read_text()
    write_report(tmp_path / "results")
    text = page.read_text()
    assert "| solver | gap % K=4 | gap % K=5 | median time K=5 |" in text
    assert "| `greedy` | 25.00 | 50.00 | 0.03 s |" in text and "| `dp` | 0.00 | 0.00 | 0.5 s |" in text
    assert "kept" in text  # the setup block (dated) is never copied into the docs


def test_new_report_has_every_block(tmp_path):
    """Without a README one is created with every generated block."""
    text = write_report(tmp_path).read_text()
    for block in ("setup", "ratio-omega", "ratio-k", "runtime", "trajectories", "training", "claims"):
        assert f"<!-- BEGIN generated:{block} -->" in text


def test_training_logs_read_and_checked(tmp_path):
    """Logs get a model column; a log with other leading columns is refused by name."""
    assert read_training_logs(tmp_path) is None
    (tmp_path / "drl.train.csv").write_text("step,loss,reward,val_energy,wall_s\n0,1,2,3,4\n")
    df = read_training_logs(tmp_path)
    assert list(df.columns) == ["model", "step", "loss", "reward", "val_energy", "wall_s"]
    assert df["model"].tolist() == ["drl"]
    (tmp_path / "bad.train.csv").write_text("epoch,loss\n0,1\n")
    with pytest.raises(InputError, match=r"bad.train.csv: a training log must start with"):
        read_training_logs(tmp_path)


def test_small_helpers():
    """Order strings parse; K lists print as ranges when consecutive."""
    assert parse_ints("2 0 1") == [2, 0, 1] and parse_ints(float("nan")) == []
    assert ks_text([4, 5, 6, 7]) == "4..7" and ks_text([4, 7]) == "4,7"

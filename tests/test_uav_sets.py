"""The committed UAV sets: files are what the generator gives, reference.csv rows are sound."""

from __future__ import annotations

import csv
import datetime as dt
import math
import re
from pathlib import Path

import pytest

from gtsp_bench.bench.runner import OMEGAS, PAPER_OMEGA_KS, RATIO_K_OMEGA
from gtsp_bench.data.io import read_instance
from gtsp_bench.data.parse import format_json_instance
from gtsp_bench.energy import evaluate
from gtsp_bench.generator import instance_set
from gtsp_bench.registry import get_solver, run_solver

REPO = Path(__file__).resolve().parents[1]
INSTANCES = REPO / "instances"
RESULTS = REPO / "results" / "paper"
#: K -> (instances, area in m) of every committed set uav-K{K}-N20-s1.
SETS = {k: (30, 1000.0) for k in range(4, 11)} | {20: (20, 1000.0), 50: (20, 1500.0),
                                                  100: (20, 2000.0), 200: (20, 3000.0)}
FIELDS = ["instance", "omega", "value", "lower_bound", "status", "source", "date"]
LARGE_OMEGAS = {0.3, 0.5, 0.6}
#: A reference's source: ``dp``, ``brute``, or the engine's ``LABEL LIMITs seed S`` (a label may
#: name its options, e.g. ``lns workers=1 60s seed 1``).
SOURCE = re.compile(r"(dp|brute|[a-z][\w-]*( [a-z_]+=[\w./-]+)*( \d+(\.\d+)?s)?( seed \d+)?)$")


def folder(k: int) -> Path:
    return INSTANCES / f"uav-K{k}-N20-s1"


def references(k: int) -> list[dict[str, str]]:
    with (folder(k) / "reference.csv").open(encoding="utf-8", newline="") as f:
        reader = csv.DictReader(f)
        assert reader.fieldnames == FIELDS
        return list(reader)


def paper_omegas(k: int) -> set[float]:
    """The omegas gtsp_bench.bench.runner solves at K = k (omega sweeps at the paper's K, else 0.5)."""
    return set(OMEGAS) | {RATIO_K_OMEGA} if k in PAPER_OMEGA_KS else {RATIO_K_OMEGA}


def test_every_committed_uav_set_is_listed_here():
    """A new committed set must get its generator settings checked too."""
    found = {int(re.fullmatch(r"uav-K(\d+)-N20-s1", p.name).group(1))
             for p in INSTANCES.glob("uav-K*-N20-s1")}
    assert found == set(SETS)


@pytest.mark.parametrize("k", sorted(SETS))
def test_set_files_are_what_the_generator_gives(k):
    """The set holds instances 0 .. n-1 and the first and last are byte for byte the generator's."""
    n, area = SETS[k]
    names = sorted(p.name for p in folder(k).glob("*.json"))
    assert names == [f"uav-K{k}-N20-s1-{i:03d}.json" for i in range(n)]
    fresh = instance_set(n, k, 1, area=area)
    for inst in (fresh[0], fresh[-1]):
        assert (folder(k) / f"{inst.name}.json").read_text(encoding="utf-8") == format_json_instance(inst)
    assert fresh[0].meta["generator"]["area"] == area
    assert tuple(fresh[0].depot) == (area / 2, 0.0)


@pytest.mark.parametrize("k", sorted(SETS))
def test_reference_rows_follow_the_schema(k):
    """Rows name existing instances, once per omega, sorted; values are finite and above bounds."""
    rows = references(k)
    assert rows
    stems = {p.stem for p in folder(k).glob("*.json")}
    keys = [(r["instance"], float(r["omega"])) for r in rows]
    assert keys == sorted(keys) and len(set(keys)) == len(keys)
    for r in rows:
        assert r["instance"] in stems
        assert 0.0 <= float(r["omega"]) <= 1.0
        value = float(r["value"])
        assert math.isfinite(value) and value > 0 and repr(value) == r["value"]
        if r["lower_bound"]:
            assert float(r["lower_bound"]) <= value
        assert r["status"] in ("optimal", "best_known")
        assert SOURCE.match(r["source"]), r["source"]
        if r["status"] == "optimal":
            assert r["source"] == "dp" or r["source"].startswith(("milp", "brute"))
            assert r["lower_bound"] == "" or math.isclose(float(r["lower_bound"]), value, rel_tol=1e-6)
        dt.date.fromisoformat(r["date"])


@pytest.mark.parametrize("k", [k for k in SETS if k <= 10])
def test_small_sets_have_dp_optima_at_the_runners_omegas(k):
    """Every (instance, omega) the runner solves at K <= 10 has a proven dp optimum."""
    rows = {(r["instance"], float(r["omega"])): r for r in references(k)}
    for i in range(SETS[k][0]):
        for w in paper_omegas(k):
            row = rows[(f"uav-K{k}-N20-s1-{i:03d}", w)]
            assert (row["status"], row["source"]) == ("optimal", "dp")


@pytest.mark.parametrize("k", [k for k in SETS if k > 10])
def test_large_sets_have_whole_instances_at_three_omegas(k):
    """Rows come in whole instances (omega 0.3, 0.5, 0.6), starting at instance 0."""
    per_instance: dict[str, set[float]] = {}
    for r in references(k):
        per_instance.setdefault(r["instance"], set()).add(float(r["omega"]))
    assert all(ws == LARGE_OMEGAS for ws in per_instance.values())
    assert sorted(per_instance) == [f"uav-K{k}-N20-s1-{i:03d}" for i in range(len(per_instance))]


@pytest.mark.parametrize("k", [4, 7])
def test_optimal_rows_agree_with_dp(k):
    """A few rows re-solved by dp (fast at K <= 7): same tour value, re-priced by the evaluator."""
    rows = [r for r in references(k) if r["status"] == "optimal"]
    for r in (rows[0], rows[len(rows) // 2], rows[-1]):
        inst = read_instance(folder(k) / f"{r['instance']}.json")
        omega = float(r["omega"])
        res = run_solver(get_solver("dp"), inst, omega, time_limit=60.0)
        assert evaluate(inst, omega, res.order, res.heads).objective == res.objective
        assert math.isclose(res.objective, float(r["value"]), rel_tol=1e-12)


def test_references_match_the_committed_results_optima():
    """Every dp optimum in results/paper/*.csv (written to 10 significant digits) is a reference row."""
    refs = {(r["instance"], float(r["omega"])): float(r["value"])
            for k in SETS if k <= 10 for r in references(k)}
    checked = 0
    for path in sorted(RESULTS.glob("*.csv")):
        with path.open(encoding="utf-8", newline="") as f:
            for row in csv.DictReader(f):
                if row.get("reference") == "dp" and row.get("ref_status") == "optimal" and row["optimum"]:
                    value = refs[(row["instance"], float(row["omega"]))]
                    assert float(f"{value:.10g}") == float(row["optimum"]), (path.name, row["instance"])
                    checked += 1
    assert checked > 0

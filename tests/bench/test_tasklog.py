"""The task log: torn lines cut off, records checked against the schema and skipped with the
line named, failures old and new, and which logged solves a run redoes."""

from __future__ import annotations

import json

import pytest

from gtsp_bench.bench.tasklog import TaskLog, failure_cause, has_answer, needs_run


def record(name: str, objective: float = 10.0, **kw) -> dict:
    """A well-formed task-log record of a greedy solve on a 2-cluster instance ``name``."""
    return {"key": f"{name}#0123|greedy|w=0.5|seed=0|tl=10", "instance": name, "solver": "greedy",
            "omega": 0.5, "seed": 0, "time_limit": 10.0, "status": "feasible",
            "objective": objective, "order": [1, 0], "heads": [0, 2], "note": "", **kw}


def test_task_log_drops_torn_line(tmp_path):
    """A torn last line is cut off; later appends start on a fresh line; the last record wins."""
    log = TaskLog(tmp_path / "runs.jsonl")
    a, b = record("a"), record("b")
    log.append(a)
    log.append(b)
    log.close()
    with open(log.path, "a") as f:
        f.write('{"key": "c", "v"')
    assert set(log.load()) == {a["key"], b["key"]}
    log.append({**a, "objective": 9.0})
    log.close()
    records = log.load()
    assert records[a["key"]]["objective"] == 9.0 and len(log.path.read_text().splitlines()) == 3
    assert log.skipped == []


def test_an_append_never_glues_onto_a_torn_last_line(tmp_path):
    """A log whose last line was torn (a run killed mid-write) and not cut by load(): the next
    append starts a new line, so the torn line is skipped with a warning and the new record
    kept."""
    log = TaskLog(tmp_path / "runs.jsonl")
    a, b = record("a"), record("b")
    log.append(a)
    log.close()
    with open(log.path, "a") as f:
        f.write('{"key": "c", "obj')
    log.append(b)
    log.append({**a, "objective": 8.0})
    log.close()
    assert log.path.read_text().splitlines()[1] == '{"key": "c", "obj'
    records = log.load()
    assert records == {a["key"]: {**a, "objective": 8.0}, b["key"]: b}
    assert log.skipped == [f"{log.path}:2: not a JSON record"]


@pytest.mark.parametrize("last", [b'{"key": "x", "objective": 1\n', b"\x00\x00\x00\n", b"\xff\xfe{]\n"])
def test_a_corrupt_last_line_is_skipped_not_a_crash(tmp_path, last):
    """A complete but corrupt last line (cut JSON, zero bytes a crash left, bytes that are not
    UTF-8) is skipped and named; the records before it load."""
    log = TaskLog(tmp_path / "runs.jsonl")
    a = record("a")
    log.append(a)
    log.close()
    with open(log.path, "ab") as f:
        f.write(last)
    assert log.load() == {a["key"]: a}
    assert log.skipped == [f"{log.path}:2: not a JSON record"]


@pytest.mark.parametrize("bad, reason", [
    ({"key": ["x"]}, "'key' is not a non-empty string"),
    ({**record("a"), "objective": "abc"}, "objective 'abc' of a feasible solve is not a finite"),
    ({"key": record("a")["key"]}, "solver None does not match the key"),
    ({**record("a"), "objective": float("inf")}, "not a finite number"),
    ({**record("a"), "status": "done"}, "status 'done' is not one of"),
    ({**record("a"), "solver": "dp"}, "solver 'dp' does not match the key"),
    ({**record("a"), "omega": 0.3}, "omega 0.3 does not match the key"),
    ({**record("a"), "order": [0, 0]}, "order is not a permutation"),
    ({**record("a"), "order": [0, 1, 2], "heads": [0, 0, 0]}, "order has 3 entries, not 2"),
    ({**record("a"), "heads": [0]}, "heads has 1 entries, not 2"),
    ({**record("a"), "heads": [0, 3]}, "heads names a node outside its cluster"),
    ({**record("a"), "order": [True, 0]}, "order is not a list of integers"),
    ({**record("a"), "status": "failed"}, "objective 10.0 of a failed solve is not null"),
    ({**record("a"), "status": "failed", "objective": None}, "without an objective has a tour"),
    ({**record("a"), "runtime_s": "fast"}, "runtime_s 'fast' is not a number"),
    ({**record("a"), "status": "failed", "objective": None, "order": [], "heads": [],
      "cause": "cosmic rays"}, "cause 'cosmic rays' is not one of"),
    ([1, 2], "not a JSON object"),
])
def test_task_log_skips_bad_records_with_a_warning(tmp_path, bad, reason):
    """A record of the wrong shape (the key a list, a text objective, a bare key, a tour of the
    wrong length, ...) is skipped and named by line; the good record before it stays."""
    log = TaskLog(tmp_path / "runs.jsonl")
    good = record("a")
    log.append(good)
    log.close()
    with open(log.path, "a") as f:
        f.write(json.dumps(bad) + "\n")
    records = log.load({good["key"]: (1, 3)})
    assert records == {good["key"]: good}
    assert len(log.skipped) == 1 and log.skipped[0].startswith(f"{log.path}:2: ")
    assert reason in log.skipped[0]


def test_task_log_accepts_failures_old_and_new(tmp_path):
    """Failures with a null objective, older ones with NaN, refusals, and a time_limit row killed
    without an answer all load; an old 'worker died' note counts as the infrastructure's fault."""
    log = TaskLog(tmp_path / "runs.jsonl")
    base = {k: v for k, v in record("a").items() if k not in ("order", "heads", "objective")}
    rows = [
        {**base, "key": base["key"] + "1", "status": "failed", "objective": None, "cause": "solver"},
        {**base, "key": base["key"] + "2", "status": "failed", "objective": float("nan"),
         "note": "worker died (exit code -9)"},
        {**base, "key": base["key"] + "3", "status": "refused", "objective": None},
        {**base, "key": base["key"] + "4", "status": "time_limit", "objective": None},
    ]
    for row in rows:
        log.append(row)
    log.close()
    records = log.load()
    assert len(records) == 4 and log.skipped == []
    assert [failure_cause(records[r["key"]]) for r in rows] == ["solver", "infrastructure", None, None]
    assert [needs_run(records[r["key"]], False) for r in rows] == [False, True, False, False]
    assert [needs_run(records[r["key"]], True) for r in rows] == [True, True, False, False]
    assert needs_run(None, False) and not any(has_answer(records[r["key"]]) for r in rows)

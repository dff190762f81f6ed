"""Tasks: log keys with and without solver options, the task message, a run folder's paths."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from gtsp_bench.bench.tasks import RunFolder, StoredInstance, Task, _task_message, hard_limit_for, task_key
from gtsp_bench.data.parse import format_json_instance
from gtsp_bench.generator import generate_instance


def _stored() -> StoredInstance:
    inst = generate_instance(3, 2, seed=0, name="tiny")
    return StoredInstance(inst, format_json_instance(inst), "abcd", Path("tiny.json"))


def test_task_key_names_options_only_when_given():
    s = _stored()
    plain = task_key(s, "greedy", 0.5, 0, 10.0)
    assert plain == "tiny#abcd|greedy|w=0.5|seed=0|tl=10"
    assert task_key(s, "greedy", 0.5, 0, 10.0, ()) == plain
    keyed = task_key(s, "lns", 0.3, 2, 5.0, (("stop_at_convergence", True), ("trials", 4)))
    assert keyed == "tiny#abcd|lns[stop_at_convergence=True,trials=4]|w=0.3|seed=2|tl=5"


def test_task_message_carries_options_when_there_are_some():
    s = _stored()
    bare = _task_message(Task("k", "greedy", 0.5, s, 0, 1.0))
    assert bare == {"fingerprint": "abcd", "text": s.text, "omega": 0.5, "seed": 0, "time_limit": 1.0,
                    "hard_limit": hard_limit_for(1.0)}
    msg = _task_message(Task("k", "lns", 0.5, s, 0, 1.0, (("stop_at_convergence", True),)))
    assert msg["options"] == {"stop_at_convergence": True}


def test_run_folder_paths_and_hard_limit():
    @dataclass(frozen=True)
    class Config(RunFolder):
        out_dir: Path
        time_limit: float

    c = Config(Path("out"), 5.0)
    assert c.log_path == Path("out/tmp/runs.jsonl") and c.lock_path == Path("out/tmp/bench.lock")
    assert c.hard_limit() == 2 * 5.0 + 10.0


def test_where_solves_run_names_the_executor():
    from gtsp_bench.bench.tasks import where_solves_run

    assert where_solves_run("local", 2) == "2 worker(s)"
    assert where_solves_run("dask", 3) == "3 local Dask worker(s)"
    assert where_solves_run("tcp://h:8786", 2) == "the Dask scheduler tcp://h:8786"

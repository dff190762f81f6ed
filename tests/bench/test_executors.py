"""The executors: the paper's sweep on Dask gives the local pool's objectives, a runner killed
(SIGINT, SIGKILL) mid-sweep with either executor loses no finished solve, a Dask worker lost
under a solve is retried, one output folder takes one run at a time, and bad executors are
refused in one line."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest

from gtsp_bench.bench import executors
from gtsp_bench.bench.runner import make_config, run_bench
from gtsp_bench.bench.tasklog import exclusive_lock
from gtsp_bench.cli import main
from gtsp_bench.errors import InputError
from tests import runner_solvers
from tests.conftest import REPO

runner_solvers.register()

dask_mark = pytest.mark.dask


@pytest.fixture(scope="module")
def scheduler():
    """The address of a 2-worker LocalCluster (processes, one thread each), shared by the tests
    that name an existing scheduler (``tcp://...``)."""
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=None, memory_limit=0)
    try:
        yield cluster.scheduler_address
    finally:
        executors.close_executors()
        cluster.close()


def _config(tmp_path: Path, out: str = "out", **kw):
    kw = {"out_dir": tmp_path / out, "instance_dir": tmp_path / "inst",
          "checkpoint_dir": tmp_path / "ckpt", "progress": False, "n_nodes": 4, "jobs": 2, **kw}
    return make_config(**kw)


def _log_lines(config) -> list[str]:
    return config.log_path.read_text().splitlines() if config.log_path.exists() else []


def _quiet(msg: str) -> None:
    pass


# ---------------------------------------------------------------------- same answers
@dask_mark
def test_dask_gives_the_local_pools_objectives_and_a_rerun_reuses_every_solve(tmp_path, scheduler):
    """The paper's omega sweep (greedy against dp, K = 4, two instances, the quick omegas) on a
    2-worker Dask cluster gives the local pool's objectives and tours row for row; a second run on
    Dask re-uses every solve."""
    kw = {"experiments": "ratio-omega", "ks": "4", "solvers": "greedy", "n_instances": 2,
          "quick": True}
    local = _config(tmp_path, "local", **kw)
    dask = _config(tmp_path, "dask", executor=scheduler, **kw)
    first = run_bench(local, log=_quiet)
    on_dask = run_bench(dask, log=_quiet)
    assert on_dask.run == first.run == first.tasks > 0 and on_dask.failed == 0
    a = pd.read_csv(local.out_dir / "ratio-omega.csv")
    b = pd.read_csv(dask.out_dir / "ratio-omega.csv")
    assert len(a) == len(b) == 12 and set(a["status"]) <= {"optimal", "feasible"}
    for col in ("instance", "omega", "solver", "status", "objective", "optimum", "order", "heads"):
        assert a[col].tolist() == b[col].tolist(), col
    again = run_bench(dask, log=_quiet)
    assert again.run == 0 and again.cached == again.tasks == first.tasks


@dask_mark
def test_a_solve_on_a_dask_worker_may_run_one_thread(scheduler):
    """Dask workers are counted one per core, one thread each: a solve there is told it may run
    one thread (lns's islands stay one), whatever the machine's cores."""
    distributed = pytest.importorskip("distributed")
    from tests.bench.test_pool import _msg

    with distributed.Client(scheduler) as client:
        out = client.submit(executors.solve_on_worker, "t-threads", "tests.runner_solvers:Threads",
                            "test", 0, _msg(0.3), 60.0, pure=False).result(timeout=120)
    rec = out["record"]
    assert rec["status"] == "feasible" and rec["stats"]["workers"] == 1


@dask_mark
def test_a_set_sweep_on_dask_matches_the_local_pool_and_holds_the_lock(tmp_path, scheduler, capsys):
    """`bench sets --set FOLDER` with greedy and lns (seeded) on a Dask scheduler gives the local pool's
    objectives solve for solve, re-uses every solve on a second run, and a sweep on a locked
    folder stops at once with one line naming the lock."""
    from gtsp_bench.data.io import write_instance
    from gtsp_bench.generator import generate_instance

    folder = tmp_path / "tiny"
    for i in range(3):
        write_instance(generate_instance(4, 3, seed=i, name=f"tiny-{i}"), folder / f"tiny-{i}.json")
    argv = ["bench", "sets", "--set", str(folder), "--solvers", "greedy,lns", "--omegas", "0.3,0.6",
            "--time-limit", "2", "--jobs", "2", "--no-progress"]
    assert main([*argv, "--out", str(tmp_path / "local")]) == 0
    assert main([*argv, "--out", str(tmp_path / "dask"), "--executor", scheduler]) == 0
    a = pd.read_csv(tmp_path / "local" / "rows.csv")
    b = pd.read_csv(tmp_path / "dask" / "rows.csv")
    assert len(a) == len(b) == 3 * 2 * 2 and a["objective"].notna().all()
    for col in ("instance", "omega", "solver", "status", "objective"):
        assert a[col].tolist() == b[col].tolist(), col
    capsys.readouterr()
    assert main([*argv, "--out", str(tmp_path / "dask"), "--executor", scheduler]) == 0
    assert "12 already in" in capsys.readouterr().err
    lock = tmp_path / "dask" / "tmp" / "bench.lock"
    with exclusive_lock(lock, "a test"):
        assert main([*argv, "--out", str(tmp_path / "dask")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{lock}: locked by another gtsp-bench bench" in err


def test_a_kill_is_taken_once_by_racing_processes(tmp_path):
    """The test solvers' kill count is taken under a lock: eight processes racing for one kill,
    exactly one gets it (without the lock two Dask workers both read 1 and both died)."""
    from concurrent.futures import ProcessPoolExecutor

    kills = tmp_path / "kills"
    kills.write_text("1")
    with ProcessPoolExecutor(max_workers=8) as pool:
        taken = list(pool.map(runner_solvers.take_kill, [kills] * 8))
    assert taken.count(True) == 1
    assert kills.read_text() == "0"


@dask_mark
def test_a_dask_worker_lost_under_a_solve_is_retried_on_another(tmp_path, scheduler):
    """SIGKILL of the Dask worker running a solve (a machine lost mid-task): the scheduler gives
    the task to another worker and the solve is logged once, solved."""
    kills = tmp_path / "kills"
    kills.write_text("1")
    from distributed import Client

    with Client(scheduler) as client:  # the workers started before this test
        client.run(runner_solvers.set_env, runner_solvers.KILLS_FILE, str(kills))
    config = _config(tmp_path, experiments="ratio-k", ks="3", solvers="t-kills-dask", n_instances=2,
                     reference="t-fixed", executor=scheduler)
    summary = run_bench(config, log=_quiet)
    records = [json.loads(line) for line in _log_lines(config)]
    assert kills.read_text() == "0"
    assert summary.failed == 0 and len(records) == summary.tasks == 4
    assert all(r["status"] == "feasible" for r in records)


# ---------------------------------------------------------------------- killed runners
def _tiny_set(tmp_path: Path) -> Path:
    """Two generated instances of K = 3, N = 4 in a folder of their own."""
    from gtsp_bench.data.io import write_instance
    from gtsp_bench.generator import generate_instance

    folder = tmp_path / "tiny"
    for i in range(2):
        write_instance(generate_instance(3, 4, seed=i, name=f"tiny-{i}"), folder / f"tiny-{i}.json")
    return folder


def _sweep_argv(tmp_path: Path, executor: str) -> list[str]:
    """The kill tests' run: 20 t-slow solves (0.3 s each), 2 instances x 10 omegas."""
    return ["bench", "sets", "--set", str(_tiny_set(tmp_path)), "--solvers", "t-slow", "--omegas",
            "0,0.1,0.2,0.3,0.4,0.5,0.6,0.7,0.8,0.9", "--jobs", "2", "--executor", executor,
            "--out", str(tmp_path / "out"), "--no-progress"]


def _launch(tmp_path: Path, executor: str) -> tuple[subprocess.Popen, object]:
    """``gtsp-bench bench sets`` of :func:`_sweep_argv` in a child process."""
    config = _config(tmp_path)
    argv = _sweep_argv(tmp_path, executor)
    # SIGINT as a terminal gives it: a shell's background job (e.g. CI started with `&`) starts its
    # children with SIGINT ignored, and Python then installs no KeyboardInterrupt handler
    launcher = ("import signal; signal.signal(signal.SIGINT, signal.default_int_handler); "
                "import tests.runner_solvers as t; t.register(); from gtsp_bench.cli import main; "
                f"raise SystemExit(main({argv!r}))")
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    proc = subprocess.Popen([sys.executable, "-c", launcher], cwd=REPO, env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    return proc, config


def _descendants(pid: int) -> list:
    import psutil

    try:
        return psutil.Process(pid).children(recursive=True)
    except psutil.NoSuchProcess:
        return []


@pytest.mark.parametrize("executor, sig", [
    ("local", signal.SIGINT),  # the local pool under SIGKILL: tests/test_runner.py
    pytest.param("dask", signal.SIGKILL, marks=dask_mark),
    pytest.param("tcp", signal.SIGINT, marks=dask_mark),
])
def test_a_runner_killed_mid_sweep_loses_no_finished_solve(tmp_path, request, capsys, executor, sig):
    """SIGINT or SIGKILL of a running `gtsp-bench bench` (on the local pool, on its own Dask
    cluster, on an existing one) once some solves are logged: every logged solve is kept and
    re-used, the rerun (on the existing Dask cluster where the run was on Dask) runs exactly the
    missing ones, and the killed run leaves no process of its own behind."""
    address = request.getfixturevalue("scheduler") if executor in ("dask", "tcp") else None
    proc, config = _launch(tmp_path, address if executor == "tcp" else executor)
    total = 2 * 10  # 2 instances x 10 omegas
    deadline = time.monotonic() + 90
    family = []
    try:
        while len(_log_lines(config)) < 3 and time.monotonic() < deadline:
            family = _descendants(proc.pid) or family
            time.sleep(0.02)
    finally:
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
    before = _log_lines(config)
    assert 3 <= len(before) < total, f"the run was not stopped midway:\n{err}"
    if sig == signal.SIGINT:
        assert proc.returncode == 130 and err.rstrip().endswith("gtsp-bench: interrupted"), err
    assert main(_sweep_argv(tmp_path, address or "local")) == 0
    err = capsys.readouterr().err
    after = _log_lines(config)
    assert f"{total} solves, {len(before)} already in" in err
    assert f"{total - len(before)} solves run" in err and " 0 failed" in err
    assert after[: len(before)] == before and len(after) == total
    gone_by = time.monotonic() + 30
    while any(p.is_running() and p.status() != "zombie" for p in family) and time.monotonic() < gone_by:
        time.sleep(0.2)
    left = [p for p in family if p.is_running() and p.status() != "zombie"]
    assert not left, f"left behind: {[p.cmdline()[:3] for p in left]}"


# ---------------------------------------------------------------------- one run per folder
def test_a_second_run_on_the_same_folder_stops_at_once_naming_the_lock(tmp_path, capsys):
    """While a run holds OUT/tmp/bench.lock, `gtsp-bench bench` on that folder exits 2 with one
    line naming the lock and its holder's process, and writes nothing; once it is free the run
    goes ahead."""
    config = _config(tmp_path)
    argv = ["bench", "heuristics", "-K", "3", "--solvers", "greedy", "--instances", "1",
            "--nodes", "4", "--jobs", "1", "--out", str(config.out_dir), "--instance-dir",
            str(tmp_path / "inst"), "--no-progress"]
    with exclusive_lock(config.lock_path, "a test"):
        assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err == (f"gtsp-bench: error: {config.lock_path}: locked by another gtsp-bench bench "
                   f"(process {os.getpid()}) using the same folder; wait for it to finish or "
                   f"choose another output folder")
    assert not config.log_path.exists() and not list(config.out_dir.glob("*.csv"))
    assert main(argv) == 0 and len(_log_lines(config)) == 2


def test_a_lock_held_by_a_killed_process_does_not_block(tmp_path):
    """A process killed with SIGKILL while holding the lock leaves no stale lock behind."""
    lock = tmp_path / "tmp" / "bench.lock"
    code = ("import sys, time; from pathlib import Path\n"
            "from gtsp_bench.bench.tasklog import exclusive_lock\n"
            "with exclusive_lock(Path(sys.argv[1]), 'x'):\n"
            "    print('held', flush=True); time.sleep(60)\n")
    proc = subprocess.Popen([sys.executable, "-c", code, str(lock)], stdout=subprocess.PIPE, text=True,
                            env={**os.environ, "PYTHONPATH": str(REPO)})
    try:
        assert proc.stdout.readline().strip() == "held"
        with pytest.raises(InputError, match=rf"locked by y \(process {proc.pid}\)"), \
                exclusive_lock(lock, "y"):
            pass
    finally:
        proc.kill()
        proc.wait()
    with exclusive_lock(lock, "y") as held:
        assert held == lock and lock.read_text().strip() == str(os.getpid())


# ---------------------------------------------------------------------- bad executors
def test_an_unreachable_scheduler_is_one_line_exit_2(tmp_path, capsys, monkeypatch):
    """A scheduler address where nothing listens: one line naming it, exit code 2."""
    pytest.importorskip("distributed")
    import socket

    with socket.socket() as s:  # a free port: nothing listens there
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    monkeypatch.setattr(executors, "CONNECT_TIMEOUT_S", 1.0)
    argv = ["bench", "heuristics", "-K", "3", "--solvers", "greedy", "--instances", "1",
            "--nodes", "4", "--executor", f"tcp://127.0.0.1:{port}", "--out", str(tmp_path / "out"),
            "--instance-dir", str(tmp_path / "inst"), "--no-progress"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith(f"gtsp-bench: error: tcp://127.0.0.1:{port}: cannot reach the Dask "
                              f"scheduler (")
    assert not any(line.startswith("Traceback") for line in err)


def test_dask_not_installed_names_the_extra(monkeypatch):
    """Without the distributed package the Dask executors say which extra to install."""
    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(InputError, match=r"need the dask extra \(pip install 'gtsp-bench\[dask\]'\)"):
        executors.open_executor("dask", 2)


def test_executor_names_are_checked_before_anything_runs(tmp_path, capsys):
    """A bad --executor is refused by make_config, before any file is written."""
    with pytest.raises(InputError, match="bad executor 'spark'"):
        _config(tmp_path, executor="spark")
    assert main(["bench", "--executor", "tcp://host", "--out", str(tmp_path / "o")]) == 2
    assert "tcp://HOST:PORT" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()
    assert isinstance(executors.open_executor("local", 3), executors.LocalExecutor)

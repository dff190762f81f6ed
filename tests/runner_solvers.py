"""Misbehaving and slow solvers for tests/test_runner.py, kept light: the runner's worker
processes import this module as ``tests.runner_solvers``."""

from __future__ import annotations

import time

from gtsp_bench.registry import register_solver
from gtsp_bench.solver import Solution


class Crash:
    """Raises on every solve."""

    def solve(self, instance, omega, *, time_limit=None, seed=0):
        raise RuntimeError("boom")


class Hang:
    """Ignores its time limit and sleeps far beyond it."""

    def solve(self, instance, omega, *, time_limit=None, seed=0):
        time.sleep(60)
        raise AssertionError("not reached")


class Slow:
    """Greedy after a 0.3 s pause: a run long enough to be killed midway, even on a loaded machine."""

    def solve(self, instance, omega, *, time_limit=None, seed=0):
        from gtsp_bench.solvers.heuristics.greedy import Greedy

        time.sleep(0.3)
        return Greedy().solve(instance, omega)


class DieAboveHalf:
    """Kills its own process (exit code 3) when omega > 0.5, as a crash in native code would;
    greedy otherwise."""

    def solve(self, instance, omega, *, time_limit=None, seed=0):
        import os

        from gtsp_bench.solvers.heuristics.greedy import Greedy

        if omega > 0.5:
            os._exit(3)
        return Greedy().solve(instance, omega)


class Banner:
    """Greedy after writing a banner straight to file descriptor 1, as highspy 1.16 does."""

    def solve(self, instance, omega, *, time_limit=None, seed=0):
        import os

        from gtsp_bench.solvers.heuristics.greedy import Greedy

        os.write(1, b"Running HiGHS 1.16.0: banner on fd 1\nCopyright (c) 2026\n")
        print("a stray print")
        return Greedy().solve(instance, omega)


#: Environment variable naming the file that holds how many more solves KilledFromOutside kills.
KILLS_FILE = "GTSP_BENCH_TEST_KILLS"


def take_kill(path) -> bool:
    """Count the number in the file ``path`` down by one if it is > 0, under an exclusive lock
    (two workers solving at once must not both read the same count and both die); whether it
    was."""
    import fcntl

    with open(path, "r+") as f:
        fcntl.flock(f, fcntl.LOCK_EX)
        left = int(f.read() or 0)
        if left > 0:
            f.seek(0)
            f.truncate()
            f.write(str(left - 1))
            f.flush()
        return left > 0  # the lock goes with the file's closing


class KilledFromOutside:
    """While the number in the file ``$GTSP_BENCH_TEST_KILLS`` is > 0, counts it down and kills
    its own worker with SIGKILL mid-solve (as the OOM killer or ``kill -9`` would); greedy
    otherwise."""

    def solve(self, instance, omega, *, time_limit=None, seed=0):
        import os
        import signal
        from pathlib import Path

        from gtsp_bench.solvers.heuristics.greedy import Greedy

        if take_kill(Path(os.environ[KILLS_FILE])):
            os.kill(os.getpid(), signal.SIGKILL)
        return Greedy().solve(instance, omega)


def set_env(name: str, value: str) -> None:
    """Set an environment variable in this process (run on Dask workers started earlier)."""
    import os

    os.environ[name] = value


class KillsItsDaskWorker:
    """Like KilledFromOutside, but kills the process that started its worker: on a Dask worker,
    that Dask worker (as a machine lost mid-task would be); greedy otherwise."""

    def solve(self, instance, omega, *, time_limit=None, seed=0):
        import os
        import signal
        from pathlib import Path

        from gtsp_bench.solvers.heuristics.greedy import Greedy

        if take_kill(Path(os.environ[KILLS_FILE])):
            os.kill(os.getppid(), signal.SIGKILL)
            time.sleep(1)  # never answers: its Dask worker is gone
        return Greedy().solve(instance, omega)


class OutOfMemory:
    """Raises MemoryError, as an allocation beyond the machine's memory does."""

    def solve(self, instance, omega, *, time_limit=None, seed=0):
        raise MemoryError("Unable to allocate 500. GiB for an array")


class Refuses:
    """Refuses every instance by design (an InputError), as dp above its memory limit does."""

    def solve(self, instance, omega, *, time_limit=None, seed=0):
        from gtsp_bench.errors import InputError

        raise InputError(f"refuses {instance.name} by design")


class FixedTour:
    """Clusters in index order, every head 0: feasible, usually not optimal."""

    def solve(self, instance, omega, *, time_limit=None, seed=0):
        from gtsp_bench.energy import evaluate

        order, heads = list(range(instance.n_clusters)), [0] * instance.n_clusters
        return Solution(order, heads, evaluate(instance, omega, order, heads).objective)


class Echo:
    """Returns its warm start unchanged (FixedTour's tour without one)."""

    def solve(self, instance, omega, *, time_limit=None, seed=0, initial=None):
        if initial is None:
            return FixedTour().solve(instance, omega)
        return Solution(initial.order, initial.heads, initial.objective)


class Revised(FixedTour):
    """FixedTour with a revision tag the tests change (as a learned policy's new weights would)."""

    REV = "a"

    @classmethod
    def revision(cls) -> str:
        return cls.REV


class _GreedyAfterImport:
    """Greedy, after importing ``module`` (a library that may not share a process with another)."""

    module = ""

    def solve(self, instance, omega, *, time_limit=None, seed=0):
        import importlib

        from gtsp_bench.solvers.heuristics.greedy import Greedy

        lib = importlib.import_module(self.module)
        sol = Greedy().solve(instance, omega)
        stats = {"module": self.module}
        if self.module == "torch":
            stats["torch_threads"] = lib.get_num_threads()
        return Solution(sol.order, sol.heads, sol.objective, sol.status, stats=stats)


class UsesHighs(_GreedyAfterImport):
    """Imports highspy."""

    module = "highspy"


class UsesOrtools(_GreedyAfterImport):
    """Imports ortools' CP-SAT."""

    module = "ortools.sat.python.cp_model"


class UsesTorch(_GreedyAfterImport):
    """Imports torch and reports its thread count."""

    module = "torch"


def register() -> None:
    """Register these solvers as t-crash, t-hang, t-slow, t-fixed, t-echo, t-revised, t-highs,
    t-ortools, t-torch, t-banner, t-killed, t-kills-dask, t-oom, t-refuses and t-missing (whose
    class does not exist), all with ``bench=False``."""
    for name, cls in (("t-crash", "Crash"), ("t-hang", "Hang"), ("t-slow", "Slow"),
                      ("t-banner", "Banner"), ("t-killed", "KilledFromOutside"),
                      ("t-kills-dask", "KillsItsDaskWorker"),
                      ("t-oom", "OutOfMemory"), ("t-refuses", "Refuses"),
                      ("t-fixed", "FixedTour"), ("t-echo", "Echo"), ("t-revised", "Revised"),
                      ("t-highs", "UsesHighs"),
                      ("t-ortools", "UsesOrtools"), ("t-torch", "UsesTorch"),
                      ("t-missing", "NoSuchClass")):
        register_solver(name, f"tests.runner_solvers:{cls}", "runner test solver", bench=False,
                        replace=True)


class Threads:
    """Greedy, its stats the threads its worker process was told a solve may run: lns's default
    ``workers`` there, and ``OMP_NUM_THREADS``."""

    def solve(self, instance, omega, *, time_limit=None, seed=0):
        import os

        from gtsp_bench.solvers.heuristics.greedy import Greedy
        from gtsp_bench.solvers.heuristics.lns_islands import default_workers

        sol = Greedy().solve(instance, omega)
        stats = {"workers": default_workers(), "omp": os.environ.get("OMP_NUM_THREADS")}
        return Solution(sol.order, sol.heads, sol.objective, sol.status, stats=stats)

"""Several threads searching at once for :mod:`gtsp_bench.solvers.heuristics.lns` (option ``workers``).

On the large GTSPLIB files the first tour decides lns's basin more than the time it is given
(2000C10k.0 ended at 1.47 and 1.39 % after 120 s against 1.49 and 1.40 % after 60 s, seeds 1 and
2), and the macro start is the better basin on some files and the worse on others
(docs/notes/lns-vs-glns.md). With ``workers`` threads the trials run as **islands**: each thread
searches from its own first tour (the usual one, then the macro tour on a planar instance, then
random-insertion tours) with its own random numbers, independently until the ``exchange`` share of
the trial phase has passed; then every island goes on from the best island's best tour (its own
random numbers still). In the end phase every thread re-solves regions of the best island's tour,
each change merged into it (:func:`~.lns_paths.shared_region_passes`): one tour at twice the
regions a second did better than each island re-solving its own best, the cheaper kept
(measured in docs/notes/, 2026-11-29). The kernels release the GIL (numba ``nogil``)
and numba keeps one random state per thread, so the threads run on separate cores with plain
:mod:`threading`; the problem's arrays are shared, read-only.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from concurrent.futures import ThreadPoolExecutor
from typing import TYPE_CHECKING

from gtsp_bench.solvers.heuristics import lns_kernels as kernels

from gtsp_bench.solver import allowed_threads

if TYPE_CHECKING:
    from gtsp_bench.solvers.heuristics.lns import _Run, _Search

#: Threads of a large time-limited search by default, where the cores allow (the islands measured:
#: the usual start and the macro tour).
AUTO_WORKERS = 2


def default_workers(environ: Mapping[str, str] | None = None, cores: int | None = None) -> int:
    """The default ``workers``: :data:`AUTO_WORKERS`, at most the cores this process may run on
    and at most the threads a solve may run where the environment says so
    (:func:`gtsp_bench.solver.allowed_threads`)."""
    return allowed_threads(AUTO_WORKERS, environ, cores)


def island_kinds(search: _Search, workers: int) -> list[str]:
    """The first tour of each island: the search's usual start (the warm start, else greedy, or
    the macro tour with ``macro``), then the macro tour where the instance has points, then
    random insertion."""
    first = "initial" if search.initial is not None else "macro" if search.s.macro else "greedy"
    others = ["macro"] if search.centre is not None and first != "macro" else []
    return ([first] + others + ["random"] * workers)[:workers]


def merge(runs: list[_Run]) -> _Run:
    """The island with the cheapest tour, its counts summed over all islands."""
    win = min(runs, key=lambda r: r.best_cost)
    for r in runs:
        if r is not win:
            win.done += r.done
            win.trials += r.trials
            win.windows += r.windows
            win.window_saving += r.window_saving
    win.converged = all(r.converged for r in runs)
    win.timed_out = any(r.timed_out for r in runs)
    return win


def run_islands(search: _Search, workers: int, deadline: float, final: float | None = None
                ) -> tuple[_Run, list[float]]:
    """Run ``workers`` islands of ``search``'s trials until ``deadline`` (a time limit is needed),
    then, given ``final``, the end phase (region re-solves of the best island's tour by all
    threads) until ``final``; returns the merged state (:func:`merge`) and each island's best
    cost. First tours by :func:`island_kinds`, one exchange of the best tour after
    ``search.s.exchange`` of the trials' time (1.0: none)."""
    seeds = search.rng.integers(2**31 - 1, size=workers)
    rngs = search.rng.spawn(workers)
    kinds = island_kinds(search, workers)
    clock0 = time.perf_counter()
    middle = clock0 + search.s.exchange * max(0.0, deadline - clock0)
    runs: list[_Run | None] = [None] * workers

    def first(j: int) -> None:
        kernels.seed(int(seeds[j]))  # numba's random state is the thread's own
        run = search.first(middle, kinds[j])
        search.trials(run, middle, rngs[j])
        runs[j] = run

    def rest(j: int) -> None:
        run = runs[j]
        assert run is not None
        run.timed_out = False
        search.trials(run, deadline, rngs[j])

    with ThreadPoolExecutor(max_workers=workers, thread_name_prefix="lns-island") as pool:
        list(pool.map(first, range(workers)))
        done = [r for r in runs if r is not None]
        if search.s.exchange < 1.0:
            win = min(done, key=lambda r: r.best_cost)
            for r in done:
                if r is not win:
                    r.best, r.best_cost = win.best.copy(), win.best_cost
            list(pool.map(rest, range(workers)))
    if final is not None:  # every thread on the best island's tour
        search.finish(min(done, key=lambda r: r.best_cost), final, rngs)
    return merge(done), [r.best_cost for r in done]

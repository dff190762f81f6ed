"""The settings of :mod:`gtsp_bench.solvers.heuristics.lns`, and its **effort** presets.

An effort preset, in the spirit of GLNS's modes, says when the search ends (:data:`EFFORTS`):

``fast``
    three warm trials from the first tour, then stop (what ``stop_at_convergence=true`` does);
``default``
    more trials, with a cold restart from a random-insertion tour after trials in a row that did
    not improve their start, then stop;
``slow``
    the same with more trials and more patience before a cold restart;
``budget``
    go on until the time limit: trials fitted to it, cold restarts, region re-solves after a
    failed trial from ``FAIL_FROM`` to ``FAIL_TO`` clusters, two threads where two cores are free,
    and above ``LARGE`` region re-solves at the end (the fixed-budget benchmarks run this).

With the first three the time limit is a cap, not a target. ``trials`` and ``restart_after``
given explicitly win over the preset's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gtsp_bench.solvers.heuristics.lns_islands import default_workers
from gtsp_bench.solvers.heuristics.lns_paths import END_TEMPERATURE

from gtsp_bench.checks import check_bool, check_choice, check_float, check_int
from gtsp_bench.errors import InputError

#: Above this many clusters an iteration removes at most 25 of them by default (100 up to it).
LARGE = 400
#: From ``FAIL_FROM`` up to ``FAIL_TO`` clusters, effort ``budget`` re-solves regions after a
#: failed trial by default (:meth:`LnsSettings.fail_passes_for`).
FAIL_FROM = 200
FAIL_TO = 1500
#: The end phase's share of the time limit by default (:meth:`LnsSettings.path_share_for`): up to
#: ``FAIL_TO`` clusters, and above it, where no region re-solves run between the trials.
PATHS = 0.3
PATHS_ABOVE_FAIL_TO = 0.8
#: Double-bridge kicks after a failed trial by default with effort ``budget``: from ``FAIL_FROM``
#: to ``LARGE`` clusters on symmetric costs, at every size on directed ones
#: (:meth:`LnsSettings.kicks_for`).
KICKS = 10_000


@dataclass(frozen=True)
class Effort:
    """An effort preset: whether the search ends on its own (``stops``), after how many trials
    (``trials``; with ``budget`` the trials after which it counts as converged), and after how
    many trials in a row without improvement the next starts cold (``restart_after``; 0: never)."""

    stops: bool
    trials: int
    restart_after: int


#: The effort presets by name (module docstring).
EFFORTS: dict[str, Effort] = {
    "fast": Effort(stops=True, trials=3, restart_after=0),
    "default": Effort(stops=True, trials=12, restart_after=2),
    "slow": Effort(stops=True, trials=40, restart_after=3),
    "budget": Effort(stops=False, trials=3, restart_after=2),
}


#: Options that may be ``None`` (a default of the effort or of the instance), with their
#: least value: checked only when given.
_OPTIONAL_INTS = (("iterations", 1), ("trials", 1), ("patience", 1), ("max_removals", 1),
                  ("neighbours", 1), ("restart_after", 0), ("reopt_window", 0), ("workers", 1),
                  ("fail_passes", 0), ("kicks", 0))
#: Boolean options that may be ``None`` (decided by the effort or the instance).
_OPTIONAL_BOOLS = ("stop_at_convergence", "points", "quadrants", "mirror", "plateau")


@dataclass(frozen=True)
class LnsSettings:
    """Validated settings of :class:`Lns` (see there)."""

    iterations: int | None = None
    trials: int | None = None
    patience: int | None = None
    remove_fraction: float = 0.3
    max_removals: int | None = None
    start_temperature: float | None = None
    end_temperature: float = 0.003
    reaction: float = 0.1
    noise: float = 0.1
    neighbours: int | None = None
    stop_at_convergence: bool | None = None
    restart_after: int | None = None
    reopt_window: int | None = None
    fit_to_time: bool = True
    fit_trials: int = 32
    points: bool | None = None
    quadrants: bool | None = None
    macro: bool = False
    macro_iterations: int = 5
    macro_groups: float = 5.0
    starts: int = 1
    start_iterations: int = 5
    paths: float | None = None
    path_clusters: int = 80
    path_iterations: int = 5
    path_temperature: float = 3.0
    fail_passes: int | None = None
    fail_temperature: float = 3.0
    workers: int | None = None
    exchange: float = 0.5
    effort: str | None = None
    mirror: bool | None = None
    plateau: bool | None = None
    regional: float | None = None
    kicks: int | None = None

    def __post_init__(self) -> None:
        # the options that may be None (the effort's or the instance's default): checked if given
        for name, low in _OPTIONAL_INTS:
            if getattr(self, name) is not None:
                check_int(name, getattr(self, name), low)
        for name in _OPTIONAL_BOOLS:
            if getattr(self, name) is not None:
                check_bool(name, getattr(self, name))
        check_float("remove_fraction", self.remove_fraction, 0.0, 1.0)
        if self.effort is not None:
            check_choice("effort", self.effort, tuple(EFFORTS))
            if self.stop_at_convergence is not None:
                raise InputError("give effort or stop_at_convergence, not both "
                                 "(stop_at_convergence=true is effort=fast, false is effort=budget)")
        if self.start_temperature is not None:
            check_float("start_temperature", self.start_temperature, 0.0, math.inf, open_low=False)
        check_float("end_temperature", self.end_temperature, 0.0, math.inf, open_low=False)
        if self.end_temperature > self.hottest:
            raise InputError(
                f"end_temperature ({self.end_temperature!r}) must not exceed start_temperature "
                f"({self.hottest!r})"
            )
        check_float("reaction", self.reaction, 0.0, 1.0)
        check_float("noise", self.noise, 0.0, math.inf, open_low=False)
        check_bool("fit_to_time", self.fit_to_time)
        check_int("fit_trials", self.fit_trials, 1)
        check_bool("macro", self.macro)
        check_int("macro_iterations", self.macro_iterations, 0)
        check_float("macro_groups", self.macro_groups, 0.0, math.inf, open_low=False)
        check_int("starts", self.starts, 1)
        check_int("start_iterations", self.start_iterations, 1)
        if self.paths is not None:
            check_float("paths", self.paths, 0.0, 1.0, open_low=False)
        check_int("path_clusters", self.path_clusters, 2)
        check_int("path_iterations", self.path_iterations, 0)
        for name in ("path_temperature", "fail_temperature"):  # a region's trial ends at the low
            check_float(name, getattr(self, name), END_TEMPERATURE, math.inf, open_low=False)
        check_float("exchange", self.exchange, 0.0, 1.0, open_low=False)
        if self.regional is not None:
            check_float("regional", self.regional, 0.0, 1.0, open_low=False)

    @property
    def preset(self) -> Effort:
        """The effort preset: ``effort`` (default ``default``); ``stop_at_convergence`` true is
        ``fast``, false ``budget``."""
        if self.stop_at_convergence is not None:
            return EFFORTS["fast" if self.stop_at_convergence else "budget"]
        return EFFORTS[self.effort or "default"]

    @property
    def stops(self) -> bool:
        """Whether the search ends after its trials (every preset but ``budget``)."""
        return self.preset.stops

    @property
    def trial_count(self) -> int:
        """Trials until the search has converged: ``trials``, else the preset's."""
        return self.trials if self.trials is not None else self.preset.trials

    @property
    def cold_after(self) -> int:
        """Trials in a row without improvement before a cold restart (0: never):
        ``restart_after``, else the preset's."""
        return self.restart_after if self.restart_after is not None else self.preset.restart_after

    @property
    def hottest(self) -> float:
        """The start temperature (default 0.3 when the search :attr:`stops`, else 1.0: a search
        that uses its whole time limit can afford to wander further before it cools)."""
        if self.start_temperature is not None:
            return self.start_temperature
        return 0.3 if self.stops else 1.0

    def iterations_for(self, n: int) -> int:
        """Iterations per trial for a cycle of ``n`` clusters (default ``max(100, 25 n)``)."""
        return self.iterations if self.iterations is not None else max(100, 25 * n)

    def neighbours_for(self, n: int, symmetric: bool) -> int:
        """Neighbour-list length for ``n`` clusters (default 10 on symmetric costs; on directed
        costs every other cluster: there the nearest clusters, by the cheapest arc either way, say
        little about where a cluster fits)."""
        if self.neighbours is not None:
            return self.neighbours
        return 10 if symmetric else max(1, n - 1)

    def quadrants_for(self, n: int) -> bool:
        """Whether the neighbour lists of ``n`` clusters take the nearest in each quadrant
        (default: above ``LARGE`` clusters)."""
        return self.quadrants if self.quadrants is not None else n > LARGE

    def max_removals_for(self, n: int) -> int:
        """Most clusters removed in one iteration for ``n`` clusters (default 100 up to
        ``LARGE`` clusters, 25 above: there an iteration's insertion and local search grow with
        the removals, and many small iterations did better in a fixed time)."""
        if self.max_removals is not None:
            return self.max_removals
        return 100 if n <= LARGE else 25

    def reopt_window_for(self, n: int) -> int:
        """Half-width of an iteration's windowed re-opt for ``n`` clusters (default 0, the full
        re-opt, up to ``LARGE`` clusters; 4 above: there a full re-opt per local search round cost
        more than the rest of the iteration)."""
        if self.reopt_window is not None:
            return self.reopt_window
        return 0 if n <= LARGE else 4

    def path_share_for(self, n: int, symmetric: bool, timed: bool) -> float:
        """The share of the budget kept at the end for region re-solves of a cycle of ``n``
        clusters: above ``LARGE`` clusters on symmetric costs in a run with a time limit
        (``timed``) that does not :attr:`stop <stops>`, ``paths`` (by default ``PATHS``, and
        ``PATHS_ABOVE_FAIL_TO`` above ``FAIL_TO`` clusters), else 0. Above ``FAIL_TO`` no region
        re-solves run between the trials (:meth:`fail_passes_for`), and on the six files of
        2,000-3,023 clusters at 60 s (three seeds) the mean gap was 0.60 % with 0.3, 0.52 % with
        0.6, 0.47 and 0.52 % in two runs with 0.8, and 0.51 % with 1.0 (no trials after the first
        tour; ``docs/notes/2026-11-29-lns-longer-end-phase.md``); from 400 to 1,500 clusters 0.6
        was within the noise of 0.3 (``2026-11-30-lns-end-phase-share.md``)."""
        if not (n > LARGE and symmetric and timed and not self.stops):
            return 0.0
        if self.paths is not None:
            return self.paths
        return PATHS_ABOVE_FAIL_TO if n > FAIL_TO else PATHS

    def fail_passes_for(self, n: int, symmetric: bool) -> int:
        """Passes of region re-solves over the start of a trial that did not improve it, on a
        cycle of ``n`` clusters: ``fail_passes`` on symmetric costs (0 on directed ones: the
        regions are symmetric sub-problems), by default 1 from ``FAIL_FROM`` to ``FAIL_TO``
        clusters with effort ``budget``, else 0. On GLNS's 45 files (ten seeds) a pass took
        207si1032 to its best known for the first time and gained on four of the five files of 200
        clusters and more, and lost on the smaller 134gr666; on the large files at 60 s it gained
        on most files up to 1,480 clusters and lost on those of 2,000 and 2,811
        (``docs/notes/2026-11-28-fail-passes-from-200.md`` and
        ``2026-11-28-passes-to-1500-and-root-purge.md``)."""
        if not symmetric:
            return 0
        if self.fail_passes is not None:
            return self.fail_passes
        return 1 if FAIL_FROM <= n <= FAIL_TO and not self.stops else 0

    def kicks_for(self, n: int, symmetric: bool) -> int:
        """Double-bridge kicks of the start of a trial that did not improve it, on a cycle of
        ``n`` clusters: ``kicks``, by default ``KICKS`` with effort ``budget`` from ``FAIL_FROM``
        to ``LARGE`` clusters on symmetric costs and at every size on directed ones, else 0. On
        six large files of 235-464 clusters at 60 s (three seeds, both arms in one session)
        10,000 kicks lowered the mean gap from 0.300 to 0.214 %; at GLNS's shorter budgets below
        200 clusters they were within the noise on symmetric costs, and on GLNS's six directed
        files they took ``89rbg443`` from 32 to 49 runs of 60 at the best known, the other five
        at it in every run either way (``docs/notes/2026-11-30-lns-kicks.md``,
        ``2026-11-30-lns-kicks-default.md``, ``2026-11-30-lns-directed-kicks.md``)."""
        if self.kicks is not None:
            return self.kicks
        if self.stops:
            return 0
        return KICKS if not symmetric or FAIL_FROM <= n <= LARGE else 0

    def workers_for(self, timed: bool) -> int:
        """Threads searching a cycle of any size: ``workers`` (default
        :func:`~gtsp_bench.solvers.heuristics.lns_islands.default_workers`, 2 where two cores are
        free) in a run with a time limit (``timed``) that does not :attr:`stop <stops>`, else 1.
        On GLNS's 45 files at half of GLNS's time, one solve at a time on two cores, two threads
        at every size raised the runs at the best known from 401 to 417 of 450 (one thread up to
        ``LARGE`` clusters before; ``docs/notes/2026-11-29-lns-two-threads.md``)."""
        if not (timed and not self.stops):
            return 1
        return self.workers if self.workers is not None else default_workers()

    def mirror_for(self, symmetric: bool) -> bool:
        """Whether the second trial starts from the best tour reversed: ``mirror``, by default on
        asymmetric costs with effort ``budget`` (there a tour and its reversal can lie in separate
        basins, and the trials, which keep a tour's direction, do not cross from one to the other;
        on ``35ftv170`` the reversal of the 1,205 optimum is a trap at 1,247)."""
        if self.mirror is not None:
            return self.mirror
        return not symmetric and not self.stops

    def plateau_for(self) -> bool:
        """Whether a new tour that costs the same as the current one replaces it in a trial
        (``plateau``; by default with effort ``budget``)."""
        if self.plateau is not None:
            return self.plateau
        return not self.stops

    def regional_for(self, n: int) -> int:
        """Clusters a regional restart of a cycle of ``n`` clusters takes out (0: none, every
        restart is cold): ``regional`` times ``n``, by default 0 with every effort (0.3 with effort
        ``budget``, restarts alternating, improved the mean gap of the ``glns`` benchmark but gave
        a worse worst run; the rule of :func:`~.lns.restart_kind` was probed on four files only:
        ``docs/notes/2026-11-28-lns-regional-restart.md``)."""
        share = self.regional if self.regional is not None else 0.0
        return 0 if share <= 0.0 else max(1, min(n - 1, round(share * n)))

    def patience_for(self, n: int) -> int:
        """Iterations without a new trial best that end a trial (default ``max(50, 5 n)`` with
        ``stop_at_convergence``; else none: each trial cools over all its iterations, which on
        GTSPLIB's 87-217-cluster instances gave lower gaps within GLNS's budgets)."""
        if self.patience is not None:
            return self.patience
        return max(50, 5 * n) if self.stops else self.iterations_for(n)


__all__ = ["EFFORTS", "FAIL_FROM", "FAIL_TO", "KICKS", "LARGE", "PATHS", "PATHS_ABOVE_FAIL_TO",
           "Effort", "LnsSettings"]

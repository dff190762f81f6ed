"""A GLNS-class large neighbourhood search (after Smith and Imeson, Comput. Oper. Res. 87, 2017).

Each iteration removes some clusters from the current tour (**random**, **worst**, a **segment**,
or those nearest a random head: **distance**) and puts them back (the **cheapest**, **farthest**
or a **randomised** pick next, each at its cheapest edge and head, prices noisy every other
iteration), then runs the local search of :mod:`gtsp_bench.solvers.heuristics.lns_local`. The
inner loops are compiled with numba. Operators are drawn by roulette on adaptive weights; a new
tour replaces the current one by simulated-annealing acceptance, cooling over a trial. The first
trial starts from the greedy tour (or the warm start, the macro tour, or the best of a race of
``starts``) improved by the local search, later ones from the best tour so far; a trial that did
not improve it makes the next one hotter, and after ``restart_after`` such trials the next starts
cold from a random-insertion tour (with ``regional``, a restart after a chain that improved the
best tour starts from it with the region around its dearest cluster re-planned); on asymmetric
costs the second trial of a ``budget`` run starts
from the best tour reversed (``mirror``). Above ``LARGE`` clusters the windowed re-opt and sampled
removals of :mod:`gtsp_bench.solvers.heuristics.lns_window`, quadrant neighbour lists, edge costs
from the coordinates (:mod:`gtsp_bench.solvers.heuristics.lns_costs`) and region re-solves at the
end (:mod:`gtsp_bench.solvers.heuristics.lns_paths`) apply; a ``budget`` run takes two threads
where two cores are free (:mod:`gtsp_bench.solvers.heuristics.lns_islands`).
``docs/solvers/heuristics.md`` (lns) describes every option and the measurements behind the
defaults.

The search has converged after ``trials`` trials. How it ends is its ``effort``
(:mod:`gtsp_bench.solvers.heuristics.lns_settings`): ``fast``, ``default`` and ``slow`` stop
there, the time limit only a cap; ``budget`` goes on with more trials until the time limit
(status ``feasible``) and fits its trials to it (``fit_to_time``, ``fit_trials``). A run that
converges is reproducible for a seed; one cut by the time limit before it converged has status
``time_limit``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from gtsp_bench.solvers.heuristics import lns_kernels as kernels
from gtsp_bench.solvers.heuristics.greedy import greedy_tour
from gtsp_bench.solvers.heuristics.lns_costs import cluster_arrays, kernel_costs, points_of
from gtsp_bench.solvers.heuristics.lns_islands import run_islands
from gtsp_bench.solvers.heuristics.lns_macro import (
    centre_groups,
    centre_order,
    cluster_centres,
    macro_tour,
)
from gtsp_bench.solvers.heuristics.lns_paths import Regions, region_passes, shared_region_passes
from gtsp_bench.solvers.heuristics.lns_settings import EFFORTS, LARGE, Effort, LnsSettings
from gtsp_bench.solvers.heuristics.local_search import anchor_node, deadline_after, is_past

from gtsp_bench.instance import Instance
from gtsp_bench.problem import Problem, price
from gtsp_bench.solver import Progress, Solution, no_progress

__all__ = ["EFFORTS", "LARGE", "Effort", "Lns", "LnsSettings"]

REMOVALS, INSERTIONS, REL_TOL = kernels.REMOVALS, kernels.INSERTIONS, kernels.REL_TOL
#: A trial that does not improve the best tour doubles the next one's temperatures, up to this factor.
MAX_HEAT = 8.0
#: With ``fit_trials``, a trial still runs at least this many iterations per cluster (up to
#: ``LARGE`` clusters; above, its whole ``iterations``: there an annealing run of 10 iterations per
#: cluster ended about where it began, and longer ones went further).
FIT_FLOOR = 10
#: Seconds between two looks at the clock (the compiled trial runs in chunks about this long).
CHUNK_SECONDS = 0.01
#: Iterations of a raced start's short trial between two looks at the clock.
RACE_CHUNK = 200
#: Double-bridge kicks per call of their kernel (a look at the clock after each call).
KICK_CHUNK = 64


@dataclass
class _Run:
    """Mutable state of one search's trials: its best tour, operator weights and counts."""

    best: np.ndarray
    best_cost: float
    weights_r: np.ndarray
    weights_i: np.ndarray
    clock0: float  #: when its iterations began (their rate is measured from here)
    done: int = 0  #: iterations done
    best_at: int = 0  #: the iteration that found the best tour
    trials: int = 0
    converged: bool = False
    timed_out: bool = False
    windows: int = 0  #: regions re-solved (``paths``, ``fail_passes``)
    window_saving: float = 0.0


def restart_kind(regional: int, restarts: int, won: bool) -> str:
    """The kind of a restart: ``"regional"`` (re-plan a region of the best tour) when ``regional``
    is on, the run has restarted before and the chain that ends ``won`` (improved the run's best
    tour); else ``"random"`` (cold, from a random-insertion tour). A run whose chains stop
    improving its best restarts cold every time, so that one trapped in a basin can leave it."""
    return "regional" if regional and restarts > 0 and won else "random"


class _Search:
    """State of one LNS run on a priced problem."""

    def __init__(self, problem: Problem, settings: LnsSettings, rng: np.random.Generator,
                 initial: np.ndarray | None = None, progress: Progress = no_progress) -> None:
        self.p = problem
        self.s = settings
        self.rng = rng
        self.initial = initial  #: a warm start's tour (node ids), the first tour
        self.progress = progress  #: told each better tour's cost
        self.edge = kernel_costs(problem, settings.points)
        self.node, self.start, self.cluster_of = cluster_arrays(problem)
        self.symmetric = bool(problem.symmetric)
        n = problem.n_clusters
        count = settings.neighbours_for(n, self.symmetric)
        wants = settings.quadrants_for(n) or settings.macro or settings.starts > 1
        points = points_of(problem) if wants else None
        #: Each cluster's centre on a planar instance (for the quadrants or the macro tour).
        self.centre = None if points is None else cluster_centres(points[0], self.start)
        if points is None or not settings.quadrants_for(n):
            self.near = kernels.neighbours(self.edge, self.start, count)
        else:
            self.near = kernels.neighbours(self.edge, self.start, count, self.centre)
        self.max_remove = max(1, min(n - 2, settings.max_removals_for(n),
                                     math.ceil(settings.remove_fraction * n)))
        #: Passes of region re-solves after a failed trial (``fail_passes``; 0 on directed costs).
        self.fail_passes = settings.fail_passes_for(n, self.symmetric)
        #: Double-bridge kicks after a failed trial (``kicks``).
        self.kicks = settings.kicks_for(n, self.symmetric)
        #: The regions of the end phase (above ``LARGE`` clusters) and of ``fail_passes``:
        #: symmetric costs only (:meth:`polish`); none where neither can run.
        wanted = self.symmetric and (n > LARGE or self.fail_passes > 0)
        self.regions = Regions(self.near, self.centre) if wanted else None

    def local_search(self, t: np.ndarray) -> tuple[np.ndarray, float]:
        t = np.array(t, dtype=np.int64)
        tol = REL_TOL * max(1.0, abs(kernels.tour_cost(t, self.edge, self.node)))
        cost = kernels.local_search(t, self.edge, self.node, self.start, self.near, self.cluster_of, tol,
                                    np.ones(self.p.n_clusters, dtype=np.bool_), self.symmetric)
        return t, cost

    def start_tour(self, kind: str, deadline: float | None) -> np.ndarray:
        """A first tour before the local search: ``"macro"``, the macro tour on a planar instance
        (:mod:`gtsp_bench.solvers.heuristics.lns_macro`; elsewhere the greedy tour); ``"random"``,
        a random-insertion tour (the cold restarts' start); ``"initial"``, the warm start; else the
        greedy tour."""
        n = self.p.n_clusters
        if kind == "initial" and self.initial is not None:
            return self.initial.copy()
        if kind == "random":
            return kernels.random_insertion_tour(self.edge, self.node, self.start, self.near,
                                                 self.cluster_of)
        if kind != "macro" or self.centre is None or n < 5:
            return greedy_tour(self.p, anchor_node(self.p))
        groups = centre_groups(self.centre, self.s.macro_groups) if self.s.macro_groups else None
        order = centre_order(self.centre, self.s.macro_iterations * n, LARGE, deadline, groups)
        return macro_tour(order, self.edge, self.node, self.start, self.cluster_of)

    def start_kinds(self) -> list[str]:
        """The first tours to race (:meth:`race`): the first ``starts`` of the warm start (if
        any), greedy, macro (planar instances only), then random-insertion tours."""
        kinds = ["initial"] if self.initial is not None else []
        kinds += ["greedy"] + (["macro"] if self.centre is not None else [])
        return (kinds + ["random"] * self.s.starts)[: self.s.starts]

    def trial_settings(self, cur: np.ndarray, heat: float, iterations: int,
                       patience: int) -> np.ndarray:
        """:func:`run_trial`'s settings for a trial from ``cur``: temperatures and noise scaled by
        the mean edge of ``cur`` times ``heat``."""
        s = self.s
        mean_edge = float(np.mean(self.p.edge_costs(cur, np.roll(cur, -1)))) * heat
        return kernels.trial_settings(iterations, patience, s.hottest * mean_edge,
                                      s.end_temperature * mean_edge, self.max_remove,
                                      s.noise * mean_edge, s.reaction,
                                      s.reopt_window_for(self.p.n_clusters), s.plateau_for())

    def race(self, kinds: list[str], deadline: float | None
             ) -> tuple[np.ndarray, float, np.ndarray, np.ndarray, int]:
        """Each first tour of ``kinds`` improved by the local search, then one short trial from it
        (``start_iterations`` per cluster, annealed over the usual temperatures); returns the
        cheapest trial's best tour, its cost, that trial's operator weights and the iterations
        done. A deadline that passes ends the race (after at least the first start's local
        search)."""
        length = max(100, self.s.start_iterations * self.p.n_clusters)
        won: tuple[np.ndarray, float, np.ndarray, np.ndarray] | None = None
        done = 0
        for kind in kinds:
            if won is not None and is_past(deadline):
                break
            t, cost = self.local_search(self.start_tour(kind, deadline))
            best, best_cost, weights_r, weights_i, count = kernels.one_trial(
                t, cost, self.trial_settings(t, 1.0, length, length), RACE_CHUNK, self.edge,
                self.node, self.start, self.near, self.cluster_of, self.symmetric, deadline)
            done += count
            if won is None or best_cost < won[1] - REL_TOL * abs(won[1]):
                won = (best, best_cost, weights_r, weights_i)
        assert won is not None
        return (*won, done)

    def first(self, deadline: float | None, kind: str | None = None) -> _Run:
        """The state before the trials: the first tour improved by the local search (``kind``,
        default the race of ``starts`` or the greedy/``macro`` start)."""
        s = self.s
        weights_r, weights_i = np.ones(len(REMOVALS)), np.ones(len(INSERTIONS))
        kinds, done = self.start_kinds(), 0
        if kind is None and len(kinds) > 1 and self.p.n_clusters >= 4:
            clock0 = time.perf_counter()  # the race counts in the rate of iterations
            best, best_cost, weights_r, weights_i, done = self.race(kinds, deadline)
        else:  # up to 3 clusters the re-opt solves it
            kind = kind or ("initial" if self.initial is not None else "macro" if s.macro else "greedy")
            best, best_cost = self.local_search(self.start_tour(kind, deadline))
            clock0 = time.perf_counter()
        self.progress(best_cost)
        return _Run(best, best_cost, weights_r, weights_i, clock0, done, best_at=done)

    def trials(self, run: _Run, deadline: float | None, rng: np.random.Generator) -> None:
        """Trials from ``run``'s best tour until converged (an effort that :attr:`stops
        <LnsSettings.stops>`) or the deadline, updating ``run`` in place."""
        p, s = self.p, self.s
        n = p.n_clusters
        iterations, patience = s.iterations_for(n), s.patience_for(n)
        floor = FIT_FLOOR * n if n <= LARGE else iterations  # a fitted trial's least length
        # A cycle of at most 3 clusters is fixed by its heads: re-opt solved it, nothing to search.
        run.converged = run.converged or n < 4
        exact = n < 4
        steps, heat = 1, 1.0
        # Trials restart from the base: the best tour, or after a cold restart that run's best.
        base, base_cost, fails = run.best.copy(), run.best_cost, 0
        cold = s.cold_after > 0 and (s.stops or deadline is not None)
        fit = s.fit_to_time and not s.stops and deadline is not None
        # The second trial runs from the best tour reversed (asymmetric costs: trials keep a tour's
        # direction, and each direction can be its own basin); then the trials go on as before.
        mirror = s.mirror_for(self.symmetric) and not exact
        regional = s.regional_for(n)  # clusters a regional restart re-plans
        restarts, mark = 0, run.best_cost  # restarts so far; the best when the last one came
        saved: tuple[np.ndarray, float, float, int] | None = None  # the base the mirror set aside
        while not exact and not (run.converged and (s.stops or deadline is None)):
            if is_past(deadline):
                run.timed_out = True
                break
            if cold and fails >= s.cold_after:
                kind = restart_kind(regional, restarts, run.best_cost < mark)
                restarts, mark = restarts + 1, run.best_cost
                fresh = kernels.regional_tour(run.best, regional, self.edge, self.node, self.start,
                                              self.near, self.cluster_of, self.symmetric) \
                    if kind == "regional" else self.start_tour("random", deadline)
                base, base_cost = self.local_search(fresh)
                heat, fails = 1.0, 0
                self.offer(run, base, base_cost)
            elif mirror and run.trials == 1:
                saved, mirror = (base, base_cost, heat, fails), False
                base, base_cost = self.local_search(run.best[::-1])
                heat = 1.0
                self.offer(run, base, base_cost)
            cur, trial_best = base.copy(), base.copy()
            settings = self.trial_settings(cur, heat, iterations, patience)
            costs = np.array([base_cost, run.best_cost, base_cost])
            counts = np.array([0, 0, run.done, run.best_at], dtype=np.int64)
            while True:
                if deadline is None:
                    steps = iterations
                tick = time.perf_counter()
                ended = kernels.run_trial(cur, run.best, trial_best, costs, counts, run.weights_r,
                                          run.weights_i, settings, steps, self.edge, self.node,
                                          self.start, self.near, self.cluster_of, self.symmetric)
                spent = time.perf_counter() - tick
                if spent < CHUNK_SECONDS / 2 and not ended:
                    steps = min(2 * steps, iterations)
                elif spent > 2 * CHUNK_SECONDS:
                    steps = max(1, steps // 2)
                if costs[1] < run.best_cost:
                    self.progress(float(costs[1]))
                run.best_cost, run.done, run.best_at = float(costs[1]), int(counts[2]), int(counts[3])
                if fit and not ended and run.done > 0:
                    # The trial ends with the budget, cooled, when it cannot run all its iterations:
                    # its length is the iterations the rate so far leaves time for (at most its own).
                    # And at least fit_trials trials fit in the budget (short budgets: more, shorter
                    # trials, so that cold restarts come in time).
                    now = time.perf_counter()
                    rate = run.done / max(now - run.clock0, 1e-9)
                    left = rate * max(0.0, deadline - now)
                    share = max(floor, rate * (deadline - run.clock0) / s.fit_trials)
                    settings[0] = min(iterations, max(counts[0] + 1, int(min(counts[0] + left, share))))
                    ended = counts[0] >= settings[0]
                if ended:
                    break
                if is_past(deadline):
                    run.timed_out = True
                    break
            if run.timed_out:
                break
            run.trials += 1
            if saved is not None:  # the mirror trial: its tour is the base only if it beat the old one
                old_cost = saved[1]
                if costs[2] < old_cost - REL_TOL * abs(old_cost):
                    base, base_cost, heat, fails = trial_best.copy(), float(costs[2]), 1.0, 0
                else:
                    base, base_cost, heat, fails = saved
                saved = None
            # A trial that did not improve its base: the next one starts hotter (and after
            # restart_after of them, from a fresh tour).
            elif costs[2] < base_cost - REL_TOL * abs(base_cost):
                base, base_cost, heat, fails = trial_best.copy(), float(costs[2]), 1.0, 0
            else:
                heat, fails = min(MAX_HEAT, 2 * heat), fails + 1
                if self.kicks:  # double-bridge kicks of the base
                    base_cost = self.kick(base, base_cost, self.kicks, deadline)
                    self.offer(run, base, base_cost)
                if self.fail_passes and self.regions is not None:  # re-solve the base's regions
                    gain = self.polish(run, base, deadline, [rng], self.fail_passes,
                                       temperature=s.fail_temperature)
                    if gain > 0.0:
                        base_cost = p.tour_cost(base)
                        self.offer(run, base, base_cost)
            run.converged = run.converged or run.trials >= s.trial_count

    def offer(self, run: _Run, tour: np.ndarray, cost: float) -> None:
        """A copy of ``tour`` (of cost ``cost``) becomes ``run``'s best, reported to
        ``progress``, when it is cheaper beyond the tolerance."""
        if cost < run.best_cost - REL_TOL * abs(run.best_cost):
            run.best, run.best_cost = tour.copy(), cost
            self.progress(cost)

    def kick(self, tour: np.ndarray, cost: float, count: int, deadline: float | None) -> float:
        """``count`` double-bridge kicks of ``tour`` (changed in place), each followed by the
        local search, a kicked tour kept when it costs no more
        (:func:`~gtsp_bench.solvers.heuristics.lns_local.kick_search`), in chunks until
        ``deadline``; returns the tour's cost."""
        tol = REL_TOL * max(1.0, abs(cost))
        while count > 0 and not is_past(deadline):
            chunk = min(count, KICK_CHUNK)
            cost = kernels.kick_search(tour, cost, chunk, self.edge, self.node, self.start,
                                       self.near, self.cluster_of, tol, self.symmetric)
            count -= chunk
        return cost

    def polish(self, run: _Run, tour: np.ndarray, deadline: float | None,
               rngs: list[np.random.Generator], passes: int | None = None, *,
               temperature: float) -> float:
        """Region re-solves of ``tour`` (changed in place; ``path_clusters`` clusters each) until
        ``deadline`` or ``passes`` passes, by one thread per generator of ``rngs``
        (:func:`~gtsp_bench.solvers.heuristics.lns_paths.region_passes`; several, until
        ``deadline`` only: :func:`~gtsp_bench.solvers.heuristics.lns_paths.shared_region_passes`),
        each region's annealing trial starting at ``temperature`` times its paths' mean edge,
        counted in ``run``'s stats; returns the saving."""
        assert self.regions is not None
        size, iterations = self.s.path_clusters, self.s.path_iterations
        if len(rngs) == 1:
            saved, count = region_passes(self.p, tour, self.regions, size, iterations, deadline,
                                         rngs[0], passes, self.progress, temperature)
        else:
            assert deadline is not None and passes is None
            saved, count = shared_region_passes(self.p, tour, self.regions, size, iterations,
                                                deadline, rngs, self.progress, temperature)
        run.windows, run.window_saving = run.windows + count, run.window_saving + saved
        return saved

    def finish(self, run: _Run, deadline: float, rngs: list[np.random.Generator]) -> None:
        """The end phase (``paths``): region re-solves of ``run``'s best tour until ``deadline``,
        by one thread per generator of ``rngs`` (:meth:`polish`), their trials starting at
        ``path_temperature`` (the re-solves after a failed trial at ``fail_temperature``)."""
        self.polish(run, run.best, deadline, rngs, temperature=self.s.path_temperature)
        run.best_cost = self.p.tour_cost(run.best)
        self.progress(run.best_cost)

    def run(self, deadline: float | None) -> tuple[np.ndarray, float, dict, bool]:
        """Search until converged (an effort that stops) or the deadline; returns (tour, cost,
        stats, whether the deadline came before convergence)."""
        p, s = self.p, self.s
        kernels.seed(int(self.rng.integers(2**31 - 1)))
        final = deadline
        timed = deadline is not None
        tail = s.path_share_for(p.n_clusters, self.symmetric, timed)
        if tail > 0.0:  # the trials stop early; the rest of the budget re-solves regions
            clock0 = time.perf_counter()
            deadline = clock0 + (1.0 - tail) * max(0.0, deadline - clock0)
        workers = s.workers_for(timed)
        islands: list[float] = []
        if workers > 1:  # every thread re-solves regions of the best island's tour at the end
            run, islands = run_islands(self, workers, deadline, final if tail > 0.0 else None)
        else:
            run = self.first(deadline)
            self.trials(run, deadline, self.rng)
            if tail > 0.0:
                self.finish(run, final, [self.rng])
        weights = dict(zip(REMOVALS, run.weights_r, strict=True))
        weights.update(zip(INSERTIONS, run.weights_i, strict=True))
        stats = {"iterations": run.done, "trials": run.trials, "best_at": run.best_at,
                 "converged": run.converged,
                 "weights": {k: round(float(w), 3) for k, w in weights.items()}}
        if workers > 1:
            stats.update(workers=workers, island_costs=[round(c, 6) for c in islands])
        if run.windows:
            stats.update(windows=run.windows, window_saving=round(run.window_saving, 6))
        return run.best, run.best_cost, stats, run.timed_out and not run.converged


class Lns:
    """GLNS-style large neighbourhood search, compiled inner loops (module docstring).

    Asymmetric costs are priced in their direction (no 2-opt there). Each option is a field of
    :class:`LnsSettings`; ``docs/solvers/heuristics.md`` (lns) gives the details and measurements.

    Warm start (``initial``): the first trial starts from that tour, improved by the local search
    (with ``starts``, it is the first tour raced; with two threads, the first island's). A warm
    start whose claimed lower bound meets its objective is returned at once, unchanged: nothing
    can improve it. Each better tour is reported to ``progress``.

    Parameters
    ----------
    effort
        When the search ends (:data:`~gtsp_bench.solvers.heuristics.lns_settings.EFFORTS`):
        ``fast``, ``default`` (the default) or ``slow`` stop after their trials, the time limit a
        cap; ``budget`` uses the whole time limit.
    iterations, trials, patience
        Iterations per trial (default ``max(100, 25 n)``, n = clusters incl. the depot's); trials
        until the search counts as converged (default: the effort's); iterations without a new
        trial best that end a trial (default ``max(50, 5 n)`` when the search stops, else none).
    remove_fraction, max_removals
        At most this share of the clusters, in (0, 1], and at most this many (>= 1; default 100,
        or 25 above ``LARGE`` clusters) are removed per iteration.
    start_temperature, end_temperature
        Annealing temperatures as multiples of the tour's mean edge cost (>= 0; defaults 0.3 when
        the search stops, 1.0 with ``budget``, and 0.003).
    reaction, noise
        Weight of the newest score in an operator's weight, in (0, 1]; noisy insertions add up
        to ``noise`` times the mean edge cost to each price (>= 0).
    neighbours
        Moves join a cluster only to its nearest clusters (default 10; all on asymmetric costs).
    stop_at_convergence
        ``true``: effort ``fast``; ``false``: effort ``budget`` (not with ``effort``).
    restart_after
        Trials in a row without improvement before a cold restart (0: never; default: the
        effort's).
    reopt_window
        An iteration re-opts only the heads within this many positions of a change (>= 0; default
        0 = the full re-opt up to ``LARGE`` clusters, 4 above).
    fit_to_time, fit_trials
        With effort ``budget``, trials end, cooled, at the limit and are short enough
        for ``fit_trials`` (>= 1, default 32) to fit (at least ``FIT_FLOOR`` iterations per cluster).
    points, quadrants
        Edge costs from the coordinates, not the matrix (the same numbers; default from 2,000
        nodes up on a planar rule); neighbour lists by quadrant around a cluster's centre
        (planar instances; default above ``LARGE`` clusters).
    macro, macro_iterations, macro_groups
        The first trial starts from the macro tour (planar instances; default off): the clusters
        in the order of a short tour through their centres (an annealing trial of
        ``macro_iterations`` per cluster, >= 0), entering each group of centres at most
        ``macro_groups`` (>= 0, default 5; 0: no groups) median nearest-centre distances apart
        once, with optimal heads (:mod:`gtsp_bench.solvers.heuristics.lns_macro`).
    starts, start_iterations
        First tours raced (>= 1; default 1, no race): greedy, macro (planar instances), then
        random insertion, each improved by the local search and one short trial of
        ``start_iterations`` (>= 1) iterations per cluster; the trials start from the best.
    paths, path_clusters, path_iterations, path_temperature
        Share of the time limit, in [0, 1] (default 0.3, and 0.8 above ``FAIL_TO`` clusters:
        :meth:`LnsSettings.path_share_for`), kept for region re-solves of the best
        tour at the end (above ``LARGE`` clusters, symmetric costs, timed, effort ``budget``): the
        ``path_clusters`` (>= 2, default 80) clusters nearest a
        random one, the tour's paths through them re-solved as a small GTSP with
        ``path_iterations`` (>= 0, default 5) iterations per cluster, in the end phase an annealing
        trial that starts at ``path_temperature`` (>= 0.003, where it ends; default 3.0) times the
        paths' mean edge (:mod:`gtsp_bench.solvers.heuristics.lns_paths`).
    fail_passes, fail_temperature
        Passes of region re-solves over the start of each trial that did not improve it
        (symmetric costs, any size; >= 0; default 1 from ``FAIL_FROM`` (200) to ``FAIL_TO``
        (1,500) clusters with effort ``budget``, else 0: :meth:`LnsSettings.fail_passes_for`),
        their trials starting at ``fail_temperature`` (>= 0.003; default 3.0) times the paths'
        mean edge.
    workers, exchange
        Threads of a timed search with effort ``budget`` (>= 1; default
        :func:`~gtsp_bench.solvers.heuristics.lns_islands.default_workers`), run as
        islands that go on from the best island's tour after the ``exchange`` share of the
        trials' time (in [0, 1], default 0.5; 1: never;
        :mod:`gtsp_bench.solvers.heuristics.lns_islands`); in the end phase (``paths``) all
        re-solve regions of the best island's tour.
    mirror
        The second trial starts from the best tour reversed, and its tour replaces the base only
        if it beat it (default: on asymmetric costs with effort ``budget``; a tour's direction can
        be a basin of its own there).
    plateau
        A new tour that costs the same as the current one replaces it in a trial (annealing's
        ``exp(0) = 1``; default: with effort ``budget``, where on integer costs with many ties,
        such as ``89rbg443``'s, the search can then drift along a plateau; else it is rejected,
        as before).
    regional
        A restart after a chain that improved the best tour (not the first restart) is regional,
        not cold (in [0, 1]; 0: every restart cold; :func:`restart_kind`): from the best tour, the
        cluster with the largest removal saving and the clusters whose heads are nearest it, this
        share of all, are taken out and put back by random insertion
        (:func:`~gtsp_bench.solvers.heuristics.lns_kernels.regional_tour`), then the local search
        and trials as after a cold restart (default 0, off; the notes measure 0.3).
    kicks
        Double-bridge kicks of the start of each trial that did not improve it, each followed by
        the local search and kept when no dearer (>= 0; an iterated local search between the
        trials, :func:`~gtsp_bench.solvers.heuristics.lns_local.kick_search`; default 10,000 with
        effort ``budget`` from 200 to 400 clusters on symmetric costs and at every size on
        directed ones, else 0: :meth:`LnsSettings.kicks_for`).
    """

    asymmetric = True
    capped = True  #: given no time limit, run_solver gives it the default one

    def __init__(
        self, effort: str | None = None, iterations: int | None = None, trials: int | None = None,
        patience: int | None = None,
        remove_fraction: float = 0.3, max_removals: int | None = None, start_temperature: float | None = None,
        end_temperature: float = 0.003, reaction: float = 0.1, noise: float = 0.1,
        neighbours: int | None = None, stop_at_convergence: bool | None = None,
        restart_after: int | None = None,
        reopt_window: int | None = None, fit_to_time: bool = True, fit_trials: int = 32,
        points: bool | None = None, quadrants: bool | None = None, macro: bool = False,
        macro_iterations: int = 5, macro_groups: float = 5.0, starts: int = 1,
        start_iterations: int = 5,
        paths: float | None = None, path_clusters: int = 80, path_iterations: int = 5,
        path_temperature: float = 3.0,
        fail_passes: int | None = None, fail_temperature: float = 3.0,
        workers: int | None = None, exchange: float = 0.5, mirror: bool | None = None,
        plateau: bool | None = None, regional: float | None = None, kicks: int | None = None,
    ) -> None:
        self.settings = LnsSettings(iterations, trials, patience, remove_fraction, max_removals,
                                    start_temperature, end_temperature, reaction, noise,
                                    neighbours, stop_at_convergence, restart_after, reopt_window,
                                    fit_to_time, fit_trials, points, quadrants, macro,
                                    macro_iterations, macro_groups, starts, start_iterations, paths,
                                    path_clusters, path_iterations, path_temperature,
                                    fail_passes, fail_temperature, workers,
                                    exchange, effort, mirror, plateau, regional, kicks)
        kernels.warm_up()  # compiled or loaded here (a worker's start-up), not in a solve's clock

    def solve(
        self, instance: Instance, omega: float | None, *, time_limit: float | None = None,
        seed: int = 0, initial: Solution | None = None, progress: Progress = no_progress,
    ) -> Solution:
        """Search until its effort ends it or the time limit, from the warm start ``initial`` if
        given (class docstring), reporting each better tour.

        Without a time limit (``None``; :func:`gtsp_bench.registry.run_solver` gives the default
        one) every effort stops after its trials. The status is ``time_limit`` only when the
        limit came before the search converged.
        """
        deadline = deadline_after(time_limit)
        if initial is not None and initial.lower_bound is not None and \
                initial.objective - initial.lower_bound <= REL_TOL * max(1.0, abs(initial.objective)):
            progress(initial.objective)
            return Solution(initial.order, initial.heads, initial.objective,
                            stats={"warm_start": "at its lower bound"})
        problem = price(instance, omega)
        start = None if initial is None else problem.to_tour(initial.order, initial.heads)
        search = _Search(problem, self.settings, np.random.default_rng(seed), start, progress)
        tour, _, stats, timed_out = search.run(deadline)
        if initial is not None:
            stats["warm_start"] = True
        order, heads = problem.to_solution(tour)
        return Solution(order, heads, objective=problem.tour_cost(tour),
                        status="time_limit" if timed_out else "feasible", stats=stats)

"""Labels of the local policy's imitation training: instance sets, their ``lns`` tours, and a
cache that keeps both between runs.

A label set is a mix entry ``(K, count, area)`` (the UAV generator's squares, omega of instance i
drawn from ``[label_seed, K, i]``) or ``(K, count, area, "tiled")`` (:mod:`~.tiled`, omega 0).
Every instance is solved by ``lns`` with ``stop_at_convergence`` (seed i for instance i), in
forked worker processes when asked: the same labels either way. The validation sets (seed
:data:`VAL_SEED`, omega 0.3 and 0.6 in turn) are priced the same way. Both go into one ``.npz``
cache, a key per set, so a second run with the same mix solves nothing.
"""

from __future__ import annotations

import io
import multiprocessing
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Protocol

import numpy as np
from gtsp_bench.solvers.learned.tiled import tiled_set

from gtsp_bench.data.io import atomic_write_bytes
from gtsp_bench.generator import instance_set

#: Seeds of the validation set (never used for training or testing).
VAL_SEED = 818_273

#: A label set: ``(K, instances, area)`` (the UAV generator's squares) or ``(K, instances, area,
#: "tiled")`` (:mod:`~.tiled`; its area is ignored).
Entry = tuple[int, int, float] | tuple[int, int, float, str]


def parse_entry(e: Entry) -> tuple[int, int, float, bool]:
    """K, instances, area and whether tiled, of a label-set entry."""
    return int(e[0]), int(e[1]), float(e[2]), len(e) > 3 and e[3] == "tiled"  # type: ignore[misc]


class LabelConfig(Protocol):
    """What labelling reads of a run's settings (:class:`~.imitation.ImitationConfig` has it)."""

    @property
    def mix(self) -> Sequence[Entry]: ...
    @property
    def val(self) -> Sequence[Entry]: ...
    @property
    def nodes(self) -> int: ...
    @property
    def omega_max(self) -> float: ...
    @property
    def label_seed(self) -> int: ...


def fork_pool(workers: int, warm: bool = False) -> Any:
    """A ``fork`` pool of ``workers`` processes (``None`` for one: work in this process). With
    ``warm``, lns's kernels are compiled here first (once), so that the workers inherit them."""
    if workers <= 1:
        return None
    global _WARM
    if warm and not _WARM:
        from gtsp_bench.registry import get_solver

        inst = instance_set(1, 5, 1, 20)[0]
        get_solver("lns", stop_at_convergence=True).solve(inst, 0.5, time_limit=10.0, seed=0)
        _WARM = True
    return multiprocessing.get_context("fork").Pool(workers)


_WARM = False


def label_set(k: int, count: int, area: float, seed: int, nodes: int, omega_max: float,
              tiled: bool = False) -> tuple[list[Any], np.ndarray]:
    """Instances and omegas of one label set (omega of instance i from ``[seed, K, i]``; 0 for
    a tiled set)."""
    if tiled:
        return tiled_set(count, k, seed), np.zeros(count)
    insts = instance_set(count, k, seed, nodes, area=area)
    omegas = np.array([np.random.default_rng([seed, k, i, 7]).uniform(0.0, omega_max)
                       for i in range(count)])
    return insts, omegas


#: The instances and omegas being labelled (set before a pool forks: instances don't pickle).
_JOBS: tuple[Sequence[Any], Sequence[float]] = ((), ())


def _solve_one(i: int) -> tuple[tuple[int, ...], float]:
    """Label ``i`` of :data:`_JOBS`: ``lns`` (stop at convergence, seed ``i``)."""
    from gtsp_bench.energy import evaluate
    from gtsp_bench.registry import get_solver

    inst, w = _JOBS[0][i], float(_JOBS[1][i])
    sol = get_solver("lns", stop_at_convergence=True).solve(inst, w, time_limit=120.0, seed=i)
    return sol.order, evaluate(inst, w, sol.order, sol.heads).objective


def solve_labels(insts: Sequence[Any], omegas: Sequence[float], say: Any = None,
                 workers: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Orders ``(n, K)`` and objectives ``(n,)`` of ``lns`` (stop at convergence) on each, in
    ``workers`` forked processes when more than one: the same labels either way."""
    global _JOBS
    _JOBS = (insts, omegas)
    pool = fork_pool(workers, warm=True)
    run = pool.imap(_solve_one, range(len(insts)), chunksize=2) if pool else map(
        _solve_one, range(len(insts)))
    orders, values = [], []
    for i, (order, value) in enumerate(run):
        orders.append(order)
        values.append(value)
        if say is not None and (i + 1) % 100 == 0:
            say(f"labels K={insts[i].n_clusters}: {i + 1}/{len(insts)}")
    if pool is not None:
        pool.close()
        pool.join()
    _JOBS = ((), ())
    return np.array(orders, dtype=np.int64), np.array(values)


def validation_set(e: Entry, nodes: int) -> tuple[list[Any], list[float]]:
    """Instances and omegas of a validation entry (seed :data:`VAL_SEED`; omega 0.3 and 0.6 in
    turn, 0 for a tiled set)."""
    k, n, area, tiled = parse_entry(e)
    insts = label_set(k, n, area, VAL_SEED, nodes, 0.0, tiled)[0]
    return insts, [0.0 if tiled else 0.3 if i % 2 == 0 else 0.6 for i in range(n)]


def load_or_solve_labels(cfg: LabelConfig, cache: Path | None, say: Any = None,
                         workers: int = 1,
                         ) -> tuple[dict[Entry, np.ndarray], dict[Entry, np.ndarray], float]:
    """Label orders per mix entry and the reference values of each validation entry (``lns``'s,
    as the labels'), from ``cache`` when it holds them (the references under ``val_...`` keys);
    returns both and the seconds spent solving new ones (added to the cache)."""
    stored: dict[str, np.ndarray] = {}
    if cache is not None and cache.is_file():
        with np.load(cache) as f:
            stored = {key: f[key] for key in f.files}
    out: dict[Entry, np.ndarray] = {}
    refs: dict[Entry, np.ndarray] = {}
    spent = 0.0
    jobs = [(e, False) for e in cfg.mix] + [(e, True) for e in cfg.val]
    for e, is_val in jobs:
        k, n, area, tiled = parse_entry(e)
        if is_val:  # seed VAL_SEED, omegas 0.3 / 0.6 (or 0), not omega_max's
            key = f"val_K{k}_n{n}_tiled" if tiled else f"val_K{k}_n{n}_a{area:g}_N{cfg.nodes}"
        else:
            key = (f"K{k}_n{n}_tiled_s{cfg.label_seed}" if tiled else
                   f"K{k}_n{n}_a{area:g}_s{cfg.label_seed}_w{cfg.omega_max:g}_N{cfg.nodes}")
        if key not in stored:
            t = time.perf_counter()
            insts, omegas = (validation_set(e, cfg.nodes) if is_val else label_set(
                k, n, area, cfg.label_seed, cfg.nodes, cfg.omega_max, tiled))
            orders, values = solve_labels(insts, omegas, say, workers)
            stored[key] = values if is_val else orders
            spent += time.perf_counter() - t
            if cache is not None:
                buf = io.BytesIO()
                np.savez_compressed(buf, **stored)
                atomic_write_bytes(cache, buf.getvalue())
        (refs if is_val else out)[e] = stored[key]
    return out, refs, spent

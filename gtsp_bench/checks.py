"""Solver options: validation (a bad value raises :class:`InputError` naming the option) and
the default time limit of the search solvers."""

from __future__ import annotations

import math

import numpy as np

from gtsp_bench.errors import InputError

#: Time limit of the search solvers when none is given: seconds per cluster, and the cap.
SECONDS_PER_CLUSTER, MAX_DEFAULT_SECONDS = 0.5, 60.0


def default_time_limit(n_clusters: int) -> float:
    """The time limit used when none is given: ``0.5 s * K``, at least 1 s, at most 60 s."""
    return min(MAX_DEFAULT_SECONDS, max(1.0, SECONDS_PER_CLUSTER * n_clusters))


def check_int(name: str, value: object, low: int) -> int:
    """``value`` as an int if it is an integer >= ``low``, else :class:`InputError`."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
        raise InputError(f"{name} must be an integer >= {low}, got {value!r}")
    return int(value)


def check_float(name: str, value: object, low: float, high: float, *, open_low: bool = True) -> float:
    """``value`` as a float if it is a finite number in ``(low, high]`` (``[low, high]`` when
    not ``open_low``; ``high = inf``: no upper bound), else :class:`InputError`."""
    ok = not isinstance(value, bool) and isinstance(value, (int, float, np.integer, np.floating))
    if ok:
        v = float(value)  # type: ignore[arg-type]
        ok = math.isfinite(v) and (v > low if open_low else v >= low) and v <= high
    if not ok:
        bracket = "(" if open_low else "["
        raise InputError(f"{name} must be a number in {bracket}{low:g}, {high:g}], got {value!r}")
    return float(value)  # type: ignore[arg-type]

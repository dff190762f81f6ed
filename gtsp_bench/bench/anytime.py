"""Anytime metrics of a solve from its trajectory: the primal integral and times to target.

A solve's trajectory is its incumbents over time (``[[time_s, objective, lower_bound], ...]`` in
the task log; the last point is the answer). Against a reference value ``ref``:

primal gap (Berthold 2013)
    ``gamma(t) = |obj(t) - ref| / max(|obj(t)|, |ref|)`` with ``obj(t)`` the incumbent at time
    ``t``; 1 before the first incumbent (or when the two have opposite signs), 0 when both are 0;
``primal_integral``
    the integral of ``gamma`` over ``[0, T]`` divided by ``T``, the solve's time limit (its
    runtime where it has none): 0 for the reference found at once, 1 for nothing found in time.
    After its answer a solve keeps its answer up to ``T``;
``time_to_1pct_s``, ``time_to_0p1pct_s``
    the first time, within ``T``, the incumbent is within 1 % / 0.1 % of the reference
    (``(obj - ref) / |ref|``), NaN when it never is.

The rows keep the trajectory compactly (:func:`format_trajectory`), so the metrics can be
computed again from a ``rows.csv``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

#: The targets of the time-to-target columns, as fractions of the reference.
TARGETS = {"time_to_1pct_s": 0.01, "time_to_0p1pct_s": 0.001}

Point = tuple[float, float, float | None]


def points_of(trajectory: object, runtime_s: float, objective: float) -> list[Point]:
    """A record's trajectory as ``(time_s, objective, lower_bound)`` tuples; a record without one
    (an older log, a failed solve) is its answer at its runtime, or nothing."""
    out: list[Point] = []
    if isinstance(trajectory, list):
        for p in trajectory:
            if isinstance(p, (list, tuple)) and len(p) == 3:
                out.append((float(p[0]), float(p[1]), None if p[2] is None else float(p[2])))
    if not out and math.isfinite(objective):
        out = [(runtime_s if math.isfinite(runtime_s) else 0.0, objective, None)]
    return out


def primal_gap(objective: float, reference: float) -> float:
    """Berthold's primal gap of ``objective`` to ``reference``, in [0, 1]."""
    if objective == reference == 0:
        return 0.0
    if objective * reference < 0:
        return 1.0
    return min(1.0, abs(reference - objective) / max(abs(objective), abs(reference)))


def primal_integral(points: Sequence[Point], reference: float, horizon: float) -> float:
    """The primal integral over ``[0, horizon]`` divided by ``horizon`` (NaN without a reference
    or a positive horizon)."""
    if not (math.isfinite(reference) and math.isfinite(horizon) and horizon > 0):
        return math.nan
    total, t, gap = 0.0, 0.0, 1.0
    for time_s, obj, _ in points:
        step = min(max(time_s, t), horizon)
        total += gap * (step - t)
        t, gap = step, primal_gap(obj, reference)
    total += gap * (horizon - t)
    return total / horizon


def time_to_target(points: Sequence[Point], reference: float, target: float,
                   horizon: float = math.inf) -> float:
    """The first time, up to ``horizon``, the incumbent is within ``target`` (a fraction) of
    ``reference``; NaN when it never is."""
    if not math.isfinite(reference) or reference == 0:
        return math.nan
    for time_s, obj, _ in points:
        if time_s > horizon:
            break
        if (obj - reference) / abs(reference) <= target + 1e-12:
            return time_s
    return math.nan


def proof_time(points: Sequence[Point], objective: float, tolerance: float) -> float:
    """The first time the bound is within ``tolerance`` of ``objective`` (the answer's cost): when
    a solve that proved its answer optimal had done so, before any work after its search (a
    certificate written, say); NaN when no point says so.

    With integer costs a search proves its tour once the bound passes the cost less 1, so
    ``tolerance`` 1 there.
    """
    for time_s, _, bound in points:
        if bound is not None and bound >= objective - tolerance - 1e-9 * abs(objective):
            return time_s
    return math.nan


def format_trajectory(points: Sequence[Point]) -> str:
    """``time:objective[:bound]`` points joined by ``;`` (times to 4 significant digits)."""
    return ";".join(f"{t:.4g}:{o:.10g}" + ("" if b is None else f":{b:.10g}") for t, o, b in points)


def parse_trajectory(text: str) -> list[Point]:
    """The points of :func:`format_trajectory`'s text (empty text: none)."""
    out: list[Point] = []
    for part in filter(None, str(text).split(";")):
        fields = part.split(":")
        out.append((float(fields[0]), float(fields[1]), float(fields[2]) if len(fields) > 2 else None))
    return out


def metrics(points: Sequence[Point], reference: float, horizon: float) -> dict[str, float]:
    """The anytime columns of one solve."""
    out = {"primal_integral": primal_integral(points, reference, horizon)}
    for column, target in TARGETS.items():
        out[column] = time_to_target(points, reference, target, horizon)
    return out


__all__ = [
    "TARGETS", "format_trajectory", "metrics", "parse_trajectory", "points_of", "primal_gap",
    "primal_integral", "proof_time", "time_to_target",
]

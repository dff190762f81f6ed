"""Input checks, in one place: every option, argument and parameter the core, the CLI and the
solvers take is checked by a function here. A bad value raises :class:`InputError` with a message
naming it; a good one is returned in its canonical type."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TypeVar

import numpy as np

from gtsp_bench.errors import InputError

#: Time limit of the search solvers when none is given: seconds per cluster, and the cap.
SECONDS_PER_CLUSTER, MAX_DEFAULT_SECONDS = 0.5, 60.0

T = TypeVar("T")


def is_int(value: object) -> bool:
    """Whether ``value`` is an integer (Python or numpy), not a bool."""
    return not isinstance(value, bool) and isinstance(value, (int, np.integer))


def is_number(value: object) -> bool:
    """Whether ``value`` is a real number (Python or numpy int or float), not a bool."""
    return not isinstance(value, bool) and isinstance(value, (int, float, np.integer, np.floating))


def default_time_limit(n_clusters: int) -> float:
    """The time limit used when none is given: ``0.5 s * K``, at least 1 s, at most 60 s."""
    return min(MAX_DEFAULT_SECONDS, max(1.0, SECONDS_PER_CLUSTER * n_clusters))


def check_int(name: str, value: object, low: int) -> int:
    """``value`` as an int if it is an integer >= ``low``, else :class:`InputError`."""
    if not is_int(value) or value < low:  # type: ignore[operator]
        raise InputError(f"{name} must be an integer >= {low}, got {value!r}")
    return int(value)  # type: ignore[call-overload]


def check_float(name: str, value: object, low: float, high: float, *, open_low: bool = True) -> float:
    """``value`` as a float if it is a finite number in ``(low, high]`` (``[low, high]`` when
    not ``open_low``; ``high = inf``: no upper bound), else :class:`InputError`."""
    ok = is_number(value)
    if ok:
        v = float(value)  # type: ignore[arg-type]
        ok = math.isfinite(v) and (v > low if open_low else v >= low) and v <= high
    if not ok:
        bracket = "(" if open_low else "["
        raise InputError(f"{name} must be a number in {bracket}{low:g}, {high:g}], got {value!r}")
    return float(value)  # type: ignore[arg-type]


def check_bool(name: str, value: object) -> bool:
    """``value`` if it is ``True`` or ``False``, else :class:`InputError`."""
    if not isinstance(value, bool):
        raise InputError(f"{name} must be true or false, got {value!r}")
    return value


def check_choice(name: str, value: T, choices: Sequence[T]) -> T:
    """``value`` if it is one of ``choices``, else :class:`InputError` listing them."""
    if value not in choices:
        valid = ", ".join(repr(c) for c in choices)
        raise InputError(f"{name} must be one of {valid}, got {value!r}")
    return value


def check_omega(omega: object) -> float:
    """``omega`` as a float, or :class:`InputError` unless it is a number in [0, 1]."""
    if not is_number(omega):
        raise InputError(f"omega must be a number in [0, 1], got {omega!r}")
    value = float(omega)  # type: ignore[arg-type]
    if not 0.0 <= value <= 1.0:  # also rejects NaN
        raise InputError(f"omega must be in [0, 1], got {omega!r}")
    return value


def check_time_limit(time_limit: object) -> float | None:
    """A valid time limit (seconds, > 0, or ``None``) or :class:`InputError`."""
    if time_limit is None:
        return None
    if not is_number(time_limit):
        raise InputError(f"time limit must be a number of seconds, got {time_limit!r}")
    if not time_limit > 0 or math.isnan(time_limit):  # type: ignore[operator, arg-type]
        raise InputError(f"time limit must be > 0 seconds, got {time_limit!r}")
    return float(time_limit)  # type: ignore[arg-type]


def check_seed(seed: object) -> int:
    """A valid seed (an integer >= 0, as numpy's generators take) or :class:`InputError`."""
    return check_int("seed", seed, 0)


def check_mapping(name: str, value: object) -> dict:
    """A copy of ``value`` as a dict if it is a mapping (e.g. keyword options), else
    :class:`InputError`."""
    if not isinstance(value, Mapping):
        raise InputError(f"{name} must be a mapping of names to values, got {value!r}")
    return dict(value)


_K_FORMS = "a range 4..10, a list 4,7,10 or a mix 4..7,10"


def parse_ks(text: object) -> tuple[int, ...]:
    """Parse a set of cluster counts: a range ``4..10``, a list ``4,7,10`` or a mix ``4..7,10``.

    Spaces are ignored; the result is sorted and without repeats.

    Raises
    ------
    InputError
        One line naming the bad part: not a number or range, a reversed range, or K < 1.
    """
    out: set[int] = set()
    for part in str(text).replace(" ", "").split(","):
        lo, sep, hi = part.partition("..")
        try:
            a = int(lo)
            b = int(hi) if sep else a
        except ValueError:
            what = "empty entry" if not part else f"{part!r} is not a number or a range"
            raise InputError(f"bad K {text!r}: {what} (expected {_K_FORMS})") from None
        if a < 1:
            raise InputError(f"bad K {text!r}: cluster counts must be >= 1, got {a}")
        if b < a:
            raise InputError(f"bad K {text!r}: range {part} is reversed (write {b}..{a})")
        out.update(range(a, b + 1))
    return tuple(sorted(out))


def parse_omegas(text: object) -> tuple[float, ...]:
    """Parse a comma-separated list of omegas, e.g. ``0,0.5,0.9``, each checked by
    :func:`check_omega`; the order is kept.

    Raises
    ------
    InputError
        An entry that is not a number in [0, 1], or an empty list.
    """
    out = []
    for part in str(text).replace(" ", "").split(","):
        try:
            out.append(check_omega(float(part)))
        except (ValueError, InputError):
            raise InputError(f"bad omegas {text!r}: {part!r} is not a number in [0, 1] "
                             "(expected a list like 0,0.5,0.9)") from None
    return tuple(out)

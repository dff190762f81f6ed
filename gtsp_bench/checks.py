"""Input checks, in one place: every option, argument and parameter the core, the CLI and the
solvers take is checked by a function here. A bad value raises :class:`InputError` with a message
naming it; a good one is returned in its canonical type."""

from __future__ import annotations

import argparse
import json
import math
import os
from collections.abc import Mapping, Sequence
from typing import Any, TypeVar

import numpy as np

from gtsp_bench.errors import InputError

#: Time limit of the search solvers when none is given: seconds per cluster, and the cap.
SECONDS_PER_CLUSTER, MAX_DEFAULT_SECONDS = 0.5, 60.0

T = TypeVar("T")


def is_int(value: object) -> bool:
    """Whether ``value`` is an integer (Python or numpy), not a bool."""
    return not isinstance(value, bool) and isinstance(value, (int, np.integer))


def all_ints(values: Sequence[object]) -> bool:
    """Whether every item is an integer (:func:`is_int`): one pass over the items' types when
    they are plain Python ints (a JSON file's), one call of :func:`is_int` each otherwise."""
    return set(map(type, values)) <= {int} or all(is_int(v) for v in values)


def is_number(value: object) -> bool:
    """Whether ``value`` is a real number (Python or numpy int or float), not a bool."""
    return not isinstance(value, bool) and isinstance(value, (int, float, np.integer, np.floating))


#: Relative tolerance under which two objective values are the same value.
SAME_VALUE_TOL = 1e-9


def strictly_better(objective: float, value: float) -> bool:
    """Whether ``objective`` lies below ``value`` by more than :data:`SAME_VALUE_TOL` (relative,
    at least that much absolute): the one rule for "a new best known" and "below a reference"."""
    return objective < value - SAME_VALUE_TOL * max(1.0, abs(value))


def default_time_limit(n_clusters: int) -> float:
    """The time limit used when none is given: ``0.5 s * K``, at least 1 s, at most 60 s."""
    return min(MAX_DEFAULT_SECONDS, max(1.0, SECONDS_PER_CLUSTER * n_clusters))


def time_limit_or_default(time_limit: object, n_clusters: int) -> float:
    """A solver's time limit: ``time_limit`` checked by :func:`check_time_limit`, or when it is
    ``None`` the default for ``n_clusters`` clusters (:func:`default_time_limit`)."""
    checked = check_time_limit(time_limit)
    return checked if checked is not None else default_time_limit(n_clusters)


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
        if math.isinf(high):
            raise InputError(f"{name} must be a number {'>' if open_low else '>='} {low:g}, got {value!r}")
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
#: Largest cluster count a K set may name (GTSPLIB's largest instance has 17,180 clusters).
MAX_K = 100_000


def parse_names(text: str | Sequence[str], what: str, valid: Sequence[str] | None = None) -> tuple[str, ...]:
    """Names from ``"a, b,c"`` (or a sequence of names): stripped, empty entries and repeats dropped,
    in the given order; each must be in ``valid`` when that is given.

    Raises
    ------
    InputError
        ``unknown {what} 'x' (valid: ...)`` for a name outside ``valid``.
    """
    parts = text.split(",") if isinstance(text, str) else [str(p) for p in text]
    names = tuple(dict.fromkeys(p.strip() for p in parts if p.strip()))
    if valid is not None:
        for n in names:
            if n not in valid:
                raise InputError(f"unknown {what} {n!r} (valid: {', '.join(valid)})")
    return names


def parse_ks(text: object) -> tuple[int, ...]:
    """Parse a set of cluster counts: a range ``4..10``, a list ``4,7,10`` or a mix ``4..7,10``.

    Spaces are ignored; the result is sorted and without repeats.

    Raises
    ------
    InputError
        One line naming the bad part: not a number or range, a reversed range, K < 1 or
        K > :data:`MAX_K`.
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
        if b > MAX_K:
            raise InputError(f"bad K {text!r}: cluster counts above {MAX_K} are not benchmarked")
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



#: The executors :func:`check_executor` accepts besides a scheduler address.
EXECUTORS = ("local", "dask")


def parse_seeds(text: str | Sequence[int]) -> tuple[int, ...]:
    """Solver seeds: a list ``0,1,2``, a range ``0..4`` or a mix; order kept, repeats dropped."""
    if not isinstance(text, str):
        seeds = tuple(dict.fromkeys(check_seed(s) for s in text))
        if not seeds:
            raise InputError("bad seeds: no seed given")
        return seeds
    out: list[int] = []
    for part in text.replace(" ", "").split(","):
        lo, sep, hi = part.partition("..")
        try:
            a, b = int(lo), int(hi) if sep else int(lo)
            if b < a:
                raise ValueError
            out += [check_seed(s) for s in range(a, b + 1)]
        except (ValueError, InputError):
            raise InputError(f"bad seeds {text!r}: {part!r} is not a seed or a range "
                             "(expected e.g. 0,1,2 or 0..4)") from None
    return tuple(dict.fromkeys(out))


def check_executor(text: object) -> str:
    """Where the runner's solves run: ``local`` (this machine's worker pool), ``dask`` (a Dask
    cluster on this machine) or ``tcp://HOST:PORT`` (an existing Dask scheduler), returned as
    given (the address without surrounding spaces).

    Raises
    ------
    InputError
        Anything else, or an address without a host or with a bad port.
    """
    from urllib.parse import urlsplit

    value = str(text).strip()
    if value in EXECUTORS:
        return value
    expected = f"expected {', '.join(EXECUTORS)} or a Dask scheduler's tcp://HOST:PORT"
    if not value.startswith("tcp://"):
        raise InputError(f"bad executor {text!r} ({expected})")
    try:
        parts = urlsplit(value)
        port = parts.port
    except ValueError:
        port = None
        parts = None
    if parts is None or not parts.hostname or port is None or port < 1 or parts.path or parts.query:
        raise InputError(f"bad executor {text!r}: a Dask scheduler's address is tcp://HOST:PORT "
                         f"with a port 1..65535")
    return value

# ---------------------------------------------------------------------- numbers of an instance
#: Largest coordinate magnitude accepted: its ulp (about 1.2e-7) stays far below the millimetre of
#: a UAV file and the unit rounding of the TSPLIB rules, and squared distances cannot overflow.
MAX_COORD = 1e9
#: Largest cost a tour may reach (a bound from the instance's extremes): below 2^53, sums of whole
#: numbers are exact and two tours whose costs differ are told apart.
MAX_TOUR_COST = float(2**53)


def _fmt(value: float) -> str:
    return f"{value:.6g}" if math.isfinite(value) else ("nan" if math.isnan(value) else repr(value))


def check_finite_array(what: str, values: np.ndarray, bound: float) -> None:
    """:class:`InputError` naming the first entry of ``values`` that is NaN, infinite or beyond
    ``±bound``; ``what`` names the array and the entry's index is appended."""
    arr = np.asarray(values, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        bad = ~(np.abs(arr) <= bound)
    if not bad.any():
        return
    index = tuple(int(i) for i in np.argwhere(bad)[0])
    value = float(arr[index])
    where = f"{what}[{']['.join(map(str, index))}]" if index else what
    if math.isnan(value):
        raise InputError(f"{where} is nan (not a number)")
    kind = "infinite" if math.isinf(value) else f"beyond ±{bound:g}"
    raise InputError(f"{where} = {_fmt(value)} is {kind}: distances and energies would not be "
                     f"exact enough to order tours")


def _derived_params(params: Any) -> dict[str, float]:
    """The energy model's derived quantities, each finite or :class:`InputError` naming it."""
    names = ("p_hover", "p_move", "flight_energy_per_m", "p_los", "path_loss_db", "p_ch_w",
             "noise_w", "r_data", "d0", "rx_energy")
    out = {}
    for name in names:
        try:
            value = float(getattr(params, name))
        except (OverflowError, ZeroDivisionError, ValueError):
            value = math.inf
        if not math.isfinite(value) or (name == "r_data" and value <= 0):
            raise InputError(f"energy parameters give {name} = {_fmt(value)}: the energy model "
                             f"needs finite, positive derived values")
        out[name] = value
    return out


def tour_cost_bound(instance: Any) -> float:
    """An upper bound on the cost of any tour of ``instance`` (the weighted energy for any omega
    of a UAV instance, else the length), from each cluster's extremes: O(n)."""
    k = instance.n_clusters
    with np.errstate(over="ignore", invalid="ignore"):
        if instance.edge_weight_type == "EXPLICIT":
            longest = float(np.max(np.abs(instance.weights)))
        elif instance.edge_weight_type == "GEO":
            longest = 20_038.0  # half the earth's circumference in km (TSPLIB's radius): the most
        elif instance.edge_weight_type == "GEOM":
            longest = 20_037_509.0  # the same in metres (GEOM's radius 6,378,388 m)
        else:
            pts = instance.node_points
            lo, hi = pts.min(axis=0), pts.max(axis=0)
            # the box's diagonal bounds every Euclidean distance (ATT's pseudo-Euclidean is
            # shorter), +1 for the TSPLIB rules' rounding up
            longest = float(np.hypot(*(hi - lo))) + 1.0
        if instance.params is None:
            return (k + 1) * longest
        p = instance.params
        d = _derived_params(p)
        total = (k + 1) * longest * d["flight_energy_per_m"]
        for cluster in instance.clusters:
            n = len(cluster)
            spread = float(np.hypot(*(cluster.max(axis=0) - cluster.min(axis=0))))
            amp = max(p.eps_fs * spread**2, p.eps_mp * spread**4)
            ground = (n - 1) * (p.message_bits * (p.e_elec + amp) + d["rx_energy"])
            try:
                ground += p.upload_energy(n) + p.hover_energy(n)
            except (OverflowError, ZeroDivisionError):
                return math.inf
            total += ground
    return float(total)


def check_instance_numbers(instance: Any) -> None:
    """Coordinates, matrix weights, energy parameters and the distances and energies they give
    must be finite and small enough that double precision orders tours correctly.

    Raises
    ------
    InputError
        Naming the offending value: a coordinate beyond ``±MAX_COORD``, a NaN or infinite weight,
        an energy parameter whose derived quantities overflow, or an instance whose tours could
        cost more than ``MAX_TOUR_COST``.
    """
    if instance.edge_weight_type == "EXPLICIT":
        check_finite_array("weight", instance.weights, MAX_TOUR_COST)
    else:
        if not np.all(np.abs(instance.coords) <= MAX_COORD):  # all at once, then name the first
            for k, cluster in enumerate(instance.clusters):
                check_finite_array(f"clusters[{k}]", cluster, MAX_COORD)
        if instance.depot is not None:
            check_finite_array("depot", instance.depot, MAX_COORD)
    bound = tour_cost_bound(instance)
    if not bound <= MAX_TOUR_COST:
        what = "energy" if instance.params is not None else "length"
        raise InputError(f"a tour's {what} could reach {_fmt(bound)}, beyond {MAX_TOUR_COST:g} where "
                         f"double precision no longer orders tours exactly (coordinates or energy "
                         f"parameters too large)")


# ---------------------------------------------------------------------- memory
def memory_limit_bytes() -> int | None:
    """Memory this process may still allocate: the least of the address-space limit (``ulimit
    -v``) less what is mapped now, and the system's available memory; ``None`` if unknown."""
    limits = []
    try:
        import resource

        soft = resource.getrlimit(resource.RLIMIT_AS)[0]
        if soft != resource.RLIM_INFINITY:
            mapped = 0
            try:
                with open("/proc/self/statm") as f:
                    mapped = int(f.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
            except (OSError, ValueError):
                pass
            limits.append(max(soft - mapped, 0))
    except (ImportError, ValueError, OSError):
        pass
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    limits.append(int(line.split()[1]) * 1024)
                    break
    except (OSError, ValueError, IndexError):
        pass
    return min(limits) if limits else None


def check_memory(what: str, need_bytes: float, hint: str) -> None:
    """:class:`InputError` when ``need_bytes`` (an estimate made before allocating) exceeds what
    :func:`memory_limit_bytes` says this process can use; ``hint`` names a smaller setting."""
    limit = memory_limit_bytes()
    if limit is not None and need_bytes > limit:
        raise InputError(f"{what} needs about {need_bytes / 2**30:.3g} GiB of memory, more than the "
                         f"{limit / 2**30:.3g} GiB available; {hint}")


# ---------------------------------------------------------------------- the runner's task log
#: Statuses of a record in the runner's task log: a solver's own (see the registry), ``failed``
#: (``cause`` says whose fault) and ``refused`` (the solver declines the input by design).
LOG_STATUSES = ("optimal", "feasible", "time_limit", "failed", "refused")
#: Causes of a failed solve: the solver's own error, or the machinery around it (its worker
#: died or was killed from outside, or memory ran out), which a later run retries.
FAILURE_CAUSES = ("solver", "infrastructure")
_NUMERIC_FIELDS = ("lower_bound", "runtime_s", "ground_J", "flight_J", "hover_J", "distance_m",
                   "task_wall_s", "time_limit")


def _int_list(name: str, value: object, length: int | None) -> list[int]:
    if not isinstance(value, list) or not all(is_int(v) for v in value):
        raise InputError(f"{name} is not a list of integers")
    if length is not None and len(value) != length:
        raise InputError(f"{name} has {len(value)} entries, not {length}")
    return value


def check_log_record(record: object, sizes: Sequence[int] | None = None) -> dict[str, Any]:
    """A record read back from the runner's task log, or :class:`InputError` saying what is wrong.

    Parameters
    ----------
    record
        The decoded JSON line.
    sizes
        Cluster sizes of the instance the record's key names, when known: ``order`` must then be
        a permutation of its clusters and ``heads`` valid indices.

    The key is ``NAME#HASH|SOLVER[@REVISION][[OPTIONS]]|w=OMEGA|seed=SEED|tl=LIMIT``; ``solver``, ``omega``
    (and ``seed`` and ``time_limit`` when present) must agree with it. A solved status needs a
    finite ``objective`` and an ``order`` and ``heads`` of one entry per cluster; ``failed`` and
    ``refused`` need a null (or NaN, as older logs wrote) objective and no tour; ``time_limit``
    is either (a solve stopped by its limit, or one killed at the hard limit without an answer).
    An optional ``trajectory`` (``[[time_s, objective, lower_bound], ...]``) must have times that
    never fall, objectives that never rise and end at ``objective``, and bounds that never fall.
    """
    if not isinstance(record, dict):
        raise InputError("not a JSON object")
    key = record.get("key")
    if not isinstance(key, str) or not key:
        raise InputError("'key' is not a non-empty string")
    parts = key.split("|")
    if len(parts) != 5 or not parts[2].startswith("w=") or not parts[3].startswith("seed="):
        raise InputError(f"key {key!r} is not NAME#HASH|SOLVER|w=OMEGA|seed=SEED|tl=LIMIT")
    if record.get("solver") != parts[1].split("[")[0].split("@")[0]:
        raise InputError(f"solver {record.get('solver')!r} does not match the key")
    omega = record.get("omega")
    if not is_number(omega) or f"{omega:g}" != parts[2][2:]:
        raise InputError(f"omega {omega!r} does not match the key")
    if "seed" in record and (not is_int(record["seed"]) or str(record["seed"]) != parts[3][5:]):
        raise InputError(f"seed {record['seed']!r} does not match the key")
    status = record.get("status")
    if status not in LOG_STATUSES:
        raise InputError(f"status {status!r} is not one of {', '.join(LOG_STATUSES)}")
    objective = record.get("objective")
    no_answer = objective is None or (isinstance(objective, float) and math.isnan(objective))
    if status in ("optimal", "feasible") or (status == "time_limit" and not no_answer):
        if not is_number(objective) or not math.isfinite(objective):
            raise InputError(f"objective {objective!r} of a {status} solve is not a finite number")
        k = None if sizes is None else len(sizes)
        order = _int_list("order", record.get("order"), k)
        heads = _int_list("heads", record.get("heads"), len(order))
        if sorted(order) != list(range(len(order))):
            raise InputError("order is not a permutation of the clusters")
        if sizes is not None and any(not 0 <= h < n for h, n in zip(heads, sizes, strict=True)):
            raise InputError("heads names a node outside its cluster")
    elif not no_answer:
        raise InputError(f"objective {objective!r} of a {status} solve is not null")
    elif record.get("order") or record.get("heads"):
        raise InputError(f"a {status} solve without an objective has a tour")
    if "cause" in record and record["cause"] not in FAILURE_CAUSES:
        raise InputError(f"cause {record['cause']!r} is not one of {', '.join(FAILURE_CAUSES)}")
    for name in _NUMERIC_FIELDS:
        value = record.get(name)
        if value is not None and not is_number(value):
            raise InputError(f"{name} {value!r} is not a number")
    if "note" in record and not isinstance(record["note"], str):
        raise InputError("note is not a string")
    if "trajectory" in record:
        _check_trajectory(record["trajectory"], None if no_answer else objective)
    return record


def _check_trajectory(points: object, objective: object) -> None:
    """The optional ``trajectory`` of a task record: ``[[time_s, objective, lower_bound], ...]``
    with times that never fall, objectives that never rise, bounds (a number or null) that never
    fall once given, and the last objective equal to the record's; none without an answer."""
    if not isinstance(points, list):
        raise InputError("trajectory is not a list")
    if objective is None:
        if points:
            raise InputError("a solve without an objective has a trajectory")
        return
    last_t, last_obj, last_lb = 0.0, math.inf, -math.inf
    for i, point in enumerate(points):
        if not isinstance(point, list) or len(point) != 3:
            raise InputError(f"trajectory point {i} is not [time_s, objective, lower_bound]")
        t, obj, lb = point
        if not is_number(t) or not math.isfinite(t) or t < last_t:
            raise InputError(f"trajectory point {i}: time {t!r} is not a number >= the one before")
        if not is_number(obj) or not math.isfinite(obj) or obj > last_obj:
            raise InputError(f"trajectory point {i}: objective {obj!r} is not a number <= the one before")
        if lb is not None and (not is_number(lb) or not math.isfinite(lb) or lb < last_lb):
            raise InputError(f"trajectory point {i}: lower bound {lb!r} is not a number >= the one before")
        last_t, last_obj, last_lb = t, obj, last_lb if lb is None else lb
    if points and last_obj != objective:
        raise InputError(f"the trajectory ends at {last_obj!r}, not at the objective {objective!r}")


# ---------------------------------------------------------------------- argparse types
def arg_float(text: str) -> float:
    """argparse type: a number."""
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None


def arg_int(text: str) -> int:
    """argparse type: an integer."""
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None


def arg_float_or_none(text: str) -> float | None:
    """argparse type: a number, or ``none``."""
    return None if text.strip().lower() == "none" else arg_float(text)


def arg_seed(text: str) -> int:
    """argparse type: a seed (:func:`check_seed`)."""
    try:
        return check_seed(arg_int(text))
    except InputError as e:
        raise argparse.ArgumentTypeError(f"a {e}") from None


def arg_key_value(text: str) -> tuple[str, Any]:
    """argparse type: ``KEY=VALUE``, the value read as JSON when it parses, else the text."""
    key, sep, raw = text.partition("=")
    if not sep or not key:
        raise argparse.ArgumentTypeError(f"expected KEY=VALUE, got {text!r}")
    try:
        value = json.loads(raw)
    except json.JSONDecodeError:
        value = raw
    return key, value

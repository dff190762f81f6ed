"""Option validation helpers, the default time limit, the numbers of an instance, memory and the
runner's log records."""

from __future__ import annotations

import math
import os
import re
import subprocess
import sys

import numpy as np
import pytest

from gtsp_bench.checks import (
    MAX_TOUR_COST,
    all_ints,
    check_executor,
    check_finite_array,
    check_float,
    check_int,
    check_log_record,
    check_mapping,
    default_time_limit,
    parse_ks,
    parse_omegas,
    strictly_better,
    tour_cost_bound,
)
from gtsp_bench.errors import InputError


def test_check_int():
    """Integers at or above the bound pass (numpy ones too); bools, floats, small values fail."""
    assert check_int("n", 3, 1) == 3 and check_int("n", np.int64(1), 1) == 1
    for bad in (0, -1, 2.0, True, "3", None):
        with pytest.raises(InputError, match="n must be an integer >= 1"):
            check_int("n", bad, 1)


def test_all_ints_takes_python_and_numpy_ints_and_nothing_else():
    """Plain ints (the fast path), numpy ints among them (the item-by-item path) and an empty list
    pass; one bool, float, string or None among thousands of ints fails."""
    many = list(range(5000))
    assert all_ints(many) and all_ints([]) and all_ints([*many, np.int64(3), np.int32(-1)])
    for bad in (True, 1.0, np.float64(1), "1", None, [1]):
        assert not all_ints([*many, bad]) and not all_ints([bad])


def test_check_float():
    """Open and closed lower bounds, the upper bound; NaN and infinity always fail."""
    assert check_float("x", 1, 0.0, 1.0) == 1.0
    assert check_float("x", 0, 0.0, 1.0, open_low=False) == 0.0
    assert check_float("x", 1e300, 0.0, math.inf) == 1e300
    for bad in (0, 1.01, math.nan, True, "0.5"):
        with pytest.raises(InputError, match=r"x must be a number in \(0, 1\]"):
            check_float("x", bad, 0.0, 1.0)
    with pytest.raises(InputError, match="x must be a number"):
        check_float("x", math.inf, 0.0, math.inf)


def test_default_time_limit():
    """Half a second per cluster, at least 1 s, at most 60 s."""
    assert default_time_limit(1) == 1.0
    assert default_time_limit(20) == 10.0
    assert default_time_limit(1000) == 60.0


def test_check_mapping():
    """A mapping comes back as a dict of its own (a copy); anything else fails."""
    options = {"dim": 16}
    copy = check_mapping("opts", options)
    assert copy == options and copy is not options
    for bad in (None, "dim", [("dim", 16)]):
        with pytest.raises(InputError, match="opts must be a mapping"):
            check_mapping("opts", bad)


def test_parse_ks_ranges_lists_and_mixes():
    """The one K-set syntax: a range, a list, a mix; spaces ignored, sorted, no repeats."""
    assert parse_ks("4..10") == tuple(range(4, 11))
    assert parse_ks("4,7,10") == (4, 7, 10)
    assert parse_ks("4..7,10") == (4, 5, 6, 7, 10)
    assert parse_ks(" 10, 4..5 ,5") == (4, 5, 10)
    assert parse_ks("7") == (7,) and parse_ks("3..3") == (3,)
    assert parse_ks("7, 4,5..6,4") == (4, 5, 6, 7)


@pytest.mark.parametrize("text, message", [
    ("10..4", "range 10..4 is reversed (write 4..10)"),
    ("4..x", "'4..x' is not a number or a range"),
    ("four", "'four' is not a number or a range"),
    ("4;7", "'4;7' is not a number or a range"),
    ("4..", "'4..' is not a number or a range"),
    ("4,,7", "empty entry"),
    ("", "empty entry"),
    ("0", "cluster counts must be >= 1, got 0"),
    ("-2..3", "cluster counts must be >= 1, got -2"),
    ("4..10000000000", "cluster counts above 100000 are not benchmarked"),
])
def test_parse_ks_bad_input(text, message):
    """Bad text: one line naming the K set and the bad part, with the accepted forms."""
    with pytest.raises(InputError) as info:
        parse_ks(text)
    assert str(info.value).startswith(f"bad K {text!r}: ") and message in str(info.value)
    assert "\n" not in str(info.value)


def test_parse_omegas():
    """Comma-separated omegas in [0, 1], order kept; anything else is refused."""
    assert parse_omegas("0,0.5,0.9") == (0.0, 0.5, 0.9) and parse_omegas("0.6, 0.3") == (0.6, 0.3)
    for bad in ("0.5,x", "1.5", "", "nan", "0.5,"):
        with pytest.raises(InputError, match="bad omegas"):
            parse_omegas(bad)


def test_check_executor():
    """local, dask or a scheduler's tcp://HOST:PORT (spaces around it dropped); anything else,
    an address without a host or a port, or with a bad port, is refused naming the forms."""
    assert check_executor("local") == "local" and check_executor("dask") == "dask"
    assert check_executor(" tcp://10.0.0.5:8786 ") == "tcp://10.0.0.5:8786"
    assert check_executor("tcp://[::1]:8786") == "tcp://[::1]:8786"
    with pytest.raises(InputError, match=r"bad executor 'spark' \(expected local, dask or a Dask"):
        check_executor("spark")
    for bad in ("tcp://host", "tcp://:8786", "tcp://host:0", "tcp://host:70000", "tcp://host:x",
                "tcp://host:8786/path"):
        with pytest.raises(InputError, match=r"a Dask scheduler's address is tcp://HOST:PORT"):
            check_executor(bad)


def test_check_finite_array_names_the_entry_and_the_kind():
    """nan is named as nan, inf as infinite, a huge finite value with the bound; good passes."""
    check_finite_array("w", np.array([[0.0, 1.0], [1.0, 0.0]]), 10.0)
    with pytest.raises(InputError, match=r"^w\[1\]\[0\] is nan \(not a number\)$"):
        check_finite_array("w", np.array([[0.0, 1.0], [math.nan, 0.0]]), 10.0)
    with pytest.raises(InputError, match=r"^w\[1\] = -inf is infinite"):
        check_finite_array("w", np.array([0.0, -math.inf]), 10.0)
    with pytest.raises(InputError, match=r"^w\[0\] = 11 is beyond ±10"):
        check_finite_array("w", np.array([11.0]), 10.0)


def test_tour_cost_bound_is_an_upper_bound():
    """No tour of a generated instance costs more than the bound, for omega 0 and 1."""
    from gtsp_bench.energy import evaluate
    from gtsp_bench.generator import generate_instance

    inst = generate_instance(5, 6, seed=3)
    bound = tour_cost_bound(inst)
    rng = np.random.default_rng(0)
    for _ in range(50):
        order = rng.permutation(5).tolist()
        heads = rng.integers(0, 6, size=5).tolist()
        for omega in (0.0, 1.0):
            assert evaluate(inst, omega, order, heads).objective <= bound
    assert bound < MAX_TOUR_COST


def test_memory_limit_follows_ulimit_v():
    """Under `ulimit -v 1 GiB` the limit is at most 1 GiB; check_memory refuses beyond it."""
    code = (
        "import resource\n"
        "resource.setrlimit(resource.RLIMIT_AS, (2**30, 2**30))\n"
        "from gtsp_bench.checks import memory_limit_bytes, check_memory\n"
        "from gtsp_bench.errors import InputError\n"
        "assert 0 < memory_limit_bytes() <= 2**30, memory_limit_bytes()\n"
        "try:\n"
        "    check_memory('a table', 2**31, 'try less')\n"
        "except InputError as e:\n"
        "    print(e)\n"
    )
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60,
                          env=env)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("a table needs about 2 GiB of memory, more than the ")
    assert proc.stdout.rstrip().endswith("GiB available; try less")


def test_check_log_record_accepts_a_real_record():
    """A record as the runner writes it passes unchanged, with and without the cluster sizes."""
    rec = {"key": "i#ab|dp@v1|w=0.3|seed=0|tl=10", "solver": "dp", "omega": 0.3, "seed": 0,
           "status": "optimal", "objective": 12.5, "order": [2, 0, 1], "heads": [0, 1, 0],
           "lower_bound": 12.5, "runtime_s": 0.1, "note": ""}
    assert check_log_record(rec) is rec
    assert check_log_record(rec, (1, 2, 1)) is rec
    with pytest.raises(InputError, match="heads names a node outside its cluster"):
        check_log_record(rec, (1, 1, 1))
    with pytest.raises(InputError, match="is not NAME#HASH"):
        check_log_record({**rec, "key": "i|dp"})


def test_a_record_of_a_solver_with_options_matches_its_key():
    """A key names the solver's options after its name (and revision): such a record is the
    solver's, so a rerun re-uses it; a record of another solver under that key is refused."""
    rec = {"key": "i#ab|milp-textbook[subtour='mtz']|w=0.5|seed=0|tl=60", "solver": "milp-textbook",
           "omega": 0.5, "seed": 0, "status": "optimal", "objective": 12.5, "order": [1, 0],
           "heads": [0, 0], "runtime_s": 0.1, "note": ""}
    assert check_log_record(rec) is rec
    revised = {**rec, "key": "i#ab|drl@f98[heads='optimal']|w=0.5|seed=0|tl=none", "solver": "drl"}
    assert check_log_record(revised) is revised
    with pytest.raises(InputError, match="solver 'milp' does not match the key"):
        check_log_record({**rec, "solver": "milp"})


def test_no_hand_written_type_checks_outside_this_module():
    """Input checks live in gtsp_bench.checks: no other module of the package or of solvers/
    writes its own ``isinstance(x, bool)`` test (the sign of a hand-rolled number check)."""
    import ast

    from .conftest import REPO

    found = []
    for path in sorted([*(REPO / "gtsp_bench").rglob("*.py"), *(REPO / "solvers").rglob("*.py")]):
        if path.name == "checks.py" and path.parent.name == "gtsp_bench":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if (isinstance(node, ast.Call) and getattr(node.func, "id", None) == "isinstance"
                    and len(node.args) == 2 and ast.unparse(node.args[1]) == "bool"):
                found.append(f"{path.relative_to(REPO)}:{node.lineno}")
    assert not found, f"use gtsp_bench.checks instead: {found}"


def test_time_limit_or_default():
    """A given limit is checked and kept; None takes the per-K default; a bad one is refused."""
    from gtsp_bench.checks import time_limit_or_default

    assert time_limit_or_default(2, 50) == 2.0
    assert time_limit_or_default(None, 50) == default_time_limit(50) == 25.0
    with pytest.raises(InputError, match="time limit must be > 0 seconds"):
        time_limit_or_default(0, 50)


def test_parse_names_strips_dedupes_and_checks():
    """Comma lists and sequences give the same names, in order, without blanks or repeats; a name
    outside valid is one line listing the valid ones."""
    from gtsp_bench.checks import parse_names

    assert parse_names(" a, b,,a ,c", "solver") == ("a", "b", "c")
    assert parse_names(["b", " a", "", "b"], "solver", ["a", "b"]) == ("b", "a")
    assert parse_names("", "solver") == ()
    with pytest.raises(InputError, match=r"^unknown solver 'x' \(valid: a, b\)$"):
        parse_names("a,x", "solver", ["a", "b"])


def test_check_log_record_checks_the_trajectory():
    """An optional trajectory must have times that never fall, objectives that never rise and
    end at the record's objective, and bounds that never fall; a record without an answer has
    an empty one at most."""
    rec = {"key": "i#ab|milp|w=0.3|seed=0|tl=10", "solver": "milp", "omega": 0.3, "seed": 0,
           "status": "optimal", "objective": 12.5, "order": [2, 0, 1], "heads": [0, 1, 0],
           "lower_bound": 12.5, "trajectory": [[0.1, 14.0, None], [0.2, 14.0, 9.0], [0.3, 12.5, 12.5]]}
    assert check_log_record(rec) is rec
    for trajectory, message in [
        ([[0.1, 12.0, None], [0.2, 12.5, None]], "objective 12.5 is not a number <= the one before"),
        ([[0.1, 13.0, 9.0], [0.2, 12.5, 8.0]], "lower bound 8.0 is not a number >= the one before"),
        ([[0.2, 13.0, None], [0.1, 12.5, None]], "time 0.1 is not a number >= the one before"),
        ([[0.1, 13.0, None]], "the trajectory ends at 13.0, not at the objective 12.5"),
        ([[0.1, 12.5]], "trajectory point 0 is not"),
        ({"t": 1}, "trajectory is not a list"),
    ]:
        with pytest.raises(InputError, match=re.escape(message)):
            check_log_record({**rec, "trajectory": trajectory})
    failed = {"key": rec["key"], "solver": "milp", "omega": 0.3, "status": "failed", "objective": None}
    assert check_log_record({**failed, "trajectory": []})
    with pytest.raises(InputError, match="a solve without an objective has a trajectory"):
        check_log_record({**failed, "trajectory": [[0.1, 12.5, None]]})


def test_strictly_better_needs_more_than_the_tolerance():
    assert strictly_better(1204.0, 1205.0)
    assert not strictly_better(1205.0, 1205.0)
    assert not strictly_better(1205.0 - 1e-7, 1205.0)  # 8e-11 relative: the same value
    assert not strictly_better(1206.0, 1205.0)
    assert not strictly_better(-5e-10, 0.0)  # an absolute tolerance near zero
    assert strictly_better(-2e-9, 0.0)

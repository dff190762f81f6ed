"""Option validation helpers and the default time limit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gtsp_bench.checks import (
    check_float,
    check_int,
    check_mapping,
    default_time_limit,
    parse_ks,
    parse_omegas,
)
from gtsp_bench.errors import InputError


def test_check_int():
    """Integers at or above the bound pass (numpy ones too); bools, floats, small values fail."""
    assert check_int("n", 3, 1) == 3 and check_int("n", np.int64(1), 1) == 1
    for bad in (0, -1, 2.0, True, "3", None):
        with pytest.raises(InputError, match="n must be an integer >= 1"):
            check_int("n", bad, 1)


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

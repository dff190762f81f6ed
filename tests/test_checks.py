"""Option validation helpers and the default time limit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gtsp_bench.checks import check_float, check_int, check_mapping, default_time_limit
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

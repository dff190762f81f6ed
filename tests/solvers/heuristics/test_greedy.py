"""The paper's greedy: a hand-traced run, feasibility, never below the optimum."""

from __future__ import annotations

import numpy as np
import pytest

from gtsp_bench.data.io import read_instance
from gtsp_bench.generator import generate_instance
from gtsp_bench.instance import Instance
from gtsp_bench.registry import run_solver
from tests.conftest import GTSPLIB
from tests.tiny_cases import not_below


def test_hand_traced_greedy():
    """Pure distance (omega = 0): from the depot, nearest head first, then nearest again."""
    inst = Instance(name="line", depot=np.array([0.0, 0.0]), clusters=(
        np.array([[100.0, 0.0], [300.0, 0.0]]),    # nearest to the depot: (100, 0)
        np.array([[50.0, 100.0], [200.0, 10.0]]),  # from (100,0): (200,10) is 100.5 m, (50,100) 111.8
        np.array([[400.0, 0.0]]),
    ))
    r = run_solver("greedy", inst, 0.0)
    assert r.order == (0, 1, 2)
    assert r.heads == (0, 1, 0)


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("omega", [0.0, 0.5, 0.9])
def test_greedy_is_feasible_and_never_below_the_optimum(seed, omega):
    """On small random instances greedy >= brute-force optimum."""
    inst = generate_instance(4, 4, seed=seed)
    g = run_solver("greedy", inst, omega)
    b = run_solver("brute", inst, omega)
    assert g.status == "feasible"
    assert not_below(g.objective, b.objective)


def test_greedy_on_gtsplib():
    """Without a depot greedy still returns a valid tour of every cluster."""
    r = run_solver("greedy", read_instance(GTSPLIB / "11berlin52.gtsp.gz"), None)
    assert sorted(r.order) == list(range(11))
    assert r.objective >= 4040  # the proven optimum

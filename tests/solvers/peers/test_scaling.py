"""Integer arc costs for the peers: exact folding of node costs, whole numbers kept, and costs
that would overflow or cannot be scaled refused in one line."""

from __future__ import annotations

import numpy as np
import pytest
from gtsp_bench.solvers.peers import scaling as peer
from gtsp_bench.solvers.peers.scaling import folded_costs

from gtsp_bench.data.io import read_instance
from gtsp_bench.errors import InputError
from gtsp_bench.generator import generate_instance
from gtsp_bench.instance import Instance
from gtsp_bench.problem import price
from tests.conftest import GTSPLIB


def test_folded_costs_price_tours_exactly():
    """Half of each end's node cost on every edge: a tour's folded sum is its cost (scaled)."""
    inst = generate_instance(5, 4, seed=0)
    problem = price(inst, 0.6)
    cost, scale = folded_costs(problem, solver="pyvrp", library="PyVRP")
    rng = np.random.default_rng(0)
    for _ in range(5):
        tour = np.array([problem.depot] + [rng.choice(c) for c in problem.clusters[:-1]])
        folded = cost[tour, np.roll(tour, -1)].sum() / scale
        assert folded == pytest.approx(problem.tour_cost(tour), rel=1e-6)
    assert cost.dtype == np.int64 and 0.9e7 <= cost.max() <= 1.1e7


def test_whole_number_costs_are_not_scaled():
    """GTSPLIB weights are integers: they are used as they are."""
    problem = price(read_instance(GTSPLIB / "11berlin52.gtsp.gz"), None)
    cost, scale = folded_costs(problem, solver="pyvrp", library="PyVRP")
    assert scale == 1.0
    assert np.array_equal(cost, problem.edge_cost.astype(np.int64))


def test_costs_that_would_overflow_the_integer_sums_are_refused(monkeypatch):
    """Costs whose integer scaling would overflow PyVRP's int64 sums, that cannot be scaled (a
    subnormal largest cost) or that are not finite give one InputError line, never a wrong tour."""
    problem = price(generate_instance(3, 2, seed=0), 0.5)
    assert folded_costs(problem, solver="pyvrp", library="PyVRP")[0].max() > 0
    monkeypatch.setattr(peer, "MAX_TOUR_UNITS", 10)
    with pytest.raises(InputError, match="would overflow PyVRP's 64-bit sums"):
        folded_costs(problem, solver="pyvrp", library="PyVRP")
    monkeypatch.undo()
    tiny = Instance(name="tiny", clusters=(np.array([[0.0, 0.0]]), np.array([[1.0, 0.0]])),
                    params=None, edge_weight_type="EXPLICIT",
                    weights=np.array([[0.0, 1e-320], [1e-320, 0.0]]))
    with pytest.raises(InputError, match="too small to scale to integers"):
        folded_costs(price(tiny, None), solver="pyvrp", library="PyVRP")
    far = Instance(name="far", clusters=(np.array([[0.0, 0.0]]), np.array([[1e308, -1e308]])),
                   params=None, edge_weight_type="EUC_2D")
    with np.errstate(over="ignore"):  # built directly: a file would be refused at load
        far_problem = price(far, None)
    with pytest.raises(InputError, match="not finite numbers"):
        folded_costs(far_problem, solver="pyvrp", library="PyVRP")

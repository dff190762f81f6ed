"""The evaluator: eq. (11), cluster ground energy, a hand-worked tour, bad solutions, batches."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from gtsp_bench.energy import (
    check_omega,
    cluster_ground_energy,
    evaluate,
    evaluate_batch,
    member_tx_energy,
    node_ground_energy,
)
from gtsp_bench.errors import InfeasibleSolutionError, InputError
from gtsp_bench.generator import generate_batch
from gtsp_bench.instance import Instance
from gtsp_bench.params import EnergyParams

P = EnergyParams()


def test_member_energy_reference_values():
    """Eq. (11): 0.6 J at 50 m (free space) and 1.44 J at 100 m (multipath), as the doc says."""
    assert member_tx_energy(50.0, P) == pytest.approx(0.6, rel=1e-9)
    assert member_tx_energy(100.0, P) == pytest.approx(1.44, rel=1e-9)
    # The regime switches at d0: just below uses eps_fs d^2, just above eps_mp d^4.
    below, above = member_tx_energy(P.d0 - 1e-6, P), member_tx_energy(P.d0 + 1e-6, P)
    assert below == pytest.approx(above, rel=1e-5)


def test_cluster_ground_energy_by_hand():
    """Three members on a line: each head's energy is its members' sends + receives + upload."""
    pts = np.array([[0.0, 0.0], [50.0, 0.0], [150.0, 0.0]])
    upload = P.p_ch_w * 2 * 8e6 / P.r_data
    rx = 2 * 0.4
    tx = {d: 8e6 * (50e-9 + (10e-12 * d**2 if d <= P.d0 else 0.0013e-12 * d**4))
          for d in (50.0, 100.0, 150.0)}
    expected = [tx[50.0] + tx[150.0], tx[50.0] + tx[100.0], tx[150.0] + tx[100.0]]
    got = cluster_ground_energy(pts, P)
    np.testing.assert_allclose(got, np.array(expected) + rx + upload, rtol=1e-12)


def test_hand_worked_tour(tiny):
    """depot -> (0,300) -> (300,0) -> depot at omega = 0.3, every part written out by hand."""
    omega = 0.3
    ev = evaluate(tiny, omega, order=[0, 1], heads=[0, 1])
    dist = 300.0 + math.hypot(300.0, 300.0) + 300.0
    per_m = (math.sqrt((0.5 * 9.81) ** 3 / (2 * math.pi * 0.2**2 * 4 * 1.225)) + 5.0) / 15.0
    t_hover = 8e6 / P.r_data  # cluster 1 has N = 2 nodes: D = 1 message; cluster 0 none
    hover = t_hover * (P.p_hover + 0.0126)
    member = 8e6 * (50e-9 + 0.0013e-12 * math.hypot(100.0, 300.0) ** 4)
    ground = member + 0.4 + P.p_ch_w * t_hover
    assert ev.distance == pytest.approx(dist, rel=1e-12)
    assert ev.energy.flight == pytest.approx(per_m * dist, rel=1e-12)
    assert ev.energy.hover == pytest.approx(hover, rel=1e-12)
    assert ev.energy.ground == pytest.approx(ground, rel=1e-12)
    total = omega * ground + (1 - omega) * (per_m * dist + hover)
    assert ev.objective == pytest.approx(total, rel=1e-12)
    assert ev.energy.total == ev.objective


def test_reversed_tour_has_the_same_energy(tiny):
    """Edge costs are symmetric: reversing the order changes nothing."""
    a = evaluate(tiny, 0.5, [0, 1], [0, 0])
    b = evaluate(tiny, 0.5, [1, 0], [0, 0])
    assert a.objective == pytest.approx(b.objective, rel=1e-12)


@pytest.mark.parametrize(
    ("order", "heads", "message"),
    [
        ([0], [0, 0], "order lists 1 clusters but the instance has 2"),
        ([0, 0], [0, 0], "cluster 0 is visited 2 times"),
        ([0, 2], [0, 0], "order names cluster 2"),
        ([0, 1], [0], "heads has 1 entries"),
        ([0, 1], [0, 2], r"heads\[1\] = 2 is not a node of cluster 1 \(it has 2 nodes\)"),
        ([0, 1], [1, 0], r"heads\[0\] = 1 is not a node of cluster 0"),
        ([0, 1], [-1, 0], r"heads\[0\] = -1"),
        ([0, 1.0], [0, 0], "order must be a list of integers"),
        ([0, 1], [0, True], "heads must be a list of integers"),
        ([0, 10**30], [0, 0], "order holds an integer far outside any index"),
        ([0, 1], [0, -(10**30)], "heads holds an integer far outside any index"),
    ],
)
def test_infeasible_solutions_are_rejected(tiny, order, heads, message):
    """Each cluster exactly once and each head a valid index, else a clear error."""
    with pytest.raises(InfeasibleSolutionError, match=message):
        evaluate(tiny, 0.5, order, heads)


@pytest.mark.parametrize("omega", [-0.1, 1.5, float("nan"), None, "0.5", True])
def test_omega_outside_unit_interval_is_rejected(tiny, omega):
    """omega must be a number in [0, 1]."""
    with pytest.raises(InputError, match="omega"):
        evaluate(tiny, omega, [0, 1], [0, 0])
    with pytest.raises(InputError, match="omega"):
        check_omega(omega)


def test_batch_evaluator_equals_single_evaluator():
    """evaluate_batch gives the same parts as evaluate on every instance of a random batch."""
    rng = np.random.default_rng(7)
    coords = generate_batch(rng, 16, 5, 6)
    depot = np.array([500.0, 0.0])
    order = np.array([rng.permutation(5) for _ in range(16)])
    heads = rng.integers(0, 6, size=(16, 5))
    omega = rng.uniform(0, 1, size=16)
    got = evaluate_batch(coords, depot, order, heads, omega)
    for i in range(16):
        inst = Instance(name=f"b{i}", clusters=tuple(coords[i]), depot=depot)
        ev = evaluate(inst, omega[i], order[i].tolist(), heads[i].tolist())
        assert got["total"][i] == pytest.approx(ev.objective, rel=1e-12)
        assert got["ground"][i] == pytest.approx(ev.energy.ground, rel=1e-12)
        assert got["flight"][i] == pytest.approx(ev.energy.flight, rel=1e-12)
        assert got["hover"][i] == pytest.approx(ev.energy.hover, rel=1e-12)
        assert got["distance"][i] == pytest.approx(ev.distance, rel=1e-12)


def test_batch_evaluator_rejects_infeasible_rows():
    """A repeated cluster or an out-of-range head in a batch is an error."""
    coords = generate_batch(np.random.default_rng(0), 2, 3, 4)
    depot = np.array([500.0, 0.0])
    with pytest.raises(InfeasibleSolutionError, match="permutation"):
        evaluate_batch(coords, depot, [[0, 1, 2], [0, 0, 2]], [[0, 0, 0]] * 2, 0.5)
    with pytest.raises(InfeasibleSolutionError, match="head index"):
        evaluate_batch(coords, depot, [[0, 1, 2]] * 2, [[0, 4, 0]] * 2, 0.5)


def test_ground_energy_depends_only_on_heads_and_is_minimal_near_the_centre():
    """At omega = 1 the optimum picks, in each cluster, the node of least ground energy."""
    inst = Instance(name="g", clusters=tuple(generate_batch(np.random.default_rng(3), 1, 3, 5)[0]),
                    depot=np.array([500.0, 0.0]))
    ground = node_ground_energy(inst)
    best = min(
        evaluate(inst, 1.0, list(o), list(h)).objective
        for o in itertools.permutations(range(3))
        for h in itertools.product(range(5), repeat=3)
    )
    per_cluster_min = sum(ground[o:o + s].min() for o, s in zip(inst.offsets, inst.sizes, strict=True))
    assert best == pytest.approx(per_cluster_min, rel=1e-12)


def test_distance_only_instance_has_no_energy():
    """For a distance-only GTSP the objective is the tour length and omega is ignored."""
    inst = Instance(name="d", clusters=(np.array([[0.0, 0.0]]), np.array([[3.0, 4.0]])),
                    params=None, edge_weight_type="EUC_2D")
    ev = evaluate(inst, None, [0, 1], [0, 0])
    assert ev.energy is None
    assert ev.objective == ev.distance == 10.0

"""The one energy evaluator: every solver's result, and the RL reward, are priced here.

Objective (paper eq. 19)::

    E = omega * ground + (1 - omega) * (flight + hover)

* ground: for each cluster k with head b_k, every other member sends l bits to b_k (eq. 11) and
  b_k receives them (l * E_elec each), then b_k uploads D_k = (N_k - 1) l bits to the UAV (E_{b_k});
* flight: P_move / v_UAV times the horizontal length of depot -> heads -> depot at height H;
* hover: E_{c_k} = D_k / r_data * (P_hover + P_com) per cluster.

For a distance-only GTSP (``instance.params is None``) the objective is the tour length and the
energy parts are ``None``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from gtsp_bench.checks import check_omega
from gtsp_bench.errors import InfeasibleSolutionError, InputError
from gtsp_bench.instance import Instance, tour_length
from gtsp_bench.params import EnergyParams


@dataclass(frozen=True)
class Energy:
    """Energy of a solution in J: the weighted total and its unweighted parts."""

    total: float
    ground: float
    flight: float
    hover: float


@dataclass(frozen=True)
class Evaluation:
    """What the evaluator says of a solution.

    Attributes
    ----------
    objective
        Weighted total energy in J (UAV instance) or tour length (distance-only GTSP).
    energy
        The parts, or ``None`` for a distance-only GTSP.
    distance
        Length of the closed tour (m for UAV instances).
    """

    objective: float
    energy: Energy | None
    distance: float


# ---------------------------------------------------------------------- ground network
def member_tx_energy(d: np.ndarray, params: EnergyParams) -> np.ndarray:
    """Energy for a member to send l bits over distance ``d`` to its head, eq. (11) (J)."""
    d = np.asarray(d, dtype=np.float64)
    amp = np.where(d <= params.d0, params.eps_fs * d**2, params.eps_mp * d**4)
    return params.message_bits * (params.e_elec + amp)


def cluster_ground_energy(points: np.ndarray, params: EnergyParams) -> np.ndarray:
    """Ground energy of a cluster for each choice of head.

    Parameters
    ----------
    points
        ``(..., N, 2)`` node coordinates of one cluster (leading axes batch over clusters of
        equal size).
    params
        Energy parameters.

    Returns
    -------
    numpy.ndarray
        ``(..., N)``: entry i is the ground energy when node i is the head: every other member's
        transmission (eq. 11) and reception (l * E_elec) plus the head's upload E_{b_k}.
    """
    points = np.asarray(points, dtype=np.float64)
    n = points.shape[-2]
    x, y = points[..., 0], points[..., 1]
    dx = x[..., :, None] - x[..., None, :]
    dy = y[..., :, None] - y[..., None, :]
    # dx**2 + dy**2 is what a sum over an axis of length 2 gives, several times faster
    tx = member_tx_energy(np.sqrt(dx**2 + dy**2), params)
    # The diagonal (a head sending to itself) costs E_elec * l although d = 0: remove it.
    tx_sum = tx.sum(axis=-1) - params.message_bits * params.e_elec
    return tx_sum + (n - 1) * params.rx_energy + params.upload_energy(n)


def node_ground_energy(instance: Instance) -> np.ndarray:
    """Ground energy of each node's cluster if that node is its head, ``(n,)`` in global order."""
    params = _require_params(instance)
    return np.concatenate([cluster_ground_energy(c, params) for c in instance.clusters])


def cluster_hover_energy(instance: Instance) -> np.ndarray:
    """UAV hovering + communication energy E_{c_k} at each cluster, ``(K,)``."""
    params = _require_params(instance)
    return np.array([params.hover_energy(int(n)) for n in instance.sizes], dtype=np.float64)


def _require_params(instance: Instance) -> EnergyParams:
    if instance.params is None:
        raise InputError(f"{instance.name} is a distance-only instance: it has no energy model")
    return instance.params


# ---------------------------------------------------------------------- evaluator
def evaluate(
    instance: Instance, omega: float | None, order: Sequence[int], heads: Sequence[int]
) -> Evaluation:
    """Check a solution and price it.

    Parameters
    ----------
    instance
        The instance.
    omega
        Weight of the ground energy in [0, 1]; ignored (may be ``None``) for a distance-only GTSP.
    order
        Cluster indices in visiting order, depot excluded, each cluster exactly once.
    heads
        ``heads[k]``: index of cluster k's head inside cluster k.

    Returns
    -------
    Evaluation

    Raises
    ------
    InfeasibleSolutionError
        When a cluster is missed or repeated, or a head index is invalid.
    InputError
        When omega is outside [0, 1] for a UAV instance.
    """
    order_arr, heads_arr = instance.check_solution(order, heads)
    distance = tour_length(instance, order_arr, heads_arr)
    if instance.params is None:
        return Evaluation(objective=distance, energy=None, distance=distance)
    w = check_omega(omega)
    nodes = instance.offsets + heads_arr
    ground = float(node_ground_energy(instance)[nodes].sum())
    hover = float(cluster_hover_energy(instance).sum())
    flight = instance.params.flight_energy_per_m * distance
    total = w * ground + (1.0 - w) * (flight + hover)
    energy = Energy(total=total, ground=ground, flight=flight, hover=hover)
    return Evaluation(objective=total, energy=energy, distance=distance)


def evaluate_batch(
    coords: np.ndarray,
    depot: np.ndarray,
    order: np.ndarray,
    heads: np.ndarray,
    omega: float | np.ndarray,
    params: EnergyParams | None = None,
    *,
    ground: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """Vectorised :func:`evaluate` for a batch of UAV instances with equal K and N.

    Parameters
    ----------
    coords
        ``(B, K, N, 2)`` node coordinates.
    depot
        ``(2,)`` or ``(B, 2)`` depot coordinates.
    order
        ``(B, K)`` visiting orders (each row a permutation of 0..K-1).
    heads
        ``(B, K)`` head index inside each cluster, indexed by cluster.
    omega
        Scalar or ``(B,)`` weights in [0, 1].
    params
        Energy parameters (defaults if ``None``).
    ground
        Optional precomputed :func:`cluster_ground_energy` of ``coords``, ``(B, K, N)``.

    Returns
    -------
    dict
        ``total``, ``ground``, ``flight``, ``hover`` and ``distance``, each ``(B,)``.

    Raises
    ------
    InfeasibleSolutionError
        If a row of ``order`` is not a permutation or a head is out of range.
    """
    params = params or EnergyParams()
    coords = np.asarray(coords, dtype=np.float64)
    b, k, n, _ = coords.shape
    order = np.asarray(order, dtype=np.int64)
    heads = np.asarray(heads, dtype=np.int64)
    if order.shape != (b, k) or heads.shape != (b, k):
        raise InfeasibleSolutionError(f"order and heads must have shape {(b, k)}")
    if not np.array_equal(np.sort(order, axis=1), np.broadcast_to(np.arange(k), (b, k))):
        raise InfeasibleSolutionError("a row of order is not a permutation of the clusters")
    if np.any((heads < 0) | (heads >= n)):
        raise InfeasibleSolutionError(f"a head index is outside 0..{n - 1}")
    w = np.asarray(omega, dtype=np.float64)
    if np.any(~((w >= 0) & (w <= 1))):
        raise InputError("omega must be in [0, 1]")
    rows = np.arange(b)[:, None]
    head_xy = coords[rows, np.arange(k)[None, :], heads]  # (B, K, 2), by cluster
    path = head_xy[rows, order]  # (B, K, 2), in visiting order
    dep = np.broadcast_to(np.asarray(depot, dtype=np.float64), (b, 2))[:, None, :]
    path = np.concatenate([dep, path, dep], axis=1)
    distance = np.sqrt(((path[:, 1:] - path[:, :-1]) ** 2).sum(axis=-1)).sum(axis=1)
    if ground is None:
        ground = cluster_ground_energy(coords, params)
    ground_total = np.take_along_axis(ground, heads[..., None], axis=2)[..., 0].sum(axis=1)
    hover = np.full(b, k * params.hover_energy(n))
    flight = params.flight_energy_per_m * distance
    total = w * ground_total + (1.0 - w) * (flight + hover)
    return {"total": total, "ground": ground_total, "flight": flight, "hover": hover,
            "distance": distance}

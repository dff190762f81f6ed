"""Optimal heads for a fixed cluster order: a shortest path through the layered graph.

For a fixed visiting order, choosing the heads is a shortest path
depot -> layer(order[0]) -> ... -> layer(order[-1]) -> depot, where crossing node v costs its node
cost and each edge its edge cost: O(K N^2). Without a depot the tour is a cycle, solved for every
start node of the smallest cluster at once. Any solver can use it to improve a tour.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from gtsp_bench.problem import Problem


def optimal_heads(problem: Problem, order: Sequence[int]) -> tuple[np.ndarray, float]:
    """The cheapest tour visiting the instance clusters in ``order``.

    Parameters
    ----------
    problem
        The priced problem.
    order
        Instance cluster indices in visiting order (the depot excluded), each once.

    Returns
    -------
    tour : numpy.ndarray
        Node ids of the tour, starting with the depot when there is one.
    cost : float
        Its cost (node costs + edge costs), as :meth:`Problem.tour_cost` computes it.
    """
    layers = [problem.clusters[int(c)] for c in order]
    if problem.depot is None and layers:  # a cycle: start at its smallest cluster (fewest starts)
        first = min(range(len(layers)), key=lambda i: len(layers[i]))
        layers = layers[first:] + layers[:first]
    edge, node = problem.edge_cost, problem.node_cost
    if problem.depot is not None:
        starts = np.array([problem.depot])
    else:
        starts, layers = layers[0], layers[1:]
    # cost[s, j]: cheapest path from start s to node j of the current layer, node costs included.
    # The current layer is first the starts themselves: s reaches only itself.
    cost = np.full((len(starts), len(starts)), np.inf)
    np.fill_diagonal(cost, node[starts])
    prev = starts
    back = []
    for layer in layers:
        step = cost[:, :, None] + edge[prev[:, None], layer[None, :]]  # (S, prev, layer)
        back.append(step.argmin(axis=1))
        cost = step.min(axis=1) + node[layer]
        prev = layer
    closing = cost + edge[starts[:, None], prev[None, :]]  # return to the start
    s, j = np.unravel_index(int(np.argmin(closing)), closing.shape)
    best = float(closing[s, j])
    path = []
    for layer_index in range(len(layers) - 1, -1, -1):
        path.append(int(layers[layer_index][j]))
        j = int(back[layer_index][s, j])
    path.append(int(starts[s]))
    return np.array(path[::-1], dtype=np.int64), best

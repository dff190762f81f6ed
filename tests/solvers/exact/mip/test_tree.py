"""The open nodes of the branch and cut: the heap order."""

from __future__ import annotations

import heapq

import numpy as np
from gtsp_bench.solvers.exact.mip.tree import Node


def test_nodes_come_off_the_heap_by_bound_then_creation():
    free = np.zeros(0, dtype=np.int8)
    heap: list[Node] = []
    for bound, seq in ((3.0, 1), (1.0, 4), (1.0, 2), (2.0, 3)):
        heapq.heappush(heap, Node(bound, seq, free))
    assert [(n.bound, n.seq) for n in (heapq.heappop(heap) for _ in range(4))] == [
        (1.0, 2), (1.0, 4), (2.0, 3), (3.0, 1)]

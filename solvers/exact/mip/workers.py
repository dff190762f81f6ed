"""The state that the branch and cut's workers share: the incumbent and the open nodes.

With ``MipOptions.workers`` above 1 the search after the root runs on that many threads, each a
worker with its own copy of the LP (:meth:`~gtsp_bench.solvers.exact.mip.backends.LpModel.copy`):
each takes the best open node (or the newest it made itself, while that one's bound is near the
best: :meth:`OpenNodes.take`), solves it, dives into a child and puts the other back, as the
single search does. HiGHS solves an LP without Python's lock, so the workers' LPs run on separate
cores; the separation and the bookkeeping between LPs hold it. They share:

* :class:`Incumbent`: the best tour, its cost and the proven bound, changed under a lock (a
  better tour found by one worker prunes the others' nodes at once);
* :class:`OpenNodes`: the heap of open nodes and the bound of the node each worker holds (the
  search's bound is the least of them), under a lock; a worker with nothing to take waits while
  another still works (its children may come);
* the pseudo-costs, the pinned columns, the root's fixings and the proof log (whose methods take
  its own lock).

Cuts stay in the LP of the worker that found them; each worker numbers its new cuts from its own
range (:data:`CUT_ID_RANGE`), so that the proof log keeps one row per id.
"""

from __future__ import annotations

import heapq
import math
import threading
from collections.abc import Callable

import numpy as np
from gtsp_bench.solvers.exact.mip.tree import Node

from gtsp_bench.solver import Progress

#: Ids of the cuts a worker adds start at its number times this (the root's cuts keep theirs).
CUT_ID_RANGE = 2**40
#: Seconds a worker without a node waits before it looks again (a child or the end may come).
WAIT_SECONDS = 0.05


class Incumbent:
    """The best tour of a search, its cost and the search's proven lower bound.

    Parameters
    ----------
    tour
        The first incumbent (problem node ids).
    cost
        Its cost.
    bound
        The first lower bound.
    progress
        Told the cost and the bound (at most the cost) after every change, under the lock.
    """

    def __init__(self, tour: np.ndarray, cost: float, bound: float, progress: Progress) -> None:
        self.lock = threading.RLock()
        self.tour, self.cost, self.bound = tour, cost, bound
        self.progress = progress

    def offer(self, tour: np.ndarray, cost: float) -> bool:
        """Take ``tour`` if it is cheaper; whether it was."""
        with self.lock:
            if cost >= self.cost:
                return False
            self.tour, self.cost = tour, cost
            self.report()
            return True

    def raise_bound(self, bound: float) -> None:
        """The bound is at least ``bound``."""
        with self.lock:
            if bound > self.bound:
                self.bound = bound

    def report(self) -> None:
        """Tell ``progress`` the cost and the bound."""
        with self.lock:
            self.progress(self.cost, min(self.bound, self.cost))


class OpenNodes:
    """The open nodes of a branch and cut, and the node each worker holds.

    Parameters
    ----------
    first
        The first node (the root's).
    """

    def __init__(self, first: Node) -> None:
        self.cond = threading.Condition()
        self.heap: list[Node] = [first]
        self.held: dict[int, float] = {}  # worker -> the bound of the node it holds
        self.seq = 0
        self.closed = False  # a worker failed or the caller was interrupted: every worker ends

    def next_seq(self) -> int:
        """A new creation number (ties of equal bounds go to the older node)."""
        with self.cond:
            self.seq += 1
            return self.seq

    def put(self, node: Node) -> None:
        """An open node."""
        with self.cond:
            heapq.heappush(self.heap, node)
            self.cond.notify()

    def hold(self, worker: int, node: Node) -> None:
        """``worker`` goes on with ``node`` (a child it dives into, or the same node)."""
        with self.cond:
            self.held[worker] = node.bound

    def take(self, worker: int, stop: Callable[[], bool],
             near: Callable[[float], float] | None = None) -> Node | None:
        """The best open node for ``worker`` (which holds none after this call until it gets one);
        ``None`` when none is left and no other worker holds one, or once ``stop()`` or
        :meth:`close`.

        With ``near``, a function of the best open bound: the newest of the nodes that ``worker``
        made (:attr:`Node.worker`) whose bound is at most ``near(best bound)``, if there is one
        (it is likely the sibling of the worker's last dive, a few column bounds from its LP),
        else the best."""
        with self.cond:
            self.held.pop(worker, None)
            while not (self.closed or stop()):
                if self.heap:
                    node = self._pop(worker, near)
                    self.held[worker] = node.bound
                    return node
                if not self.held:  # nothing open and nobody working: the tree is done
                    self.cond.notify_all()
                    return None
                self.cond.wait(WAIT_SECONDS)
            return None

    def _pop(self, worker: int, near: Callable[[float], float] | None) -> Node:
        """Remove and return the node :meth:`take` gives ``worker`` (the heap is not empty)."""
        if near is not None:
            limit = near(self.heap[0].bound)
            own = [i for i, n in enumerate(self.heap) if n.worker == worker and n.bound <= limit]
            if own:
                node = self.heap.pop(max(own, key=lambda i: self.heap[i].seq))
                heapq.heapify(self.heap)
                return node
        return heapq.heappop(self.heap)

    def top(self, default: float) -> float:
        """The best open node's bound (``default`` when none is open)."""
        with self.cond:
            return self.heap[0].bound if self.heap else default

    def bound(self) -> float:
        """The least bound of the open and the held nodes (infinite when there are none)."""
        with self.cond:
            return min(([self.heap[0].bound] if self.heap else []) + list(self.held.values()),
                       default=math.inf)

    def close(self) -> None:
        """End the search: ``take`` gives no more nodes, and workers stop at their next node."""
        with self.cond:
            self.closed = True
            self.cond.notify_all()

    def drop(self, worker: int) -> None:
        """``worker`` ends (the node it held, if any, was put back)."""
        with self.cond:
            self.held.pop(worker, None)
            self.cond.notify_all()

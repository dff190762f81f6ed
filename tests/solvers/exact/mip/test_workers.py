"""The state the branch and cut's workers share: the incumbent and the open nodes."""

from __future__ import annotations

import threading
import time

import numpy as np
from gtsp_bench.solvers.exact.mip.tree import Node
from gtsp_bench.solvers.exact.mip.workers import Incumbent, OpenNodes


def _node(bound: float, seq: int, worker: int = 0) -> Node:
    return Node(bound, seq, np.full(3, -1, dtype=np.int8), worker=worker)


def _waiting_take(tree: OpenNodes, worker: int) -> tuple[threading.Thread, list[Node | None]]:
    """``worker``'s ``take`` on a thread of its own, started and given 0.1 s; what it got."""
    got: list[Node | None] = []
    waiter = threading.Thread(target=lambda: got.append(tree.take(worker, lambda: False)))
    waiter.start()
    time.sleep(0.1)
    return waiter, got


def test_the_incumbent_takes_cheaper_tours_only_and_its_bound_only_rises():
    """A dearer or equal tour is refused; the bound never falls; ``progress`` hears the cost and
    the bound capped at the cost."""
    heard: list[tuple[float, float]] = []
    inc = Incumbent(np.array([0, 1]), 10.0, 3.0, lambda cost, bound=None: heard.append((cost, bound)))
    assert not inc.offer(np.array([1, 0]), 10.0) and inc.tour.tolist() == [0, 1]
    assert inc.offer(np.array([1, 0]), 8.0) and inc.cost == 8.0 and inc.tour.tolist() == [1, 0]
    inc.raise_bound(5.0)
    inc.raise_bound(4.0)
    assert inc.bound == 5.0
    inc.raise_bound(9.0)
    inc.report()
    assert heard == [(8.0, 3.0), (8.0, 8.0)]


def test_open_nodes_give_the_best_first_and_count_held_ones_in_the_bound():
    """Nodes come out by bound, then age; a held node's bound counts in the least bound until its
    worker takes another or ends; ``top`` sees the open ones only."""
    tree = OpenNodes(_node(1.0, 0))
    tree.put(_node(0.5, 2))
    tree.put(_node(0.5, 1))
    first = tree.take(0, lambda: False)
    assert (first.bound, first.seq) == (0.5, 1)
    assert tree.bound() == 0.5 and tree.top(99.0) == 0.5
    tree.hold(0, _node(0.7, 3))  # worker 0 dives into a child
    second = tree.take(1, lambda: False)
    assert (second.bound, second.seq) == (0.5, 2)
    assert tree.bound() == 0.5  # worker 1 holds it
    assert tree.take(1, lambda: False).bound == 1.0
    assert tree.bound() == 0.7 and tree.top(99.0) == 99.0
    tree.drop(0)
    assert tree.bound() == 1.0
    tree.drop(1)
    assert tree.bound() == float("inf")


def test_a_worker_takes_its_own_newest_node_while_near_the_best():
    """With ``near``, a worker gets the newest node it made among those with bounds up to
    ``near(best bound)``; the best one when it made none there; the heap stays in order."""
    tree = OpenNodes(_node(1.0, 0))
    for bound, seq, worker in [(1.2, 1, 1), (1.1, 2, 1), (1.3, 3, 0), (2.5, 4, 1), (1.05, 5, 0)]:
        tree.put(_node(bound, seq, worker))

    def near(best: float) -> float:
        return best + 0.5

    assert tree.take(1, lambda: False, near).seq == 2  # its newest within 1.5 (not seq 4 at 2.5)
    assert tree.take(0, lambda: False, near).seq == 5
    assert tree.take(0, lambda: False, near).seq == 3  # (the best, 1.0, is worker 0's too: older)
    assert tree.take(1, lambda: False, lambda best: best).seq == 0  # none of its own that near
    assert [tree.take(1, lambda: False).seq for _ in range(2)] == [1, 4]  # by bound without near


def test_a_worker_without_a_node_waits_for_the_children_of_another():
    """With nothing open while another worker holds a node, ``take`` waits: it gets the child that
    worker puts back; once nothing is open or held it returns ``None``, as after ``stop()``."""
    tree = OpenNodes(_node(0.0, 0))
    assert tree.take(0, lambda: False).seq == 0
    waiter, got = _waiting_take(tree, 1)
    assert not got  # still waiting: worker 0 may branch
    tree.put(_node(0.3, 1))
    waiter.join(5)
    assert got and got[0].seq == 1
    waiter, done = _waiting_take(tree, 0)  # worker 0 finds nothing open and waits ...
    assert not done
    tree.drop(1)  # ... and ends once worker 1 ends too
    waiter.join(5)
    assert done == [None]
    tree.put(_node(0.9, 2))
    assert tree.take(0, lambda: True) is None  # stopped: no node, even with one open


def test_a_closed_tree_gives_no_more_nodes_and_wakes_its_waiters():
    """After ``close`` a waiting worker gets ``None`` at once, and so does any later ``take``,
    even with nodes open."""
    tree = OpenNodes(_node(0.0, 0))
    assert tree.take(0, lambda: False).seq == 0
    waiter, got = _waiting_take(tree, 1)
    tree.close()
    waiter.join(5)
    assert got == [None]
    tree.put(_node(0.5, 1))
    assert tree.take(0, lambda: False) is None

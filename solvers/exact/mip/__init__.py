"""The exact solvers' GTSP MILP, written once for every LP/MIP library.

Formulation over the candidate heads left by :func:`gtsp_bench.solvers.exact.prune.prune_heads`
(node ``i`` in GTSP cluster ``c(i)``; the depot, when there is one, is a cluster of one node):

* ``y_i`` in {0, 1}: node ``i`` is its cluster's head; ``x_e`` in {0, 1} for every edge
  ``e = {i, j}`` with ``c(i) != c(j)`` (symmetric: one variable per edge);
* minimise ``sum_i node_cost_i y_i + sum_e edge_cost_e x_e``;
* ``Cluster(C)``: ``y(C) = 1`` for every cluster;
* ``Degree(i)``: ``x(delta(i)) = 2 y_i``;
* ``Subtour(S, C, D)``, added as cuts: ``x(delta(S)) >= 2 (y(S & C) + y(D - S) - 1)`` for any
  node set ``S`` and clusters ``C != D`` (when ``S`` misses the whole of ``D``:
  ``x(delta(S)) >= 2 y(S & C)``). With the degree rows it is written over the edges inside the
  smaller of the two sides (fewer nonzeros): ``x(E(S)) <= y(S - C) + y(S & D)`` or
  ``x(E(T)) <= y(T) + y(T & C) - y(T & D)`` with ``T = V - S``. Every cut is thus
  ``x(E(side)) + sum_i a_i y_i <= b``: a :class:`~gtsp_bench.solvers.exact.mip.separation.Cuts`
  block stores ``side``, ``a`` and ``b``.

A tour through three or fewer clusters needs no model: one cyclic order exists, and
:func:`gtsp_bench.solvers.heads.optimal_heads` gives its optimal heads (one cluster: a single
node; two: an edge used twice).

:func:`~gtsp_bench.solvers.exact.mip.solve.solve_exact` runs the method on any
:class:`~gtsp_bench.solvers.exact.mip.backends.Backend` (a thin LP/MIP wrapper that knows nothing
of the GTSP):

1. an upper bound from the large neighbourhood search
   :class:`gtsp_bench.solvers.heuristics.lns.Lns` (one trial);
2. exact pruning of candidate heads;
3. a root loop on the LP relaxation over a core of cheap edges: columns of negative reduced cost
   are priced in, columns whose reduced cost exceeds the gap to the upper bound are fixed to 0,
   and violated cuts are separated at the fractional solution: node-cluster rows
   ``x(i : D) <= y_i`` by enumeration, generalized subtour cuts by one max-flow per cluster on
   the support graph (exact for that cluster and a source cluster), and blossoms of the tour
   over the clusters (handles grown along its fractional part); slack cuts are purged;
4. unless the root proved the upper bound optimal, LNS restarts with other seeds (a small share
   of the time limit) and, after a better tour, the root loop again; then branch and cut with
   the backend as LP solver: best first with bounded dives, the same cuts, pricing and
   reduced-cost fixing at every node, strong branching on ``y`` first (reliability branching
   once the strong-branching LPs mostly stop at their cap; a child shown empty fixes the column
   at the node instead), by two workers where two cores are free (``workers``: threads taking
   the best open nodes, each with its own LP). A backend with lazy constraints (Gurobi) solves
   the MILP itself instead, over every column not fixed, adding subtour rows from a callback.

Branching ourselves replaced re-solving HiGHS's MILP after each subtour solution: on a K = 20
instance whose root gap stayed open, HiGHS spent 110 s on 3 nodes without finishing (it can
neither separate subtours inside its search nor take lazy rows in highspy 1.15.1), where the
branch and cut here proves it in about 20 s.

Modules, each importing only the ones above it:

* :mod:`~gtsp_bench.solvers.exact.mip.options`: :class:`MipOptions` (the solvers' shared options),
  the upper-bound tour and its restarts;
* :mod:`~gtsp_bench.solvers.exact.mip.model`: the numerical tolerances, :class:`GtspModel` (columns,
  base rows, cycles and tour of an integer point), :func:`build_model`, the core columns;
* :mod:`~gtsp_bench.solvers.exact.mip.flow`: the compiled max-flow and residual reachability
  (numba) under the generalized subtour separation;
* :mod:`~gtsp_bench.solvers.exact.mip.separation`: :class:`Cuts` and the separators (subtour
  rows of an integer point, generalized subtour cuts by max-flow, node-cluster rows, blossoms,
  :func:`separate`);
* :mod:`~gtsp_bench.solvers.exact.mip.backends`: LP/MIP results, the ``Backend`` and
  ``LazyMipBackend`` protocols, :class:`LpModel` (the model held in a backend) and the HiGHS and
  Gurobi backends (highspy and gurobipy are imported when a backend is built, never on import);
* :mod:`~gtsp_bench.solvers.exact.mip.branching`: pseudo-costs and reliability branching
  (:class:`PseudoCosts`, :func:`choose`), independent of the backend;
* :mod:`~gtsp_bench.solvers.exact.mip.tree`: the open nodes (column fixes per model column);
* :mod:`~gtsp_bench.solvers.exact.mip.workers`: the incumbent and the open nodes that the branch
  and cut's workers share (each thread with its own copy of the LP);
* :mod:`~gtsp_bench.solvers.exact.mip.columns`: columns leaving the node LPs once their reduced
  cost has stayed large, and the column bounds that move the LP from one node to another;
* :mod:`~gtsp_bench.solvers.exact.mip.certify`: the proof log and the certificate it becomes;
* :mod:`~gtsp_bench.solvers.exact.mip.tree_search`: the branch and cut after the root, on one
  worker or more;
* :mod:`~gtsp_bench.solvers.exact.mip.branch_cut`: the search's state, its root loop and the
  backend's lazy MILP;
* :mod:`~gtsp_bench.solvers.exact.mip.solve`: :func:`solve_exact` and :class:`MipSolver`, the base
  of the ``milp`` and ``gurobi`` solvers (:mod:`gtsp_bench.solvers.exact.milp`,
  :mod:`gtsp_bench.solvers.exact.gurobi`).
"""

"""Built-in solvers, grouped by kind: ``exact/``, ``heuristics/``, ``learned/``, ``peers/``.

This folder is installed as ``gtsp_bench.solvers``. Adding a built-in solver is one class in a file
under it plus one line in :data:`BUILTIN` below. Targets are ``"module:Class"`` strings so that a
solver's heavy imports (torch, highspy, ortools, ...) happen only when it is used; this module
imports nothing of the project, so the registry can read it without an import cycle. Solvers from
other packages register through the ``gtsp_bench.solvers`` entry-point group instead (see
``docs/adding-a-solver.md``).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Builtin:
    """One built-in solver: its name, ``"module:Class"``, a one-line description, and whether
    the runner uses it by default (``False`` for test oracles, duplicates and optional extras)."""

    name: str
    target: str
    description: str
    bench: bool = True


_H = "gtsp_bench.solvers.heuristics"
_E = "gtsp_bench.solvers.exact"
_L = "gtsp_bench.solvers.learned"
_P = "gtsp_bench.solvers.peers"

BUILTIN: tuple[Builtin, ...] = (
    Builtin("greedy", f"{_H}.greedy:Greedy",
            "paper's greedy: next (cluster, head) with the least added weighted energy"),
    Builtin("greedy+ls", f"{_H}.local_search:GreedyLS",
            "greedy, then the shared 2-opt/or-opt/heads local search"),
    Builtin("greedy+ils", f"{_H}.ils:GreedyILS",
            "greedy, then double-bridge kicks + lns's local search for 0.01 s x K (learned control)",
            bench=False),
    Builtin("aco", f"{_H}.aco:Aco",
            "paper's ACO baseline (Yang et al. 2008 ant system; 30 ants, 200 iterations)"),
    Builtin("aco+ls", f"{_H}.aco:AcoLS", "aco, then the shared 2-opt/or-opt/heads local search"),
    Builtin("lns", f"{_H}.lns:Lns",
            "GLNS-style large neighbourhood search + local search (seeded, time-limited)"),
    Builtin("brute", f"{_E}.brute:Brute",
            "exhaustive search over orders and heads (exact; tiny instances only)", bench=False),
    Builtin("dp", f"{_E}.dp:DynamicProgramming",
            "Held-Karp DP over (visited clusters, last node): exact, fast up to K ~ 12", bench=False),
    Builtin("milp", f"{_E}.milp:Milp",
            "HiGHS MILP: lifted subtour cuts, pricing, own branch and cut (exact; the reference)",
            bench=False),
    Builtin("milp-textbook", f"{_E}.textbook:MilpTextbook",
            "the hand-written MILP (DFJ, MTZ or flow) in cvxpy, solved whole by HiGHS/Gurobi", bench=False),
    Builtin("gurobi", f"{_E}.gurobi:Gurobi",
            "the milp model through gurobipy, lazy subtour rows (exact; optional extra)", bench=False),
    Builtin("drl", f"{_L}.solver:DRL",
            "paper's Seq2Seq pointer policy (LSTM decoder), greedy, paper's head rule"),
    Builtin("drl-sample", f"{_L}.solver:DRLSample",
            "paper's policy: best of the greedy and 64 sampled tours", bench=False),
    Builtin("am", f"{_L}.solver:AM",
            "attention model, best of K greedy POMO starts, optimal heads for the order"),
    Builtin("local", f"{_L}.local_solver:Local",
            "local-view policy re-encoded each step (imitation of lns), greedy; -p starts=S rotated views"),
    Builtin("local-search", f"{_L}.search:LocalSearchSolver",
            "local-view policy as a search: multi-start, 2-opt/or-opt, segments re-decoded by the "
            "policy, then kicks (0.01 s x K)", bench=False),
    Builtin("pyvrp", f"{_P}.pyvrp:PyVRPPeer",
            "PyVRP 0.14 as a peer: one-vehicle VRP with mutually exclusive client groups",
            bench=False),
    Builtin("ortools", f"{_P}.ortools:OrToolsPeer",
            "OR-Tools routing as a peer: one vehicle, a mandatory disjunction per cluster, GLS",
            bench=False),
    Builtin("lkh", f"{_P}.lkh:LKH",
            "LKH-3 (elkai) as a peer on the Noon-Bean ATSP of the GTSP (optional extra)", bench=False),
)

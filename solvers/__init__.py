"""Built-in solvers, one module each. Registering one is one line below.

Targets are ``"module:Class"`` strings so that a solver's heavy imports (torch, highspy,
ortools, ...) happen only when it is used. To add your own, see the README ("Adding a solver").
"""

from gtsp_bench.registry import register_solver

register_solver("greedy", "solvers.greedy:Greedy",
                "paper's greedy: next (cluster, head) with the least added weighted energy")
register_solver("brute", "solvers.brute:Brute",
                "exhaustive search over orders and heads (exact; tiny instances only)", bench=False)
register_solver("dp", "solvers.dp:DynamicProgramming",
                "Held-Karp DP over (visited clusters, last node): exact, fast up to K ~ 12",
                bench=False)
register_solver("aco", "solvers.aco:Aco",
                "paper's ACO baseline (Yang et al. 2008 ant system; 30 ants, 200 iterations)")
register_solver("aco+ls", "solvers.aco:AcoLS", "aco, then the shared 2-opt/or-opt/heads local search")
register_solver("greedy+ls", "solvers.local_search:GreedyLS",
                "greedy, then the shared 2-opt/or-opt/heads local search")
register_solver("lns", "solvers.lns:Lns",
                "GLNS-style large neighbourhood search + local search (seeded, time-limited)")
register_solver("pyvrp", "solvers.pyvrp_peer:PyVRPPeer",
                "PyVRP 0.14 as a peer: one-vehicle VRP with mutually exclusive client groups",
                bench=False)
register_solver("drl", "solvers.drl:DRL",
                "paper's Seq2Seq pointer policy (LSTM decoder), greedy, paper's head rule")
register_solver("drl-sample", "solvers.drl:DRLSample",
                "paper's policy: best of the greedy and 64 sampled tours", bench=False)
register_solver("am", "solvers.am:AM",
                "attention model, best of K greedy POMO starts, optimal heads for the order")
register_solver("milp", "solvers.milp:Milp",
                "HiGHS MILP: lifted subtour cuts, pricing, own branch and cut (exact; the reference)",
                bench=False)
register_solver("gurobi", "solvers.gurobi:Gurobi",
                "the milp model through gurobipy, lazy subtour rows (exact; optional extra)",
                bench=False)

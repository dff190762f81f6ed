"""Exact solvers: brute force, Held-Karp DP, and the MILP (HiGHS or Gurobi backend)."""

"""Heuristics: the paper's greedy and ACO, the shared local search, and LNS."""

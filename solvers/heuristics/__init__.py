"""Heuristics: the paper's greedy and ACO, the shared local search, and LNS."""

from pathlib import Path

from gtsp_bench.solvers.heuristics.kernel_cache import clear_stale

clear_stale(Path(__file__).parent)  # before any cached lns kernel loads (see kernel_cache)

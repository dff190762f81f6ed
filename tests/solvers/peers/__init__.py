"""Tests of gtsp_bench.solvers.peers."""

"""Tests of gtsp_bench.solvers.learned."""

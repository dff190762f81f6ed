"""Tests of gtsp_bench.solvers.exact.mip."""

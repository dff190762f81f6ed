"""Tests of gtsp_bench.solvers."""

"""Tests of gtsp_bench.report."""

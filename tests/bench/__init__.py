"""Tests of gtsp_bench.bench."""

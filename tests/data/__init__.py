"""Tests of gtsp_bench.data."""

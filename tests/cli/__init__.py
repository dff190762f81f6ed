"""Tests of gtsp_bench.cli."""

"""Benchmarks: their definitions, the engine that runs them, and the machinery under it (tasks,
the task log, worker processes, executors, rows)."""

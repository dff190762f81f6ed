"""Exceptions of gtsp-bench.

:class:`InputError` is bad input from a user (a file, a parameter, a solution): the CLI prints its
message on one line and exits with code 2. :class:`SolverError` is a solver that misbehaved (an
infeasible tour, a claimed objective the evaluator does not confirm).
:class:`OneLineParser` is the argument parser of every command line of the project.
"""

from __future__ import annotations

import argparse


class InputError(ValueError):
    """Bad user input; the message is one line and names the file or option when there is one."""


class InfeasibleSolutionError(InputError):
    """A solution that does not visit every cluster exactly once with a valid head."""


class SolverError(RuntimeError):
    """A solver returned something the evaluator rejects, or failed outright."""


class OneLineParser(argparse.ArgumentParser):
    """argparse whose bad-argument message is the project's one line, ``gtsp-bench: error: ...``,
    with exit code 2 (the CLI, its sub-commands and the ``python -m`` benchmark tools)."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"gtsp-bench: error: {message}\n")

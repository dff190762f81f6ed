"""Exceptions of gtsp-bench.

:class:`InputError` is bad input from a user (a file, a parameter, a solution): the CLI prints its
message on one line and exits with code 2. :class:`SolverError` is a solver that misbehaved (an
infeasible tour, a claimed objective the evaluator does not confirm).
"""

from __future__ import annotations


class InputError(ValueError):
    """Bad user input; the message is one line and names the file or option when there is one."""


class InfeasibleSolutionError(InputError):
    """A solution that does not visit every cluster exactly once with a valid head."""


class SolverError(RuntimeError):
    """A solver returned something the evaluator rejects, or failed outright."""

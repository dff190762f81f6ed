"""gtsp-bench: a benchmark suite and solver library for UAV data collection as a GTSP.

The public API needs numpy only (no torch):

>>> from gtsp_bench import generate_instance, run_solver
>>> result = run_solver("greedy", generate_instance(4, seed=1), omega=0.5)
"""

from gtsp_bench.data.io import read_instance, read_solution, write_instance
from gtsp_bench.energy import Energy, Evaluation, evaluate, evaluate_batch
from gtsp_bench.errors import InfeasibleSolutionError, InputError, SolverError
from gtsp_bench.generator import generate_batch, generate_instance
from gtsp_bench.instance import Instance
from gtsp_bench.params import EnergyParams
from gtsp_bench.problem import Problem, price
from gtsp_bench.registry import get_solver, register_solver, run_solver, solver_names
from gtsp_bench.solver import BatchSolver, Progress, Result, Solution, Solver, TrajectoryPoint

__version__ = "0.1.0"

__all__ = [
    "BatchSolver",
    "Energy",
    "EnergyParams",
    "Evaluation",
    "InfeasibleSolutionError",
    "InputError",
    "Instance",
    "Problem",
    "Progress",
    "Result",
    "Solution",
    "Solver",
    "SolverError",
    "TrajectoryPoint",
    "evaluate",
    "evaluate_batch",
    "generate_batch",
    "generate_instance",
    "get_solver",
    "price",
    "read_instance",
    "read_solution",
    "register_solver",
    "run_solver",
    "solver_names",
    "write_instance",
]

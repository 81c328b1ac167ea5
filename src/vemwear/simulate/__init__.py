"""The time loop of the fully discrete scheme and its inputs and outputs."""

from .loop import Result, SolverOptions, simulate
from .problem import Discretization, Problem
from .timegrid import TimeGrid

__all__ = ["Discretization", "Problem", "Result", "SolverOptions", "TimeGrid", "simulate"]

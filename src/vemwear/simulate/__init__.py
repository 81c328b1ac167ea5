"""The time loop of the fully discrete scheme and its inputs and outputs."""

from ..contact.parts import ContactPart
from .constraints import Prescribed
from .discrete import Discretization
from .loop import Result, SolverOptions, simulate
from .problem import Problem
from .rigidparts import RigidPart
from .timegrid import TimeGrid

__all__ = [
    "ContactPart",
    "Discretization",
    "Prescribed",
    "Problem",
    "Result",
    "RigidPart",
    "SolverOptions",
    "TimeGrid",
    "simulate",
]

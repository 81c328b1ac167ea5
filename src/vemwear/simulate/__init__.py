"""The time loop of the fully discrete scheme and its inputs and outputs."""

from ..contact.parts import ContactPart
from .adapt import AdaptiveStep, adapt
from .adaptive_time import Segment, simulate_adaptive
from .constraints import Prescribed
from .discrete import Discretization
from .estimate import Estimate, estimate
from .loop import Result, SolverOptions, simulate
from .problem import Problem
from .rigidparts import RigidPart
from .timegrid import TimeGrid

__all__ = [
    "AdaptiveStep",
    "ContactPart",
    "Discretization",
    "Estimate",
    "Prescribed",
    "Problem",
    "Result",
    "RigidPart",
    "Segment",
    "SolverOptions",
    "TimeGrid",
    "adapt",
    "estimate",
    "simulate",
    "simulate_adaptive",
]

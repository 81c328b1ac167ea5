"""The time loop of the fully discrete scheme and its inputs and outputs.

The adaptive runs in time (:func:`simulate_adaptive`) are imported on first use: a run
on one mesh does not load them.
"""

from typing import TYPE_CHECKING

from ..contact.parts import ContactPart
from ..util.lazy import lazy_names
from .adapt import AdaptiveStep, adapt
from .constraints import Prescribed
from .discrete import Discretization
from .estimate import Estimate, estimate
from .loop import Result, SolverOptions, simulate
from .problem import Problem
from .rigidparts import RigidPart
from .timegrid import TimeGrid

if TYPE_CHECKING:
    from .adaptive_time import Segment, simulate_adaptive

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

#: The names of the adaptive runs in time -> their module (imported on first use).
_LAZY = {"Segment": ".adaptive_time", "simulate_adaptive": ".adaptive_time"}

__getattr__, __dir__ = lazy_names(__name__, _LAZY)

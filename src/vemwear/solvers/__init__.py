"""Solvers of the step problem: condensed and full semismooth Newton, Uzawa."""

from .linalg import BACKENDS, factorize, resolve_backend
from .newton import CondensedNewton, FullNewton, NewtonOptions
from .system import (
    ContactSystem,
    ConvergenceError,
    StepData,
    StepSolution,
    kkt_residuals,
)
from .uzawa import Uzawa, UzawaOptions

SOLVERS = {"newton": CondensedNewton, "newton-full": FullNewton, "uzawa": Uzawa}

__all__ = [
    "BACKENDS",
    "SOLVERS",
    "CondensedNewton",
    "ContactSystem",
    "ConvergenceError",
    "FullNewton",
    "NewtonOptions",
    "StepData",
    "StepSolution",
    "Uzawa",
    "UzawaOptions",
    "factorize",
    "kkt_residuals",
    "resolve_backend",
]

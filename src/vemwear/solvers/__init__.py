"""Solvers of the step problem: condensed and full semismooth Newton, Uzawa."""

from .backends import (
    BACKENDS,
    available_backends,
    factorize,
    resolve_backend,
    schur_factorize,
)
from .full import FullNewton
from .newton import CondensedNewton, NewtonOptions
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
    "available_backends",
    "factorize",
    "kkt_residuals",
    "resolve_backend",
    "schur_factorize",
]

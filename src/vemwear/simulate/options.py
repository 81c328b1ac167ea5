"""The options of the step solver (:class:`SolverOptions`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..solvers import SOLVERS, NewtonOptions, UzawaOptions

__all__ = ["SolverOptions"]


@dataclass(frozen=True)
class SolverOptions:
    """Which solver and how tightly.

    Parameters
    ----------
    method : {"newton", "newton-full", "uzawa"}
        ``newton``: semismooth Newton condensed on Gamma_C, one factorization of K
        for the whole run (default). ``newton-full``: Newton on all dofs, a new
        factorization per iteration (the plain path). ``uzawa``: the paper's
        Uzawa iteration with two multipliers.
    tol : float
        Bound on the scaled KKT residuals of every step.
    max_iter : int or None
        Iteration limit per step (default: 100 for Newton, 200000 for Uzawa).
    backend : {"auto", "scipy", "pardiso", "petsc"}
        Sparse direct solver (``petsc``: MUMPS over the ranks of an MPI job, for the
        condensed ``newton`` only).
    """

    method: str = "newton"
    tol: float = 1e-10
    max_iter: int | None = None
    backend: str = "auto"

    def __post_init__(self) -> None:
        if self.method not in SOLVERS:
            raise ValueError(
                f"solver: unknown method {self.method!r}; expected one of {list(SOLVERS)}"
            )
        if self.backend == "petsc" and self.method != "newton":
            raise ValueError(
                f"solver: the petsc backend runs the condensed method 'newton' only, not "
                f"{self.method!r}"
            )
        if not (self.tol > 0):
            raise ValueError(f"solver: tol must be positive, got {self.tol}")
        if self.max_iter is not None and self.max_iter < 1:
            raise ValueError(f"solver: max_iter must be >= 1, got {self.max_iter}")

    def build(self, system):
        cls = SOLVERS[self.method]
        kw: dict[str, Any] = {"tol": self.tol, "backend": self.backend}
        if self.max_iter is not None:
            kw["max_iter"] = self.max_iter
        if self.method == "uzawa":
            return cls(system, UzawaOptions(**kw))
        return cls(system, NewtonOptions(**kw))

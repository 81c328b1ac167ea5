"""The seam between the time loop and the step solvers: what a step solver offers.

:class:`StepSolver` is what every solver of :data:`vemwear.solvers.SOLVERS` gives the
time loop (:func:`vemwear.simulate.levels.run_levels`); :class:`BatchStepSolver` adds
what the condensed Newton offers besides: the displacements of many levels recovered
in one block solve, and the prediction of runs of levels on one piece. The loop asks
``batch`` and ``predicts`` instead of probing the solver's attributes.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Protocol, runtime_checkable

from numpy.typing import NDArray

from .system import StepData, StepSolution

__all__ = ["BatchStepSolver", "StepSolver"]


@runtime_checkable
class StepSolver(Protocol):
    """A solver of the step problem (3.21) of one time level."""

    method: str

    def solve(
        self, step: StepData, guess: StepSolution | None = None, recover: bool = True
    ) -> StepSolution:
        """The solution of ``step`` from ``guess``; with ``recover``, also ``u``."""
        ...

    @property
    def batch(self) -> bool:
        """Whether the solver is a :class:`BatchStepSolver`."""
        ...

    @property
    def predicts(self) -> bool:
        """Whether :meth:`BatchStepSolver.predict` pays for this problem."""
        ...

    @property
    def setup_timings(self) -> dict[str, float]:
        """Wall times of the set-up's parts (ordering, factorization, ...), or empty."""
        ...


class BatchStepSolver(StepSolver, Protocol):
    """A step solver that recovers many levels' displacements in one block solve and
    predicts runs of levels on one piece of the step problem."""

    def recover_many(
        self,
        steps: list[StepData],
        p_rigids: list[NDArray[Any]],
        p_softs: list[NDArray[Any]],
        out: NDArray[Any] | None = None,
        ys: list[NDArray[Any]] | None = None,
    ) -> NDArray[Any]:
        """The displacements of several levels, one block solve (columns); ``ys``, the
        levels' normal displacements, give the rigid amplitudes under load control."""
        ...

    def displacement_scales(
        self,
        steps: list[StepData],
        ys: list[NDArray[Any]],
        p_rigids: list[NDArray[Any]],
        p_softs: list[NDArray[Any]],
    ) -> NDArray[Any]:
        """The scale of the normal displacements of each level's certificate."""
        ...

    def predict(
        self,
        guess: StepSolution,
        step: StepData,
        advance: Callable[[NDArray[Any]], NDArray[Any] | None],
        limit: int,
        times: Sequence[float] | NDArray[Any],
    ) -> list[tuple[StepData, StepSolution]]:
        """Levels from ``step`` on, on one piece of the step problem, certified."""
        ...

"""Where the time loop puts finished levels, and the state a run resumes from.

The loop (:func:`vemwear.simulate.loop.run_levels`) keeps no arrays over the time
levels: it hands every finished level to a :class:`LevelSink` and forgets it, so its
memory does not grow with the number of levels. :func:`vemwear.simulate.simulate`
uses an in-memory sink that builds a :class:`~vemwear.simulate.Result`; a run of
the command line streams the levels into an HDF5 file (:mod:`vemwear.post.stream`).

A :class:`LoopState` is all the loop needs to go on from a level exactly as an
uninterrupted run would, bitwise: the wear of the next level, the warm start (the last
step's solution), and the levels whose displacement is still waiting for its block of
back-substitutions. :func:`state_arrays` and :func:`state_from_arrays` turn it into
plain arrays for a checkpoint file and back.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from ..solvers import StepSolution

__all__ = ["LevelSink", "LoopState", "StoragePlan", "state_arrays", "state_from_arrays"]


@dataclass(frozen=True)
class StoragePlan:
    """Which levels a run keeps.

    Parameters
    ----------
    n_levels : int
        L, the number of time levels.
    levels : (K,) ndarray of int
        The levels whose contact arrays are kept (increasing; they include the final
        level and every level of ``u_levels``).
    u_levels : (S,) ndarray of int
        The levels whose full displacement is recovered and kept (increasing).
    """

    n_levels: int
    levels: NDArray[np.int64]
    u_levels: NDArray[np.int64]

    @classmethod
    def make(cls, n_levels: int, u_levels: Any, every: int = 1) -> StoragePlan:
        """Contact arrays every ``every``-th level, at the final one and at ``u_levels``."""
        if int(every) < 1:
            raise ValueError(f"every must be >= 1, got {every}")
        L = int(n_levels)
        u = np.unique(np.asarray(u_levels, dtype=np.int64))
        if u.size and (u[0] < 0 or u[-1] >= L):
            raise ValueError(f"displacement levels outside 0 .. {L - 1}")
        base = np.arange(0, L, int(every), dtype=np.int64)
        levels = np.union1d(np.union1d(base, u), [L - 1]).astype(np.int64)
        return cls(L, levels, u)

    def slots(self) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        """``(row, slot)``: for each level its row among ``levels`` and its slot among
        ``u_levels``, -1 where it has none."""
        row = -np.ones(self.n_levels, dtype=np.int64)
        row[self.levels] = np.arange(len(self.levels))
        slot = -np.ones(self.n_levels, dtype=np.int64)
        slot[self.u_levels] = np.arange(len(self.u_levels))
        return row, slot


@dataclass
class Pending:
    """A finished level whose displacement waits for its block of back-substitutions."""

    level: int
    w: NDArray[np.float64]
    solution: StepSolution


@dataclass
class LoopState:
    """Where a run stands after ``completed`` levels (enough to go on bitwise).

    Parameters
    ----------
    completed : int
        Number of finished levels (their contact arrays are final).
    w : (m,) ndarray
        The wear ``w^n`` of level ``n = completed`` (3.22).
    guess : StepSolution or None
        The solution of the last finished level, the warm start of the next one.
    pending : list of Pending
        Finished levels whose displacement is not recovered yet.
    """

    completed: int
    w: NDArray[np.float64]
    guess: StepSolution | None = None
    pending: list[Pending] = field(default_factory=list)

    @property
    def complete_upto(self) -> int:
        """Levels below this one are complete, displacements included."""
        return min([self.completed, *(p.level for p in self.pending)])


class LevelSink(Protocol):
    """Receives the finished levels of a run."""

    def level(self, n: int, w: NDArray[np.float64], solution: StepSolution) -> None:
        """Level ``n`` is solved: wear ``w`` (= w^n) and the step's solution."""

    def displacement(
        self, n: int, u: NDArray[np.float64], residuals: NDArray[np.float64] | None
    ) -> None:
        """The displacement ``u`` (n_points, 2) of level ``n`` and its KKT residuals
        (None: those the level was handed over with still hold)."""

    def checkpoint(self, state: LoopState) -> None:
        """Make every level handed over so far durable together with ``state``."""


# A sink may also have ``dofs(n, u)`` (every dof of a higher-order space) and
# ``displacement_rows(levels)``: the (k, n_dofs) array where it keeps the displacements
# of these stored levels, for the loop to write them in place (or None), before it
# hands each row over by ``displacement`` as usual.


_SOLUTION = ("u_nu", "p_rigid", "p_soft")


def state_arrays(state: LoopState) -> dict[str, NDArray[Any]]:
    """Plain arrays of a state (for ``numpy.savez``)."""
    m = len(state.w)

    def rows(values: list[Any]) -> NDArray[np.float64]:
        return np.array(values, dtype=np.float64).reshape(len(values), m)

    out: dict[str, NDArray[Any]] = {
        "completed": np.array(state.completed, dtype=np.int64),
        "w": np.asarray(state.w),
        "has_guess": np.array(state.guess is not None),
        "pending_levels": np.array([p.level for p in state.pending], dtype=np.int64),
        "pending_w": rows([p.w for p in state.pending]),
        "pending_iterations": np.array(
            [p.solution.iterations for p in state.pending], dtype=np.int64
        ),
    }
    for name in _SOLUTION:
        out[f"pending_{name}"] = rows([getattr(p.solution, name) for p in state.pending])
    g = state.guess
    if g is not None:
        for name in _SOLUTION:
            out[f"guess_{name}"] = np.asarray(getattr(g, name))
        out["guess_iterations"] = np.array(g.iterations, dtype=np.int64)
        if g.u is not None:
            out["guess_u"] = np.asarray(g.u)
    return out


def state_from_arrays(data: Any) -> LoopState:
    """The state saved by :func:`state_arrays` (a mapping of arrays, e.g. an npz file)."""

    def solution(prefix: str, i: int | None = None) -> StepSolution:
        def get(name: str) -> NDArray[np.float64]:
            a = np.array(data[f"{prefix}{name}"])
            return a if i is None else a[i].copy()

        u = None
        if i is None and "guess_u" in data:
            u = np.array(data["guess_u"])
        its = np.array(data[f"{prefix}iterations"])
        return StepSolution(
            u=u,
            u_nu=get("u_nu"),
            p_rigid=get("p_rigid"),
            p_soft=get("p_soft"),
            iterations=int(its if i is None else its[i]),
            residuals={},
        )

    levels = np.array(data["pending_levels"], dtype=np.int64)
    pending_w = np.array(data["pending_w"])
    pending = [
        Pending(int(lv), pending_w[i].copy(), solution("pending_", i))
        for i, lv in enumerate(levels)
    ]
    return LoopState(
        completed=int(data["completed"]),
        w=np.array(data["w"]),
        guess=solution("guess_") if bool(data["has_guess"]) else None,
        pending=pending,
    )

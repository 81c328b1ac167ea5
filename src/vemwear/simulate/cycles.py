"""Long fretting histories by cycle jumps (docs/method.md, section 6d).

For a periodic loading (the foundation velocity, the loads and the prescribed
displacements repeat with the period P), the state at the start of a cycle is the wear
alone: the step problems are quasistatic. A cycle jump computes one cycle with the
scheme (3.21)-(3.23) from the wear ``w_c`` at its start, giving the wear increment of
that cycle ``f_c = w_{c+1} - w_c``, and extrapolates the increments of the next
``J - 1`` cycles from the two last computed ones (a second-order rule in the cycle
number, like Adams-Bashforth): with ``s = (f_c - f_b) / (c - b)`` the change of the
increment per cycle since the previously computed cycle b,

    w_{c+J} = w_{c+1} + (J - 1) f_c + s (J - 1) J / 2

(the first jump, with no earlier cycle, uses ``s = 0``). The jump is controlled: it is
shortened so that the extrapolated increment stays below ``max_increment`` times the
layer thickness g at every node, and the last jump ends at the requested number of
cycles. With J = 1 every cycle is computed and the result is that of the whole history
computed at once (to round-off in the periodic data).

The time grid of the problem is one cycle, ``[0, P]``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from .loop import Result
    from .options import SolverOptions
    from .problem import Problem

__all__ = ["CycleJump", "CycleResult", "simulate_cycles"]


@dataclass(frozen=True)
class CycleJump:
    """The cycles of a long history and how far to extrapolate.

    Parameters
    ----------
    cycles : int
        Number of load cycles N (>= 1).
    jump : int
        Cycles advanced per computed cycle J (1: every cycle is computed).
    max_increment : float
        Largest extrapolated wear increment per jump, as a fraction of g at each node.
    """

    cycles: int
    jump: int = 1
    max_increment: float = 0.05

    def __post_init__(self) -> None:
        if int(self.cycles) != self.cycles or self.cycles < 1:
            raise ValueError(f"cycles must be an integer >= 1, got {self.cycles}")
        if int(self.jump) != self.jump or self.jump < 1:
            raise ValueError(f"jump must be an integer >= 1, got {self.jump}")
        if not (0 < self.max_increment <= 1):
            raise ValueError(f"max_increment must be in (0, 1], got {self.max_increment}")


@dataclass
class CycleResult:
    """The wear over a long history.

    Attributes
    ----------
    cycle : (B + 1,) int array
        The cycle numbers at which the wear is known: 0, then after every jump.
    computed : (B,) int array
        The cycles that were computed (each followed by a jump).
    wear : (B + 1, m) array
        The wear at the contact nodes at the start of cycle ``cycle[i]``.
    last : Result
        The last computed cycle, every level of it.
    seconds : float
        Wall time.
    """

    cycle: NDArray[np.int64]
    computed: NDArray[np.int64]
    wear: NDArray[np.float64]
    last: Result
    seconds: float = 0.0
    jumps: list[int] = field(default_factory=list)


def simulate_cycles(
    problem: Problem,
    cycles: CycleJump,
    solver: SolverOptions | str = "newton",
    *,
    progress: bool = False,
) -> CycleResult:
    """Run ``cycles.cycles`` load cycles of ``problem`` (whose time grid is one cycle),
    computing one cycle in every ``cycles.jump`` and extrapolating the wear between.

    Returns
    -------
    CycleResult
    """
    from .loop import simulate

    t0 = time.perf_counter()
    g = problem.nodal["g"]
    w = np.zeros(len(problem.contact.nodes))
    done = 0
    cycle, computed, wears, jumps = [0], [], [w.copy()], []
    last = None
    prev: tuple[int, NDArray[np.float64]] | None = None
    while done < cycles.cycles:
        r = simulate(problem, solver, store="final", initial_wear=w)
        # the last level of the cycle, t = P, is the first of the next: its wear
        w_next = np.array(r.wear[-1], dtype=float)
        f = w_next - w  # the increment of this cycle
        J = min(cycles.jump, cycles.cycles - done)
        slope = (f - prev[1]) / (done - prev[0]) if prev is not None else np.zeros_like(f)
        while J > 1 and float(np.max(np.abs(_extra(f, slope, J)) / g)) > cycles.max_increment:
            J -= 1  # control: the extrapolated wear at most max_increment * g per jump
        w = w_next + _extra(f, slope, J)
        prev = (done, f)
        computed.append(done)
        done += J
        cycle.append(done)
        wears.append(w.copy())
        jumps.append(J)
        last = r
    assert last is not None
    return CycleResult(
        np.array(cycle),
        np.array(computed),
        np.array(wears),
        last,
        time.perf_counter() - t0,
        jumps,
    )


def _extra(f: NDArray[np.float64], slope: NDArray[np.float64], J: int) -> NDArray[np.float64]:
    """The wear of the ``J - 1`` cycles after a computed one (increments ``f + i slope``,
    ``i = 1 .. J - 1``)."""
    return (J - 1) * f + slope * ((J - 1) * J / 2)

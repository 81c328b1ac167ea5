"""Partitions of [0, T] (paper Section 3.4): uniform, explicit steps, repeating patterns.

The scheme (3.21)-(3.23) runs on any partition ``0 = t_0 < ... < t_N = T`` with steps
``k_n = t_{n+1} - t_n``; Example 5.3 uses a non-uniform one (docs/method.md, section 4).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray


@dataclass(frozen=True, eq=False)
class TimeGrid:
    """Time levels ``0 = t_0 < t_1 < … < t_N = T``; ``k_n = t_{n+1} - t_n``.

    Build one with :meth:`uniform`, :meth:`from_steps` or :meth:`pattern`, or from the
    levels themselves.

    Parameters
    ----------
    t : array_like
        The levels: finite, strictly increasing, starting at 0 (stored read-only).

    Raises
    ------
    ValueError
        If the levels are empty, not finite, do not start at 0 or do not increase
        strictly (the message names the offending pair).

    Examples
    --------
    >>> from vemwear import TimeGrid
    >>> TimeGrid.uniform(T=1.0, steps=4).t
    array([0.  , 0.25, 0.5 , 0.75, 1.  ])
    >>> TimeGrid.from_steps([0.25, 0.25, 0.5]).k
    array([0.25, 0.25, 0.5 ])
    >>> TimeGrid([0.0, 0.5, 0.4])
    Traceback (most recent call last):
    ...
    ValueError: time grid: levels must increase strictly (t[1] = 0.5, t[2] = 0.4)
    """

    t: NDArray[np.float64]

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=float)
        if t.ndim != 1 or t.size < 1:
            raise ValueError("time grid: needs at least the level t_0 = 0")
        if not np.all(np.isfinite(t)):
            raise ValueError("time grid: levels must be finite numbers")
        if t[0] != 0.0:
            raise ValueError(f"time grid: must start at t = 0, starts at {t[0]:g}")
        if np.any(np.diff(t) <= 0):
            i = int(np.flatnonzero(np.diff(t) <= 0)[0])
            raise ValueError(
                "time grid: levels must increase strictly "
                f"(t[{i}] = {t[i]:g}, t[{i + 1}] = {t[i + 1]:g})"
            )
        t.setflags(write=False)
        object.__setattr__(self, "t", t)

    @classmethod
    def uniform(cls, T: float, steps: int) -> TimeGrid:
        """``steps`` equal steps of size ``T / steps``.

        Parameters
        ----------
        T : float
            The final time, > 0.
        steps : int
            The number of steps, >= 1.
        """
        if int(steps) != steps or steps < 1:
            raise ValueError(f"time grid: steps must be a positive integer, got {steps}")
        if not T > 0:
            raise ValueError(f"time grid: T must be positive, got {T}")
        return cls(np.linspace(0.0, float(T), int(steps) + 1))

    @classmethod
    def from_steps(cls, steps: Sequence[float] | ArrayLike) -> TimeGrid:
        """Levels from an explicit list of step sizes ``k_0, k_1, ...``.

        Parameters
        ----------
        steps : sequence of float
            The step sizes, each > 0; ``T`` is their sum.
        """
        k = np.asarray(steps, dtype=float)
        if k.ndim != 1 or k.size == 0 or np.any(~(k > 0)):
            raise ValueError(f"time grid: step sizes must be positive numbers, got {k.tolist()}")
        return cls(np.concatenate([[0.0], np.cumsum(k)]))

    @classmethod
    def pattern(cls, T: float, pattern: Sequence[float]) -> TimeGrid:
        """Repeat the step sizes of ``pattern`` until T; the last step is cut to end at T.

        The paper's Example 5.3 uses ``pattern = [1/128, 3/128]`` with T = 1.

        Parameters
        ----------
        T : float
            The final time, > 0.
        pattern : sequence of float
            The step sizes to repeat, each > 0.
        """
        k = np.asarray(pattern, dtype=float)
        if k.ndim != 1 or k.size == 0 or np.any(~(k > 0)):
            raise ValueError(f"time grid: pattern must be positive step sizes, got {k.tolist()}")
        if not T > 0:
            raise ValueError(f"time grid: T must be positive, got {T}")
        reps = int(np.ceil(T / k.sum() + 1e-9)) + 1
        t = np.concatenate([[0.0], np.cumsum(np.tile(k, reps))])
        eps = 1e-9 * T
        t = t[t < T - eps]
        return cls(np.concatenate([t, [float(T)]]))

    @property
    def T(self) -> float:
        """The final time ``t_N``."""
        return float(self.t[-1])

    @property
    def k(self) -> NDArray[np.float64]:
        """Step sizes."""
        return np.diff(self.t)

    @property
    def n_steps(self) -> int:
        """The number of steps ``N``."""
        return len(self.t) - 1

    def index(self, times: ArrayLike, rtol: float = 1e-9) -> NDArray[np.int64]:
        """Indices of the levels at the given times.

        Parameters
        ----------
        times : array_like
            Times, each a level of the grid up to ``rtol * max(T, 1)``.
        rtol : float
            Relative tolerance of the match.

        Raises
        ------
        ValueError
            If a time is not a level (the message lists those).
        """
        times = np.atleast_1d(np.asarray(times, dtype=float))
        idx = self.nearest(times)
        off = np.abs(self.t[idx] - times) > rtol * max(self.T, 1.0)
        if np.any(off):
            raise ValueError(f"times {times[off].tolist()} are not levels of the time grid")
        return idx

    def nearest(self, times: ArrayLike) -> NDArray[np.int64]:
        """Indices of the levels nearest to ``times`` (the first of two as near), by
        bisection: no (times, levels) array, which took 640 MB and 10 s for the four
        default output times of 2e7 levels."""
        times = np.atleast_1d(np.asarray(times, dtype=float))
        t = self.t
        j = np.clip(np.searchsorted(t, times), 1, max(len(t) - 1, 1))
        i = j - 1
        if len(t) == 1:
            return np.zeros(times.shape, dtype=np.int64)
        right = np.abs(t[j] - times) < np.abs(t[i] - times)
        return np.where(right, j, i).astype(np.int64)

    def describe(self) -> dict:
        """``T``, the number of levels and the smallest and largest steps (JSON-friendly)."""
        k = self.k
        return {
            "T": self.T,
            "levels": len(self.t),
            "k_min": float(k.min()) if k.size else 0.0,
            "k_max": float(k.max()) if k.size else 0.0,
        }

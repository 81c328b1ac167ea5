"""Normal compliance laws ``p(r)`` of the soft layer (paper H(p), Section 2).

A law is Lipschitz, monotone and zero for ``r <= 0``; it gives the soft-layer pressure
``p_soft = p(u_nu - w)`` of (2.5). Every law gives its values, a (generalized)
derivative for Newton's method (docs/method.md, section 5), and its Lipschitz
constant ``L_p`` for the smallness condition of Theorem 3.4.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray


class ComplianceLaw:
    """Interface of a compliance law: ``p(r)``, ``p.derivative(r)`` and ``p.lipschitz``.

    Attributes
    ----------
    lipschitz : float
        The Lipschitz constant ``L_p`` of H(p) (Theorem 3.4).
    elementwise : bool
        True when ``p`` acts entry by entry on arrays of any shape, the same numbers
        as on each row (then several levels' penetrations are one call).
    piecewise_linear : bool
        True when ``p`` is linear on segments and :meth:`segments` gives them (then
        the step problem is linear on pieces; ``vemwear.solvers.pieces``).
    """

    lipschitz: float
    elementwise: ClassVar[bool] = False
    piecewise_linear: ClassVar[bool] = False

    def __call__(self, r: ArrayLike) -> NDArray[np.float64]:  # pragma: no cover - interface
        raise NotImplementedError

    def derivative(self, r: ArrayLike) -> NDArray[np.float64]:  # pragma: no cover - interface
        raise NotImplementedError

    def segments(self, r: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The slope ``s`` and offset ``q`` of the segment of each entry of ``r``:
        ``p = s r + q`` on that segment, ``s`` the derivative :meth:`derivative` gives;
        the same numbers for every ``r`` of a segment (laws with ``piecewise_linear``)."""
        raise NotImplementedError  # pragma: no cover - interface

    def describe(self) -> dict:  # pragma: no cover - interface
        raise NotImplementedError


@dataclass(frozen=True)
class LinearCompliance(ComplianceLaw):
    """The linear law ``p(r) = c r_+`` (the paper's examples use c = 0.4).

    Parameters
    ----------
    c : float
        The stiffness of the soft layer, >= 0; also the Lipschitz constant ``L_p``.

    Raises
    ------
    ValueError
        If ``c`` is negative or not finite.

    Examples
    --------
    >>> from vemwear import LinearCompliance
    >>> p = LinearCompliance(0.4)
    >>> p([-0.1, 0.0, 0.5])  # no pressure out of contact
    array([0. , 0. , 0.2])
    >>> p.lipschitz
    0.4
    """

    c: float
    elementwise: ClassVar[bool] = True
    piecewise_linear: ClassVar[bool] = True

    def __post_init__(self) -> None:
        if not np.isfinite(self.c) or self.c < 0:
            raise ValueError(f"compliance: stiffness c must be >= 0, got {self.c}")

    @property
    def lipschitz(self) -> float:  # type: ignore[override]
        return float(self.c)

    def __call__(self, r: ArrayLike) -> NDArray[np.float64]:
        return self.c * np.maximum(np.asarray(r, dtype=float), 0.0)

    def derivative(self, r: ArrayLike) -> NDArray[np.float64]:
        return np.where(np.asarray(r, dtype=float) > 0.0, self.c, 0.0)

    def segments(self, r: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        s = self.derivative(r)
        return s, np.zeros_like(s)

    def describe(self) -> dict:
        return {"type": "linear", "c": self.c}


@dataclass(frozen=True)
class TableCompliance(ComplianceLaw):
    """Piecewise-linear ``p`` through the points ``(r_i, p_i)``, ``0 = r_0 < r_1 < ...``.

    ``p = 0`` for ``r <= 0``; beyond the last point it continues with the last slope.
    The Lipschitz constant ``L_p`` is the largest slope.

    Parameters
    ----------
    r : tuple of float
        The penetrations ``r_i``, strictly increasing, starting at 0 (at least two).
    p : tuple of float
        The pressures ``p_i = p(r_i)``, non-decreasing, starting at 0.

    Raises
    ------
    ValueError
        If the table is not a monotone law through (0, 0) (the message names the entry).

    Examples
    --------
    A layer that stiffens: slope 0.1 up to r = 0.1, then 0.4.

    >>> from vemwear import TableCompliance
    >>> p = TableCompliance(r=(0.0, 0.1, 0.2), p=(0.0, 0.01, 0.05))
    >>> p([0.05, 0.15, 0.3])  # beyond the last point: the last slope
    array([0.005, 0.03 , 0.09 ])
    >>> round(p.lipschitz, 12)
    0.4
    >>> TableCompliance(r=(0.0, 0.1), p=(0.0, -1.0))
    Traceback (most recent call last):
    ...
    ValueError: compliance table: p must be non-decreasing (p[0] = 0.0 > p[1] = -1.0)
    """

    r: tuple[float, ...]
    p: tuple[float, ...]
    _slopes: NDArray[np.float64] = field(init=False, repr=False, compare=False)
    _offsets: NDArray[np.float64] = field(init=False, repr=False, compare=False)
    elementwise: ClassVar[bool] = True
    piecewise_linear: ClassVar[bool] = True

    def __post_init__(self) -> None:
        r = np.asarray(self.r, dtype=float)
        p = np.asarray(self.p, dtype=float)
        if r.ndim != 1 or r.shape != p.shape or r.size < 2:
            raise ValueError("compliance table: r and p must be lists of equal length >= 2")
        if not (np.all(np.isfinite(r)) and np.all(np.isfinite(p))):
            raise ValueError("compliance table: r and p must be finite numbers")
        if r[0] != 0.0 or p[0] != 0.0:
            raise ValueError(
                "compliance table: must start at r = 0 with p = 0 "
                f"(got r[0] = {r[0]}, p[0] = {p[0]}),"
                " since p(r) = 0 for r <= 0"
            )
        if np.any(np.diff(r) <= 0):
            i = int(np.flatnonzero(np.diff(r) <= 0)[0])
            raise ValueError(f"compliance table: r must increase strictly (r[{i}] >= r[{i + 1}])")
        slopes = np.diff(p) / np.diff(r)
        if np.any(slopes < 0):
            i = int(np.flatnonzero(slopes < 0)[0])
            raise ValueError(
                "compliance table: p must be non-decreasing "
                f"(p[{i}] = {p[i]} > p[{i + 1}] = {p[i + 1]})"
            )
        object.__setattr__(self, "r", tuple(r.tolist()))
        object.__setattr__(self, "p", tuple(p.tolist()))
        object.__setattr__(self, "_slopes", slopes)
        object.__setattr__(self, "_offsets", p[:-1] - slopes * r[:-1])  # p_k - s_k r_k

    @property
    def lipschitz(self) -> float:  # type: ignore[override]
        return float(self._slopes.max())

    def _segment(self, r: NDArray[np.float64]) -> NDArray[np.int64]:
        return np.clip(np.searchsorted(np.asarray(self.r), r, side="right") - 1, 0, len(self.r) - 2)

    def __call__(self, r: ArrayLike) -> NDArray[np.float64]:
        r = np.asarray(r, dtype=float)
        k = self._segment(r)
        val = np.asarray(self.p)[k] + self._slopes[k] * (r - np.asarray(self.r)[k])
        return np.where(r > 0.0, val, 0.0)

    def derivative(self, r: ArrayLike) -> NDArray[np.float64]:
        r = np.asarray(r, dtype=float)
        return np.where(r > 0.0, self._slopes[self._segment(r)], 0.0)

    def segments(self, r: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        r = np.asarray(r, dtype=float)
        k = self._segment(r)
        on = r > 0.0
        return np.where(on, self._slopes[k], 0.0), np.where(on, self._offsets[k], 0.0)

    def describe(self) -> dict:
        return {"type": "table", "r": list(self.r), "p": list(self.p)}


@dataclass(frozen=True)
class CallableCompliance(ComplianceLaw):
    """A user law from the Python API: ``p`` and its derivative ``dp`` as callables.

    :class:`vemwear.Problem` checks H(p) on samples (``check_law``): zero for
    ``r <= 0``, non-negative, monotone.

    Parameters
    ----------
    p : callable
        ``p(r)`` for an array ``r`` of penetrations, elementwise.
    dp : callable
        Its (generalized) derivative, elementwise, for Newton's method.
    lipschitz : float, optional
        The user's bound on ``dp``; only used for the smallness estimate of
        Theorem 3.4 (NaN: unknown).

    Examples
    --------
    >>> import numpy as np
    >>> from vemwear import CallableCompliance
    >>> p = CallableCompliance(
    ...     lambda r: 0.4 * np.maximum(r, 0.0) ** 2, lambda r: 0.8 * np.maximum(r, 0.0)
    ... )
    >>> p(np.array([-1.0, 0.5])), p.derivative(np.array([-1.0, 0.5]))
    (array([0. , 0.1]), array([0. , 0.4]))
    """

    p: Callable[[NDArray[np.float64]], NDArray[np.float64]]
    dp: Callable[[NDArray[np.float64]], NDArray[np.float64]]
    lipschitz: float = float("nan")  # type: ignore[assignment]

    def __call__(self, r: ArrayLike) -> NDArray[np.float64]:
        return np.asarray(self.p(np.asarray(r, dtype=float)), dtype=float)

    def derivative(self, r: ArrayLike) -> NDArray[np.float64]:
        return np.asarray(self.dp(np.asarray(r, dtype=float)), dtype=float)

    def describe(self) -> dict:
        return {"type": "callable", "p": getattr(self.p, "__name__", repr(self.p))}


def check_law(law: ComplianceLaw, scale: float = 1.0, samples: int = 201) -> None:
    """Check H(p) on samples of ``[-scale, 2 scale]``: zero for r <= 0, non-negative, monotone."""
    r = np.linspace(-scale, 2 * scale, samples)
    v = law(r)
    if v.shape != r.shape or not np.all(np.isfinite(v)):
        raise ValueError("compliance: p(r) must return finite values of the shape of r")
    if np.any(v[r <= 0] != 0):
        raise ValueError("compliance: p(r) must be 0 for r <= 0 (no pressure without penetration)")
    if np.any(v < 0):
        raise ValueError(f"compliance: p(r) is negative at r = {r[v < 0][0]:g}")
    if np.any(np.diff(v) < -1e-14 * max(1.0, np.abs(v).max())):
        i = int(np.flatnonzero(np.diff(v) < 0)[0])
        raise ValueError(f"compliance: p is not monotone near r = {r[i]:g}")


def as_law(spec: ComplianceLaw | float | Sequence) -> ComplianceLaw:
    """A law from a law, a number c (linear law), or a pair of lists (table)."""
    if isinstance(spec, ComplianceLaw):
        return spec
    if np.isscalar(spec):
        return LinearCompliance(float(spec))  # type: ignore[arg-type]
    r, p = spec  # type: ignore[misc]
    return TableCompliance(tuple(r), tuple(p))

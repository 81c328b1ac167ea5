"""Values of a configuration as the library takes them, expressions as callables.

A coefficient ``g``, ``mu``, ``kappa`` or ``gap`` written as an expression in ``x, y,
z`` becomes a :class:`NodalExpression` of the contact nodes, a load ``f1`` or ``f2``
with expressions in ``x, y, z, t`` (or traction tables) a :class:`FieldExpression` of
points and time, a ``v_star`` with expressions in ``t`` a :class:`VelocityExpression`
of time, one with expressions in ``x, y, z`` (and ``t``) a :class:`VelocityField` of the
contact nodes and time, and ``{ rotation = ... }`` a
:class:`~vemwear.contact.RotatingFoundation`; :func:`library_data` turns any value of the
schema (number, table, expression or array of these) into what the library takes,
:func:`velocity_data` a ``v_star``.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..contact import RotatingFoundation, table_values
from .expr import Expression
from .sections import Section

__all__ = [
    "FieldExpression",
    "NodalExpression",
    "VelocityExpression",
    "VelocityField",
    "library_data",
    "velocity_data",
]


class NodalExpression:
    """``g``, ``mu`` or ``kappa`` as an expression in ``x, y, z``, called with the (m, 2)
    or (m, 3) contact nodes (``z = 0`` in 2D); ``__name__`` is its text."""

    def __init__(self, expr: Expression) -> None:
        self.expr, self.__name__ = expr, expr.text

    def __call__(self, points: NDArray[np.float64]) -> NDArray[np.float64]:
        P = np.asarray(points, dtype=float)
        if "z" not in self.expr.names:
            return self.expr(x=P[..., 0], y=P[..., 1])
        z = P[..., 2] if P.shape[-1] == 3 else np.zeros(P.shape[:-1])
        return self.expr(x=P[..., 0], y=P[..., 1], z=z)


class FieldExpression:
    """A load of numbers, expressions in ``x, y, z, t`` and (a traction) tables
    ``{along, at, values}``: ``f(points, t)`` -> (m, d), d = 2 or 3 its components
    (``z = 0`` in 2D).

    ``arc(points)`` gives the arc length along the load's boundary part (tables along
    ``s``)."""

    def __init__(
        self,
        parts: Sequence[Expression | float | Section],
        text: str,
        arc: Callable[[NDArray[np.float64]], NDArray[np.float64]] | None = None,
    ) -> None:
        self.parts = tuple(c.model_dump() if isinstance(c, Section) else c for c in parts)
        self.__name__, self.arc = text, arc
        self.uses_t = any(isinstance(c, Expression) and "t" in c.names for c in self.parts)

    def __call__(self, x: NDArray[np.float64], t: float) -> NDArray[np.float64]:
        X = np.asarray(x, dtype=float)
        P = X.reshape(-1, 3 if X.ndim == 2 and X.shape[1] == 3 else 2)
        env = {"x": P[:, 0], "y": P[:, 1], "t": np.full(len(P), float(t))}
        if any(isinstance(c, Expression) and "z" in c.names for c in self.parts):
            env["z"] = P[:, 2] if P.shape[1] == 3 else np.zeros(len(P))
        cols = []
        for i, c in enumerate(self.parts):
            if isinstance(c, dict):
                cols.append(table_values(c, P, functools.partial(self._arc, P), f"f2[{i}]"))
            else:
                cols.append(_value(c, env))
        return np.column_stack(cols)

    def _arc(self, P: NDArray[np.float64]) -> NDArray[np.float64]:
        if self.arc is None:
            raise ValueError("f2: a table along s needs a boundary part")
        return self.arc(P)


class VelocityExpression:
    """``v_star`` of numbers and expressions in ``t``: ``v(t)`` -> 2-vector."""

    def __init__(self, parts: Sequence[Expression | float], text: str) -> None:
        self.parts, self.__name__ = tuple(parts), text

    def __call__(self, t: float) -> NDArray[np.float64]:
        return np.array([float(_value(c, {"t": np.array([float(t)])})[0]) for c in self.parts])

    def at_times(self, t: NDArray[np.float64]) -> NDArray[np.float64]:
        """``v(t)`` at many times at once: (len(t), 2)."""
        ts = np.asarray(t, dtype=float).ravel()
        return np.column_stack(
            [np.broadcast_to(_value(c, {"t": ts}), ts.shape) for c in self.parts]
        )


class VelocityField:
    """``v_star`` of numbers and expressions in ``x, y, z, t``: ``v(points, t)`` -> (m, d)
    at the (m, d) contact nodes (``z = 0`` in 2D); a field of the points (``spatial``)."""

    spatial = True

    def __init__(self, parts: Sequence[Expression | float], text: str) -> None:
        self.parts, self.__name__ = tuple(parts), text

    def __call__(self, points: NDArray[np.float64], t: float) -> NDArray[np.float64]:
        P = np.asarray(points, dtype=float)
        env = {"x": P[:, 0], "y": P[:, 1], "t": np.full(len(P), float(t))}
        env["z"] = P[:, 2] if P.shape[1] == 3 else np.zeros(len(P))
        return np.column_stack([_value(c, env) for c in self.parts])


class OmegaExpression:
    """The angular velocity of a rotation as an expression in ``t``: ``omega(t)``."""

    def __init__(self, expr: Expression) -> None:
        self.expr, self.__name__ = expr, expr.text

    def __call__(self, t: float) -> float:
        return float(self.expr(t=np.array([float(t)]))[0])


def velocity(parts: Sequence[Expression | float], text: str) -> Any:
    """A ``v_star`` array with expressions: of ``t`` alone, or a field of ``x, y, z``."""
    if any(isinstance(c, Expression) and c.names & {"x", "y", "z"} for c in parts):
        return VelocityField(parts, text)
    return VelocityExpression(parts, text)


def velocity_data(v: Any, raw: Any) -> Any:
    """A ``v_star`` of the schema as the library takes it: an array (numbers,
    expressions of t or of x, y, z, t), a table, or a rotation."""
    rot = getattr(v, "rotation", None)
    if rot is None:
        return library_data(v, velocity, raw)
    omega = rot.omega
    return RotatingFoundation(
        center=tuple(rot.center),
        axis=tuple(rot.axis),
        omega=OmegaExpression(omega) if isinstance(omega, Expression) else float(omega),
    )


def _value(c: Expression | float, env: dict[str, NDArray[np.float64]]) -> NDArray[np.float64]:
    return c(**env) if isinstance(c, Expression) else np.full(len(env["t"]), float(c))


def library_data(v: Any, cls: Callable[..., Any] | None, raw: Any) -> Any:
    """A number, table (as a dict) or expression of the schema as the library takes it."""
    if isinstance(v, Expression):
        return NodalExpression(v)
    if isinstance(v, Section):
        return v.model_dump(by_alias=True)
    if cls and isinstance(v, list) and any(isinstance(c, Expression | Section) for c in v):
        return cls(v, "[" + ", ".join(repr(c) for c in raw) + "]")
    return tuple(v) if isinstance(v, list) else v

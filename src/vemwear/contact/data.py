"""Contact data: coefficients along Gamma_C (g, mu, kappa) and the foundation velocity v*(t).

A coefficient along Gamma_C is a number, a callable of the node coordinates
(Python API), or a piecewise-linear table ``{"along": "x" | "y" | "s", "at": [...],
"values": [...]}`` in a coordinate of the node (``s`` is the arc length along the
contact part); :func:`table_values` evaluates such a table at any boundary points (a
traction component of a config file may be one too). ``v*(t)`` is a 2-vector, a
callable of t, or a table ``{"t": [...], "values": [[vx, vy], ...]}`` interpolated
linearly in time. The
coefficients enter the scheme at the contact nodes (nodal quadrature, docs/method.md,
section 3); v*(t) through the friction direction ``n* = -v* / |v*|`` (2.2) and the
wear rate ``kappa |v*(t)| p(u_nu - w)`` of (3.22).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .boundary import ContactBoundary

NodalField = float | Mapping[str, Any] | Callable[[NDArray[np.float64]], ArrayLike]


def nodal_values(spec: NodalField, cb: ContactBoundary, name: str) -> NDArray[np.float64]:
    """Values of a coefficient at the contact nodes (shape (m,))."""
    if callable(spec):
        v = np.asarray(spec(cb.points), dtype=float)
        v = np.broadcast_to(v, (cb.m,)).copy()
    elif isinstance(spec, Mapping):
        v = table_values(spec, cb.points, lambda: cb.s, name)
    else:
        v = np.full(cb.m, float(spec))
    if not np.all(np.isfinite(v)):
        a = int(np.flatnonzero(~np.isfinite(v))[0])
        raise ValueError(
            f"{name} is not finite on the contact part: it is {v[a]:g} at contact node {a} "
            f"(vertex {cb.nodes[a]}, x = {cb.points[a].tolist()})"
        )
    return v


def table_values(
    spec: Mapping[str, Any],
    points: NDArray[np.float64],
    arc: Callable[[], NDArray[np.float64]],
    name: str,
) -> NDArray[np.float64]:
    """A table ``{"along", "at", "values"}`` at boundary points (shape (n,)).

    Parameters
    ----------
    spec : mapping
        ``along`` (``"x"``, ``"y"`` or ``"s"``; default ``"x"``), ``at`` (strictly
        increasing) and ``values``; piecewise linear, constant beyond the ends.
    points : (n, 2) array
        The points.
    arc : callable
        ``arc()`` -> (n,) arc lengths of the points along their part (called for
        ``along = "s"`` only).
    name : str
        The coefficient, for messages.
    """
    along = spec.get("along", "x")
    if along not in ("x", "y", "z", "s") or (along == "z" and np.shape(points)[1] < 3):
        raise ValueError(f"{name}: 'along' must be 'x', 'y' or 's' (3D: 'z'), got {along!r}")
    at = np.asarray(spec["at"], dtype=float)
    vals = np.asarray(spec["values"], dtype=float)
    if at.ndim != 1 or at.shape != vals.shape or at.size < 1 or np.any(np.diff(at) <= 0):
        raise ValueError(f"{name}: 'at' must increase strictly and match 'values' in length")
    coord = arc() if along == "s" else np.asarray(points, dtype=float)[:, "xyz".index(along)]
    return np.interp(coord, at, vals)


@dataclass(frozen=True)
class FoundationVelocity:
    """``v*(t)``; gives ``n*(t) = -v*/|v*|`` and ``|v*(t)|`` (paper 2.2)."""

    spec: ArrayLike | Mapping[str, Any] | Callable[[float], ArrayLike]

    def __call__(self, t: float) -> NDArray[np.float64]:
        s = self.spec
        if callable(s):
            v = np.asarray(s(t), dtype=float)
        elif isinstance(s, Mapping):
            ts = np.asarray(s["t"], dtype=float)
            vals = np.asarray(s["values"], dtype=float)
            v = np.array([np.interp(t, ts, vals[:, c]) for c in range(vals.shape[1])])
        else:
            v = np.asarray(s, dtype=float)
        if v.shape not in ((2,), (3,)) or not np.all(np.isfinite(v)):
            raise ValueError(f"v_star({t:g}) must be a finite 2- or 3-vector, got {v!r}")
        return v

    @property
    def steady(self) -> bool:
        """Whether v* is one constant vector (neither a function of t nor a table)."""
        return not (callable(self.spec) or isinstance(self.spec, Mapping))

    def n_star(self, t: float) -> NDArray[np.float64]:
        """``-v*/|v*|``, or zero where the foundation stands still."""
        v = self(t)
        nv = float(np.linalg.norm(v))
        return -v / nv if nv > 0.0 else np.zeros(len(v))

    def speed(self, t: float) -> float:
        return float(np.linalg.norm(self(t)))

    def describe(self) -> Any:
        s = self.spec
        if callable(s):
            return getattr(s, "__name__", "callable")
        if isinstance(s, Mapping):
            return {k: np.asarray(v).tolist() for k, v in s.items()}
        return np.asarray(s, dtype=float).tolist()

"""Contact data: coefficients along Gamma_C (g, mu, kappa) and the foundation velocity v*(t).

A coefficient along Gamma_C is a number, a callable of the node coordinates
(Python API), or a piecewise-linear table ``{"along": "x" | "y" | "s", "at": [...],
"values": [...]}`` in a coordinate of the node (``s`` is the arc length along the
contact part); :func:`table_values` evaluates such a table at any boundary points (a
traction component of a config file may be one too). ``v*(t)`` is a 2-vector, a
callable of t, or a table ``{"t": [...], "values": [[vx, vy], ...]}`` interpolated
linearly in time; a sliding *field* ``v*(x, t)`` is a callable of the points and the
time (``FoundationVelocity(f, spatial=True)``) or a :class:`RotatingFoundation`
(``v* = omega x (x - c)``, a disc turning under the body). The
coefficients enter the scheme at the contact nodes (nodal quadrature, docs/method.md,
section 3); v* through the friction direction ``n* = -v*_tau / |v*_tau|`` (2.2) and the
wear rate ``kappa |v*_tau| p(u_nu - w)`` of (3.22), node by node (section 3b).
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
    """The foundation velocity ``v*``: of the time alone, or a field ``v*(x, t)``.

    Parameters
    ----------
    spec : vector, mapping, callable or RotatingFoundation
        A constant 2- or 3-vector; a table ``{"t": [...], "values": [...]}`` (linear in
        t); a callable ``f(t)`` -> vector; or, with ``spatial=True`` (or a spec with a
        true attribute ``spatial``, as :class:`RotatingFoundation`), a callable
        ``f(points, t)`` of the (m, d) contact nodes and the time -> (m, d) velocities
        (or one d-vector for all).
    spatial : bool
        Whether ``spec`` is a field of the points and the time.

    ``v*(t)`` (:meth:`__call__`) exists for the forms of the time alone;
    :meth:`at` evaluates every form at points.
    """

    spec: ArrayLike | Mapping[str, Any] | Callable[..., ArrayLike]
    spatial: bool = False

    def __post_init__(self) -> None:
        if getattr(self.spec, "spatial", False):
            object.__setattr__(self, "spatial", True)
        if self.spatial and not callable(self.spec):
            raise ValueError("a spatial v_star must be a callable f(points, t)")

    def __call__(self, t: float) -> NDArray[np.float64]:
        if self.spatial:
            raise ValueError(
                "v_star depends on the position: evaluate it at points (FoundationVelocity.at)"
            )
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

    def at(self, points: NDArray[np.float64], t: float) -> NDArray[np.float64]:
        """``v*(x_a, t)`` at the (m, d) ``points``, (m, d); not checked for being finite
        (the caller names the node and the level)."""
        P = np.asarray(points, dtype=float)
        if not self.spatial:
            return np.broadcast_to(self(t), P.shape).copy()
        v = np.asarray(self.spec(P, t), dtype=float)  # type: ignore[operator]
        if v.shape not in (P.shape, (P.shape[1],)):
            raise ValueError(
                f"v_star(x, {t:g}) must give a {P.shape[1]}-vector at each of the {len(P)} "
                f"points, got shape {v.shape}"
            )
        return np.broadcast_to(v, P.shape).copy()

    @property
    def steady(self) -> bool:
        """Whether v* is the same at every time: one constant vector, or a rotation with
        a constant omega (the same field at every level)."""
        s = self.spec
        if isinstance(s, RotatingFoundation):
            return not callable(s.omega)
        return not (callable(s) or isinstance(s, Mapping))

    def n_star(self, t: float) -> NDArray[np.float64]:
        """``-v*/|v*|``, or zero where the foundation stands still."""
        v = self(t)
        nv = float(np.linalg.norm(v))
        return -v / nv if nv > 0.0 else np.zeros(len(v))

    def speed(self, t: float) -> float:
        return float(np.linalg.norm(self(t)))

    def describe(self) -> Any:
        s = self.spec
        if isinstance(s, RotatingFoundation):
            return s.describe()
        if callable(s):
            return getattr(s, "__name__", "callable")
        if isinstance(s, Mapping):
            return {k: np.asarray(v).tolist() for k, v in s.items()}
        return np.asarray(s, dtype=float).tolist()


@dataclass(frozen=True)
class RotatingFoundation:
    """A counterface turning about an axis: ``v*(x, t) = omega(t) a x (x - c)``.

    Parameters
    ----------
    center : 2- or 3-vector
        A point c of the axis (in 2D the axis is normal to the plane through c).
    axis : 3-vector
        The direction a of the axis (normalized here); in 2D it must be (0, 0, +-1).
    omega : float or callable
        The angular velocity (rad per unit time), or a callable ``omega(t)``.

    A field of the points and the time (``spatial``): pass it as ``v_star``.
    """

    center: ArrayLike
    axis: ArrayLike = (0.0, 0.0, 1.0)
    omega: float | Callable[[float], float] = 1.0
    spatial: bool = True

    def __post_init__(self) -> None:
        c = np.asarray(self.center, dtype=float)
        a = np.asarray(self.axis, dtype=float)
        if c.shape not in ((2,), (3,)) or not np.all(np.isfinite(c)):
            raise ValueError(f"rotation: center must be 2 or 3 finite numbers, got {c.tolist()}")
        if a.shape != (3,) or not np.all(np.isfinite(a)) or not np.linalg.norm(a) > 0:
            raise ValueError(f"rotation: axis must be a nonzero 3-vector, got {a.tolist()}")
        a = a / np.linalg.norm(a)
        if len(c) == 2 and not np.allclose(a[:2], 0.0, atol=1e-12):
            raise ValueError(
                f"rotation: in 2D the axis is normal to the plane, (0, 0, 1) or (0, 0, -1); "
                f"got {np.asarray(self.axis, dtype=float).tolist()}"
            )
        object.__setattr__(self, "center", c)
        object.__setattr__(self, "axis", a)

    def angular_velocity(self, t: float) -> float:
        w = self.omega
        return float(w(t)) if callable(w) else float(w)

    def __call__(self, points: NDArray[np.float64], t: float) -> NDArray[np.float64]:
        P = np.asarray(points, dtype=float)
        c, a = np.asarray(self.center), np.asarray(self.axis)
        w = self.angular_velocity(t)
        if P.shape[1] != len(c):
            raise ValueError(
                f"rotation: the center has {len(c)} components, the points {P.shape[1]}"
            )
        d = P - c
        if len(c) == 2:  # omega e_z x d, e_z = sign(a_z) e_z
            s = w * float(np.sign(a[2]))
            return np.column_stack([-s * d[:, 1], s * d[:, 0]])
        return w * np.cross(a, d)

    def describe(self) -> dict[str, Any]:
        w = self.omega
        return {
            "rotation": {
                "center": np.asarray(self.center).tolist(),
                "axis": np.asarray(self.axis).tolist(),
                "omega": getattr(w, "__name__", "callable") if callable(w) else float(w),
            }
        }

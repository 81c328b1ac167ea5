"""Several contact parts, each with its own data (docs/method.md, section 3b).

A :class:`ContactPart` is one named boundary part of Gamma_C with its own layer
thickness g, friction and wear coefficients mu and kappa, compliance law p, initial
gap and foundation velocity v*(t). The scheme sees them through nodal arrays: every
contact node belongs to one part (:attr:`ContactBoundary.part`), and
:class:`NodalLaw` applies each part's law at its nodes.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .data import FoundationVelocity, NodalField
from .law import ComplianceLaw, LinearCompliance

__all__ = ["ContactPart", "NodalLaw", "tangential_velocity", "velocity_levels"]


@dataclass(frozen=True, eq=False)
class ContactPart:
    """One part of Gamma_C and its data.

    Parameters
    ----------
    part : str
        The boundary part of the mesh.
    p : ComplianceLaw
        Normal compliance law of the soft layer.
    g, mu, kappa : NodalField
        Thickness of the soft layer (> 0), friction coefficient (>= 0), wear
        coefficient (>= 0) along the part.
    v_star : FoundationVelocity or 2-vector
        Velocity of the foundation under this part.
    gap : NodalField
        Initial gap (>= 0) between the body and the layer: the penetration is
        ``u_nu - gap - w`` and the constraint ``u_nu - gap <= g``.
    """

    part: str = "contact"
    p: ComplianceLaw = field(default_factory=lambda: LinearCompliance(0.4))
    g: NodalField = 0.1
    mu: NodalField = 0.0
    kappa: NodalField = 0.0
    v_star: FoundationVelocity | ArrayLike = (1.0, 0.0)
    gap: NodalField = 0.0

    def __post_init__(self) -> None:
        if not isinstance(self.v_star, FoundationVelocity):
            object.__setattr__(self, "v_star", FoundationVelocity(self.v_star))

    @property
    def velocity(self) -> FoundationVelocity:
        return self.v_star  # type: ignore[return-value]


@dataclass(frozen=True, eq=False)
class NodalLaw(ComplianceLaw):
    """The compliance laws of several parts, each applied at its own nodes.

    Parameters
    ----------
    laws : sequence of ComplianceLaw
        One law per part.
    part : (m,) int array
        The part of every contact node.
    """

    laws: tuple[ComplianceLaw, ...]
    part: NDArray[np.int64]

    @property
    def lipschitz(self) -> float:  # type: ignore[override]
        return float(max(law.lipschitz for law in self.laws))

    def _apply(self, r: ArrayLike, derivative: bool) -> NDArray[np.float64]:
        r = np.asarray(r, dtype=float)
        out = np.zeros_like(r)
        for i, law in enumerate(self.laws):
            sel = self.part == i
            out[sel] = law.derivative(r[sel]) if derivative else law(r[sel])
        return out

    def __call__(self, r: ArrayLike) -> NDArray[np.float64]:
        return self._apply(r, False)

    def derivative(self, r: ArrayLike) -> NDArray[np.float64]:
        return self._apply(r, True)

    def describe(self) -> dict[str, Any]:
        return {"type": "by part", "laws": [law.describe() for law in self.laws]}


def tangential_velocity(
    parts: Sequence[ContactPart],
    part: NDArray[np.int64],
    tangents: NDArray[np.float64],
    t: float,
) -> NDArray[np.float64]:
    """``v*(t) · tau_a`` at every contact node, with the v* of the node's part.

    The tangential part of the foundation velocity is ``v*_tau = (v* . tau_a) tau_a``
    in 2D; its sign gives the friction direction ``n* = -v*_tau / |v*_tau|`` and its
    length the wear rate ``alpha = kappa |v*_tau|`` (docs/method.md, section 3b).
    """
    V = np.array([pc.velocity(t) for pc in parts])  # (n_parts, d)
    v = V[part]
    if tangents.shape[1] != v.shape[1]:
        raise ValueError(
            f"v_star has {v.shape[1]} components, the contact tangents {tangents.shape[1]}"
        )
    out = v[:, 0] * tangents[:, 0] + v[:, 1] * tangents[:, 1]
    if tangents.shape[1] == 3:  # 3D: tau_a is the line of v*_tau (contact.boundary3d)
        out = out + v[:, 2] * tangents[:, 2]
    return np.asarray(out, dtype=np.float64)


def velocity_levels(v: FoundationVelocity, t: NDArray[np.float64]) -> NDArray[np.float64]:
    """``v*(t_n)`` at many times at once, (len(t), d), not checked for being finite.

    Numbers and tables of t are evaluated in one go, as is a callable with a method
    ``at_times(t)`` (the expressions of a configuration file); any other callable one
    time at a time.
    """
    ts = np.asarray(t, dtype=float).ravel()
    if ts.size == 0:
        return np.zeros((0, len(v(0.0))))
    s = v.spec
    if callable(s):
        many = getattr(s, "at_times", None)
        if many is not None:
            return np.asarray(many(ts), dtype=float).reshape(len(ts), -1)
        return np.array([np.asarray(s(x), dtype=float) for x in ts]).reshape(len(ts), -1)
    if isinstance(s, Mapping):
        at, vals = np.asarray(s["t"], dtype=float), np.asarray(s["values"], dtype=float)
        return np.column_stack([np.interp(ts, at, vals[:, c]) for c in range(vals.shape[1])])
    c = np.asarray(s, dtype=float).ravel()
    return np.broadcast_to(c, (len(ts), len(c))).copy()
